//! 16-bit heightmap scaling and the JSON sidecar shared by PNG16 and RAW16.
//!
//! A 16-bit heightmap stores codes, not metres. The mapping is linear:
//! `height = min + (code - code_min) / (65535 - code_min) * (max - min)`.
//! When the written grid has nodata cells, code 0 is reserved for them (`nodata: 0`,
//! `code_min: 1`); otherwise `code_min` is 0 and every code is a height. A file read without a
//! sidecar uses `--height-range MIN,MAX` with `code_min` 0 and no nodata (8-bit PNGs map
//! 0..255 onto the range instead).
//!
//! The sidecar `<file>.json` (e.g. `depth.png.json`), written atomically beside every PNG16 /
//! RAW16 output, records the scale, the grid size, its georeferencing and CRS:
//! `{"format":"snowscape-heightmap16","unit":"m","min":..,"max":..,"nodata":0|null,
//! "code_min":..,"code_max":65535,"formula":"...","width":..,"height":..,"transform":{..},
//! "crs":..}`. Readers use it for whatever `--height-range`, `--cell-size` and `--raw-size` do
//! not give, so a file snowscape wrote reads back without options.

use crate::ReadOptions;
use crate::cells::check_cell_size;
use crate::error::{RasterError, Result, geometry_err};
use crate::write_bytes_atomic;
use serde::{Deserialize, Serialize};
use snowscape_terrain::{Crs, GeoTransform, Grid, GridGeometry};
use std::path::{Path, PathBuf};

/// The highest 16-bit code.
const CODE_MAX: u16 = u16::MAX;

/// How the codes of a 16-bit heightmap map to heights in metres.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Png16Scale {
    /// Height of the lowest data code (`code_min`), metres.
    pub min: f64,
    /// Height of code 65535, metres.
    pub max: f64,
    /// The code nodata cells were written as (0), if the grid had nodata.
    pub nodata: Option<u16>,
}

impl Png16Scale {
    /// The lowest code that is a height: 1 when 0 means nodata, else 0.
    pub fn code_min(&self) -> u16 {
        u16::from(self.nodata == Some(0))
    }

    /// The height of `code` on a scale whose top code is `code_max` (65535, or 255 for 8-bit).
    pub fn height(&self, code: u16, code_max: u16) -> f64 {
        let lo = self.code_min();
        let span = f64::from(code_max.saturating_sub(lo).max(1));
        self.min + f64::from(code.saturating_sub(lo)) / span * (self.max - self.min)
    }

    /// The nearest code of height `h` (clamped into the code range).
    pub fn code(&self, h: f32) -> u16 {
        let lo = self.code_min();
        let range = self.max - self.min;
        if range <= 0.0 {
            return lo;
        }
        let t = ((f64::from(h) - self.min) / range).clamp(0.0, 1.0);
        lo + (t * f64::from(CODE_MAX - lo)).round() as u16
    }

    /// The scale spanning the valid values of `grid` (0..0 for an all-nodata grid).
    pub fn for_grid(grid: &Grid) -> Self {
        let (min, max) = grid.value_range().unwrap_or((0.0, 0.0));
        Self {
            min: f64::from(min),
            max: f64::from(max),
            nodata: grid.mask().has_nodata().then_some(0),
        }
    }

    /// The codes of `grid`, row-major, nodata cells as the nodata code.
    pub fn encode(&self, grid: &Grid) -> Vec<u16> {
        let nodata = self.nodata.unwrap_or(0);
        grid.data()
            .iter()
            .enumerate()
            .map(|(i, &v)| {
                if grid.mask().is_valid(i) {
                    self.code(v)
                } else {
                    nodata
                }
            })
            .collect()
    }
}

/// The JSON sidecar.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub(crate) struct Sidecar {
    pub format: String,
    pub unit: String,
    pub min: f64,
    pub max: f64,
    pub nodata: Option<u16>,
    pub code_min: u16,
    pub code_max: u16,
    pub formula: String,
    pub width: usize,
    pub height: usize,
    pub transform: GeoTransform,
    pub cell_size_x: f64,
    pub cell_size_y: f64,
    pub crs: Option<Crs>,
}

const SIDECAR_FORMAT: &str = "snowscape-heightmap16";

impl Sidecar {
    fn new(scale: &Png16Scale, g: &GridGeometry) -> Self {
        Self {
            format: SIDECAR_FORMAT.into(),
            unit: "m".into(),
            min: scale.min,
            max: scale.max,
            nodata: scale.nodata,
            code_min: scale.code_min(),
            code_max: CODE_MAX,
            formula: "height = min + (code - code_min) / (code_max - code_min) * (max - min)"
                .into(),
            width: g.width(),
            height: g.height(),
            transform: *g.transform(),
            cell_size_x: g.cell_size_x(),
            cell_size_y: g.cell_size_y(),
            crs: g.crs().cloned(),
        }
    }

    fn scale(&self) -> Png16Scale {
        Png16Scale {
            min: self.min,
            max: self.max,
            nodata: self.nodata,
        }
    }
}

/// The sidecar path of `path`: the same name with `.json` appended.
pub(crate) fn sidecar_path(path: &Path) -> PathBuf {
    let mut name = path.file_name().unwrap_or_default().to_os_string();
    name.push(".json");
    path.with_file_name(name)
}

/// Writes the sidecar of a heightmap written at `path`, atomically.
pub(crate) fn write_sidecar(path: &Path, scale: &Png16Scale, g: &GridGeometry) -> Result<()> {
    let sc = sidecar_path(path);
    let json =
        serde_json::to_vec_pretty(&Sidecar::new(scale, g)).map_err(|e| RasterError::Sidecar {
            path: sc.clone(),
            reason: e.to_string(),
        })?;
    write_bytes_atomic(&sc, &json)?;
    Ok(())
}

/// The sidecar of `path`, if there is one.
pub(crate) fn read_sidecar(path: &Path) -> Result<Option<Sidecar>> {
    let sc = sidecar_path(path);
    if !sc.is_file() {
        return Ok(None);
    }
    let err = |reason: String| RasterError::Sidecar {
        path: sc.clone(),
        reason,
    };
    let text = crate::input::read_regular_text(&sc).map_err(|e| err(e.to_string()))?;
    let s: Sidecar = serde_json::from_str(&text).map_err(|e| err(e.to_string()))?;
    if s.format != SIDECAR_FORMAT {
        return Err(err(format!(
            "format {:?} is not {SIDECAR_FORMAT:?}",
            s.format
        )));
    }
    Ok(Some(s))
}

/// The scale to read with: `--height-range`, else the sidecar's, else an error.
pub(crate) fn resolve_scale(
    path: &Path,
    format: &'static str,
    opts: &ReadOptions,
    sidecar: Option<&Sidecar>,
) -> Result<Png16Scale> {
    let scale = match (opts.height_range, sidecar) {
        (Some((min, max)), _) => Png16Scale {
            min,
            max,
            nodata: None,
        },
        (None, Some(s)) => s.scale(),
        (None, None) => {
            return Err(RasterError::MissingOption {
                path: path.to_path_buf(),
                format,
                option: "--height-range MIN,MAX",
                why: "16-bit codes carry no altitude; give the heights of the lowest and \
                      highest code in metres",
            });
        }
    };
    if !(scale.min.is_finite() && scale.max.is_finite() && scale.min <= scale.max) {
        return Err(RasterError::InvalidHeightRange {
            path: path.to_path_buf(),
            min: scale.min,
            max: scale.max,
        });
    }
    Ok(scale)
}

/// The geometry of a `w x h` heightmap: `--cell-size` (local metric grid), else the sidecar's
/// georeferencing when its size matches, else an error.
pub(crate) fn resolve_geometry(
    path: &Path,
    format: &'static str,
    (w, h): (usize, usize),
    opts: &ReadOptions,
    sidecar: Option<&Sidecar>,
) -> Result<GridGeometry> {
    if let Some(c) = opts.cell_size {
        let c = check_cell_size(path, c, "--cell-size")?;
        return GridGeometry::square(w, h, c)
            .map(|g| g.with_crs(opts.crs.clone()))
            .map_err(geometry_err(path));
    }
    match sidecar {
        Some(s) if (s.width, s.height) == (w, h) => {
            let crs = opts.crs.clone().or_else(|| s.crs.clone());
            GridGeometry::from_transform(w, h, s.transform, crs).map_err(geometry_err(path))
        }
        _ => Err(RasterError::MissingOption {
            path: path.to_path_buf(),
            format,
            option: "--cell-size",
            why: "it has no georeferencing",
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_round_trip_within_half_a_step() {
        let s = Png16Scale {
            min: 1000.0,
            max: 3000.0,
            nodata: Some(0),
        };
        assert_eq!(s.code_min(), 1);
        assert_eq!(s.code(1000.0), 1);
        assert_eq!(s.code(3000.0), 65535);
        assert_eq!(s.code(5000.0), 65535);
        let step = 2000.0 / 65534.0;
        for h in [1000.0f32, 1234.5, 2999.9] {
            assert!((s.height(s.code(h), 65535) - f64::from(h)).abs() <= step / 2.0 + 1e-6);
        }
        let flat = Png16Scale {
            min: 5.0,
            max: 5.0,
            nodata: None,
        };
        assert_eq!(flat.code(5.0), 0);
        assert_eq!(flat.height(0, 65535), 5.0);
        let eight = Png16Scale {
            min: 0.0,
            max: 510.0,
            nodata: None,
        };
        assert_eq!(eight.height(255, 255), 510.0);
    }

    #[test]
    fn sidecar_path_appends_json() {
        assert_eq!(
            sidecar_path(Path::new("out/depth.png")),
            PathBuf::from("out/depth.png.json")
        );
    }

    #[test]
    fn missing_range_and_bad_range_are_errors() {
        let p = Path::new("h.png");
        let e = resolve_scale(p, "PNG16", &ReadOptions::default(), None).unwrap_err();
        assert!(e.to_string().contains("--height-range"), "{e}");
        let o = ReadOptions {
            height_range: Some((10.0, 1.0)),
            ..Default::default()
        };
        assert!(matches!(
            resolve_scale(p, "PNG16", &o, None),
            Err(RasterError::InvalidHeightRange { .. })
        ));
        let e = resolve_geometry(p, "PNG16", (2, 2), &ReadOptions::default(), None).unwrap_err();
        assert!(e.to_string().contains("--cell-size"), "{e}");
    }
}
