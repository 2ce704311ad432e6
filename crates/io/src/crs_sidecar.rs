//! CRS sidecar files and CRS text.
//!
//! A raster without an embedded CRS may have one beside it:
//! - `<name>.prj`: a WKT definition (ESRI / GDAL convention for ASCII grids and shapefiles);
//! - `CRS.txt` in the same folder: free text containing e.g. `EPSG:31287` (the convention of
//!   the shared data folder; anything after the code is ignored).
//!
//! A WKT whose root ends with `AUTHORITY["EPSG","n"]` (WKT1) or `ID["EPSG",n]` (WKT2) becomes
//! `Crs::Epsg(n)`, so GeoTIFF output can carry a proper EPSG GeoKey; other WKT is kept as is.

use crate::error::Result;
use snowscape_terrain::Crs;
use std::path::{Path, PathBuf};

/// The CRS described by the `.prj` beside `path`, or else by `CRS.txt` in its folder.
pub(crate) fn sidecar_crs(path: &Path) -> Result<Option<Crs>> {
    for candidate in sidecar_candidates(path) {
        if candidate.is_file() {
            let text = crate::input::read_regular_text(&candidate)?;
            if let Some(crs) = parse_crs_text(&text) {
                return Ok(Some(crs));
            }
        }
    }
    Ok(None)
}

fn sidecar_candidates(path: &Path) -> Vec<PathBuf> {
    let mut out = vec![path.with_extension("prj")];
    if let Some(dir) = path.parent() {
        out.push(dir.join("CRS.txt"));
    }
    out
}

/// A CRS from free text: an `EPSG:n` code anywhere, WKT, or a bare code.
pub(crate) fn parse_crs_text(text: &str) -> Option<Crs> {
    let t = text.trim();
    if looks_like_wkt(t) {
        return Some(root_epsg_of_wkt(t).map_or_else(|| Crs::Wkt(t.to_string()), Crs::Epsg));
    }
    epsg_after_prefix(t).or_else(|| Crs::parse(t))
}

pub(crate) fn looks_like_wkt(t: &str) -> bool {
    let head: String = t
        .chars()
        .take_while(|c| c.is_ascii_alphabetic() || *c == '_')
        .collect::<String>()
        .to_ascii_uppercase();
    matches!(
        head.as_str(),
        "PROJCS"
            | "GEOGCS"
            | "GEOCCS"
            | "COMPD_CS"
            | "PROJCRS"
            | "GEOGCRS"
            | "GEODCRS"
            | "BOUNDCRS"
            | "COMPOUNDCRS"
            | "PROJECTEDCRS"
            | "LOCAL_CS"
            | "ENGCRS"
            | "ENGINEERINGCRS"
    )
}

/// The code of the first `EPSG:<digits>` (case-insensitive) in `t`.
fn epsg_after_prefix(t: &str) -> Option<Crs> {
    let upper = t.to_ascii_uppercase();
    let start = upper.find("EPSG:")? + "EPSG:".len();
    let digits: String = upper[start..]
        .trim_start()
        .chars()
        .take_while(char::is_ascii_digit)
        .collect();
    digits.parse().ok().map(Crs::Epsg)
}

/// The EPSG code of a WKT's root element, when its last child is an EPSG authority.
fn root_epsg_of_wkt(wkt: &str) -> Option<u32> {
    let upper = wkt.to_ascii_uppercase();
    let pos = ["AUTHORITY[", "ID["]
        .iter()
        .filter_map(|k| upper.rfind(k).map(|p| p + k.len()))
        .max()?;
    let rest = &upper[pos..];
    let close = rest.find(']')?;
    let tail = rest[close + 1..].trim();
    // Only the root's closing bracket may follow the authority.
    if tail != "]" {
        return None;
    }
    let mut parts = rest[..close].split(',');
    let auth = parts.next()?.trim().trim_matches('"');
    let code = parts.next()?.trim().trim_matches('"');
    (auth == "EPSG").then(|| code.parse().ok()).flatten()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn epsg_in_free_text() {
        assert_eq!(parse_crs_text("EPSG:31287\n"), Some(Crs::Epsg(31287)));
        assert_eq!(
            parse_crs_text("EPSG:31254 (file says 4326: mislabeled)"),
            Some(Crs::Epsg(31254))
        );
        assert_eq!(parse_crs_text("epsg: 4326"), Some(Crs::Epsg(4326)));
        assert_eq!(parse_crs_text("  "), None);
    }

    #[test]
    fn wkt_root_authority_becomes_epsg() {
        let wkt = r#"PROJCS["MGI / Austria Lambert",GEOGCS["MGI",AUTHORITY["EPSG","4312"]],UNIT["metre",1],AUTHORITY["EPSG","31287"]]"#;
        assert_eq!(parse_crs_text(wkt), Some(Crs::Epsg(31287)));
        let esri = r#"PROJCS["MGI_Austria_Lambert",GEOGCS["GCS_MGI",DATUM["D_MGI",SPHEROID["Bessel_1841",6377397.155,299.1528128]]],UNIT["Meter",1.0]]"#;
        assert_eq!(parse_crs_text(esri), Some(Crs::Wkt(esri.to_string())));
        let wkt2 = r#"GEOGCRS["WGS 84",CS[ellipsoidal,2],ID["EPSG",4326]]"#;
        assert_eq!(parse_crs_text(wkt2), Some(Crs::Epsg(4326)));
    }

    #[test]
    fn prj_wins_over_crs_txt() {
        let d = tempfile::tempdir().unwrap();
        let dem = d.path().join("dem.asc");
        std::fs::write(d.path().join("CRS.txt"), "EPSG:31287").unwrap();
        assert_eq!(sidecar_crs(&dem).unwrap(), Some(Crs::Epsg(31287)));
        std::fs::write(d.path().join("dem.prj"), "EPSG:32611").unwrap();
        assert_eq!(sidecar_crs(&dem).unwrap(), Some(Crs::Epsg(32611)));
    }
}
