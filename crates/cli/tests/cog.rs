//! `--cog`: `snowscape convert … --cog` and `snowscape demo --cog` write Cloud-Optimized
//! GeoTIFFs that GDAL (`gdalinfo`, Debian's gdal-bin, installed by `.ci/run`) reads as COGs
//! with their georeferencing; a non-.tif output is refused.

mod common;

use common::{shared, snowscape};
use std::path::Path;
use std::process::Command;

fn gdalinfo(path: &Path) -> String {
    let o = Command::new("gdalinfo")
        .arg(path)
        .output()
        .unwrap_or_else(|e| {
            panic!(
                "gdalinfo is needed (Debian: apt-get install gdal-bin; .ci/run installs it): {e}"
            )
        });
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8_lossy(&o.stdout).into_owned()
}

#[test]
fn convert_and_demo_write_cogs_gdal_accepts() {
    let dem = shared("dem/avaframe_avaMal/avaMal.asc");
    let tmp = tempfile::tempdir().unwrap();
    let cog = tmp.path().join("mal.tif");
    let o = snowscape(&[
        "convert",
        dem.to_str().unwrap(),
        cog.to_str().unwrap(),
        "--cog",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let info = gdalinfo(&cog);
    for needle in [
        "LAYOUT=COG",
        "COMPRESSION=DEFLATE",
        "Block=256x256",
        "Overviews: ",
        "NoData Value=-9999",
    ] {
        assert!(info.contains(needle), "{needle}: {info}");
    }
    // The same corner as the source's ESRI header (xllcorner, top = yllcorner + nrows * 5).
    let plain = gdalinfo(&dem);
    let corner = |t: &str| {
        t.lines()
            .find(|l| l.starts_with("Upper Left"))
            .and_then(|l| l.split(")").next())
            .map(String::from)
    };
    assert_eq!(corner(&info), corner(&plain));
    let bad = tmp.path().join("mal.asc");
    let o = snowscape(&[
        "convert",
        dem.to_str().unwrap(),
        bad.to_str().unwrap(),
        "--cog",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(!bad.exists());

    let out = tmp.path().join("demo");
    let o = snowscape(&[
        "-q",
        "demo",
        "--size",
        "384",
        "--days",
        "3",
        "--frames",
        "0",
        "--cog",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in [
        "depth.tif",
        "bedrock.tif",
        "layers_powder.tif",
        "sun.tif",
        "avalanche_scour.tif",
    ] {
        let info = gdalinfo(&out.join(f));
        assert!(info.contains("LAYOUT=COG"), "{f}: {info}");
    }
    assert!(gdalinfo(&out.join("bedrock.tif")).contains("Overviews: 192x192"));
}
