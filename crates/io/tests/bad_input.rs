//! Bad inputs and failing outputs: each gives its specific error variant, naming the file and
//! the offending value, and never leaves a file behind.

mod common;

use common::*;
use snowscape_io::{
    AtomicWriteError, RasterError, RasterFormat, ReadOptions, read_dem, write_exr, write_geotiff,
    write_png16, write_raster, write_splat,
};
use snowscape_terrain::LayeredTerrain;
use std::path::{Path, PathBuf};

fn write_tmp(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

fn read(p: &Path) -> RasterError {
    read_dem(p, &ReadOptions::default()).unwrap_err()
}

fn assert_names(e: &RasterError, p: &Path, value: &str) {
    let msg = e.to_string();
    assert!(msg.contains(&p.display().to_string()), "no path in: {msg}");
    assert!(msg.contains(value), "no {value:?} in: {msg}");
}

const HEADER: &str =
    "ncols 4\nnrows 3\nxllcorner 0\nyllcorner 0\ncellsize 10\nNODATA_value -9999\n";

#[test]
fn truncated_geotiff_is_a_tiff_error() {
    let d = tempfile::tempdir().unwrap();
    let g = sample_grid(64, 64, None, false);
    let full = d.path().join("full.tif");
    write_geotiff(&full, &g).unwrap();
    let bytes = std::fs::read(&full).unwrap();
    let p = write_tmp(d.path(), "half.tif", &bytes[..bytes.len() / 2]);
    let e = read(&p);
    // The directory of the cut file lies past its end: said with the offset.
    assert!(
        matches!(
            e,
            RasterError::TiffTruncated { .. } | RasterError::PastEnd { .. }
        ),
        "{e:?}"
    );
    assert_names(&e, &p, "half.tif");
    // Said once, in words, with no decoder jargon in the message or its causes.
    let mut said = e.to_string();
    let mut cause = std::error::Error::source(&e);
    while let Some(c) = cause {
        said.push_str(&c.to_string());
        cause = c.source();
    }
    assert_eq!(said.matches("truncated").count(), 1, "{said}");
    assert!(!said.contains("failed to fill"), "{said}");
    // A file whose IFD comes first and whose data is cut: the decoder fails on the strips.
    let t = HandTiff {
        w: 40,
        h: 30,
        bands: vec![vec![7; 1200]],
        tile: None,
        rows_per_strip: 10,
        planar: false,
        extra: vec![u16_entry(34735, &[1, 1, 0, 0])],
    };
    let b = t.bytes();
    let p = write_tmp(d.path(), "cut.tif", &b[..b.len() - 1000]);
    let o = ReadOptions {
        cell_size: Some(1.0),
        ..Default::default()
    };
    let e = read_dem(&p, &o).unwrap_err();
    assert!(
        matches!(
            e,
            RasterError::TiffTruncated { .. }
                | RasterError::Tiff { .. }
                | RasterError::RunsPastEnd { .. }
        ),
        "{e:?}"
    );
    assert_names(&e, &p, "cut.tif");
}

#[test]
fn garbage_after_a_valid_header_is_a_tiff_error() {
    let d = tempfile::tempdir().unwrap();
    let mut b = b"II*\0\x08\0\0\0".to_vec();
    b.extend((0..4000u32).map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8));
    let p = write_tmp(d.path(), "garbage.tif", &b);
    let e = read(&p);
    assert!(
        matches!(
            e,
            RasterError::Tiff { .. }
                | RasterError::TiffTruncated { .. }
                | RasterError::TiffUnsupported { .. }
                | RasterError::TooManyCells { .. }
                | RasterError::PastEnd { .. }
                | RasterError::RunsPastEnd { .. }
        ),
        "{e:?}"
    );
    assert_names(&e, &p, "garbage.tif");
    let p = write_tmp(d.path(), "notatiff.tif", b"hello, this is text");
    assert!(matches!(read(&p), RasterError::Tiff { .. }));
}

#[test]
fn asc_with_too_many_rows_of_values() {
    let d = tempfile::tempdir().unwrap();
    let text = format!("{HEADER}1 2 3 4\n5 6 7 8\n9 10 11 12\n13 14 15 16\n");
    let p = write_tmp(d.path(), "long.asc", text.as_bytes());
    let e = read(&p);
    assert!(
        matches!(
            e,
            RasterError::AscValueCount {
                expected: 12,
                found: 16,
                line: 10,
                ..
            }
        ),
        "{e:?}"
    );
    assert_names(&e, &p, "holds 16");
}

#[test]
fn asc_with_too_few_rows_of_values() {
    let d = tempfile::tempdir().unwrap();
    let text = format!("{HEADER}1 2 3 4\n5 6 7 8\n");
    let p = write_tmp(d.path(), "short.asc", text.as_bytes());
    let e = read(&p);
    assert!(
        matches!(
            e,
            RasterError::AscValueCount {
                expected: 12,
                found: 8,
                line: 8,
                ..
            }
        ),
        "{e:?}"
    );
    assert_names(&e, &p, "= 12 values");
}

#[test]
fn asc_header_claiming_ten_billion_cells_fails_before_allocating() {
    let d = tempfile::tempdir().unwrap();
    let text = "ncols 100000\nnrows 100000\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2 3\n";
    let p = write_tmp(d.path(), "huge.asc", text.as_bytes());
    let e = read(&p);
    assert!(
        matches!(e, RasterError::TooManyCells { width: 100_000, height: 100_000, max, .. } if max == 1 << 28),
        "{e:?}"
    );
    assert_names(&e, &p, "100000x100000");
}

#[test]
fn nan_and_infinite_heights_name_their_cell() {
    let d = tempfile::tempdir().unwrap();
    // Quoted as written in the file: `1e999` once showed as `inf`, `1e39` as 40 digits.
    for tok in ["nan", "inf", "-Infinity", "1e999", "-1e39"] {
        let text = format!("{HEADER}1 2 3 4\n5 6 {tok} 8\n9 10 11 12\n");
        let p = write_tmp(d.path(), "nan.asc", text.as_bytes());
        let e = read(&p);
        assert!(
            matches!(
                e,
                RasterError::AscValue {
                    col: 2,
                    row: 1,
                    line: 8,
                    ..
                }
            ),
            "{tok}: {e:?}"
        );
        assert_names(&e, &p, &format!("{tok:?}"));
        assert_names(&e, &p, "col 2, row 1");
    }
    // NaN declared as the nodata value is nodata.
    let text = HEADER.replace("-9999", "nan") + "1 2 3 4\n5 6 NaN 8\n9 10 11 12\n";
    let p = write_tmp(d.path(), "nannd.asc", text.as_bytes());
    let g = read_dem(&p, &ReadOptions::default()).unwrap();
    assert_eq!(g.get(2, 1), None);
}

#[test]
fn zero_negative_and_nan_cell_sizes() {
    let d = tempfile::tempdir().unwrap();
    for (v, shown) in [("0", "0"), ("-5", "-5"), ("nan", "NaN")] {
        let text = HEADER.replace("cellsize 10", &format!("cellsize {v}"))
            + "1 2 3 4 5 6 7 8 9 10 11 12\n";
        let p = write_tmp(d.path(), "cell.asc", text.as_bytes());
        let e = read(&p);
        assert!(
            matches!(e, RasterError::InvalidCellSize { .. }),
            "{v}: {e:?}"
        );
        assert_names(&e, &p, &format!("cell size {shown}"));
        assert_names(&e, &p, "line 5");
    }
    let g = sample_grid(4, 4, None, false);
    let p = d.path().join("a.npy");
    write_raster(&p, &g, RasterFormat::Npy).unwrap();
    let o = ReadOptions {
        cell_size: Some(-2.0),
        ..Default::default()
    };
    let e = read_dem(&p, &o).unwrap_err();
    assert!(matches!(e, RasterError::InvalidCellSize { value, .. } if value == -2.0));
    assert_names(&e, &p, "--cell-size");
}

#[test]
fn unparsable_tokens_name_line_and_token() {
    let d = tempfile::tempdir().unwrap();
    let text = format!("{HEADER}1 2 3 4\n5 6 7 8\n9 1O 11 12\n");
    let p = write_tmp(d.path(), "tok.asc", text.as_bytes());
    let e = read(&p);
    assert!(
        matches!(&e, RasterError::AscToken { line: 9, token, .. } if token == "1O"),
        "{e:?}"
    );
    assert_names(&e, &p, "tok.asc:9");
}

#[test]
fn missing_input_is_an_io_error_naming_the_file() {
    let p = Path::new("/nonexistent-snowscape/dem.asc");
    let e = read(p);
    assert!(matches!(e, RasterError::Io { .. }));
    assert_names(&e, p, "dem.asc");
}

/// Every writer, into a folder that does not exist: a Folder error naming it, nothing created.
#[test]
fn writing_under_a_missing_folder_fails_cleanly() {
    let d = tempfile::tempdir().unwrap();
    let missing = d.path().join("no").join("such");
    let g = sample_grid(5, 4, None, true);
    let mut results: Vec<(String, RasterError)> = RasterFormat::ALL
        .iter()
        .map(|f| {
            let p = missing.join(format!("o.{}", f.extension()));
            (f.to_string(), write_raster(&p, &g, *f).unwrap_err())
        })
        .collect();
    results.push((
        "png16".into(),
        write_png16(&missing.join("d.png"), &g).unwrap_err(),
    ));
    results.push((
        "exr".into(),
        write_exr(&missing.join("l.exr"), g.geometry(), &[("a", g.data())]).unwrap_err(),
    ));
    results.push((
        "splat".into(),
        write_splat(
            &missing.join("s.png"),
            &LayeredTerrain::from_bedrock(g.clone()),
        )
        .unwrap_err(),
    ));
    for (what, e) in results {
        assert!(
            matches!(e, RasterError::Write(AtomicWriteError::Folder { .. })),
            "{what}: {e:?}"
        );
        assert!(e.to_string().contains("no/such"), "{what}: {e}");
    }
    assert!(!missing.exists());
    assert_dir_entries(d.path(), 0);
}

/// A write that fails after the data was encoded (the target is a folder, so the final rename
/// fails) leaves neither a partial file nor a temporary one.
#[test]
fn a_failed_write_leaves_no_file() {
    let d = tempfile::tempdir().unwrap();
    let target = d.path().join("out.tif");
    std::fs::create_dir(&target).unwrap();
    std::fs::write(target.join("keep"), b"x").unwrap();
    let g = sample_grid(8, 8, None, false);
    let e = write_geotiff(&target, &g).unwrap_err();
    assert!(
        matches!(e, RasterError::Write(AtomicWriteError::Write { .. })),
        "{e:?}"
    );
    assert!(e.to_string().contains("out.tif"), "{e}");
    assert_dir_entries(d.path(), 1);
    assert!(target.join("keep").is_file());
    // Validation failures happen before anything is created, and an existing file survives.
    let p = d.path().join("wind.tif");
    std::fs::write(&p, b"old").unwrap();
    let short = vec![0.0f32; 3];
    let e = snowscape_io::write_geotiff_bands(&p, g.geometry(), g.mask(), &[&short]).unwrap_err();
    assert!(matches!(
        e,
        RasterError::LengthMismatch {
            found: 3,
            expected: 64,
            ..
        }
    ));
    assert_eq!(std::fs::read(&p).unwrap(), b"old");
    assert_dir_entries(d.path(), 2);
}

#[test]
fn corrupt_sidecar_and_npy_headers() {
    let d = tempfile::tempdir().unwrap();
    let g = sample_grid(6, 6, None, false);
    let p = d.path().join("h.png");
    write_png16(&p, &g).unwrap();
    std::fs::write(d.path().join("h.png.json"), b"{not json").unwrap();
    let e = read(&p);
    assert!(matches!(e, RasterError::Sidecar { .. }), "{e:?}");
    assert_names(&e, &d.path().join("h.png.json"), "h.png.json");
    // An NPY header whose shape overflows, and one whose data is cut short.
    let o = ReadOptions {
        cell_size: Some(1.0),
        ..Default::default()
    };
    let mut b = b"\x93NUMPY\x01\x00".to_vec();
    let h = "{'descr': '<f4', 'fortran_order': False, 'shape': (99999999999, 99999999999), }";
    b.extend((h.len() as u16).to_le_bytes());
    b.extend(h.as_bytes());
    let q = write_tmp(d.path(), "big.npy", &b);
    let e = read_dem(&q, &o).unwrap_err();
    assert!(matches!(e, RasterError::Npy { .. }), "{e:?}");
    assert_names(&e, &q, "99999999999");
    let a = d.path().join("a.npy");
    write_raster(&a, &g, RasterFormat::Npy).unwrap();
    let bytes = std::fs::read(&a).unwrap();
    let q = write_tmp(d.path(), "cut.npy", &bytes[..bytes.len() - 10]);
    let e = read_dem(&q, &o).unwrap_err();
    assert!(matches!(e, RasterError::Npy { .. }), "{e:?}");
    assert_names(&e, &q, "needs 144 data bytes");
}

/// Every reader refuses devices and FIFOs before reading (a FIFO must not block the open,
/// `/dev/zero` must not be read without end).
#[test]
fn devices_and_fifos_are_refused_by_every_reader() {
    let d = tempfile::tempdir().unwrap();
    for f in RasterFormat::ALL {
        let o = ReadOptions {
            format: Some(f),
            cell_size: Some(1.0),
            height_range: Some((0.0, 1.0)),
            ..Default::default()
        };
        let e = read_dem(Path::new("/dev/zero"), &o).unwrap_err();
        assert!(
            matches!(
                e,
                RasterError::Input(snowscape_io::InputError::NotRegular { .. })
            ),
            "{f}: {e:?}"
        );
        assert!(e.to_string().contains("character device"), "{f}: {e}");
        let fifo = d.path().join(format!("pipe.{}", f.extension()));
        let made = std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .is_ok_and(|s| s.success());
        if made {
            let e = read_dem(&fifo, &o).unwrap_err();
            assert!(e.to_string().contains("FIFO"), "{f}: {e}");
        }
        let e = read_dem(d.path(), &o).unwrap_err();
        assert!(e.to_string().contains("a directory"), "{f}: {e}");
    }
}

/// A raster that reads but cannot be a terrain is refused by `read_terrain` (issue 19 item 6).
#[test]
fn read_terrain_refuses_what_cannot_be_a_terrain() {
    let d = tempfile::tempdir().unwrap();
    let head = |w: usize, h: usize| {
        format!("ncols {w}\nnrows {h}\nxllcorner 0\nyllcorner 0\ncellsize 10\nNODATA_value -9999\n")
    };
    for (name, text, needle) in [
        ("one.asc", head(1, 1) + "5\n", "1x1"),
        ("row.asc", head(5, 1) + "1 2 3 4 5\n", "5x1"),
        ("col.asc", head(1, 3) + "1\n2\n3\n", "1x3"),
        (
            "void.asc",
            head(2, 2) + "-9999 -9999\n-9999 -9999\n",
            "0 valid cells",
        ),
        (
            "lone.asc",
            head(3, 2) + "-9999 7 -9999\n-9999 -9999 -9999\n",
            "1 valid cells",
        ),
        (
            "spike.asc",
            head(2, 2) + "1 2\n1e30 4\n",
            "1e30 m at cell (col 0, row 1)",
        ),
    ] {
        let p = write_tmp(d.path(), name, text.as_bytes());
        assert!(read_dem(&p, &ReadOptions::default()).is_ok(), "{name}");
        let e = snowscape_io::read_terrain(&p, &ReadOptions::default()).unwrap_err();
        assert!(matches!(e, RasterError::Terrain { .. }), "{name}: {e:?}");
        assert_names(&e, &p, needle);
    }
}

/// An absurd read option is refused before the file is read, even by a format that would
/// ignore it (a georeferenced ASC has its own cell size): one check for every front end.
#[test]
fn absurd_read_options_are_refused_for_every_format() {
    let d = tempfile::tempdir().unwrap();
    let p = write_tmp(
        d.path(),
        "dem.asc",
        format!("{HEADER}1 2 3 4\n5 6 7 8\n9 10 11 12\n").as_bytes(),
    );
    assert!(read_dem(&p, &ReadOptions::default()).is_ok());
    for c in [-2.0, 0.0, f64::NAN, f64::INFINITY] {
        let o = ReadOptions {
            cell_size: Some(c),
            ..Default::default()
        };
        let e = read_dem(&p, &o).unwrap_err();
        assert!(
            matches!(e, RasterError::InvalidCellSize { value, .. } if value.to_bits() == c.to_bits()),
            "{e}"
        );
        assert_names(&e, &p, &format!("{c}"));
    }
    let o = ReadOptions {
        height_range: Some((5.0, 1.0)),
        ..Default::default()
    };
    assert!(matches!(
        read_dem(&p, &o).unwrap_err(),
        RasterError::InvalidHeightRange { .. }
    ));
    let o = ReadOptions {
        raw_size: Some((0, 4)),
        ..Default::default()
    };
    let e = read_dem(&p, &o).unwrap_err();
    assert!(
        matches!(
            e,
            RasterError::InvalidRawSize {
                width: 0,
                height: 4,
                ..
            }
        ),
        "{e}"
    );
    assert_names(&e, &p, "0x4");
}
