//! `snowscape convert IN OUT`: raster format conversion, georeferencing kept.

use crate::cli::ConvertArgs;
use crate::failure::{ExitCodeExt, Failure};
use anyhow::anyhow;
use snowscape_io::{RasterFormat, write_raster};

pub fn run(args: &ConvertArgs) -> Result<(), Failure> {
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
    Ok(())
}
