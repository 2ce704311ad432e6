//! Bounded fuzzing with proptest: random bytes and mutated valid files, read as every format,
//! must give `Ok` or a typed `Err`, never a panic (and never a grid beyond the cell limit).

mod common;

use common::*;
use proptest::prelude::*;
use snowscape_io::{RasterFormat, ReadOptions, read_dem, write_raster};
use snowscape_terrain::Crs;
use std::sync::OnceLock;

const MAX_CELLS: usize = 1 << 16;

/// Valid files of every format (and a few TIFF layouts), written once.
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
        for (tile, planar) in [(Some(16), true), (None, false)] {
            let t = HandTiff {
                w: 20,
                h: 9,
                bands: vec![vec![3; 180], vec![4; 180]],
                tile,
                rows_per_strip: 4,
                planar,
                extra: vec![
                    f64_entry(33550, &[1.0, 1.0, 0.0]),
                    f64_entry(33922, &[0.0, 0.0, 0.0, 5.0, 5.0, 0.0]),
                    u16_entry(34735, &[1, 1, 0, 2, 1025, 0, 1, 2, 1026, 34737, 4, 0]),
                    ascii_entry(34737, "abc|"),
                    ascii_entry(42113, "3"),
                ],
            };
            out.push((RasterFormat::GeoTiff, t.bytes()));
        }
        out
    })
}

/// Options that let every format read; RAW16 seeds (9x7, not square) need their size.
fn options(format: RasterFormat, raw_size: Option<(usize, usize)>) -> ReadOptions {
    ReadOptions {
        format: Some(format),
        cell_size: Some(2.0),
        height_range: Some((0.0, 100.0)),
        raw_size,
        max_cells: MAX_CELLS,
        crs: None,
    }
}

/// Reads `bytes` as `format`; any grid returned must respect the cell limit and be finite.
fn read_as(format: RasterFormat, bytes: &[u8], raw_size: Option<(usize, usize)>) {
    let d = tempfile::tempdir().unwrap();
    let p = d.path().join(format!("f.{}", format.extension()));
    std::fs::write(&p, bytes).unwrap();
    if let Ok(g) = read_dem(&p, &options(format, raw_size)) {
        assert!(g.geometry().len() <= MAX_CELLS);
        g.check_finite("fuzz").unwrap();
    }
}

fn format_strategy() -> impl Strategy<Value = RasterFormat> {
    prop::sample::select(RasterFormat::ALL.to_vec())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn random_bytes_never_panic(format in format_strategy(), bytes in prop::collection::vec(any::<u8>(), 0..600)) {
        read_as(format, &bytes, None);
    }

    #[test]
    fn mutated_valid_files_never_panic(
        seed in 0usize..64,
        edits in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..8),
        cut in prop::option::of(any::<prop::sample::Index>()),
    ) {
        let all = seeds();
        let (format, valid) = &all[seed % all.len()];
        let mut bytes = valid.clone();
        for (at, b) in &edits {
            let i = at.index(bytes.len());
            bytes[i] = *b;
        }
        if let Some(c) = cut {
            bytes.truncate(c.index(bytes.len() + 1));
        }
        read_as(*format, &bytes, Some((9, 7)));
    }

    #[test]
    fn asc_text_variations_never_panic(
        ncols in 0u64..20_000_000, nrows in 0u64..20_000_000,
        cell in prop::sample::select(vec!["1", "0", "-3", "nan", "inf", "1e308", "x"]),
        values in prop::collection::vec(prop::sample::select(vec!["1", "2.5", "-9999", "nan", "-inf", "1e39", "", "\n", "a"]), 0..40),
    ) {
        let text = format!(
            "ncols {ncols}\nnrows {nrows}\nxllcorner 0\nyllcorner 0\ncellsize {cell}\nNODATA_value -9999\n{}",
            values.join(" ")
        );
        read_as(RasterFormat::Asc, text.as_bytes(), None);
    }
}

#[test]
fn seeds_are_valid_files() {
    for (f, bytes) in seeds() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join(format!("v.{}", f.extension()));
        std::fs::write(&p, bytes).unwrap();
        read_dem(&p, &options(*f, Some((9, 7)))).unwrap_or_else(|e| panic!("{f}: {e}"));
    }
}
