//! Monthly summary of a station forcing file (generic or snobal CSV, see
//! `snowscape_season::forcing`): mean air temperature, precipitation, and snowfall weighted
//! by the records' snow fraction (snobal's `percent_snow`; no fraction counts as unknown).
//!
//! `cargo run -p snowscape-season --example forcing_monthly -- FILE`

use snowscape_season::forcing::from_path;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::process::ExitCode;

/// Sums over the records of one month.
#[derive(Default)]
struct Month {
    temperature_sum: f64,
    records: usize,
    precipitation: f64,
    snowfall: f64,
    /// Records that give a snow fraction.
    with_fraction: usize,
}

fn main() -> ExitCode {
    let Some(path) = std::env::args_os().nth(1).map(PathBuf::from) else {
        eprintln!("usage: forcing_monthly FILE");
        return ExitCode::from(2);
    };
    let forcing = match from_path(&path, None) {
        Ok(f) => f,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    let mut months: BTreeMap<(i32, u32), Month> = BTreeMap::new();
    for (k, r) in forcing.records.iter().enumerate() {
        let t = forcing.time_of(k);
        let m = months.entry((t.year, t.month)).or_default();
        m.temperature_sum += f64::from(r.air_temperature_c);
        m.records += 1;
        m.precipitation += f64::from(r.precipitation_mm);
        if let Some(f) = r.snow_fraction {
            m.snowfall += f64::from(r.precipitation_mm * f);
            m.with_fraction += 1;
        }
    }
    println!(
        "{}: {} records of {} h from {}",
        path.display(),
        forcing.records.len(),
        forcing.step_hours,
        forcing.start
    );
    println!("month     mean_T_C  precip_mm  snowfall_mm");
    let (mut p, mut s) = (0.0, 0.0);
    for ((y, mo), m) in &months {
        let snow = if m.with_fraction > 0 {
            format!("{:11.1}", m.snowfall)
        } else {
            format!("{:>11}", "-")
        };
        let mean_t = m.temperature_sum / m.records as f64;
        println!(
            "{y:04}-{mo:02}  {mean_t:8.2}  {:9.1}  {snow}",
            m.precipitation
        );
        p += m.precipitation;
        s += m.snowfall;
    }
    println!("total               {p:9.1}  {s:11.1}");
    ExitCode::SUCCESS
}
