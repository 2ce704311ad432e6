//! Windows of rows of a GeoTIFF ([`TiffRows`]) hold the cells, nodata and georeferencing of
//! the same rows of the whole read, for striped files and tiled (COG) ones.

mod common;

use common::*;
use snowscape_io::{ReadOptions, TiffRows, read_dem, write_cog, write_geotiff};
use snowscape_terrain::Grid;

fn check_windows(path: &std::path::Path, whole: &Grid) {
    let g = whole.geometry();
    let (w, h) = (g.width(), g.height());
    let mut rows = TiffRows::open(path, &ReadOptions::default()).unwrap();
    assert_eq!(rows.geometry(), g);
    for range in [0..1, 0..h, 3..70, h - 2..h, h - 1..h, 200..457, 511..513] {
        let win = rows.read_rows(range.clone()).unwrap();
        assert_eq!(win.geometry().width(), w);
        assert_eq!(win.geometry().height(), range.len());
        for (k, r) in range.clone().enumerate() {
            for c in 0..w {
                let (i, j) = (g.index(c, r), win.geometry().index(c, k));
                assert_eq!(
                    whole.mask().is_valid(i),
                    win.mask().is_valid(j),
                    "{range:?} ({c}, {r})"
                );
                if whole.mask().is_valid(i) {
                    assert_eq!(whole.data()[i].to_bits(), win.data()[j].to_bits());
                }
            }
        }
        // The window's cell centres are the whole grid's.
        assert_eq!(
            win.geometry().cell_centre(5, 0),
            g.cell_centre(5, range.start)
        );
    }
    assert!(rows.read_rows(h..h + 1).is_err());
    assert!(rows.read_rows(4..4).is_err());
}

#[test]
fn windows_of_striped_and_tiled_geotiffs_match_the_whole_read() {
    let d = tempfile::tempdir().unwrap();
    // 700 × 600 cells: several strips, and 512-cell COG tiles with partial ones at the edges.
    let g = sample_grid(700, 600, None, true);
    for (name, cog) in [("strips.tif", false), ("cog.tif", true)] {
        let p = d.path().join(name);
        if cog {
            write_cog(&p, &g).unwrap();
        } else {
            write_geotiff(&p, &g).unwrap();
        }
        let whole = read_dem(&p, &ReadOptions::default()).unwrap();
        check_windows(&p, &whole);
    }
}
