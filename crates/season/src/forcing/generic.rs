//! The generic forcing CSV (columns and ranges in the [parent module's docs](super)).

use super::table::{Stamp, Table};
use super::{
    AIR_TEMPERATURE_RANGE_C, ForcingError, ForcingRecord, LONGWAVE_RANGE_W_M2,
    MAX_PRECIPITATION_MM_PER_HOUR, MAX_PRECIPITATION_MM_PER_STEP, RELATIVE_HUMIDITY_RANGE,
    SHORTWAVE_RANGE_W_M2, WIND_SPEED_RANGE_M_S,
};

/// The format's name in errors.
const FORMAT: &str = "generic forcing";

/// The header of the generic format, required columns first.
pub(super) const HEADER: &str = "time,air_temperature_c,precipitation_mm,wind_speed_m_s,wind_from_deg,shortwave_in_w_m2,relative_humidity";

/// Hours between two times (the provisional step for the precipitation limit).
fn provisional_step_hours(times: &[Stamp]) -> f64 {
    match times {
        [a, b, ..] => {
            let m = b.time.minutes_since_epoch() - a.time.minutes_since_epoch();
            (m as f64 / 60.0).max(1.0 / 60.0)
        }
        [a] if a.date_only => 24.0,
        _ => 1.0,
    }
}

/// Reads every record and its time.
pub(super) fn read(
    table: &Table,
) -> Result<(Vec<ForcingRecord>, Option<Vec<Stamp>>), ForcingError> {
    let time = table.require("time", FORMAT)?;
    let temperature = table.require("air_temperature_c", FORMAT)?;
    let precipitation = table.require("precipitation_mm", FORMAT)?;
    let wind_speed = table.require("wind_speed_m_s", FORMAT)?;
    let wind_from = table.column("wind_from_deg");
    let shortwave = table.column("shortwave_in_w_m2");
    let net_shortwave = table.column("net_shortwave_w_m2");
    let longwave = table.column("longwave_in_w_m2");
    let humidity = table.column("relative_humidity");
    let snow_fraction = table.column("snow_fraction");

    let times = table
        .rows
        .iter()
        .map(|row| table.time(row, time))
        .collect::<Result<Vec<_>, _>>()?;
    // The per-step precipitation limit needs the step; the even-step check itself comes
    // after the values (it reports the first bad time, these the first bad value).
    let step_h = provisional_step_hours(&times);
    let max_precipitation =
        (MAX_PRECIPITATION_MM_PER_HOUR * step_h).min(MAX_PRECIPITATION_MM_PER_STEP);

    let mut records = Vec::with_capacity(table.rows.len());
    for row in &table.rows {
        let shortwave_in = table.optional(row, shortwave, SHORTWAVE_RANGE_W_M2, "W/m²")?;
        let net = table.optional(row, net_shortwave, SHORTWAVE_RANGE_W_M2, "W/m²")?;
        let rh = table.optional(
            row,
            humidity,
            RELATIVE_HUMIDITY_RANGE,
            "relative humidity as a fraction (not percent)",
        )?;
        records.push(ForcingRecord {
            air_temperature_c: table.required(row, temperature, AIR_TEMPERATURE_RANGE_C, "°C")?
                as f32,
            precipitation_mm: table.required(
                row,
                precipitation,
                (0.0, max_precipitation),
                "mm per step",
            )? as f32,
            wind_speed_m_s: table.required(row, wind_speed, WIND_SPEED_RANGE_M_S, "m/s")? as f32,
            wind_from_deg: table
                .optional(row, wind_from, (0.0, 360.0), "degrees")?
                .map(|v| v as f32),
            shortwave_in_w_m2: shortwave_in.map(|v| v.max(0.0) as f32),
            relative_humidity: rh.map(|v| v.min(1.0) as f32),
            net_shortwave_w_m2: net.map(|v| v.max(0.0) as f32),
            longwave_in_w_m2: table
                .optional(row, longwave, LONGWAVE_RANGE_W_M2, "W/m²")?
                .map(|v| v as f32),
            snow_fraction: table
                .optional(row, snow_fraction, (0.0, 1.0), "a fraction")?
                .map(|v| v as f32),
        });
    }
    Ok((records, Some(times)))
}

/// The series in the generic format: the station altitude as a comment, every column, an
/// empty cell for a value not measured. Reading it back gives the same series.
pub(super) fn write(forcing: &super::StationForcing) -> String {
    use std::fmt::Write;
    let mut out = String::new();
    if let Some(a) = forcing.station_altitude_m {
        let _ = writeln!(out, "# station_altitude_m = {a}");
    }
    out.push_str(HEADER);
    out.push_str(",net_shortwave_w_m2,longwave_in_w_m2,snow_fraction\n");
    let opt = |v: Option<f32>| v.map(|v| v.to_string()).unwrap_or_default();
    for (k, r) in forcing.records.iter().enumerate() {
        let _ = writeln!(
            out,
            "{},{},{},{},{},{},{},{},{},{}",
            forcing.time_of(k),
            r.air_temperature_c,
            r.precipitation_mm,
            r.wind_speed_m_s,
            opt(r.wind_from_deg),
            opt(r.shortwave_in_w_m2),
            opt(r.relative_humidity),
            opt(r.net_shortwave_w_m2),
            opt(r.longwave_in_w_m2),
            opt(r.snow_fraction),
        );
    }
    out
}
