//! Terrain input options shared by every command that reads a DEM.

use anyhow::{Context, bail};
use clap::Args;
use snowscape_io::{RasterFormat, ReadOptions, read_dem, read_terrain};
use snowscape_terrain::{Crs, Grid};
use std::path::Path;

/// How to read a terrain raster.
#[derive(Debug, Args, Clone, Default)]
pub struct DemInputArgs {
    /// Input format when the extension does not say it (asc, tif, png, raw, npy, exr).
    #[arg(long)]
    pub format: Option<String>,
    /// Cell size in metres, for formats without georeferencing (PNG16, RAW16, NPY).
    #[arg(long)]
    pub cell_size: Option<f64>,
    /// Altitude of the lowest and highest 16-bit value, metres: MIN,MAX (PNG16, RAW16).
    #[arg(long, value_name = "MIN,MAX")]
    pub height_range: Option<String>,
    /// Columns and rows of a RAW16 file: WxH (default: a square from the file size).
    #[arg(long, value_name = "WxH")]
    pub raw_size: Option<String>,
    /// Override the CRS of the input (EPSG:31287, a bare code, or WKT).
    #[arg(long)]
    pub crs: Option<String>,
}

impl DemInputArgs {
    /// The reader options these arguments describe.
    pub fn read_options(&self) -> anyhow::Result<ReadOptions> {
        let mut o = ReadOptions::default();
        if let Some(f) = &self.format {
            o.format = Some(
                f.parse::<RasterFormat>()
                    .map_err(|e| anyhow::anyhow!("--format {f:?}: {e}"))?,
            );
        }
        // The values' ranges are checked by the reader (`ReadOptions::validate`), the same
        // check as for the Python package and the editor.
        o.cell_size = self.cell_size;
        if let Some(r) = &self.height_range {
            o.height_range =
                Some(parse_pair(r, ',').with_context(|| format!("--height-range {r:?}"))?);
        }
        if let Some(s) = &self.raw_size {
            let (w, h) = parse_pair(s, 'x').with_context(|| format!("--raw-size {s:?}"))?;
            if w < 0.0 || w.fract() != 0.0 || h < 0.0 || h.fract() != 0.0 {
                bail!("--raw-size {s:?}: width and height must be whole numbers");
            }
            o.raw_size = Some((w as usize, h as usize));
        }
        if let Some(c) = &self.crs {
            o.crs = Some(Crs::parse(c).ok_or_else(|| anyhow::anyhow!("--crs: empty CRS"))?);
        }
        Ok(o)
    }

    /// Reads a terrain raster and checks it is one ([`read_terrain`]: at least 2x2 cells, a
    /// surface of valid cells, altitudes within +-1e5 m), before any work or output.
    pub fn read(&self, path: &Path) -> anyhow::Result<Grid> {
        let opts = self.read_options()?;
        Ok(read_terrain(path, &opts)?)
    }

    /// Reads any raster (`info`, `convert`): checked as a file, not as a terrain.
    pub fn read_raster(&self, path: &Path) -> anyhow::Result<Grid> {
        let opts = self.read_options()?;
        let grid = read_dem(path, &opts)?;
        grid.check_finite(&path.display().to_string())?;
        Ok(grid)
    }
}

fn parse_pair(text: &str, sep: char) -> anyhow::Result<(f64, f64)> {
    let mut parts = text.split(sep);
    let (Some(a), Some(b), None) = (parts.next(), parts.next(), parts.next()) else {
        bail!("expected two numbers separated by '{sep}'");
    };
    let parse = |s: &str| -> anyhow::Result<f64> {
        let v: f64 = s
            .trim()
            .parse()
            .with_context(|| format!("{s:?} is not a number"))?;
        if !v.is_finite() {
            bail!("{s:?} is not finite");
        }
        Ok(v)
    };
    Ok((parse(a)?, parse(b)?))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pairs_parse_and_reject() {
        assert_eq!(parse_pair("1000,2500", ',').unwrap(), (1000.0, 2500.0));
        assert_eq!(parse_pair("512x256", 'x').unwrap(), (512.0, 256.0));
        assert!(parse_pair("1,2,3", ',').is_err());
        assert!(parse_pair("a,2", ',').is_err());
        assert!(parse_pair("inf,2", ',').is_err());
    }

    /// The reader refuses the value before opening the file (the one check of every front
    /// end, `ReadOptions::validate`), naming it and the flag.
    #[test]
    fn negative_cell_size_is_rejected() {
        let a = DemInputArgs {
            cell_size: Some(-2.0),
            ..Default::default()
        };
        let e = a
            .read(Path::new("no/such/file.asc"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("-2") && e.contains("--cell-size"), "{e}");
    }
}
