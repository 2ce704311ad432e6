//! Checkpoints: the whole state of a season run in one file, so an interrupted run resumes
//! and ends bit-identical to an uninterrupted one.
//!
//! Layout (little-endian, format version 4): the magic `SNOWCKPT`, a u32 format version, four
//! u64 lengths (the JSON header, the maps, the ski tracks, the track tiles), the JSON header
//! (the caller's run state: scheduler, budget, time, the resolved scenario and a fingerprint
//! of the inputs), the four snow layers as raw f32, bottom to top, then the caller's extra
//! per-cell f32 maps, the ski tracks (the caller's JSON: skiers on the slopes and finished
//! tracks), the track texture's allocated tiles (each a u64 tile index and
//! [`TILE`]² f32 texels), and last a CRC-32 (IEEE) of every byte before it. A reader checks the
//! magic, the version, the lengths (a short file is "truncated", naming both sizes) and the
//! checksum (a flipped bit is refused) before it parses anything. The file is written
//! atomically by the caller (temporary name, then rename), so a crash mid-write leaves the
//! previous checkpoint intact.
//!
//! **Older versions.** Version 3 (before the ski area and the painted release rates were
//! checkpointed) and older are refused with [`CheckpointError::Version`], which names both
//! versions: a version-3 checkpoint lacks what a resume needs to end bit-identical to an
//! uninterrupted run, so the run is started again.
//!
//! [`read_file`] opens only a regular file (a device such as `/dev/zero` reads without end, a
//! FIFO blocks: both are refused before anything is read), refuses one longer than the
//! largest checkpoint of the terrain ([`max_len`]: a [`MAX_HEADER`] header, the maps of its
//! cells, [`MAX_TRACKS`] bytes of tracks and every tile of its track texture), and after the
//! preamble checks each length against its bound and the file's length against the one the
//! preamble announces, before the body is allocated.
//!
//! The checksum detects damage, not nonsense: a file written wrong or forged with a matching
//! checksum can still hold an index past its table, a time of −1e300 or NaN snow. The caller
//! validates every decoded value (the season does in [`crate::winter::Winter::resume`]) and
//! refuses one out of range with [`CheckpointError::Implausible`], naming the field and the
//! value (cut to [`crate::MAX_ECHO_CHARS`] characters).

use serde::{Serialize, de::DeserializeOwned};
use snowscape_skiers::texture::TILE;
use snowscape_terrain::{LayeredTerrain, random::mix64};
use std::io::{Read, Write};
use thiserror::Error;

const MAGIC: &[u8; 8] = b"SNOWCKPT";
/// The format this build writes and reads.
pub const VERSION: u32 = 4;
/// Bytes before the JSON header: magic, version, four lengths.
pub const PREAMBLE: usize = 8 + 4 + 4 * 8;
/// Largest JSON header accepted, bytes.
pub const MAX_HEADER: u64 = 64 << 20;
/// Largest ski-tracks section accepted, bytes (1 GiB: a season of 10 000 runs of 50 kB of
/// JSON each is half of it; the tracks grow with the runs, not with the terrain).
pub const MAX_TRACKS: u64 = 1 << 30;
/// Bytes of one track tile in a checkpoint: its u64 index and its texels.
pub const TILE_BYTES: u64 = 8 + 4 * (TILE * TILE) as u64;

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
    #[error(
        "checkpoint {section} section of {bytes} bytes is implausible: at most {max} bytes{unit}"
    )]
    SectionSize {
        section: &'static str,
        bytes: u64,
        max: u64,
        unit: &'static str,
    },
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

/// What a checkpoint of a terrain may hold: its cells, the caller's extra maps, and the tiles
/// of its track texture.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Bounds {
    /// Grid cells.
    pub cells: usize,
    /// Extra per-cell maps after the four layers.
    pub extra: usize,
    /// Tiles of the track texture (all of them may be allocated).
    pub tiles: usize,
}

/// The largest checkpoint within `bounds`, bytes.
pub fn max_len(bounds: Bounds) -> u64 {
    PREAMBLE as u64
        + MAX_HEADER
        + 4 * (4 + bounds.extra as u64) * bounds.cells as u64
        + MAX_TRACKS
        + TILE_BYTES * bounds.tiles as u64
        + 4
}

/// Reads and verifies the checkpoint file at `path` (as [`read`]), opening only a regular
/// file of at most [`max_len`] bytes and checking its length against the preamble's before
/// the body is allocated (module docs).
pub fn read_file<H: DeserializeOwned>(
    path: &std::path::Path,
    bounds: Bounds,
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
    let max = max_len(bounds);
    if meta.len() > max {
        return Err(CheckpointError::TooLarge {
            path: path.to_path_buf(),
            bytes: meta.len(),
            max,
        });
    }
    // `take` bounds the read even if the file grows while it is read.
    let mut r = std::io::BufReader::new(file).take(max + 1);
    read_bounded(&mut r, Some(meta.len()), bounds)
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

/// What a checkpoint holds besides its header and snow layers.
#[derive(Debug, Clone, Copy, Default)]
pub struct Payload<'a> {
    /// Extra per-cell maps, in order.
    pub extra: &'a [&'a [f32]],
    /// The ski tracks, the caller's JSON (empty: none).
    pub tracks: &'a [u8],
    /// The track texture's allocated tiles, `(index, TILE² texels)`, in index order.
    pub tiles: &'a [(usize, &'a [f32])],
}

/// A writer that sums what passes through it.
struct Summed<'w, W: Write> {
    w: &'w mut W,
    crc: crc32fast::Hasher,
    buf: Vec<u8>,
}

impl<W: Write> Summed<'_, W> {
    fn put(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        self.crc.update(bytes);
        self.w.write_all(bytes)
    }

    /// `floats` as little-endian bytes, after the u64 `prefix` when there is one.
    fn put_floats(&mut self, prefix: Option<u64>, floats: &[f32]) -> std::io::Result<()> {
        let mut buf = std::mem::take(&mut self.buf);
        buf.clear();
        if let Some(p) = prefix {
            buf.extend_from_slice(&p.to_le_bytes());
        }
        for v in floats {
            buf.extend_from_slice(&v.to_le_bytes());
        }
        let r = self.put(&buf);
        self.buf = buf;
        r
    }
}

/// Writes `header`, the snow layers of `terrain` and the `payload` to `w`.
pub fn write<H: Serialize>(
    w: &mut impl Write,
    header: &H,
    terrain: &LayeredTerrain,
    payload: Payload,
) -> Result<(), CheckpointError> {
    let json = serde_json::to_vec(header)?;
    let maps: Vec<&[f32]> = terrain
        .snow
        .iter()
        .map(|l| l.as_slice())
        .chain(payload.extra.iter().copied())
        .collect();
    let maps_len: usize = maps.iter().map(|m| 4 * m.len()).sum();
    let tiles_len = TILE_BYTES * payload.tiles.len() as u64;
    let mut out = Summed {
        w,
        crc: crc32fast::Hasher::new(),
        buf: Vec::with_capacity(terrain.geometry().len() * 4),
    };
    out.put(MAGIC)?;
    out.put(&VERSION.to_le_bytes())?;
    for len in [
        json.len() as u64,
        maps_len as u64,
        payload.tracks.len() as u64,
        tiles_len,
    ] {
        out.put(&len.to_le_bytes())?;
    }
    out.put(&json)?;
    for layer in maps {
        out.put_floats(None, layer)?;
    }
    out.put(payload.tracks)?;
    for &(index, texels) in payload.tiles {
        out.put_floats(Some(index as u64), texels)?;
    }
    let crc = out.crc.finalize();
    out.w.write_all(&crc.to_le_bytes())?;
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
    /// The ski tracks' JSON (empty: none).
    pub tracks: Vec<u8>,
    /// The track texture's tiles, `(index, TILE² texels)`, as written.
    pub tiles: Vec<(usize, Vec<f32>)>,
}

/// Reads and verifies a checkpoint written by [`write`] within `bounds`. Nothing is parsed
/// before the lengths and the checksum are checked.
pub fn read<H: DeserializeOwned>(
    r: &mut impl Read,
    bounds: Bounds,
) -> Result<Contents<H>, CheckpointError> {
    read_bounded(r, None, bounds)
}

/// The section lengths of a preamble, each checked against its bound.
fn section_lengths(pre: &[u8; PREAMBLE], bounds: Bounds) -> Result<[u64; 4], CheckpointError> {
    let word = |at: usize| u64::from_le_bytes(pre[at..at + 8].try_into().unwrap_or([0; 8]));
    let lens = [word(12), word(20), word(28), word(36)];
    let [header_len, maps_len, tracks_len, tiles_len] = lens;
    if header_len > MAX_HEADER {
        return Err(CheckpointError::HeaderTooLarge(header_len));
    }
    let maps = 4 + bounds.extra as u64;
    let expected_maps = 4 * maps * bounds.cells as u64;
    if maps_len != expected_maps {
        return Err(CheckpointError::SizeMismatch {
            expected: bounds.cells,
            found: (maps_len / (4 * maps)).min(usize::MAX as u64) as usize,
        });
    }
    if tracks_len > MAX_TRACKS {
        return Err(CheckpointError::SectionSize {
            section: "ski tracks",
            bytes: tracks_len,
            max: MAX_TRACKS,
            unit: "",
        });
    }
    let max_tiles = TILE_BYTES * bounds.tiles as u64;
    if tiles_len > max_tiles || !tiles_len.is_multiple_of(TILE_BYTES) {
        return Err(CheckpointError::SectionSize {
            section: "track tiles",
            bytes: tiles_len,
            max: max_tiles,
            unit: ", a whole number of tiles",
        });
    }
    Ok(lens)
}

/// [`read`], knowing the length of the file when it is one: a length other than the one the
/// preamble announces is refused before the body is allocated.
fn read_bounded<H: DeserializeOwned>(
    r: &mut impl Read,
    file_len: Option<u64>,
    bounds: Bounds,
) -> Result<Contents<H>, CheckpointError> {
    let mut pre = [0u8; PREAMBLE];
    let got = read_up_to(r, &mut pre)?;
    let mut magic = [0u8; 8];
    magic.copy_from_slice(&pre[..8]);
    if got < 8 || &magic != MAGIC {
        return Err(CheckpointError::BadMagic { found: magic });
    }
    // The version before the lengths: an older format's preamble is shorter.
    let version = u32::from_le_bytes([pre[8], pre[9], pre[10], pre[11]]);
    if got >= 12 && version != VERSION {
        return Err(CheckpointError::Version { found: version });
    }
    if got < PREAMBLE {
        return Err(CheckpointError::Truncated {
            expected: PREAMBLE as u64,
            found: got as u64,
        });
    }
    // Every length is bounded now: the header by MAX_HEADER, the maps and tiles by the
    // terrain, the tracks by MAX_TRACKS.
    let [header_len, maps_len, tracks_len, tiles_len] = section_lengths(&pre, bounds)?;
    let body_len = header_len + maps_len + tracks_len + tiles_len;
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
    let (header_bytes, rest) = body.split_at(header_len as usize);
    let (map_bytes, rest) = rest.split_at(maps_len as usize);
    let (track_bytes, rest) = rest.split_at(tracks_len as usize);
    let tile_bytes = &rest[..tiles_len as usize];
    let header: H = serde_json::from_slice(header_bytes)?;
    let floats = |bytes: &[u8]| -> Vec<f32> {
        bytes
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect()
    };
    let maps = 4 + bounds.extra;
    let mut all: Vec<Vec<f32>> = map_bytes
        .chunks_exact(4 * bounds.cells.max(1))
        .take(maps)
        .map(floats)
        .collect();
    all.resize(maps, Vec::new());
    let extra_maps = all.split_off(4);
    let layers: [Vec<f32>; 4] = all.try_into().unwrap_or_default();
    let tiles = tile_bytes
        .chunks_exact(TILE_BYTES as usize)
        .map(|t| {
            let index = u64::from_le_bytes(t[..8].try_into().unwrap_or([0xff; 8]));
            (
                usize::try_from(index).unwrap_or(usize::MAX),
                floats(&t[8..]),
            )
        })
        .collect();
    Ok(Contents {
        header,
        layers,
        extra: extra_maps,
        tracks: track_bytes.to_vec(),
        tiles,
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

    fn bounds(cells: usize, extra: usize) -> Bounds {
        Bounds {
            cells,
            extra,
            tiles: 1,
        }
    }

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
        let tile: Vec<f32> = (0..TILE * TILE).map(|k| k as f32 / 8192.0).collect();
        let payload = Payload {
            extra: &[&[7.0f32; 15]],
            tracks: b"[1,2]",
            tiles: &[(0, &tile[..])],
        };
        write(&mut bytes, &("day", 42u32), &t, payload).unwrap();
        let mut back = LayeredTerrain::from_bedrock(Grid::from_fn(t.geometry().clone(), |c, r| {
            (c * 7 + r) as f32
        }));
        let c: Contents<(String, u32)> = read(&mut bytes.as_slice(), bounds(15, 1)).unwrap();
        back.snow = c.layers.clone();
        assert_eq!(c.extra, vec![vec![7.0f32; 15]]);
        assert_eq!(c.tracks, b"[1,2]");
        assert_eq!(c.tiles, vec![(0, tile)]);
        assert_eq!(c.header, ("day".to_string(), 42));
        assert_eq!(back, t);
        assert_eq!(bedrock_fingerprint(&back), bedrock_fingerprint(&t));
    }

    #[test]
    fn corrupt_or_truncated_files_are_typed_errors() {
        let t = terrain();
        let mut bytes = Vec::new();
        write(&mut bytes, &1u8, &t, Payload::default()).unwrap();
        let cut = &bytes[..bytes.len() - 3];
        assert!(matches!(
            read::<u8>(&mut &cut[..], bounds(15, 0)),
            Err(CheckpointError::Truncated { expected, found })
                if expected == bytes.len() as u64 && found == cut.len() as u64
        ));
        assert!(matches!(
            read::<u8>(&mut &bytes[..10], bounds(15, 0)),
            Err(CheckpointError::Truncated { .. })
        ));
        let mut bad = bytes.clone();
        bad[0] = b'X';
        assert!(matches!(
            read::<u8>(&mut bad.as_slice(), bounds(15, 0)),
            Err(CheckpointError::BadMagic { .. })
        ));
        let mut longer = bytes.clone();
        longer.push(0);
        assert!(matches!(
            read::<u8>(&mut longer.as_slice(), bounds(15, 0)),
            Err(CheckpointError::TrailingBytes { extra: 1 })
        ));
        assert!(matches!(
            read::<u8>(&mut bytes.as_slice(), bounds(16, 0)),
            Err(CheckpointError::SizeMismatch { expected: 16, .. })
        ));
        let mut old = bytes.clone();
        old[8..12].copy_from_slice(&3u32.to_le_bytes());
        let e = read::<u8>(&mut old.as_slice(), bounds(15, 0)).unwrap_err();
        assert!(matches!(e, CheckpointError::Version { found: 3 }), "{e:?}");
        let m = e.to_string();
        assert!(m.contains("version 3") && m.contains("version 4"), "{m}");
        // A forged tile section: more tiles than the texture has, or a partial tile.
        let mut many = bytes.clone();
        many[36..44].copy_from_slice(&(2 * TILE_BYTES).to_le_bytes());
        assert!(matches!(
            read::<u8>(&mut many.as_slice(), bounds(15, 0)),
            Err(CheckpointError::SectionSize {
                section: "track tiles",
                ..
            })
        ));
        many[36..44].copy_from_slice(&7u64.to_le_bytes());
        assert!(matches!(
            read::<u8>(&mut many.as_slice(), bounds(15, 0)),
            Err(CheckpointError::SectionSize {
                section: "track tiles",
                ..
            })
        ));
        many[28..36].copy_from_slice(&(MAX_TRACKS + 1).to_le_bytes());
        assert!(matches!(
            read::<u8>(&mut many.as_slice(), bounds(15, 0)),
            Err(CheckpointError::SectionSize {
                section: "ski tracks",
                ..
            })
        ));
    }

    #[test]
    fn every_flipped_bit_is_refused() {
        let t = terrain();
        let mut bytes = Vec::new();
        let payload = Payload {
            extra: &[&[1.5f32; 15]],
            tracks: b"{}",
            tiles: &[],
        };
        write(&mut bytes, &("state", 7u32), &t, payload).unwrap();
        for byte in 0..bytes.len() {
            for bit in 0..8 {
                let mut b = bytes.clone();
                b[byte] ^= 1 << bit;
                assert!(
                    read::<(String, u32)>(&mut b.as_slice(), bounds(15, 1)).is_err(),
                    "a flip of bit {bit} of byte {byte} was accepted"
                );
            }
        }
    }
}
