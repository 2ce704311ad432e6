//! `snowscape convert IN OUT`: raster format conversion, georeferencing kept.

use crate::cli::{ConvertArgs, GlobalArgs};
use crate::failure::{ExitCodeExt, Failure};
use crate::stdout::outln;
use anyhow::anyhow;
use snowscape_io::{RasterFormat, write_raster};
use std::path::Path;

/// A file size for people: bytes, KiB, MiB or GiB with 3 significant digits.
pub fn size_text(bytes: u64) -> String {
    const UNITS: [&str; 3] = ["KiB", "MiB", "GiB"];
    if bytes < 1024 {
        return format!("{bytes} B");
    }
    let mut v = bytes as f64 / 1024.0;
    let mut unit = 0;
    while v >= 1024.0 && unit + 1 < UNITS.len() {
        v /= 1024.0;
        unit += 1;
    }
    let decimals = if v < 10.0 {
        2
    } else if v < 100.0 {
        1
    } else {
        0
    };
    format!("{v:.decimals$} {}", UNITS[unit])
}

/// The line a command prints for a file it wrote: `wrote PATH (SIZE, FORMAT, DETAIL)`.
pub fn wrote_line(path: &Path, format: &str, detail: &str) -> String {
    let size =
        std::fs::metadata(path).map_or_else(|_| "size unknown".to_string(), |m| size_text(m.len()));
    format!("wrote {} ({size}, {format}, {detail})", path.display())
}

pub fn run(args: &ConvertArgs, global: &GlobalArgs) -> Result<(), Failure> {
    let format = match &args.to {
        Some(f) => f
            .parse::<RasterFormat>()
            .map_err(|e| anyhow!("--to {f:?}: {e}"))
            .bad_input()?,
        None => RasterFormat::from_path(&args.output)
            .ok_or_else(|| {
                anyhow!(
                    "cannot tell the output format from {:?}: use a .tif, .exr, .png, .asc or .npy extension, or --to",
                    args.output
                )
            })
            .bad_input()?,
    };
    if args.cog && format != RasterFormat::GeoTiff {
        return Err(anyhow!(
            "--cog writes a Cloud-Optimized GeoTIFF: the output {:?} is not .tif",
            args.output
        ))
        .bad_input();
    }
    let grid = args.dem.read_raster(&args.input).bad_input()?;
    if args.cog {
        snowscape_io::write_cog(&args.output, &grid).job_failed()?;
    } else {
        write_raster(&args.output, &grid, format).job_failed()?;
    }
    if !global.quiet {
        let g = grid.geometry();
        let format = if args.cog {
            "Cloud-Optimized GeoTIFF".to_string()
        } else if format == RasterFormat::Png16 {
            format!("{} + JSON sidecar", format.name())
        } else {
            format.name().to_string()
        };
        let detail = format!("{} x {} cells", g.width(), g.height());
        outln!("{}", wrote_line(&args.output, &format, &detail));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_read_as_people_write_them() {
        assert_eq!(size_text(0), "0 B");
        assert_eq!(size_text(1023), "1023 B");
        assert_eq!(size_text(1536), "1.50 KiB");
        assert_eq!(size_text(200 * 1024), "200 KiB");
        assert_eq!(size_text(3 * 1024 * 1024 + 1), "3.00 MiB");
    }
}
