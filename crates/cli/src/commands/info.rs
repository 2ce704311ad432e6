//! `snowscape info FILE`: what a terrain file holds.

use crate::cli::InfoArgs;
use crate::failure::{ExitCodeExt, Failure};
use crate::report::InputSummary;
use crate::stdout::outln;

pub fn run(args: &InfoArgs) -> Result<(), Failure> {
    let grid = args.dem.read_raster(&args.file).bad_input()?;
    let s = InputSummary::of(&args.file.display().to_string(), &grid);
    if args.json {
        let text = serde_json::to_string_pretty(&s).job_failed()?;
        outln!("{text}");
        return Ok(());
    }
    let g = grid.geometry();
    let (ex, ey) = g.extent_m();
    outln!("file        {}", s.source);
    outln!(
        "grid        {} x {} cells ({} cells)",
        s.width,
        s.height,
        g.len()
    );
    outln!(
        "cell size   {:.4} m x {:.4} m",
        s.cell_size_x,
        s.cell_size_y
    );
    if g.is_geographic() {
        let t = g.transform();
        outln!(
            "            ({:.3e} x {:.3e} degrees; metric size from latitude {:.4}°)",
            t.pixel_width,
            t.pixel_height,
            g.centre_latitude_deg().unwrap_or(0.0)
        );
    }
    outln!("extent      {:.1} m x {:.1} m", ex, ey);
    outln!(
        "origin      x {:.4}, y {:.4} (north-west corner)",
        s.origin[0],
        s.origin[1]
    );
    outln!("crs         {}", s.crs.as_deref().unwrap_or("unknown"));
    match s.latitude_deg {
        Some(lat) => outln!("latitude    {lat:.4}° (grid centre)"),
        None => outln!(
            "latitude    unknown (no CRS the sun model can invert; scenarios default to 45°)"
        ),
    }
    match s.altitude_range {
        Some([lo, hi]) => outln!(
            "values      {lo:.2} .. {hi:.2} m (mean {:.2} m)",
            grid.mean().unwrap_or(f64::NAN)
        ),
        None => outln!("values      none (every cell is nodata)"),
    }
    outln!(
        "nodata      {:.2} % ({} cells)",
        100.0 * s.nodata_fraction,
        grid.mask().count_nodata()
    );
    Ok(())
}
