//! Checkpoints: the whole state of a season run in one file, so an interrupted run resumes
//! and ends bit-identical to an uninterrupted one.
//!
//! Layout (little-endian): the magic `SNOWCKPT`, a u32 format version, a u64 length and that
//! many bytes of JSON header (the caller's run state: scheduler, budget, time, and a
//! fingerprint of the inputs), then the four snow layers as raw f32, bottom to top, then the
//! caller's extra per-cell f32 maps (version 2: the season's avalanche scour and deposit). The file
//! is written atomically by the caller (temporary name, then rename), so a crash mid-write
//! leaves the previous checkpoint intact.

use serde::{Serialize, de::DeserializeOwned};
use snowscape_terrain::{LayeredTerrain, random::mix64};
use std::io::{Read, Write};
use thiserror::Error;

const MAGIC: &[u8; 8] = b"SNOWCKPT";
const VERSION: u32 = 2;

/// Why a checkpoint could not be written or read.
#[derive(Debug, Error)]
pub enum CheckpointError {
    #[error("checkpoint I/O: {0}")]
    Io(#[from] std::io::Error),
    #[error("not a snowscape checkpoint (magic bytes {found:?})")]
    BadMagic { found: [u8; 8] },
    #[error("checkpoint format version {found}, this build reads version {VERSION}")]
    Version { found: u32 },
    #[error("checkpoint header: {0}")]
    Header(#[from] serde_json::Error),
    #[error("checkpoint header of {0} bytes is implausibly large")]
    HeaderTooLarge(u64),
    #[error("checkpoint holds layers for {found} cells, the terrain has {expected}")]
    SizeMismatch { expected: usize, found: usize },
    #[error("checkpoint layers are truncated: {0}")]
    Truncated(std::io::Error),
}

/// A fingerprint of a terrain's bedrock and geometry, to refuse resuming on other inputs.
pub fn bedrock_fingerprint(terrain: &LayeredTerrain) -> u64 {
    let g = terrain.geometry();
    let mut h = mix64(g.width() as u64 ^ ((g.height() as u64) << 32));
    h = mix64(h ^ g.cell_size_x().to_bits());
    h = mix64(h ^ g.cell_size_y().to_bits());
    for &z in &terrain.bedrock {
        h = mix64(h ^ z.to_bits() as u64);
    }
    h
}

/// Writes `header`, the snow layers of `terrain` and the `extra` per-cell maps to `w`.
pub fn write<H: Serialize>(
    w: &mut impl Write,
    header: &H,
    terrain: &LayeredTerrain,
    extra: &[&[f32]],
) -> Result<(), CheckpointError> {
    let json = serde_json::to_vec(header)?;
    w.write_all(MAGIC)?;
    w.write_all(&VERSION.to_le_bytes())?;
    w.write_all(&(json.len() as u64).to_le_bytes())?;
    w.write_all(&json)?;
    let mut buf = Vec::with_capacity(terrain.geometry().len() * 4);
    for layer in terrain
        .snow
        .iter()
        .map(|l| l.as_slice())
        .chain(extra.iter().copied())
    {
        buf.clear();
        for v in layer {
            buf.extend_from_slice(&v.to_le_bytes());
        }
        w.write_all(&buf)?;
    }
    Ok(())
}

/// Reads a checkpoint written by [`write`] with `extra` extra maps: returns the header and the
/// extra maps and overwrites the snow layers of `terrain` (whose bedrock and geometry come from
/// the inputs, as in the original run).
pub fn read<H: DeserializeOwned>(
    r: &mut impl Read,
    terrain: &mut LayeredTerrain,
    extra: usize,
) -> Result<(H, Vec<Vec<f32>>), CheckpointError> {
    let mut magic = [0u8; 8];
    r.read_exact(&mut magic)?;
    if &magic != MAGIC {
        return Err(CheckpointError::BadMagic { found: magic });
    }
    let mut b4 = [0u8; 4];
    r.read_exact(&mut b4)?;
    let version = u32::from_le_bytes(b4);
    if version != VERSION {
        return Err(CheckpointError::Version { found: version });
    }
    let mut b8 = [0u8; 8];
    r.read_exact(&mut b8)?;
    let len = u64::from_le_bytes(b8);
    if len > 64 << 20 {
        return Err(CheckpointError::HeaderTooLarge(len));
    }
    let mut json = vec![0u8; len as usize];
    r.read_exact(&mut json)?;
    let header: H = serde_json::from_slice(&json)?;
    let n = terrain.geometry().len();
    let mut raw = Vec::new();
    r.read_to_end(&mut raw)?;
    let maps = 4 + extra;
    if raw.len() != 4 * maps * n {
        return Err(CheckpointError::SizeMismatch {
            expected: n,
            found: raw.len() / (4 * maps),
        });
    }
    for (k, layer) in terrain.snow.iter_mut().enumerate() {
        let bytes = &raw[k * 4 * n..(k + 1) * 4 * n];
        for (v, c) in layer.iter_mut().zip(bytes.chunks_exact(4)) {
            *v = f32::from_le_bytes([c[0], c[1], c[2], c[3]]);
        }
    }
    let extra_maps = (4..maps)
        .map(|k| {
            raw[k * 4 * n..(k + 1) * 4 * n]
                .chunks_exact(4)
                .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                .collect()
        })
        .collect();
    Ok((header, extra_maps))
}

#[cfg(test)]
mod tests {
    use super::*;
    use snowscape_terrain::{Grid, GridGeometry, SnowLayer};

    fn terrain() -> LayeredTerrain {
        let g = GridGeometry::square(5, 3, 2.0).unwrap();
        let mut t = LayeredTerrain::from_bedrock(Grid::from_fn(g, |c, r| (c * 7 + r) as f32));
        for (k, l) in SnowLayer::ALL.iter().enumerate() {
            for (i, v) in t.layer_mut(*l).iter_mut().enumerate() {
                *v = (i * (k + 1)) as f32 * 0.1;
            }
        }
        t
    }

    #[test]
    fn round_trip_is_bit_exact() {
        let t = terrain();
        let mut bytes = Vec::new();
        write(&mut bytes, &("day", 42u32), &t, &[&[7.0f32; 15]]).unwrap();
        let mut back = LayeredTerrain::from_bedrock(Grid::from_fn(t.geometry().clone(), |c, r| {
            (c * 7 + r) as f32
        }));
        let (h, extra): ((String, u32), _) = read(&mut bytes.as_slice(), &mut back, 1).unwrap();
        assert_eq!(extra, vec![vec![7.0f32; 15]]);
        assert_eq!(h, ("day".to_string(), 42));
        assert_eq!(back, t);
        assert_eq!(bedrock_fingerprint(&back), bedrock_fingerprint(&t));
    }

    #[test]
    fn corrupt_or_truncated_files_are_typed_errors() {
        let t = terrain();
        let mut bytes = Vec::new();
        write(&mut bytes, &1u8, &t, &[]).unwrap();
        let mut target = t.clone();
        let cut = &bytes[..bytes.len() - 3];
        assert!(matches!(
            read::<u8>(&mut &cut[..], &mut target, 0),
            Err(CheckpointError::SizeMismatch { .. })
        ));
        let mut bad = bytes.clone();
        bad[0] = b'X';
        assert!(matches!(
            read::<u8>(&mut bad.as_slice(), &mut target, 0),
            Err(CheckpointError::BadMagic { .. })
        ));
        assert!(read::<u8>(&mut &bytes[..10], &mut target, 0).is_err());
    }
}
