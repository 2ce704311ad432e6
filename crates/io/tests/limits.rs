//! Hostile inputs (issue 46): decompression bombs, offsets past the end, huge counts and
//! mutated valid files of every format must give a typed error (or a valid grid) naming the
//! file and the value, never a panic, and the reader's peak allocation, measured by a
//! counting allocator on the reading thread, must stay bounded whatever the file claims.

mod common;
#[path = "common/counting.rs"]
mod counting;

use common::craft::*;
use common::*;
use counting::peak_of;
use proptest::prelude::*;
use snowscape_io::{RasterError, RasterFormat, ReadOptions, read_dem, write_raster};
use snowscape_terrain::Crs;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// The most a read in the property tests (cell limit 2^16) may allocate: the grid (5 bytes a
/// cell), one chunk, and the decoders' buffers.
const FUZZ_PEAK: usize = 16 << 20;
const FUZZ_MAX_CELLS: usize = 1 << 16;

fn write_tmp(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

fn opts(max_cells: usize) -> ReadOptions {
    ReadOptions {
        cell_size: Some(1.0),
        height_range: Some((0.0, 100.0)),
        max_cells,
        ..ReadOptions::default()
    }
}

/// Reads `p` and returns the error, its message and the peak allocation.
fn refused(p: &Path, o: &ReadOptions) -> (RasterError, String, usize) {
    let (r, peak) = peak_of(|| read_dem(p, o));
    let e = r.expect_err("a hostile file must be refused");
    let msg = e.to_string();
    assert!(msg.contains(&p.display().to_string()), "no path in: {msg}");
    assert!(msg.len() < 600, "message too long: {msg}");
    assert!(!msg.contains("os error"), "a bare OS error: {msg}");
    (e, msg, peak)
}

#[test]
fn deflate_bomb_geotiff_is_refused_before_allocating() {
    let d = tempfile::tempdir().unwrap();
    // 16384² f32 = 1 GiB claimed by ~6 KB: within the default cell limit (2^28).
    let bomb = deflate_bomb_tiff(16384, 16384, 64);
    assert!(bomb.len() < 16 << 10, "{} bytes", bomb.len());
    let p = write_tmp(d.path(), "bomb.tif", &bomb);
    let (e, msg, peak) = refused(&p, &ReadOptions::default());
    assert!(matches!(e, RasterError::DecodedSize { .. }), "{e:?}");
    assert!(
        msg.contains("1073741824") && msg.contains("Deflate"),
        "{msg}"
    );
    assert!(peak < 1 << 20, "peak {peak} bytes");
    // 20000² f32 = 1.6 GB: over the default limit, and refused by plausibility when the
    // limit is raised.
    let bomb = deflate_bomb_tiff(20000, 20000, 100);
    let p = write_tmp(d.path(), "bomb20k.tif", &bomb);
    let (e, _, _) = refused(&p, &ReadOptions::default());
    assert!(matches!(e, RasterError::TooManyCells { .. }), "{e:?}");
    let (e, msg, peak) = refused(&p, &opts(1 << 30));
    assert!(matches!(e, RasterError::DecodedSize { .. }), "{e:?}");
    assert!(msg.contains("1600000000"), "{msg}");
    assert!(peak < 1 << 20, "peak {peak} bytes");
}

#[test]
fn a_strip_claiming_more_than_its_bytes_hold_names_the_strip() {
    let d = tempfile::tempdir().unwrap();
    // One strip of 4 KiB declared uncompressed, its count says 100 bytes.
    let mut b = bigtiff_u8(None);
    let valid = write_tmp(d.path(), "valid.tif", &b);
    read_dem(&valid, &ReadOptions::default()).unwrap();
    // StripByteCounts is the last LONG8 inline value before the tiepoint tags: patch it.
    let needle = (64u64 * 64).to_le_bytes();
    let at = b.windows(8).rposition(|w| w == needle).unwrap();
    b[at..at + 8].copy_from_slice(&100u64.to_le_bytes());
    let p = write_tmp(d.path(), "short_strip.tif", &b);
    let (e, msg, _) = refused(&p, &ReadOptions::default());
    assert!(matches!(e, RasterError::DecodedSize { .. }), "{e:?}");
    assert!(
        msg.contains("strip 0") && msg.contains("4096") && msg.contains("100"),
        "{msg}"
    );
}

#[test]
fn bigtiff_offset_past_the_end_is_named_not_os_error_22() {
    let d = tempfile::tempdir().unwrap();
    let offset = u64::MAX - 615;
    let p = write_tmp(d.path(), "far.tif", &bigtiff_u8(Some(offset)));
    let (e, msg, _) = refused(&p, &ReadOptions::default());
    assert!(matches!(e, RasterError::PastEnd { .. }), "{e:?}");
    assert!(
        msg.contains("strip 0 offset 18446744073709551000 is past the end of the"),
        "{msg}"
    );
    // The first IFD's offset past the end.
    let mut b = bigtiff_u8(None);
    b[8..16].copy_from_slice(&(1u64 << 62).to_le_bytes());
    let p = write_tmp(d.path(), "far_ifd.tif", &b);
    let (e, msg, _) = refused(&p, &ReadOptions::default());
    assert!(matches!(e, RasterError::PastEnd { .. }), "{e:?}");
    assert!(
        msg.contains("image directory offset 4611686018427387904"),
        "{msg}"
    );
}

#[test]
fn a_tag_of_billions_of_values_is_refused_naming_it() {
    let d = tempfile::tempdir().unwrap();
    let p = write_tmp(d.path(), "tag.tif", &tiff_huge_tag(1 << 31));
    let (e, msg, peak) = refused(&p, &ReadOptions::default());
    assert!(
        matches!(e, RasterError::GeoTiffTag { tag: 42113, .. }),
        "{e:?}"
    );
    assert!(msg.contains("2147483648"), "{msg}");
    assert!(peak < 1 << 20, "peak {peak}");
    // Fewer values than the limit, but more than the file holds.
    let p = write_tmp(d.path(), "tag2.tif", &tiff_huge_tag(1 << 20));
    let (e, msg, _) = refused(&p, &ReadOptions::default());
    assert!(matches!(e, RasterError::RunsPastEnd { .. }), "{e:?}");
    assert!(msg.contains("tag 42113 (GDAL_NODATA)"), "{msg}");
}

#[test]
fn png_bomb_is_refused_before_decoding() {
    let d = tempfile::tempdir().unwrap();
    let p = write_tmp(d.path(), "bomb.png", &png_bomb(16384, 16384));
    let (e, msg, peak) = refused(&p, &ReadOptions::default());
    assert!(matches!(e, RasterError::DecodedSize { .. }), "{e:?}");
    assert!(msg.contains("16384x16384"), "{msg}");
    assert!(peak < 1 << 20, "peak {peak}");
}

#[test]
fn exr_chunk_offset_past_the_end_is_named() {
    let d = tempfile::tempdir().unwrap();
    let g = sample_grid(40, 30, None, false);
    let valid = d.path().join("v.exr");
    write_raster(&valid, &g, RasterFormat::Exr).unwrap();
    let bytes = std::fs::read(&valid).unwrap();
    let p = write_tmp(d.path(), "far.exr", &exr_with_offset(bytes, u64::MAX - 999));
    let (e, msg, _) = refused(&p, &ReadOptions::default());
    assert!(matches!(e, RasterError::PastEnd { .. }), "{e:?}");
    assert!(msg.contains("chunk 0 offset 18446744073709550616"), "{msg}");
}

#[test]
fn npy_and_asc_claims_beyond_the_file_are_refused_cheaply() {
    let d = tempfile::tempdir().unwrap();
    let p = write_tmp(d.path(), "big.npy", &npy_claiming(16384, 16384));
    let (e, msg, peak) = refused(&p, &opts(1 << 28));
    assert!(matches!(e, RasterError::Npy { .. }), "{e:?}");
    assert!(msg.contains("1073741824 data bytes"), "{msg}");
    assert!(peak < 1 << 20, "peak {peak}");
    // 8 MiB of digits without a line break: refused at 64 KiB + 48 x 4 bytes, not buffered.
    let p = write_tmp(d.path(), "long.asc", &asc_long_line(8 << 20));
    let (e, msg, peak) = refused(&p, &ReadOptions::default());
    assert!(
        matches!(e, RasterError::AscLineTooLong { line: 7, .. }),
        "{e:?}"
    );
    assert!(msg.contains("65728 bytes"), "{msg}");
    assert!(peak < 1 << 20, "peak {peak}");
}

#[test]
fn echoed_file_text_is_clipped() {
    let d = tempfile::tempdir().unwrap();
    let long = "x".repeat(100_000);
    let t = HandTiff {
        w: 4,
        h: 4,
        bands: vec![vec![1; 16]],
        tile: None,
        rows_per_strip: 4,
        planar: false,
        extra: vec![ascii_entry(42113, &long)],
    };
    let p = write_tmp(d.path(), "nodata.tif", &t.bytes());
    let (e, msg, _) = refused(&p, &opts(1 << 20));
    assert!(
        matches!(e, RasterError::GeoTiffTag { tag: 42113, .. }),
        "{e:?}"
    );
    assert!(msg.contains("100000 bytes in all"), "{msg}");
    let p = write_tmp(
        d.path(),
        "h.npy",
        &npy_claiming(u64::MAX / 2, 99_999_999_999),
    );
    let (_, msg, _) = refused(&p, &opts(1 << 20));
    assert!(msg.len() < 400, "{msg}");
}

/// Valid small files of every format, and TIFF layouts the writer does not make.
fn seeds() -> &'static Vec<(RasterFormat, Vec<u8>)> {
    static SEEDS: OnceLock<Vec<(RasterFormat, Vec<u8>)>> = OnceLock::new();
    SEEDS.get_or_init(|| {
        let d = tempfile::tempdir().unwrap();
        let g = sample_grid(9, 7, Some(Crs::Epsg(31287)), true);
        let mut out: Vec<(RasterFormat, Vec<u8>)> = RasterFormat::ALL
            .iter()
            .map(|f| {
                let p = d.path().join(format!("s.{}", f.extension()));
                write_raster(&p, &g, *f).unwrap();
                (*f, std::fs::read(&p).unwrap())
            })
            .collect();
        out.push((RasterFormat::GeoTiff, bigtiff_u8(None)));
        out.push((RasterFormat::GeoTiff, deflate_bomb_tiff(40, 30, 8)));
        let p = d.path().join("cog.tif");
        snowscape_io::write_cog(&p, &sample_grid(40, 30, None, false)).unwrap();
        out.push((RasterFormat::GeoTiff, std::fs::read(&p).unwrap()));
        out
    })
}

/// Reads `bytes` as `format` with the fuzz cell limit: a typed error or a valid grid, and a
/// bounded peak allocation.
fn read_bounded(format: RasterFormat, bytes: &[u8]) {
    let d = tempfile::tempdir().unwrap();
    let p = write_tmp(d.path(), &format!("f.{}", format.extension()), bytes);
    let mut o = opts(FUZZ_MAX_CELLS);
    o.format = Some(format);
    o.raw_size = Some((9, 7));
    let (r, peak) = peak_of(|| read_dem(&p, &o));
    assert!(
        peak <= FUZZ_PEAK,
        "{format}: peak {peak} bytes for a {}-byte file ({:?})",
        bytes.len(),
        r.as_ref().err()
    );
    match r {
        Ok(g) => {
            assert!(g.geometry().len() <= FUZZ_MAX_CELLS);
            g.check_finite("fuzz").unwrap();
        }
        Err(e) => {
            let msg = e.to_string();
            assert!(msg.len() < 1000, "{msg}");
        }
    }
}

/// A value that is often huge: the edge cases of u32/u64 and around them.
fn huge() -> impl Strategy<Value = u64> {
    prop_oneof![
        Just(0u64),
        Just(u64::from(u32::MAX)),
        Just(u64::MAX),
        Just(u64::MAX - 615),
        Just(1u64 << 31),
        Just(1u64 << 40),
        0u64..100_000,
        any::<u64>(),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn mutated_files_of_every_format_stay_bounded(
        seed in 0usize..64,
        edits in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 0..8),
        words in prop::collection::vec((any::<prop::sample::Index>(), huge()), 0..3),
        cut in prop::option::of(any::<prop::sample::Index>()),
    ) {
        let all = seeds();
        let (format, valid) = &all[seed % all.len()];
        let mut bytes = valid.clone();
        for (at, b) in &edits {
            let i = at.index(bytes.len());
            bytes[i] ^= b;
        }
        // Huge values written over 4- or 8-byte words (sizes, counts, offsets).
        for (k, (at, v)) in words.iter().enumerate() {
            let wide = if k % 2 == 0 { 8 } else { 4 };
            if bytes.len() >= wide {
                let i = at.index(bytes.len() - wide + 1);
                bytes[i..i + wide].copy_from_slice(&v.to_le_bytes()[..wide]);
            }
        }
        if let Some(c) = cut {
            bytes.truncate(c.index(bytes.len() + 1));
        }
        read_bounded(*format, &bytes);
    }

    #[test]
    fn crafted_tiff_tags_stay_bounded(
        big in any::<bool>(),
        w in huge(), h in huge(), bits in prop::sample::select(vec![1u64, 8, 16, 32, 64, 65, 0]),
        spp in prop::sample::select(vec![1u64, 2, 16, 17, 65535]),
        compression in prop::sample::select(vec![1u64, 5, 8, 32773, 7, 50000]),
        rows in huge(), planar in 1u64..3,
        offsets in prop::collection::vec(huge(), 1..5),
        counts in prop::collection::vec(huge(), 1..5),
        tiled in any::<bool>(), tile in prop::sample::select(vec![16u64, 0, 1 << 20]),
    ) {
        let data = zlib(&[0u8; 4096]);
        let t = if big { LONG8 } else { LONG };
        let (off_tag, count_tag) = if tiled { (324, 325) } else { (273, 279) };
        let mut entries = vec![
            (256, t, vec![w], None),
            (257, t, vec![h], None),
            (258, SHORT, vec![bits], None),
            (259, SHORT, vec![compression], None),
            (277, SHORT, vec![spp], None),
            (284, SHORT, vec![planar], None),
            (off_tag, t, offsets, None),
            (count_tag, t, counts, None),
        ];
        if tiled {
            entries.push((322, t, vec![tile], None));
            entries.push((323, t, vec![tile], None));
        } else {
            entries.push((278, t, vec![rows], None));
        }
        read_bounded(RasterFormat::GeoTiff, &tiff(big, &entries, &data));
    }
}

#[test]
fn seeds_are_valid_files() {
    for (f, bytes) in seeds() {
        let d = tempfile::tempdir().unwrap();
        let p = write_tmp(d.path(), &format!("v.{}", f.extension()), bytes);
        let mut o = opts(FUZZ_MAX_CELLS);
        o.raw_size = Some((9, 7));
        read_dem(&p, &o).unwrap_or_else(|e| panic!("{f}: {e}"));
    }
}
