//! `snowscape info FILE`: what a terrain file holds.

use crate::cli::InfoArgs;
use crate::failure::{ExitCodeExt, Failure};
use crate::report::InputSummary;

pub fn run(args: &InfoArgs) -> Result<(), Failure> {
    let grid = args.dem.read_raster(&args.file).bad_input()?;
    let s = InputSummary::of(&args.file.display().to_string(), &grid);
    if args.json {
        let text = serde_json::to_string_pretty(&s).job_failed()?;
        println!("{text}");
        return Ok(());
    }
    let g = grid.geometry();
    let (ex, ey) = g.extent_m();
    println!("file        {}", s.source);
    println!(
        "grid        {} x {} cells ({} cells)",
        s.width,
        s.height,
        g.len()
    );
    println!(
        "cell size   {:.4} m x {:.4} m",
        s.cell_size_x, s.cell_size_y
    );
    if g.is_geographic() {
        let t = g.transform();
        println!(
            "            ({:.3e} x {:.3e} degrees; metric size from latitude {:.4}°)",
            t.pixel_width,
            t.pixel_height,
            g.centre_latitude_deg().unwrap_or(0.0)
        );
    }
    println!("extent      {:.1} m x {:.1} m", ex, ey);
    println!(
        "origin      x {:.4}, y {:.4} (north-west corner)",
        s.origin[0], s.origin[1]
    );
    println!("crs         {}", s.crs.as_deref().unwrap_or("unknown"));
    match s.latitude_deg {
        Some(lat) => println!("latitude    {lat:.4}° (grid centre)"),
        None => println!(
            "latitude    unknown (no CRS the sun model can invert; scenarios default to 45°)"
        ),
    }
    match s.altitude_range {
        Some([lo, hi]) => println!(
            "values      {lo:.2} .. {hi:.2} m (mean {:.2} m)",
            grid.mean().unwrap_or(f64::NAN)
        ),
        None => println!("values      none (every cell is nodata)"),
    }
    println!(
        "nodata      {:.2} % ({} cells)",
        100.0 * s.nodata_fraction,
        grid.mask().count_nodata()
    );
    Ok(())
}
