//! Cloud-Optimized GeoTIFF: the values and georeferencing read back (our reader), overviews
//! halve to one tile, and GDAL (`gdalinfo`, Debian's gdal-bin, which `.ci/run` installs) calls
//! the file a COG.

use snowscape_io::{ReadOptions, read_dem, write_cog};
use snowscape_terrain::{Crs, GeoTransform, Grid, GridGeometry, NodataMask};
use std::process::Command;

/// A 700 x 530 grid of 5 m cells in UTM 32N with a nodata corner.
fn grid() -> Grid {
    let t = GeoTransform {
        origin_x: 600_000.0,
        origin_y: 5_200_000.0,
        pixel_width: 5.0,
        pixel_height: 5.0,
    };
    let g = GridGeometry::from_transform(700, 530, t, Some(Crs::Epsg(32632))).unwrap();
    let data: Vec<f32> = (0..700 * 530)
        .map(|i| 1500.0 + ((i % 700) as f32 * 0.37).sin() * 40.0 + (i / 700) as f32 * 0.8)
        .collect();
    let invalid: Vec<bool> = (0..700 * 530)
        .map(|i| i % 700 < 40 && i / 700 < 30)
        .collect();
    Grid::new(g, data, NodataMask::from_invalid(invalid)).unwrap()
}

#[test]
fn a_cog_reads_back_and_gdal_calls_it_a_cog() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("dem_cog.tif");
    let g = grid();
    write_cog(&path, &g).unwrap();
    let back = read_dem(&path, &ReadOptions::default()).unwrap();
    assert_eq!(back.geometry().transform(), g.geometry().transform());
    assert_eq!(back.geometry().crs(), Some(&Crs::Epsg(32632)));
    for i in 0..g.data().len() {
        assert_eq!(back.mask().is_valid(i), g.mask().is_valid(i), "cell {i}");
        if g.mask().is_valid(i) {
            assert_eq!(back.data()[i].to_bits(), g.data()[i].to_bits(), "cell {i}");
        }
    }
    let out = Command::new("gdalinfo").arg(&path).output().unwrap_or_else(|e| {
        panic!("gdalinfo is needed for this test (Debian: apt-get install gdal-bin; .ci/run installs it): {e}")
    });
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(text.contains("LAYOUT=COG"), "{text}");
    assert!(text.contains("COMPRESSION=DEFLATE"), "{text}");
    assert!(text.contains("Block=256x256"), "{text}");
    // Overviews 350x265 and 175x133 (the last fits one tile).
    assert!(text.contains("Overviews: 350x265, 175x133"), "{text}");
    assert!(text.contains("NoData Value=-9999"), "{text}");
    assert!(text.contains("32632"), "{text}");
    assert!(
        text.contains("Upper Left  (  600000.000, 5200000.000)"),
        "{text}"
    );
    // GDAL reads every value as written (its checksum equals that of a plain GeoTIFF of the
    // same grid).
    let plain = dir.path().join("dem.tif");
    snowscape_io::write_geotiff(&plain, &g).unwrap();
    let checksum = |p: &std::path::Path| {
        let o = Command::new("gdalinfo")
            .args(["-checksum"])
            .arg(p)
            .output()
            .unwrap();
        String::from_utf8_lossy(&o.stdout)
            .lines()
            .find(|l| l.contains("Checksum="))
            .map(str::trim)
            .map(String::from)
    };
    assert_eq!(checksum(&path), checksum(&plain));
    assert!(checksum(&path).is_some());
}
