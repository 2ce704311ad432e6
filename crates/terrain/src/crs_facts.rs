//! What a coordinate reference system says about itself, and whether two are the same: EPSG
//! codes (given, at the WKT root as WKT1 `AUTHORITY` or WKT2 `ID`, or recognised from the name
//! of the CRSs avalanche practitioners use) and normalised WKT names compared loosely. Used
//! wherever two georeferenced inputs meet (a release shapefile's `.prj` and its DEM).

use crate::Crs;

/// What a CRS says about itself: an EPSG code (given or recognised from the name), a
/// normalised name, and whether it is geographic.
pub struct CrsFacts {
    /// The EPSG code, when given or recognised.
    pub code: Option<u32>,
    /// The root name, lower-case alphanumerics only.
    pub name: Option<String>,
    /// Whether it is a geographic (latitude-longitude) CRS.
    pub geographic: bool,
}

fn normalise_name(s: &str) -> String {
    s.chars()
        .filter(|c| c.is_ascii_alphanumeric())
        .map(|c| c.to_ascii_lowercase())
        .collect()
}

/// EPSG codes of a few CRS names as EPSG and ESRI spell them (normalised: lower-case
/// alphanumerics), for the grids avalanche practitioners use.
fn code_of_name(n: &str) -> Option<u32> {
    let fixed: &[(&str, u32)] = &[
        ("mgiaustrialambert", 31287),
        ("mgiaustriagkwest", 31254),
        ("mgiaustriagkcentral", 31255),
        ("mgiaustriagkeast", 31256),
        ("mgiaustriagkm28", 31257),
        ("mgiaustriagkm31", 31258),
        ("mgiaustriagkm34", 31259),
        ("wgs84", 4326),
        ("gcswgs1984", 4326),
        ("etrs89", 4258),
        ("gcsetrs1989", 4258),
        ("ch1903lv03", 21781),
        ("ch1903lv95", 2056),
        ("etrs89laea", 3035),
        ("etrs89extendedlaeaeurope", 3035),
        ("etrs1989laea", 3035),
    ];
    if let Some(&(_, c)) = fixed.iter().find(|(k, _)| *k == n) {
        return Some(c);
    }
    // UTM: "wgs84utmzone32n", "wgs1984utmzone32n", "etrs89utmzone32n", "etrs1989utmzone32n".
    for (prefix, north, south) in [
        ("wgs84utmzone", 32600, Some(32700)),
        ("wgs1984utmzone", 32600, Some(32700)),
        ("etrs89utmzone", 25800, None),
        ("etrs1989utmzone", 25800, None),
    ] {
        if let Some(rest) = n.strip_prefix(prefix) {
            let (zone, hemi) = rest.split_at(rest.len().saturating_sub(1));
            let zone: u32 = zone.parse().ok()?;
            if !(1..=60).contains(&zone) {
                return None;
            }
            return match hemi {
                "n" => Some(north + zone),
                "s" => south.map(|s| s + zone),
                _ => None,
            };
        }
    }
    None
}

/// The root keyword, root name and root EPSG authority of a WKT string (WKT1 `AUTHORITY`,
/// WKT2 `ID`, at bracket depth 1).
pub fn wkt_facts(wkt: &str) -> CrsFacts {
    let t = wkt.trim();
    let open = t.find(['[', '(']);
    let head = open.map_or(t, |o| &t[..o]).trim().to_ascii_uppercase();
    let geographic = matches!(head.as_str(), "GEOGCS" | "GEOGCRS" | "GEODCRS");
    let name = open.and_then(|o| {
        let rest = &t[o + 1..];
        let q0 = rest.find('"')?;
        let q1 = rest[q0 + 1..].find('"')?;
        Some(normalise_name(&rest[q0 + 1..q0 + 1 + q1]))
    });
    // Root-level authority: scan keywords at depth 1.
    let mut code = None;
    let bytes = t.as_bytes();
    let mut depth = 0i32;
    let mut i = 0;
    while i < bytes.len() {
        match bytes[i] {
            b'[' | b'(' => depth += 1,
            b']' | b')' => depth -= 1,
            b'"' => {
                // Skip quoted text.
                i += 1;
                while i < bytes.len() && bytes[i] != b'"' {
                    i += 1;
                }
            }
            _ if depth == 1 => {
                let rest = t[i..].to_ascii_uppercase();
                for kw in ["AUTHORITY[", "ID["] {
                    if rest.starts_with(kw) && (i == 0 || !bytes[i - 1].is_ascii_alphabetic()) {
                        let inner = &rest[kw.len()..];
                        let end = inner.find(']').unwrap_or(inner.len());
                        let parts: Vec<&str> = inner[..end]
                            .split(',')
                            .map(|p| p.trim().trim_matches('"').trim())
                            .collect();
                        if parts.len() >= 2 && parts[0] == "EPSG" {
                            code = parts[1].parse().ok();
                        }
                    }
                }
            }
            _ => {}
        }
        i += 1;
    }
    let code = code.or_else(|| name.as_deref().and_then(code_of_name));
    CrsFacts {
        code,
        name,
        geographic,
    }
}

/// What `crs` says about itself.
pub fn crs_facts(crs: &Crs) -> CrsFacts {
    match crs {
        Crs::Epsg(c) => CrsFacts {
            code: Some(*c),
            name: None,
            geographic: crs.is_geographic(),
        },
        Crs::Wkt(w) => wkt_facts(w),
    }
}

/// `Some(true)`: the same CRS; `Some(false)`: clearly different; `None`: cannot tell.
pub fn same_crs(a: &Crs, b: &Crs) -> Option<bool> {
    let (fa, fb) = (crs_facts(a), crs_facts(b));
    if let (Some(ca), Some(cb)) = (fa.code, fb.code) {
        return Some(ca == cb);
    }
    if fa.geographic != fb.geographic {
        return Some(false);
    }
    match (fa.name, fb.name) {
        (Some(na), Some(nb)) if na == nb => Some(true),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wkt_root_authority_and_names() {
        let wkt = r#"PROJCS["MGI / Austria Lambert",GEOGCS["MGI",AUTHORITY["EPSG","4312"]],UNIT["metre",1],AUTHORITY["EPSG","31287"]]"#;
        assert_eq!(wkt_facts(wkt).code, Some(31287));
        let esri =
            r#"PROJCS["MGI_Austria_Lambert",GEOGCS["GCS_MGI",DATUM["D_MGI"]],UNIT["Meter",1.0]]"#;
        let f = wkt_facts(esri);
        assert_eq!(f.code, Some(31287));
        assert!(!f.geographic);
        assert_eq!(
            same_crs(&Crs::Wkt(esri.into()), &Crs::Epsg(31287)),
            Some(true)
        );
        assert_eq!(
            same_crs(&Crs::Wkt(esri.into()), &Crs::Epsg(32632)),
            Some(false)
        );
        let utm = r#"PROJCS["WGS_1984_UTM_Zone_32N",GEOGCS["GCS_WGS_1984"]]"#;
        assert_eq!(wkt_facts(utm).code, Some(32632));
        let unknown = r#"PROJCS["My_Local_Grid",GEOGCS["GCS_WGS_1984"]]"#;
        assert_eq!(same_crs(&Crs::Wkt(unknown.into()), &Crs::Epsg(31287)), None);
        let geo = r#"GEOGCS["Some datum",DATUM["x"]]"#;
        assert_eq!(
            same_crs(&Crs::Wkt(geo.into()), &Crs::Wkt(unknown.into())),
            Some(false)
        );
    }
}
