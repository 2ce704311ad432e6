//! Checkpoints: the whole state of a season run in one file, so an interrupted run resumes
//! and ends bit-identical to an uninterrupted one.
//!
//! Layout (little-endian, format version 3): the magic `SNOWCKPT`, a u32 format version, a
//! u64 length of the JSON header, a u64 length of the maps, the JSON header (the caller's run
//! state: scheduler, budget, time, the resolved scenario and a fingerprint of the inputs),
//! the four snow layers as raw f32, bottom to top, then the caller's extra per-cell f32 maps,
//! and last a CRC-32 (IEEE) of every byte before it. A reader checks the magic, the version,
//! the lengths (a short file is "truncated", naming both sizes) and the checksum (a flipped
//! bit is refused) before it parses anything. The file is written atomically by the caller
//! (temporary name, then rename), so a crash mid-write leaves the previous checkpoint intact.
//!
//! [`read_file`] opens only a regular file (a device such as `/dev/zero` reads without end, a
//! FIFO blocks: both are refused before anything is read), refuses one longer than the
//! largest checkpoint of the terrain (a [`MAX_HEADER`] header and the maps of its cells), and
//! after the preamble checks the file's length against the one the preamble announces,
//! before the body is allocated.
//!
//! The checksum detects damage, not nonsense: a file written wrong or forged with a matching
//! checksum can still hold an index past its table, a time of −1e300 or NaN snow. The caller
//! validates every decoded value (the season does in [`crate::winter::Winter::resume`]) and
//! refuses one out of range with [`CheckpointError::Implausible`], naming the field and the
//! value (cut to [`crate::MAX_ECHO_CHARS`] characters).

use serde::{Serialize, de::DeserializeOwned};
use snowscape_terrain::{LayeredTerrain, random::mix64};
use std::io::{Read, Write};
use thiserror::Error;

const MAGIC: &[u8; 8] = b"SNOWCKPT";
/// The format this build writes and reads.
pub const VERSION: u32 = 3;
/// Bytes before the JSON header: magic, version, two lengths.
const PREAMBLE: usize = 8 + 4 + 8 + 8;
/// Largest JSON header accepted, bytes.
pub const MAX_HEADER: u64 = 64 << 20;

/// Why a checkpoint could not be written or read.
#[derive(Debug, Error)]
pub enum CheckpointError {
    #[error("checkpoint I/O: {0}")]
    Io(#[from] std::io::Error),
    #[error("not a snowscape checkpoint (magic bytes {found:?})")]
    BadMagic { found: [u8; 8] },
    #[error(
        "checkpoint format version {found}, this build reads version {VERSION} (start the run again without --resume)"
    )]
    Version { found: u32 },
    #[error("checkpoint is truncated: {found} bytes, its header announces {expected}")]
    Truncated { expected: u64, found: u64 },
    #[error("checkpoint has {extra} bytes after its checksum")]
    TrailingBytes { extra: u64 },
    #[error(
        "checkpoint is corrupt: its checksum is {stored:08x} but its content sums to {computed:08x} (a damaged or partly copied file)"
    )]
    Checksum { stored: u32, computed: u32 },
    #[error("checkpoint header: {0}")]
    Header(#[from] serde_json::Error),
    #[error("checkpoint header of {0} bytes is implausibly large")]
    HeaderTooLarge(u64),
    #[error("checkpoint holds layers for {found} cells, the terrain has {expected}")]
    SizeMismatch { expected: usize, found: usize },
    #[error("checkpoint {path} is {kind}, not a regular file: refusing to read it")]
    NotRegular {
        path: std::path::PathBuf,
        kind: &'static str,
    },
    #[error(
        "checkpoint {path} is {bytes} bytes, more than the {max} bytes a checkpoint of this terrain can hold"
    )]
    TooLarge {
        path: std::path::PathBuf,
        bytes: u64,
        max: u64,
    },
    #[error("cannot read checkpoint {path}: {source}")]
    Open {
        path: std::path::PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error(
        "checkpoint field {field} = {value} is implausible: {expected} (the checksum matches, so the file was written wrong or forged)"
    )]
    Implausible {
        field: String,
        value: String,
        expected: String,
    },
}

impl CheckpointError {
    /// An [`CheckpointError::Implausible`] value, cut for the message.
    pub fn implausible(
        field: impl Into<String>,
        value: impl ToString,
        expected: impl Into<String>,
    ) -> Self {
        Self::Implausible {
            field: field.into(),
            value: crate::clip_for_message(&value.to_string()),
            expected: expected.into(),
        }
    }
}

/// The largest checkpoint of a terrain of `cells` cells with `extra` extra maps, bytes.
pub fn max_len(cells: usize, extra: usize) -> u64 {
    PREAMBLE as u64 + MAX_HEADER + 4 * (4 + extra as u64) * cells as u64 + 4
}

/// Reads and verifies the checkpoint file at `path` (as [`read`]), opening only a regular
/// file of at most [`max_len`] bytes and checking its length against the preamble's before
/// the body is allocated (module docs).
pub fn read_file<H: DeserializeOwned>(
    path: &std::path::Path,
    cells: usize,
    extra: usize,
) -> Result<Contents<H>, CheckpointError> {
    let open = |source| CheckpointError::Open {
        path: path.to_path_buf(),
        source,
    };
    let not_regular = |t| CheckpointError::NotRegular {
        path: path.to_path_buf(),
        kind: snowscape_io::input::kind_of(t),
    };
    // The path's metadata first: nothing is opened, so a FIFO cannot block.
    let meta = std::fs::metadata(path).map_err(open)?;
    if !meta.is_file() {
        return Err(not_regular(meta.file_type()));
    }
    let file = std::fs::File::open(path).map_err(open)?;
    // The path could have been replaced between the check and the open.
    let meta = file.metadata().map_err(open)?;
    if !meta.is_file() {
        return Err(not_regular(meta.file_type()));
    }
    let max = max_len(cells, extra);
    if meta.len() > max {
        return Err(CheckpointError::TooLarge {
            path: path.to_path_buf(),
            bytes: meta.len(),
            max,
        });
    }
    // `take` bounds the read even if the file grows while it is read.
    let mut r = std::io::BufReader::new(file).take(max + 1);
    read_bounded(&mut r, Some(meta.len()), cells, extra)
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
    let maps: Vec<&[f32]> = terrain
        .snow
        .iter()
        .map(|l| l.as_slice())
        .chain(extra.iter().copied())
        .collect();
    let maps_len: usize = maps.iter().map(|m| 4 * m.len()).sum();
    let mut crc = crc32fast::Hasher::new();
    let mut put = |w: &mut dyn Write, bytes: &[u8]| -> std::io::Result<()> {
        crc.update(bytes);
        w.write_all(bytes)
    };
    put(w, MAGIC)?;
    put(w, &VERSION.to_le_bytes())?;
    put(w, &(json.len() as u64).to_le_bytes())?;
    put(w, &(maps_len as u64).to_le_bytes())?;
    put(w, &json)?;
    let mut buf = Vec::with_capacity(terrain.geometry().len() * 4);
    for layer in maps {
        buf.clear();
        for v in layer {
            buf.extend_from_slice(&v.to_le_bytes());
        }
        put(w, &buf)?;
    }
    w.write_all(&crc.finalize().to_le_bytes())?;
    Ok(())
}

/// What a checkpoint holds, verified.
#[derive(Debug, Clone)]
pub struct Contents<H> {
    /// The caller's run state.
    pub header: H,
    /// The four snow layers, bottom to top.
    pub layers: [Vec<f32>; 4],
    /// The caller's extra maps, in the order they were written.
    pub extra: Vec<Vec<f32>>,
}

impl<H> Contents<H> {
    /// Overwrites the snow layers of `terrain` (same geometry as the checkpoint's).
    pub fn restore_layers(&mut self, terrain: &mut LayeredTerrain) {
        for (layer, saved) in terrain.snow.iter_mut().zip(self.layers.iter_mut()) {
            std::mem::swap(layer, saved);
        }
    }
}

/// Reads and verifies a checkpoint written by [`write`] for a terrain of `cells` cells with
/// `extra` extra maps. Nothing is parsed before the lengths and the checksum are checked.
pub fn read<H: DeserializeOwned>(
    r: &mut impl Read,
    cells: usize,
    extra: usize,
) -> Result<Contents<H>, CheckpointError> {
    read_bounded(r, None, cells, extra)
}

/// [`read`], knowing the length of the file when it is one: a length other than the one the
/// preamble announces is refused before the body is allocated.
fn read_bounded<H: DeserializeOwned>(
    r: &mut impl Read,
    file_len: Option<u64>,
    cells: usize,
    extra: usize,
) -> Result<Contents<H>, CheckpointError> {
    let mut pre = [0u8; PREAMBLE];
    let got = read_up_to(r, &mut pre)?;
    let mut magic = [0u8; 8];
    magic.copy_from_slice(&pre[..8]);
    if got < 8 || &magic != MAGIC {
        return Err(CheckpointError::BadMagic { found: magic });
    }
    if got < PREAMBLE {
        return Err(CheckpointError::Truncated {
            expected: PREAMBLE as u64,
            found: got as u64,
        });
    }
    let word = |at: usize| u64::from_le_bytes(pre[at..at + 8].try_into().unwrap_or([0; 8]));
    let version = u32::from_le_bytes([pre[8], pre[9], pre[10], pre[11]]);
    if version != VERSION {
        return Err(CheckpointError::Version { found: version });
    }
    let (header_len, maps_len) = (word(12), word(20));
    if header_len > MAX_HEADER {
        return Err(CheckpointError::HeaderTooLarge(header_len));
    }
    let maps = 4 + extra;
    let expected_maps = 4 * maps as u64 * cells as u64;
    if maps_len != expected_maps {
        return Err(CheckpointError::SizeMismatch {
            expected: cells,
            found: (maps_len / (4 * maps as u64)).min(usize::MAX as u64) as usize,
        });
    }
    // Both lengths are bounded now: the header by MAX_HEADER, the maps by the terrain.
    let body_len = header_len + maps_len;
    if let Some(len) = file_len {
        let expected = PREAMBLE as u64 + body_len + 4;
        if len < expected {
            return Err(CheckpointError::Truncated {
                expected,
                found: len,
            });
        }
        if len > expected {
            return Err(CheckpointError::TrailingBytes {
                extra: len - expected,
            });
        }
    }
    let mut body = vec![0u8; body_len as usize + 4];
    let got_body = read_up_to(r, &mut body)?;
    if got_body < body.len() {
        return Err(CheckpointError::Truncated {
            expected: PREAMBLE as u64 + body.len() as u64,
            found: (PREAMBLE + got_body) as u64,
        });
    }
    let mut rest = Vec::new();
    let extra_bytes = r.take(1 << 20).read_to_end(&mut rest)?;
    if extra_bytes > 0 {
        return Err(CheckpointError::TrailingBytes {
            extra: extra_bytes as u64,
        });
    }
    let stored = u32::from_le_bytes(body[body_len as usize..].try_into().unwrap_or([0; 4]));
    let mut crc = crc32fast::Hasher::new();
    crc.update(&pre);
    crc.update(&body[..body_len as usize]);
    let computed = crc.finalize();
    if stored != computed {
        return Err(CheckpointError::Checksum { stored, computed });
    }
    let header: H = serde_json::from_slice(&body[..header_len as usize])?;
    let mut all: Vec<Vec<f32>> = body[header_len as usize..body_len as usize]
        .chunks_exact(4 * cells.max(1))
        .take(maps)
        .map(|bytes| {
            bytes
                .chunks_exact(4)
                .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                .collect()
        })
        .collect();
    all.resize(maps, Vec::new());
    let extra_maps = all.split_off(4);
    let layers: [Vec<f32>; 4] = all.try_into().unwrap_or_default();
    Ok(Contents {
        header,
        layers,
        extra: extra_maps,
    })
}

/// Fills as much of `buf` as the reader holds; returns the bytes read.
fn read_up_to(r: &mut impl Read, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut got = 0;
    while got < buf.len() {
        match r.read(&mut buf[got..]) {
            Ok(0) => break,
            Ok(n) => got += n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(got)
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
        let mut c: Contents<(String, u32)> = read(&mut bytes.as_slice(), 15, 1).unwrap();
        c.restore_layers(&mut back);
        assert_eq!(c.extra, vec![vec![7.0f32; 15]]);
        assert_eq!(c.header, ("day".to_string(), 42));
        assert_eq!(back, t);
        assert_eq!(bedrock_fingerprint(&back), bedrock_fingerprint(&t));
    }

    #[test]
    fn corrupt_or_truncated_files_are_typed_errors() {
        let t = terrain();
        let mut bytes = Vec::new();
        write(&mut bytes, &1u8, &t, &[]).unwrap();
        let cut = &bytes[..bytes.len() - 3];
        assert!(matches!(
            read::<u8>(&mut &cut[..], 15, 0),
            Err(CheckpointError::Truncated { expected, found })
                if expected == bytes.len() as u64 && found == cut.len() as u64
        ));
        assert!(matches!(
            read::<u8>(&mut &bytes[..10], 15, 0),
            Err(CheckpointError::Truncated { .. })
        ));
        let mut bad = bytes.clone();
        bad[0] = b'X';
        assert!(matches!(
            read::<u8>(&mut bad.as_slice(), 15, 0),
            Err(CheckpointError::BadMagic { .. })
        ));
        let mut longer = bytes.clone();
        longer.push(0);
        assert!(matches!(
            read::<u8>(&mut longer.as_slice(), 15, 0),
            Err(CheckpointError::TrailingBytes { extra: 1 })
        ));
        assert!(matches!(
            read::<u8>(&mut bytes.as_slice(), 16, 0),
            Err(CheckpointError::SizeMismatch { expected: 16, .. })
        ));
        let mut old = bytes.clone();
        old[8..12].copy_from_slice(&2u32.to_le_bytes());
        assert!(matches!(
            read::<u8>(&mut old.as_slice(), 15, 0),
            Err(CheckpointError::Version { found: 2 })
        ));
    }

    #[test]
    fn every_flipped_bit_is_refused() {
        let t = terrain();
        let mut bytes = Vec::new();
        write(&mut bytes, &("state", 7u32), &t, &[&[1.5f32; 15]]).unwrap();
        for byte in 0..bytes.len() {
            for bit in 0..8 {
                let mut b = bytes.clone();
                b[byte] ^= 1 << bit;
                assert!(
                    read::<(String, u32)>(&mut b.as_slice(), 15, 1).is_err(),
                    "a flip of bit {bit} of byte {byte} was accepted"
                );
            }
        }
    }
}
