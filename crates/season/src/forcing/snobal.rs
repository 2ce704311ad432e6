//! The snobal / pysnobal input CSV (the mapping is in the [parent module's docs](super)).

use super::table::{Stamp, Table};
use super::{
    AIR_TEMPERATURE_RANGE_C, ForcingError, ForcingRecord, LONGWAVE_RANGE_W_M2,
    MAX_PRECIPITATION_MM_PER_HOUR, MAX_PRECIPITATION_MM_PER_STEP, RELATIVE_HUMIDITY_RANGE,
    SHORTWAVE_RANGE_W_M2, WIND_SPEED_RANGE_M_S,
};

/// The format's name in errors.
const FORMAT: &str = "snobal input";

/// Vapour pressures accepted, Pa (saturation at 45 °C is 9.6 kPa).
const VAPOUR_PRESSURE_RANGE_PA: (f64, f64) = (0.0, 10_000.0);

/// Saturation vapour pressure over water, Pa, at `t_c` °C: the Magnus formula with the
/// Sonntag 1990 coefficients of the WMO Guide (WMO-No. 8, 2008, Annex 4.B),
/// e_s = 611.2 · exp(17.62 t / (243.12 + t)).
pub fn saturation_vapour_pressure_pa(t_c: f64) -> f64 {
    611.2 * (17.62 * t_c / (243.12 + t_c)).exp()
}

/// Reads every record, and its time when the file has a time column.
pub(super) fn read(
    table: &Table,
) -> Result<(Vec<ForcingRecord>, Option<Vec<Stamp>>), ForcingError> {
    let time = table.column("date_time").or_else(|| table.column("time"));
    let net_solar = table.require("net_solar", FORMAT)?;
    let thermal = table.column("incoming_thermal");
    let air_temp = table.require("air_temp", FORMAT)?;
    let vapour = table.column("vapor_pressure");
    let wind = table.require("wind_speed", FORMAT)?;
    let precip = table.require("precip_mass", FORMAT)?;
    let percent_snow = table.column("percent_snow");

    let times = match time {
        Some(col) => Some(
            table
                .rows
                .iter()
                .map(|row| table.time(row, col))
                .collect::<Result<Vec<_>, _>>()?,
        ),
        None => None,
    };
    let step_h = match times.as_deref() {
        Some([a, b, ..]) => ((b.time.minutes_since_epoch() - a.time.minutes_since_epoch()) as f64
            / 60.0)
            .max(1.0 / 60.0),
        _ => 1.0,
    };
    let max_precipitation =
        (MAX_PRECIPITATION_MM_PER_HOUR * step_h).min(MAX_PRECIPITATION_MM_PER_STEP);

    let mut records = Vec::with_capacity(table.rows.len());
    for row in &table.rows {
        let t = table.required(row, air_temp, AIR_TEMPERATURE_RANGE_C, "°C")?;
        let relative_humidity = match vapour {
            None => None,
            Some(col) => match table.optional(row, Some(col), VAPOUR_PRESSURE_RANGE_PA, "Pa")? {
                None => None,
                Some(e) => {
                    let e_s = saturation_vapour_pressure_pa(t);
                    let rh = e / e_s;
                    if rh > RELATIVE_HUMIDITY_RANGE.1 {
                        return Err(table.reject(
                            row,
                            col,
                            format!(
                                "a vapour pressure at most saturation ({e_s:.1} Pa at {t} °C): it gives a relative humidity of {rh:.3}"
                            ),
                        ));
                    }
                    Some(rh.min(1.0) as f32)
                }
            },
        };
        records.push(ForcingRecord {
            air_temperature_c: t as f32,
            precipitation_mm: table.required(
                row,
                precip,
                (0.0, max_precipitation),
                "kg/m² per step",
            )? as f32,
            wind_speed_m_s: table.required(row, wind, WIND_SPEED_RANGE_M_S, "m/s")? as f32,
            wind_from_deg: None,
            shortwave_in_w_m2: None,
            relative_humidity,
            net_shortwave_w_m2: Some(
                table
                    .required(row, net_solar, SHORTWAVE_RANGE_W_M2, "W/m²")?
                    .max(0.0) as f32,
            ),
            longwave_in_w_m2: table
                .optional(row, thermal, LONGWAVE_RANGE_W_M2, "W/m²")?
                .map(|v| v as f32),
            snow_fraction: table
                .optional(row, percent_snow, (0.0, 1.0), "a fraction 0..1")?
                .map(|v| v as f32),
        });
    }
    Ok((records, times))
}
