//! The binary wire format of grid data sent to the page: tiles of 16-bit quantised values.
//!
//! Cordonnier et al. 2018, Section 3 asks for avalanches and ski tracks "visualized at the speed
//! a user expects from real life"; to keep a 1024² terrain live over a WebSocket the server
//! sends only the tiles that changed, each value quantised to 16 bits.
//!
//! # Frame layout (all integers and floats little-endian)
//!
//! | offset | type | field |
//! |---|---|---|
//! | 0 | `[u8; 4]` | magic `SSW1` |
//! | 4 | `u8` | channel (see [`Channel`]) |
//! | 5 | `u8` | flags: bit 0 = full grid (every tile of the grid follows) |
//! | 6 | `u16` | tile size `T` in cells (64) |
//! | 8 | `u32` | grid width `W`, cells |
//! | 12 | `u32` | grid height `H`, cells |
//! | 16 | `f32` | `offset` |
//! | 20 | `f32` | `scale` |
//! | 24 | `u32` | sequence number of the frame (per server, increasing) |
//! | 28 | `u32` | number of tiles `N` |
//! | 32 | tiles | `N` times: `u16 tx`, `u16 ty` (tile column and row), then `w·h` `u16` values row by row, where `w = min(T, W − tx·T)`, `h = min(T, H − ty·T)` |
//!
//! A value `q` decodes as `offset + q·scale`; `q = 65535` ([`NODATA`]) is a cell without data.
//! Rows run north to south, columns west to east, as in the grid.

use thiserror::Error;

/// Magic bytes opening every frame.
pub const MAGIC: [u8; 4] = *b"SSW1";
/// Tile side in cells.
pub const TILE: usize = 64;
/// Header length in bytes.
pub const HEADER_LEN: usize = 32;
/// The quantised value of a cell without data.
pub const NODATA: u16 = u16::MAX;
/// Largest quantised value of a real cell.
const QMAX: f32 = (NODATA - 1) as f32;

/// What a frame carries.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[repr(u8)]
pub enum Channel {
    /// Bedrock altitude, m (sent once, offset = lowest altitude).
    Bedrock = 0,
    /// Compacted snow thickness, m.
    Compacted = 1,
    /// Stable snow thickness, m.
    Stable = 2,
    /// Unstable snow thickness, m.
    Unstable = 3,
    /// Powder thickness, m.
    Powder = 4,
    /// Thickness of snow flowing in a live avalanche, m.
    Flow = 5,
    /// Air temperature of the current weather period, °C.
    Temperature = 6,
    /// Sun exposure (direct sun map of the environment precompute).
    Sun = 7,
    /// Wind speed, m/s.
    Wind = 8,
    /// Painted avalanche release probability, per day, 0..1.
    AvalancheProbability = 9,
    /// Painted skier area, 0..1.
    SkiArea = 10,
}

impl Channel {
    /// Every channel, in the order of its id.
    pub const ALL: [Channel; 11] = [
        Channel::Bedrock,
        Channel::Compacted,
        Channel::Stable,
        Channel::Unstable,
        Channel::Powder,
        Channel::Flow,
        Channel::Temperature,
        Channel::Sun,
        Channel::Wind,
        Channel::AvalancheProbability,
        Channel::SkiArea,
    ];

    /// The channel's name on the page.
    pub fn name(self) -> &'static str {
        match self {
            Channel::Bedrock => "bedrock",
            Channel::Compacted => "compacted",
            Channel::Stable => "stable",
            Channel::Unstable => "unstable",
            Channel::Powder => "powder",
            Channel::Flow => "flow",
            Channel::Temperature => "temperature",
            Channel::Sun => "sun",
            Channel::Wind => "wind",
            Channel::AvalancheProbability => "avalanche_probability",
            Channel::SkiArea => "ski_area",
        }
    }

    /// The snow-layer channels, in the order of [`snowscape_terrain::SnowLayer::ALL`].
    pub const LAYERS: [Channel; 4] = [
        Channel::Compacted,
        Channel::Stable,
        Channel::Unstable,
        Channel::Powder,
    ];
}

/// A frame that could not be encoded.
#[derive(Debug, Error, PartialEq)]
pub enum WireError {
    #[error(
        "grid of {width}x{height} cells does not fit the frame format (at most 65535 tiles a side)"
    )]
    GridTooLarge { width: usize, height: usize },
    #[error("{got} values given for a {width}x{height} grid")]
    LengthMismatch {
        got: usize,
        width: usize,
        height: usize,
    },
    #[error("invalid quantisation scale {0} (must be finite and positive)")]
    BadScale(f32),
}

/// Quantisation of one channel: `value = offset + q·scale`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Quant {
    pub offset: f32,
    pub scale: f32,
}

impl Quant {
    /// Snow thickness: millimetres from 0 (up to 65.5 m).
    pub const THICKNESS: Quant = Quant {
        offset: 0.0,
        scale: 0.001,
    };
    /// A probability or a share, 0..1.
    pub const UNIT: Quant = Quant {
        offset: 0.0,
        scale: 1.0 / QMAX,
    };

    /// The quantisation spanning the finite values of `values` (a constant field gets a
    /// scale of 1).
    pub fn spanning(values: &[f32]) -> Quant {
        let (lo, hi) = values
            .iter()
            .filter(|v| v.is_finite())
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        if !lo.is_finite() || hi <= lo {
            return Quant {
                offset: if lo.is_finite() { lo } else { 0.0 },
                scale: 1.0,
            };
        }
        Quant {
            offset: lo,
            scale: (hi - lo) / QMAX,
        }
    }

    /// The quantised value of `v` (clamped to the range; NaN is [`NODATA`]).
    #[inline]
    pub fn quantise(&self, v: f32) -> u16 {
        if v.is_nan() {
            return NODATA;
        }
        ((v - self.offset) / self.scale).round().clamp(0.0, QMAX) as u16
    }

    /// The value `q` stands for (NaN for [`NODATA`]).
    pub fn value(&self, q: u16) -> f32 {
        if q == NODATA {
            f32::NAN
        } else {
            self.offset + q as f32 * self.scale
        }
    }
}

/// Number of tiles across and down a grid.
pub fn tile_counts(width: usize, height: usize) -> (usize, usize) {
    (width.div_ceil(TILE), height.div_ceil(TILE))
}

/// The tile holding cell `(col, row)`.
pub fn tile_of(col: usize, row: usize) -> (usize, usize) {
    (col / TILE, row / TILE)
}

/// A row-major grid of values to send on a channel.
#[derive(Debug, Clone, Copy)]
pub struct Field<'a> {
    pub channel: Channel,
    pub values: &'a [f32],
    pub width: usize,
    pub height: usize,
    pub quant: Quant,
}

/// Encodes the tiles `tiles` of `field`. `full` marks a frame carrying every tile of the grid.
pub fn encode_tiles(
    field: &Field,
    tiles: &[(usize, usize)],
    full: bool,
    seq: u32,
) -> Result<Vec<u8>, WireError> {
    let Field {
        channel,
        values,
        width,
        height,
        quant,
    } = *field;
    let (tw, th) = tile_counts(width, height);
    if tw > u16::MAX as usize || th > u16::MAX as usize || width > u32::MAX as usize {
        return Err(WireError::GridTooLarge { width, height });
    }
    if values.len() != width * height {
        return Err(WireError::LengthMismatch {
            got: values.len(),
            width,
            height,
        });
    }
    if !(quant.scale.is_finite() && quant.scale > 0.0) {
        return Err(WireError::BadScale(quant.scale));
    }
    let tiles: Vec<(usize, usize)> = tiles
        .iter()
        .copied()
        .filter(|&(x, y)| x < tw && y < th)
        .collect();
    let mut out = Vec::with_capacity(HEADER_LEN + tiles.len() * (4 + 2 * TILE * TILE));
    out.extend_from_slice(&MAGIC);
    out.push(channel as u8);
    out.push(u8::from(full));
    out.extend_from_slice(&(TILE as u16).to_le_bytes());
    out.extend_from_slice(&(width as u32).to_le_bytes());
    out.extend_from_slice(&(height as u32).to_le_bytes());
    out.extend_from_slice(&quant.offset.to_le_bytes());
    out.extend_from_slice(&quant.scale.to_le_bytes());
    out.extend_from_slice(&seq.to_le_bytes());
    out.extend_from_slice(&(tiles.len() as u32).to_le_bytes());
    for (tx, ty) in tiles {
        out.extend_from_slice(&(tx as u16).to_le_bytes());
        out.extend_from_slice(&(ty as u16).to_le_bytes());
        let (c0, r0) = (tx * TILE, ty * TILE);
        let (c1, r1) = ((c0 + TILE).min(width), (r0 + TILE).min(height));
        for r in r0..r1 {
            for &v in &values[r * width + c0..r * width + c1] {
                out.extend_from_slice(&quant.quantise(v).to_le_bytes());
            }
        }
    }
    Ok(out)
}

/// Every tile of a grid.
pub fn all_tiles(width: usize, height: usize) -> Vec<(usize, usize)> {
    let (tw, th) = tile_counts(width, height);
    (0..th).flat_map(|y| (0..tw).map(move |x| (x, y))).collect()
}

/// A decoded frame (the page's decoder in `web/src/wire.js` mirrors this; tests use it).
#[derive(Debug, Clone, PartialEq)]
pub struct DecodedFrame {
    pub channel: u8,
    pub full: bool,
    pub width: usize,
    pub height: usize,
    pub quant: Quant,
    pub seq: u32,
    /// `(tx, ty, values)` per tile.
    pub tiles: Vec<(usize, usize, Vec<u16>)>,
}

/// Decodes a frame; `None` when the bytes are not a well-formed frame.
pub fn decode_frame(b: &[u8]) -> Option<DecodedFrame> {
    let u16_at = |o: usize| Some(u16::from_le_bytes(b.get(o..o + 2)?.try_into().ok()?));
    let u32_at = |o: usize| Some(u32::from_le_bytes(b.get(o..o + 4)?.try_into().ok()?));
    let f32_at = |o: usize| Some(f32::from_le_bytes(b.get(o..o + 4)?.try_into().ok()?));
    if b.get(0..4)? != MAGIC {
        return None;
    }
    let tile = u16_at(6)? as usize;
    let (width, height) = (u32_at(8)? as usize, u32_at(12)? as usize);
    let quant = Quant {
        offset: f32_at(16)?,
        scale: f32_at(20)?,
    };
    let n = u32_at(28)? as usize;
    let mut o = HEADER_LEN;
    let mut tiles = Vec::new();
    for _ in 0..n {
        let (tx, ty) = (u16_at(o)? as usize, u16_at(o + 2)? as usize);
        o += 4;
        let w = (width.checked_sub(tx * tile)?).min(tile);
        let h = (height.checked_sub(ty * tile)?).min(tile);
        let vals = (0..w * h)
            .map(|k| u16_at(o + 2 * k))
            .collect::<Option<Vec<u16>>>()?;
        o += 2 * w * h;
        tiles.push((tx, ty, vals));
    }
    (o == b.len()).then_some(DecodedFrame {
        channel: *b.get(4)?,
        full: *b.get(5)? & 1 == 1,
        width,
        height,
        quant,
        seq: u32_at(24)?,
        tiles,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_of_a_partial_edge_tile() {
        let (w, h) = (70, 65);
        let values: Vec<f32> = (0..w * h).map(|i| (i % 97) as f32 * 0.01).collect();
        let field = Field {
            channel: Channel::Stable,
            values: &values,
            width: w,
            height: h,
            quant: Quant::THICKNESS,
        };
        let bytes = encode_tiles(&field, &[(1, 1), (0, 0)], false, 9).unwrap();
        let f = decode_frame(&bytes).unwrap();
        assert_eq!((f.channel, f.width, f.height, f.seq), (2, 70, 65, 9));
        assert_eq!(f.tiles.len(), 2);
        let (tx, ty, v) = &f.tiles[0];
        assert_eq!((*tx, *ty, v.len()), (1, 1, 6));
        // The last cell of the grid, (69, 64).
        let q = v[5];
        assert!((f.quant.value(q) - values[64 * w + 69]).abs() < 6e-4);
        assert_eq!(bytes.len(), HEADER_LEN + 4 + 6 * 2 + 4 + 64 * 64 * 2);
    }

    #[test]
    fn quantisation_clamps_and_marks_nodata() {
        let q = Quant::spanning(&[1000.0, f32::NAN, 3000.0]);
        assert_eq!(q.quantise(1000.0), 0);
        assert_eq!(q.quantise(3000.0), 65534);
        assert_eq!(q.quantise(5000.0), 65534);
        assert_eq!(q.quantise(f32::NAN), NODATA);
        assert!(q.value(NODATA).is_nan());
        assert!((q.value(q.quantise(2000.0)) - 2000.0).abs() < 0.02);
    }

    #[test]
    fn bad_inputs_are_errors() {
        let field = |values: &'static [f32], quant| Field {
            channel: Channel::Flow,
            values,
            width: 2,
            height: 2,
            quant,
        };
        assert!(matches!(
            encode_tiles(&field(&[0.0; 3], Quant::UNIT), &[], true, 0),
            Err(WireError::LengthMismatch { got: 3, .. })
        ));
        let bad = Quant {
            offset: 0.0,
            scale: 0.0,
        };
        assert_eq!(
            encode_tiles(&field(&[0.0; 4], bad), &[], true, 0),
            Err(WireError::BadScale(0.0))
        );
        assert!(decode_frame(b"SSW0").is_none());
    }
}
