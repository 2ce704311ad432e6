//! The GeoKey directory of GeoTIFF (OGC GeoTIFF 1.1, Section 7; tags 34735, 34736, 34737).
//!
//! Tag 34735 (`GeoKeyDirectoryTag`) holds u16 values: a header `[version=1, revision=1,
//! minor=0|1, key count]`, then one `[key id, location, count, value]` quadruple per key.
//! `location` 0 means the value is the u16 itself; 34736 points `count` doubles into
//! `GeoDoubleParamsTag` at offset `value`; 34737 points `count` characters into the
//! `GeoAsciiParamsTag` string at offset `value`, each string ending with `|`.
//! The keys used here:
//!
//! | key  | name                  | meaning                                          |
//! |------|-----------------------|--------------------------------------------------|
//! | 1024 | GTModelTypeGeoKey     | 1 projected, 2 geographic, 32767 user-defined    |
//! | 1025 | GTRasterTypeGeoKey    | 1 PixelIsArea, 2 PixelIsPoint                    |
//! | 1026 | GTCitationGeoKey      | free text (`EPSG:n` for codes above 65535)       |
//! | 3073 | PCSCitationGeoKey     | with model type 32767: `ESRI PE String = <WKT>`, |
//! |      |                       | GDAL's way to carry a WKT-only CRS               |
//! | 2048 | GeographicTypeGeoKey  | EPSG code of a geographic CRS                    |
//! | 3072 | ProjectedCSTypeGeoKey | EPSG code of a projected CRS                     |

use crate::crs_sidecar::{looks_like_wkt, parse_crs_text};
use snowscape_terrain::Crs;

pub(crate) const TAG_GEO_ASCII_PARAMS: u16 = 34737;
const KEY_MODEL_TYPE: u16 = 1024;
const KEY_RASTER_TYPE: u16 = 1025;
const KEY_CITATION: u16 = 1026;
const KEY_GEOGRAPHIC_TYPE: u16 = 2048;
const KEY_GEOG_CITATION: u16 = 2049;
const KEY_PROJECTED_TYPE: u16 = 3072;
const KEY_PCS_CITATION: u16 = 3073;
/// GeoTIFF's "user-defined" code; 0 is "undefined".
const USER_DEFINED: u16 = 32767;

/// The citation prefix GDAL writes and reads for a CRS given only as WKT.
const ESRI_PE: &str = "ESRI PE String = ";

/// GTRasterTypeGeoKey value for PixelIsPoint.
pub(crate) const RASTER_PIXEL_IS_POINT: u16 = 2;

/// The GeoKeys this crate understands.
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct GeoKeys {
    pub model_type: Option<u16>,
    pub raster_type: Option<u16>,
    pub geographic_type: Option<u16>,
    pub projected_type: Option<u16>,
    /// GTCitation, PCSCitation or GeogCitation, first found.
    pub citation: Option<String>,
}

fn usable_code(code: Option<u16>) -> Option<u32> {
    code.filter(|&c| c != 0 && c != USER_DEFINED).map(u32::from)
}

impl GeoKeys {
    /// The CRS the keys declare: a projected EPSG code, else a geographic one, else a citation
    /// that is WKT or names `EPSG:n`.
    pub fn crs(&self) -> Option<Crs> {
        if let Some(c) = usable_code(self.projected_type) {
            return Some(Crs::Epsg(c));
        }
        if let Some(c) = usable_code(self.geographic_type) {
            return Some(Crs::Epsg(c));
        }
        let cit = self.citation.as_deref()?.trim();
        let cit = cit.strip_prefix(ESRI_PE).unwrap_or(cit).trim();
        let is_code = cit.to_ascii_uppercase().starts_with("EPSG:");
        (looks_like_wkt(cit) || is_code)
            .then(|| parse_crs_text(cit))
            .flatten()
    }
}

/// The ASCII parameter `[offset, offset + count)`, without its `|` terminator.
fn ascii_param(ascii: &str, offset: u16, count: u16) -> Result<String, String> {
    let (start, end) = (
        usize::from(offset),
        usize::from(offset) + usize::from(count),
    );
    let s = ascii.get(start..end).ok_or_else(|| {
        format!(
            "ASCII parameter [{start}, {end}) lies outside the {} characters of tag 34737",
            ascii.len()
        )
    })?;
    Ok(s.trim_end_matches(['|', '\0']).to_string())
}

/// Decodes the key directory. `ascii` is the GeoAsciiParams string ("" when absent).
/// Double-valued keys are not needed here and are skipped.
pub(crate) fn decode(dir: &[u16], ascii: &str) -> Result<GeoKeys, String> {
    let [version, _, _, count] = dir
        .get(..4)
        .and_then(|h| <[u16; 4]>::try_from(h).ok())
        .ok_or_else(|| format!("{} values, fewer than the 4 of a header", dir.len()))?;
    if version != 1 {
        return Err(format!("key directory version {version}, expected 1"));
    }
    let entries = dir.get(4..4 + 4 * usize::from(count)).ok_or_else(|| {
        format!(
            "header announces {count} keys but the tag holds only {} values",
            dir.len()
        )
    })?;
    let mut keys = GeoKeys::default();
    for e in entries.chunks_exact(4) {
        let (id, location, n, value) = (e[0], e[1], e[2], e[3]);
        let short = (location == 0).then_some(value);
        match id {
            KEY_MODEL_TYPE => keys.model_type = short,
            KEY_RASTER_TYPE => keys.raster_type = short,
            KEY_GEOGRAPHIC_TYPE => keys.geographic_type = short,
            KEY_PROJECTED_TYPE => keys.projected_type = short,
            KEY_CITATION | KEY_GEOG_CITATION | KEY_PCS_CITATION
                if location == TAG_GEO_ASCII_PARAMS && keys.citation.is_none() =>
            {
                keys.citation = Some(ascii_param(ascii, value, n)?);
            }
            _ => {}
        }
    }
    Ok(keys)
}

/// The key directory and GeoAsciiParams string that describe `crs` with PixelIsArea.
pub(crate) fn encode(crs: Option<&Crs>) -> (Vec<u16>, Option<String>) {
    let mut keys: Vec<[u16; 4]> = Vec::new();
    let mut ascii = None;
    match crs {
        Some(Crs::Wkt(wkt)) => {
            // GDAL's convention: a user-defined model type and the WKT as an "ESRI PE String"
            // in PCSCitationGeoKey.
            keys.push([KEY_MODEL_TYPE, 0, 1, USER_DEFINED]);
            keys.push([KEY_RASTER_TYPE, 0, 1, 1]);
            ascii = Some((
                KEY_PCS_CITATION,
                format!("{ESRI_PE}{}", wkt.replace(['|', '\0'], "/")),
            ));
        }
        Some(crs @ Crs::Epsg(code)) => {
            let geographic = crs.is_geographic();
            keys.push([KEY_MODEL_TYPE, 0, 1, if geographic { 2 } else { 1 }]);
            keys.push([KEY_RASTER_TYPE, 0, 1, 1]);
            match u16::try_from(*code) {
                Ok(c) if geographic => keys.push([KEY_GEOGRAPHIC_TYPE, 0, 1, c]),
                Ok(c) => keys.push([KEY_PROJECTED_TYPE, 0, 1, c]),
                Err(_) => ascii = Some((KEY_CITATION, format!("EPSG:{code}"))),
            }
        }
        None => keys.push([KEY_RASTER_TYPE, 0, 1, 1]),
    }
    let ascii = ascii.map(|(key, text)| {
        let text: String = text.chars().filter(char::is_ascii).take(65_000).collect();
        let count = u16::try_from(text.len() + 1).unwrap_or(u16::MAX);
        keys.push([key, TAG_GEO_ASCII_PARAMS, count, 0]);
        format!("{text}|")
    });
    keys.sort_by_key(|k| k[0]);
    let n = u16::try_from(keys.len()).unwrap_or(u16::MAX);
    let mut dir = vec![1, 1, 0, n];
    dir.extend(keys.iter().flatten());
    (dir, ascii)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_projected_geographic_and_wkt() {
        for crs in [
            Crs::Epsg(31287),
            Crs::Epsg(4326),
            Crs::Wkt("LOCAL_CS[\"x\"]".into()),
            Crs::Wkt("PROJCS[\"custom\",UNIT[\"metre\",1]]".into()),
            Crs::Epsg(100_000),
        ] {
            let (dir, ascii) = encode(Some(&crs));
            let keys = decode(&dir, ascii.as_deref().unwrap_or("")).unwrap();
            assert_eq!(keys.raster_type, Some(1));
            assert_eq!(keys.crs(), Some(crs.clone()), "{dir:?}");
        }
        let (dir, _) = encode(None);
        assert_eq!(decode(&dir, "").unwrap().crs(), None);
    }

    #[test]
    fn keys_are_sorted_and_typed() {
        let (dir, _) = encode(Some(&Crs::Epsg(4326)));
        assert_eq!(
            dir,
            vec![1, 1, 0, 3, 1024, 0, 1, 2, 1025, 0, 1, 1, 2048, 0, 1, 4326]
        );
    }

    #[test]
    fn wkt_uses_gdal_esri_pe_convention() {
        let (dir, ascii) = encode(Some(&Crs::Wkt("PROJCS[\"a|b\"]".into())));
        assert_eq!(
            dir,
            vec![
                1, 1, 0, 3, 1024, 0, 1, 32767, 1025, 0, 1, 1, 3073, 34737, 31, 0
            ]
        );
        assert_eq!(ascii.as_deref(), Some("ESRI PE String = PROJCS[\"a/b\"]|"));
    }

    #[test]
    fn malformed_directories_are_errors() {
        assert!(decode(&[1, 1], "").is_err());
        assert!(decode(&[2, 1, 0, 0], "").is_err());
        assert!(decode(&[1, 1, 0, 5, 1024, 0, 1, 1], "").is_err());
        let e = decode(&[1, 1, 0, 1, 1026, 34737, 50, 10], "abc|").unwrap_err();
        assert!(e.contains("outside"), "{e}");
        let k = decode(&[1, 1, 0, 1, 3072, 0, 1, 32767], "").unwrap();
        assert_eq!(k.crs(), None);
    }
}
