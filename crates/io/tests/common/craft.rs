//! Crafted hostile files (decompression bombs, offsets past the end, huge counts), shared by
//! `tests/limits.rs` and `examples/reader_limits.rs` (which `scripts/reader-limits.sh` runs
//! under `ulimit -v`).
#![allow(dead_code)]

use std::io::Write;

/// TIFF field types used here.
pub const SHORT: u16 = 3;
pub const LONG: u16 = 4;
pub const ASCII: u16 = 2;
pub const LONG8: u16 = 16;

/// One IFD entry: tag, field type, values (each written in the type's size).
pub type TiffEntry = (u16, u16, Vec<u64>);

/// Where a crafted TIFF's data blob starts (right after the header).
pub fn tiff_data_start(big: bool) -> u64 {
    if big { 16 } else { 8 }
}

fn type_bytes(t: u16) -> usize {
    match t {
        1 | 2 | 6 | 7 => 1,
        3 | 8 => 2,
        4 | 9 | 11 | 13 => 4,
        _ => 8,
    }
}

/// A little-endian (Big)TIFF: header, `data` at [`tiff_data_start`], then one IFD with
/// `entries` (sorted by tag here), values that do not fit inline after it. Offsets inside
/// entries are absolute: the caller places them in `data`. A value list may be shorter than
/// the count it claims (`count` overrides it), to craft huge counts.
pub fn tiff(big: bool, entries: &[(u16, u16, Vec<u64>, Option<u64>)], data: &[u8]) -> Vec<u8> {
    let mut entries = entries.to_vec();
    entries.sort_by_key(|e| e.0);
    let mut out = Vec::new();
    out.extend(b"II");
    let ifd_at = tiff_data_start(big) + data.len() as u64 + (data.len() as u64 & 1);
    if big {
        out.extend(43u16.to_le_bytes());
        out.extend(8u16.to_le_bytes());
        out.extend(0u16.to_le_bytes());
        out.extend(ifd_at.to_le_bytes());
    } else {
        out.extend(42u16.to_le_bytes());
        out.extend((ifd_at as u32).to_le_bytes());
    }
    out.extend(data);
    if data.len() & 1 == 1 {
        out.push(0);
    }
    let (head, entry, inline) = if big { (8, 20, 8) } else { (2, 12, 4) };
    let ifd_len = head + entry * entries.len() + inline;
    let mut extra_at = ifd_at as usize + ifd_len;
    let mut extra = Vec::new();
    if big {
        out.extend((entries.len() as u64).to_le_bytes());
    } else {
        out.extend((entries.len() as u16).to_le_bytes());
    }
    for (tag, t, values, count) in &entries {
        let size = type_bytes(*t);
        let mut bytes = Vec::new();
        for v in values {
            bytes.extend(&v.to_le_bytes()[..size]);
        }
        let count = count.unwrap_or(values.len() as u64);
        out.extend(tag.to_le_bytes());
        out.extend(t.to_le_bytes());
        if big {
            out.extend(count.to_le_bytes());
        } else {
            out.extend((count as u32).to_le_bytes());
        }
        if bytes.len() <= inline {
            bytes.resize(inline, 0);
            out.extend(bytes);
        } else {
            if big {
                out.extend((extra_at as u64).to_le_bytes());
            } else {
                out.extend((extra_at as u32).to_le_bytes());
            }
            extra_at += bytes.len() + (bytes.len() & 1);
            if bytes.len() & 1 == 1 {
                bytes.push(0);
            }
            extra.extend(bytes);
        }
    }
    out.extend(vec![0u8; inline]);
    out.extend(extra);
    out
}

/// zlib-compressed bytes.
pub fn zlib(data: &[u8]) -> Vec<u8> {
    let mut e = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::best());
    e.write_all(data).unwrap();
    e.finish().unwrap()
}

/// A deflate bomb: a `w x h` f32 GeoTIFF (cell size 1 m) whose strips of `rows` rows all
/// point at the same deflated strip of zeros: a few kilobytes claiming `w h 4` bytes.
pub fn deflate_bomb_tiff(w: u64, h: u64, rows: u64) -> Vec<u8> {
    let strip = zlib(&vec![0u8; (w * rows * 4) as usize]);
    let strips = h.div_ceil(rows);
    let at = tiff_data_start(false);
    let mut counts = vec![strip.len() as u64; strips as usize];
    // The last strip holds fewer rows: same bytes (zlib stops when the strip is full).
    if let Some(c) = counts.last_mut() {
        *c = strip.len() as u64;
    }
    tiff(
        false,
        &[
            (256, LONG, vec![w], None),
            (257, LONG, vec![h], None),
            (258, SHORT, vec![32], None),
            (259, SHORT, vec![8], None),
            (262, SHORT, vec![1], None),
            (273, LONG, vec![at; strips as usize], None),
            (277, SHORT, vec![1], None),
            (278, LONG, vec![rows], None),
            (279, LONG, counts, None),
            (339, SHORT, vec![3], None),
            (33550, 12, vec![1f64.to_bits(), 1f64.to_bits(), 0], None),
            (33922, 12, vec![0, 0, 0, 0, (h as f64).to_bits(), 0], None),
        ],
        &strip,
    )
}

/// A valid 64x64 u8 BigTIFF with one uncompressed strip, whose strip offset is `offset`
/// (`None`: the right one).
pub fn bigtiff_u8(offset: Option<u64>) -> Vec<u8> {
    let data: Vec<u8> = (0..64 * 64).map(|i| (i % 200) as u8).collect();
    let at = offset.unwrap_or(tiff_data_start(true));
    tiff(
        true,
        &[
            (256, LONG, vec![64], None),
            (257, LONG, vec![64], None),
            (258, SHORT, vec![8], None),
            (259, SHORT, vec![1], None),
            (262, SHORT, vec![1], None),
            (273, LONG8, vec![at], None),
            (277, SHORT, vec![1], None),
            (278, LONG, vec![64], None),
            (279, LONG8, vec![64 * 64], None),
            (33550, 12, vec![1f64.to_bits(), 1f64.to_bits(), 0], None),
            (33922, 12, vec![0, 0, 0, 0, 64f64.to_bits(), 0], None),
        ],
        &data,
    )
}

/// A valid small TIFF whose GDAL_NODATA tag claims `count` ASCII bytes (its values' offset
/// inside the file).
pub fn tiff_huge_tag(count: u64) -> Vec<u8> {
    let data: Vec<u8> = (0..64 * 64).map(|i| (i % 200) as u8).collect();
    let at = tiff_data_start(true);
    tiff(
        true,
        &[
            (256, LONG, vec![64], None),
            (257, LONG, vec![64], None),
            (258, SHORT, vec![8], None),
            (259, SHORT, vec![1], None),
            (262, SHORT, vec![1], None),
            (273, LONG8, vec![at], None),
            (277, SHORT, vec![1], None),
            (278, LONG, vec![64], None),
            (279, LONG8, vec![64 * 64], None),
            (33550, 12, vec![1f64.to_bits(), 1f64.to_bits(), 0], None),
            (33922, 12, vec![0, 0, 0, 0, 64f64.to_bits(), 0], None),
            (
                42113,
                ASCII,
                b"-9999\0\0\0\0".iter().map(|&c| u64::from(c)).collect(),
                Some(count),
            ),
        ],
        &data,
    )
}

/// A PNG whose IHDR claims a `w x h` 16-bit grayscale image, with one tiny IDAT.
pub fn png_bomb(w: u32, h: u32) -> Vec<u8> {
    fn chunk(out: &mut Vec<u8>, kind: &[u8; 4], body: &[u8]) {
        out.extend((body.len() as u32).to_be_bytes());
        let mut crc = flate2::Crc::new();
        crc.update(kind);
        crc.update(body);
        out.extend(kind);
        out.extend(body);
        out.extend(crc.sum().to_be_bytes());
    }
    let mut out = b"\x89PNG\r\n\x1a\n".to_vec();
    let mut ihdr = Vec::new();
    ihdr.extend(w.to_be_bytes());
    ihdr.extend(h.to_be_bytes());
    ihdr.extend([16, 0, 0, 0, 0]);
    chunk(&mut out, b"IHDR", &ihdr);
    chunk(&mut out, b"IDAT", &zlib(&vec![0u8; 1 << 16]));
    chunk(&mut out, b"IEND", &[]);
    out
}

/// The offset of the first offset table of a single-part EXR (after its header).
pub fn exr_offset_table(bytes: &[u8]) -> usize {
    let mut at = 8;
    while bytes[at] != 0 {
        for _ in 0..2 {
            while bytes[at] != 0 {
                at += 1;
            }
            at += 1;
        }
        let size = i32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()) as usize;
        at += 4 + size;
    }
    at + 1
}

/// `exr` (a valid single-part file) with its first chunk offset set to `offset`.
pub fn exr_with_offset(mut exr: Vec<u8>, offset: u64) -> Vec<u8> {
    let at = exr_offset_table(&exr);
    exr[at..at + 8].copy_from_slice(&offset.to_le_bytes());
    exr
}

/// An NPY header claiming `rows x cols` f4 values, with 16 bytes of data.
pub fn npy_claiming(rows: u64, cols: u64) -> Vec<u8> {
    let mut header =
        format!("{{'descr': '<f4', 'fortran_order': False, 'shape': ({rows}, {cols}), }}");
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut out = b"\x93NUMPY\x01\x00".to_vec();
    out.extend((header.len() as u16).to_le_bytes());
    out.extend(header.as_bytes());
    out.extend([0u8; 16]);
    out
}

/// An ESRI ASCII grid of 4x3 cells whose first data line is `len` digits with no line break.
pub fn asc_long_line(len: usize) -> Vec<u8> {
    let mut out =
        b"ncols 4\nnrows 3\nxllcorner 0\nyllcorner 0\ncellsize 10\nNODATA_value -9999\n".to_vec();
    out.extend(std::iter::repeat_n(b'7', len));
    out
}
