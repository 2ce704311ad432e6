//! The plausibility check every (Geo)TIFF passes before the `tiff` crate decodes anything.
//!
//! `precheck` parses the header and the first image directory itself, in time linear in
//! the directory, and refuses, with a typed error naming the file and the value:
//! - an image directory, a tag's values, a strip or a tile whose offset is past the end of the
//!   file ([`RasterError::PastEnd`]) or that runs past it ([`RasterError::RunsPastEnd`]): a
//!   BigTIFF offset of 2^64 - 616 says so instead of "Invalid argument (os error 22)";
//! - a tag of more than [`MAX_TAG_VALUES`] values;
//! - more cells than [`crate::ReadOptions::max_cells`] ([`RasterError::TooManyCells`]);
//! - a compression other than none, LZW, Deflate and PackBits;
//! - a strip or tile whose stored bytes cannot expand to the size its tags say it decodes to,
//!   and an image whose strips or tiles together claim more decoded bytes than the whole file
//!   can expand to with its compression ([`RasterError::DecodedSize`]): the largest expansion
//!   of each compression is [`max_expansion`] (Deflate 1032:1, LZW 4096:1, PackBits 64:1,
//!   none 1:1). So a 10 KB file whose strips all point at the same few kilobytes of deflated
//!   zeros cannot make the reader allocate the gigabytes it claims.
//!
//! Only band 1's strips or tiles (plane 0 of a planar file) are checked: they are all the
//! reader decodes. The decoder then runs with [`tiff::decoder::Limits`] sized to one of them.

use crate::cells::check_cells;
use crate::error::{RasterError, Result, io_err};
use crate::input::BoundedReader;
use std::io::{Read, Seek, SeekFrom};
use std::path::Path;

/// The most values one tag may hold (a strip or tile table of 16 M entries is a 2^28-cell
/// image in 16-cell chunks; real files hold far fewer).
pub const MAX_TAG_VALUES: u64 = 1 << 24;

/// The compressions the reader decodes: (TIFF code, name, largest expansion ratio).
const COMPRESSIONS: [(u16, &str, u64); 5] = [
    (1, "uncompressed", 1),
    (5, "LZW", 4096),
    (8, "Deflate", 1032),
    (32946, "Deflate", 1032),
    (32773, "PackBits", 64),
];

/// The name and the largest expansion ratio of TIFF compression `code`, or `None` when the
/// reader does not decode it. Deflate: a 258-byte match costs at least 2 bits (1032:1); LZW:
/// a 9..12-bit code yields at most 4096 bytes (a string of the 4096-entry table); PackBits: 2
/// bytes yield at most 128.
pub fn max_expansion(code: u16) -> Option<(&'static str, u64)> {
    COMPRESSIONS
        .iter()
        .find(|c| c.0 == code)
        .map(|&(_, name, ratio)| (name, ratio))
}

/// The layout of the first image, as its tags give it, checked.
#[derive(Debug, Clone)]
pub(crate) struct Layout {
    /// Decoded bytes of the largest strip or tile of band 1.
    pub max_chunk_bytes: u64,
    /// Stored bytes of the largest strip or tile of band 1.
    pub max_stored_bytes: u64,
}

/// One directory entry: tag, field type, value count, and where its values are.
#[derive(Debug, Clone, Copy)]
struct Entry {
    tag: u16,
    type_: u16,
    count: u64,
    /// Offset of the values in the file (inline values: the offset of the entry's value field).
    at: u64,
}

/// Byte size of one value of TIFF field type `t` (`None` for an unknown type: the decoder
/// skips such entries).
fn type_size(t: u16) -> Option<u64> {
    Some(match t {
        1 | 2 | 6 | 7 => 1,
        3 | 8 => 2,
        4 | 9 | 11 | 13 => 4,
        5 | 10 | 12 | 16 | 17 | 18 => 8,
        _ => return None,
    })
}

fn tag_name(tag: u16) -> &'static str {
    match tag {
        256 => "ImageWidth",
        257 => "ImageLength",
        258 => "BitsPerSample",
        259 => "Compression",
        273 => "StripOffsets",
        277 => "SamplesPerPixel",
        278 => "RowsPerStrip",
        279 => "StripByteCounts",
        284 => "PlanarConfiguration",
        322 => "TileWidth",
        323 => "TileLength",
        324 => "TileOffsets",
        325 => "TileByteCounts",
        33550 => "ModelPixelScale",
        33922 => "ModelTiepoint",
        34264 => "ModelTransformation",
        34735 => "GeoKeyDirectory",
        34737 => "GeoAsciiParams",
        42113 => "GDAL_NODATA",
        _ => "",
    }
}

fn tag_label(tag: u16) -> String {
    match tag_name(tag) {
        "" => format!("tag {tag}"),
        name => format!("tag {tag} ({name})"),
    }
}

struct Ifd<'a, R> {
    path: &'a Path,
    r: &'a mut BoundedReader<R>,
    big: bool,
    little: bool,
    len: u64,
    entries: Vec<Entry>,
}

impl<R: Read + Seek> Ifd<'_, R> {
    fn bytes<const N: usize>(&mut self) -> Result<[u8; N]> {
        let mut b = [0u8; N];
        self.r.read_exact(&mut b).map_err(|e| {
            if e.kind() == std::io::ErrorKind::UnexpectedEof {
                RasterError::TiffTruncated {
                    path: self.path.to_path_buf(),
                    bytes: self.len,
                }
            } else {
                io_err(self.path)(e)
            }
        })?;
        if !self.little {
            b.reverse();
        }
        Ok(b)
    }
    fn u16(&mut self) -> Result<u16> {
        Ok(u16::from_le_bytes(self.bytes()?))
    }
    fn u32(&mut self) -> Result<u32> {
        Ok(u32::from_le_bytes(self.bytes()?))
    }
    fn u64(&mut self) -> Result<u64> {
        Ok(u64::from_le_bytes(self.bytes()?))
    }
    fn offset(&mut self) -> Result<u64> {
        if self.big {
            self.u64()
        } else {
            self.u32().map(u64::from)
        }
    }
    fn seek(&mut self, at: u64) -> Result<()> {
        self.r
            .seek(SeekFrom::Start(at))
            .map_err(io_err(self.path))?;
        Ok(())
    }

    fn find(&self, tag: u16) -> Option<Entry> {
        self.entries.iter().find(|e| e.tag == tag).copied()
    }

    /// The first `n` values of an integer tag (BYTE, SHORT, LONG, LONG8, IFD), as u64.
    fn values(&mut self, e: Entry, n: u64) -> Result<Vec<u64>> {
        let n = n.min(e.count);
        let mut out = Vec::with_capacity(n as usize);
        self.seek(e.at)?;
        for _ in 0..n {
            out.push(match e.type_ {
                1 | 7 => u64::from(self.bytes::<1>()?[0]),
                3 => u64::from(self.u16()?),
                4 | 13 => u64::from(self.u32()?),
                16 | 18 => self.u64()?,
                t => {
                    return Err(RasterError::GeoTiffTag {
                        path: self.path.to_path_buf(),
                        tag: e.tag,
                        name: tag_name(e.tag),
                        reason: format!("field type {t} is not an unsigned integer type"),
                    });
                }
            });
        }
        Ok(out)
    }

    fn first(&mut self, tag: u16) -> Result<Option<u64>> {
        match self.find(tag) {
            None => Ok(None),
            Some(e) if e.count == 0 => Ok(None),
            Some(e) => Ok(self.values(e, 1)?.first().copied()),
        }
    }
}

/// Checks the header and first image directory of the TIFF behind `r` (see the module docs),
/// and leaves `r` at the start of the file. `Ok(None)` when the file does not start like a
/// TIFF or lacks a size tag: the decoder then reports what is wrong.
pub(crate) fn precheck<R: Read + Seek>(
    path: &Path,
    r: &mut BoundedReader<R>,
    max_cells: usize,
) -> Result<Option<Layout>> {
    let len = r.len();
    let layout = precheck_inner(path, r, len, max_cells);
    r.seek(SeekFrom::Start(0)).map_err(io_err(path))?;
    layout
}

fn precheck_inner<R: Read + Seek>(
    path: &Path,
    r: &mut BoundedReader<R>,
    len: u64,
    max_cells: usize,
) -> Result<Option<Layout>> {
    let Some(mut ifd) = first_directory(path, r, len)? else {
        return Ok(None);
    };
    let (Some(w), Some(h)) = (ifd.first(256)?, ifd.first(257)?) else {
        return Ok(None);
    };
    check_cells(path, w, h, max_cells)?;
    if w == 0 || h == 0 {
        return Ok(None);
    }
    let unsupported = |what: String| RasterError::TiffUnsupported {
        path: path.to_path_buf(),
        what,
    };
    let code = ifd.first(259)?.unwrap_or(1);
    let (compression, ratio) = u16::try_from(code)
        .ok()
        .and_then(max_expansion)
        .ok_or_else(|| {
            unsupported(format!(
                "compression {code} (this reader decodes none, LZW, Deflate and PackBits)"
            ))
        })?;
    let spp = ifd.first(277)?.unwrap_or(1).max(1);
    let bits = ifd.first(258)?.unwrap_or(1);
    if !(1..=64).contains(&bits) {
        return Err(unsupported(format!("{bits} bits per sample")));
    }
    let planar = ifd.first(284)?.unwrap_or(1) == 2;
    let chunk_samples = if planar { 1 } else { spp };
    let tiled = ifd.find(322).is_some() || ifd.find(324).is_some();
    let (cw, ch, off_tag, count_tag, kind) = if tiled {
        let tw = ifd.first(322)?.unwrap_or(0);
        let th = ifd.first(323)?.unwrap_or(0);
        (tw, th, 324, 325, "tile")
    } else {
        let rps = ifd.first(278)?.unwrap_or(h).min(h);
        (w, rps, 273, 279, "strip")
    };
    if cw == 0 || ch == 0 {
        return Err(unsupported(format!("{kind}s of {cw}x{ch} cells")));
    }
    let (across, down) = (w.div_ceil(cw), h.div_ceil(ch));
    // Both are at most the cell count (checked above), so the product fits.
    let chunks = across * down;
    let (Some(offs), Some(counts)) = (ifd.find(off_tag), ifd.find(count_tag)) else {
        return Ok(None);
    };
    for e in [offs, counts] {
        if e.count < chunks {
            return Err(RasterError::GeoTiffTag {
                path: path.to_path_buf(),
                tag: e.tag,
                name: tag_name(e.tag),
                reason: format!(
                    "{} values, but the {w}x{h} image in {kind}s of {cw}x{ch} needs {chunks}",
                    e.count
                ),
            });
        }
    }
    let chunk_layout = Chunks {
        size: (w, h),
        chunk: (cw, ch),
        count: chunks,
        tiled,
        bits,
        samples: chunk_samples,
        compression,
        ratio,
    };
    check_chunks(&mut ifd, (offs, counts), &chunk_layout).map(Some)
}

/// The first image directory of a TIFF or BigTIFF file of `len` bytes read by `r`: its
/// header and every entry whose values lie inside the file (`None`: not a TIFF).
fn first_directory<'a, R: Read + Seek>(
    path: &'a Path,
    r: &'a mut BoundedReader<R>,
    len: u64,
) -> Result<Option<Ifd<'a, R>>> {
    if len < 8 {
        return Ok(None);
    }
    let mut sig = [0u8; 4];
    r.read_exact(&mut sig).map_err(io_err(path))?;
    let little = match &sig[..2] {
        b"II" => true,
        b"MM" => false,
        _ => return Ok(None),
    };
    let magic = if little {
        u16::from_le_bytes([sig[2], sig[3]])
    } else {
        u16::from_be_bytes([sig[2], sig[3]])
    };
    let big = match magic {
        42 => false,
        43 => true,
        _ => return Ok(None),
    };
    let mut ifd = Ifd {
        path,
        r,
        big,
        little,
        len,
        entries: Vec::new(),
    };
    if big && (len < 16 || ifd.u16()? != 8 || ifd.u16()? != 0) {
        return Ok(None);
    }
    let at = ifd.offset()?;
    let head = if big { 8 } else { 2 };
    if at.saturating_add(head) > len {
        return Err(RasterError::PastEnd {
            path: path.to_path_buf(),
            what: "the first image directory".into(),
            offset: at,
            bytes: len,
        });
    }
    ifd.seek(at)?;
    let n = if big {
        ifd.u64()?
    } else {
        u64::from(ifd.u16()?)
    };
    let entry_size: u64 = if big { 20 } else { 12 };
    let need = n
        .checked_mul(entry_size)
        .and_then(|b| b.checked_add(head))
        .unwrap_or(u64::MAX);
    if at.saturating_add(need) > len {
        return Err(RasterError::RunsPastEnd {
            path: path.to_path_buf(),
            what: format!("the first image directory of {n} entries"),
            offset: at,
            count: need,
            bytes: len,
        });
    }
    let inline = if big { 8 } else { 4 };
    for k in 0..n {
        let entry_at = at + head + k * entry_size;
        ifd.seek(entry_at)?;
        let tag = ifd.u16()?;
        let type_ = ifd.u16()?;
        let count = ifd.offset()?;
        let value_field = entry_at + 4 + if big { 8 } else { 4 };
        let Some(size) = type_size(type_) else {
            continue;
        };
        if count > MAX_TAG_VALUES {
            return Err(RasterError::GeoTiffTag {
                path: path.to_path_buf(),
                tag,
                name: tag_name(tag),
                reason: format!("{count} values, more than the {MAX_TAG_VALUES} a tag may hold"),
            });
        }
        let bytes = count * size;
        let at = if bytes <= inline {
            value_field
        } else {
            let o = ifd.offset()?;
            if o > len {
                return Err(RasterError::PastEnd {
                    path: path.to_path_buf(),
                    what: format!("the values of {}", tag_label(tag)),
                    offset: o,
                    bytes: len,
                });
            }
            if o + bytes > len {
                return Err(RasterError::RunsPastEnd {
                    path: path.to_path_buf(),
                    what: format!("the {count} values of {}", tag_label(tag)),
                    offset: o,
                    count: bytes,
                    bytes: len,
                });
            }
            o
        };
        ifd.entries.push(Entry {
            tag,
            type_,
            count,
            at,
        });
    }
    Ok(Some(ifd))
}

/// A band's strips or tiles as the directory lays them out, for [`check_chunks`].
struct Chunks {
    /// The image's size, cells.
    size: (u64, u64),
    /// A chunk's size, cells.
    chunk: (u64, u64),
    /// How many chunks band 1 has.
    count: u64,
    /// Whether they are tiles (else strips).
    tiled: bool,
    /// Bits per sample and samples per chunk pixel.
    bits: u64,
    samples: u64,
    /// The compression's name and its largest expansion ratio.
    compression: &'static str,
    ratio: u64,
}

/// Checks that band 1's chunks lie inside the file (offsets `offs`, stored lengths `counts`)
/// and cannot decode to more than their compression allows, each and together.
fn check_chunks<R: Read + Seek>(
    ifd: &mut Ifd<'_, R>,
    (offs, counts): (Entry, Entry),
    c: &Chunks,
) -> Result<Layout> {
    let (path, len) = (ifd.path, ifd.len);
    let ((w, h), (cw, ch), chunks, tiled) = (c.size, c.chunk, c.count, c.tiled);
    let (compression, ratio) = (c.compression, c.ratio);
    let kind = if tiled { "tile" } else { "strip" };
    let row_bytes = |width: u64| -> u64 {
        width
            .saturating_mul(c.bits)
            .saturating_mul(c.samples)
            .div_ceil(8)
    };
    let offsets = ifd.values(offs, chunks)?;
    let stored = ifd.values(counts, chunks)?;
    let mut total: u64 = 0;
    let mut layout = Layout {
        max_chunk_bytes: 0,
        max_stored_bytes: 0,
    };
    for (i, (&o, &c)) in offsets.iter().zip(&stored).enumerate() {
        let rows = if tiled {
            ch
        } else {
            ch.min(h - (i as u64) * ch)
        };
        let decoded = row_bytes(cw).saturating_mul(rows);
        let what = || format!("{kind} {i}");
        if o > len {
            return Err(RasterError::PastEnd {
                path: path.to_path_buf(),
                what: what(),
                offset: o,
                bytes: len,
            });
        }
        if o.saturating_add(c) > len {
            return Err(RasterError::RunsPastEnd {
                path: path.to_path_buf(),
                what: what(),
                offset: o,
                count: c,
                bytes: len,
            });
        }
        if c.saturating_mul(ratio) < decoded {
            return Err(RasterError::DecodedSize {
                path: path.to_path_buf(),
                what: format!("{kind} {i} ({cw}x{rows} cells)"),
                decoded,
                stored: c,
                compression,
                ratio,
            });
        }
        total = total.saturating_add(decoded);
        layout.max_chunk_bytes = layout.max_chunk_bytes.max(decoded);
        layout.max_stored_bytes = layout.max_stored_bytes.max(c);
    }
    // Strips or tiles may share bytes (a bomb points them all at the same few kilobytes):
    // the whole file bounds what they can decode to together.
    if total > len.saturating_mul(ratio) {
        return Err(RasterError::DecodedSize {
            path: path.to_path_buf(),
            what: format!("the {w}x{h} image ({chunks} {kind}s of band 1)"),
            decoded: total,
            stored: len,
            compression,
            ratio,
        });
    }
    Ok(layout)
}
