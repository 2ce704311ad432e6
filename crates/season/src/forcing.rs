//! Station forcing series (hourly or daily weather at one station), read into a typed
//! [`StationForcing`] from two CSV formats, detected by their header.
//!
//! # The generic format
//!
//! ```text
//! # Any line starting with '#' is a comment; one may give the station altitude:
//! # station_altitude_m = 2061
//! time,air_temperature_c,precipitation_mm,wind_speed_m_s,wind_from_deg,shortwave_in_w_m2,relative_humidity
//! 1983-10-01T00:00,4.0,0.0,2.3,270,0,0.65
//! 1983-10-01T01:00,4.1,0.2,2.3,265,0,0.66
//! ```
//!
//! | column | unit | required | accepted values |
//! |---|---|---|---|
//! | `time` | ISO 8601 `YYYY-MM-DD`, `YYYY-MM-DDTHH:MM` or `YYYY-MM-DD HH:MM` (no time zone) | yes | evenly spaced, increasing |
//! | `air_temperature_c` | °C | yes | −90..=60 |
//! | `precipitation_mm` | mm of water (kg/m²) fallen during the step that starts at `time` | yes | 0..=[`MAX_PRECIPITATION_MM_PER_HOUR`]·step, at most [`MAX_PRECIPITATION_MM_PER_STEP`] |
//! | `wind_speed_m_s` | m/s | yes | 0..=100 |
//! | `wind_from_deg` | degrees clockwise from north the wind blows FROM | no | 0..=360 |
//! | `shortwave_in_w_m2` | incoming (global) shortwave, W/m² | no | −20..=1500 (night-time sensor offsets below 0 read as 0) |
//! | `net_shortwave_w_m2` | absorbed shortwave (1 − albedo)·incoming, W/m² | no | as above |
//! | `longwave_in_w_m2` | incoming longwave, W/m² | no | 0..=1000 |
//! | `relative_humidity` | a FRACTION 0..1 (not percent) | no | 0..=1.05 (sensor overshoot above 1 reads as 1) |
//! | `snow_fraction` | share of the step's precipitation that falls as snow, 0..1 | no | 0..=1 |
//!
//! Names are matched case-insensitively after trimming; extra columns are ignored; an empty
//! cell in an optional column is "not measured" (`None`). A record covers the step that starts
//! at its time, so a daily series (`YYYY-MM-DD`) gives each day's totals and means. The step is
//! the difference of the first two times (a one-record file: 24 h for a date, 1 h for a time);
//! every later time must be exactly one step after the previous one, so a gap or a repeated
//! time is an error naming its line, never silently filled.
//!
//! # The snobal / pysnobal input format
//!
//! A header containing `air_temp` and `precip_mass` is read as the input of the snobal
//! energy-balance model (Marks et al. 1999, Hydrol. Process. 13; the `gold.snobal.data.input`
//! files of pysnobal): `date_time` (or `time`), `net_solar` W/m², `incoming_thermal` W/m²,
//! `air_temp` °C, `vapor_pressure` Pa, `wind_speed` m/s, `soil_temp` °C, `precip_mass` kg/m²
//! per step, `percent_snow` 0..1, `rho_snow` kg/m³, `precip_temp` °C. It maps onto a record as
//!
//! - `air_temp` → [`ForcingRecord::air_temperature_c`]; `precip_mass` (kg/m² = mm) →
//!   [`ForcingRecord::precipitation_mm`]; `wind_speed` → [`ForcingRecord::wind_speed_m_s`];
//!   no wind direction (`None`);
//! - `net_solar` is NET shortwave (already × (1 − albedo)): it goes to
//!   [`ForcingRecord::net_shortwave_w_m2`], and `shortwave_in_w_m2` stays `None`;
//! - `incoming_thermal` → [`ForcingRecord::longwave_in_w_m2`]; `percent_snow` →
//!   [`ForcingRecord::snow_fraction`];
//! - relative humidity = `vapor_pressure` / e_s(`air_temp`), with the saturation vapour
//!   pressure over water of the Magnus formula, e_s(T) = 611.2 Pa · exp(17.62 T / (243.12 + T))
//!   (WMO Guide to Instruments and Methods of Observation, WMO-No. 8, 2008, Annex 4.B; the
//!   Sonntag 1990 coefficients). Relative humidity is taken with respect to water below 0 °C
//!   too, as WMO defines it. A ratio in (1, 1.05] reads as 1; above 1.05 is an error;
//! - `soil_temp`, `rho_snow` and `precip_temp` are not used.
//!
//! Times come from the `date_time` column; a file without a time column starts at
//! [`SNOBAL_DEFAULT_START`] (1983-10-01T00:00, the start of the pysnobal test season) with an
//! hourly step. Neither format carries the station altitude except through the
//! `# station_altitude_m = ...` comment; [`from_path`]'s override wins over it.
//!
//! Every value is checked (non-numbers, NaN and infinities, values outside the ranges above):
//! a [`ForcingError`] names the file, line, column and value.
//!
//! # Limits
//!
//! A forcing file is read whole, so its size is bounded before anything is allocated, and
//! so is every part of it; past a limit the reader stops with a typed error naming it:
//!
//! | what | limit |
//! |---|---|
//! | the file | [`MAX_FILE_BYTES`] (512 MiB; only a regular file is opened) |
//! | one line | [`MAX_LINE_BYTES`] (64 KiB) |
//! | one field (cell or column name) | [`MAX_FIELD_BYTES`] (1 KiB) |
//! | columns in the header | [`MAX_COLUMNS`] (1024) |
//! | records | [`MAX_RECORDS`] (hourly records for 300 years) |
//!
//! The header is read in time linear in its length, and an error message repeats at most
//! [`crate::MAX_ECHO_CHARS`] characters of any value from the file.

mod generic;
mod snobal;
mod table;
pub mod time;

#[cfg(test)]
mod tests;

pub use snobal::saturation_vapour_pressure_pa;
pub use time::ForcingTime;

use std::path::{Path, PathBuf};
use thiserror::Error;

/// Air temperatures accepted, °C (the coldest and hottest air ever measured lie inside).
pub const AIR_TEMPERATURE_RANGE_C: (f64, f64) = (-90.0, 60.0);
/// Heaviest precipitation accepted per hour of step, mm (the world's one-hour record is 305 mm).
pub const MAX_PRECIPITATION_MM_PER_HOUR: f64 = 400.0;
/// Heaviest precipitation accepted in one step, mm (the world's one-day record is 1825 mm).
pub const MAX_PRECIPITATION_MM_PER_STEP: f64 = 2000.0;
/// Mean wind speeds accepted, m/s.
pub const WIND_SPEED_RANGE_M_S: (f64, f64) = (0.0, 100.0);
/// Shortwave fluxes accepted, W/m² (the solar constant is 1361; pyranometers read slightly
/// negative at night, which is taken as 0).
pub const SHORTWAVE_RANGE_W_M2: (f64, f64) = (-20.0, 1500.0);
/// Incoming longwave accepted, W/m².
pub const LONGWAVE_RANGE_W_M2: (f64, f64) = (0.0, 1000.0);
/// Relative humidity accepted, as a fraction (a little overshoot of 1 reads as 1).
pub const RELATIVE_HUMIDITY_RANGE: (f64, f64) = (0.0, 1.05);
/// Station altitudes accepted, metres above sea level.
pub const STATION_ALTITUDE_RANGE_M: (f64, f64) = (-500.0, 9000.0);
/// Largest forcing file read, bytes (512 MiB: 300 years of hourly records of 200 bytes).
pub const MAX_FILE_BYTES: u64 = 512 << 20;
/// Longest line accepted, bytes.
pub const MAX_LINE_BYTES: usize = 64 << 10;
/// Longest field (a cell or a column name) accepted, bytes.
pub const MAX_FIELD_BYTES: usize = 1024;
/// Most columns a header may have (a format needs at most eleven; extra ones are ignored).
pub const MAX_COLUMNS: usize = 1024;
/// Most records a file may hold: hourly records for 300 years (366-day years).
pub const MAX_RECORDS: usize = 24 * 366 * 300;
/// Where a snobal file without a time column starts (the pysnobal test season, hourly).
pub const SNOBAL_DEFAULT_START: ForcingTime = ForcingTime {
    year: 1983,
    month: 10,
    day: 1,
    hour: 0,
    minute: 0,
};

/// A station's forcing series: evenly spaced records from `start`.
#[derive(Debug, Clone, PartialEq)]
pub struct StationForcing {
    /// Station altitude, metres above sea level, when the file or the caller gives it.
    pub station_altitude_m: Option<f64>,
    /// Hours between records (1 for hourly, 24 for daily series).
    pub step_hours: f64,
    /// Time of the first record (which covers `start .. start + step_hours`).
    pub start: ForcingTime,
    /// One record per step, never empty.
    pub records: Vec<ForcingRecord>,
}

/// The weather during one step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ForcingRecord {
    /// Mean air temperature, °C.
    pub air_temperature_c: f32,
    /// Precipitation during the step, mm of water (kg/m²).
    pub precipitation_mm: f32,
    /// Mean wind speed, m/s.
    pub wind_speed_m_s: f32,
    /// Direction the wind blows from, degrees clockwise from north.
    pub wind_from_deg: Option<f32>,
    /// Incoming (global) shortwave radiation, W/m².
    pub shortwave_in_w_m2: Option<f32>,
    /// Relative humidity with respect to water, a fraction 0..=1.
    pub relative_humidity: Option<f32>,
    /// Net (absorbed) shortwave, W/m²: (1 − albedo) times the incoming, as snobal's
    /// `net_solar`. Not interchangeable with [`Self::shortwave_in_w_m2`].
    pub net_shortwave_w_m2: Option<f32>,
    /// Incoming longwave radiation, W/m².
    pub longwave_in_w_m2: Option<f32>,
    /// Share of the precipitation falling as snow, 0..=1 (snobal's `percent_snow`).
    pub snow_fraction: Option<f32>,
}

/// Why a forcing file could not be read. Each names the file, and the line, column and value
/// where one is at fault.
#[derive(Debug, Error)]
pub enum ForcingError {
    #[error("cannot read forcing file {path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}:{line}: malformed CSV: {message}")]
    Csv {
        path: PathBuf,
        line: u64,
        message: String,
    },
    #[error("{path}: no header row (expected a CSV header such as `{expected}`)")]
    NoHeader {
        path: PathBuf,
        expected: &'static str,
    },
    #[error(
        "{path}:{line}: no column `{column}` in the header, which the {format} format needs (the header has: {header})"
    )]
    MissingColumn {
        path: PathBuf,
        line: u64,
        column: &'static str,
        format: &'static str,
        header: String,
    },
    #[error(
        "{path}:{line}: column `{column}` appears twice in the header (columns {first} and {second})"
    )]
    DuplicateColumn {
        path: PathBuf,
        line: u64,
        column: String,
        first: usize,
        second: usize,
    },
    #[error("{path}:{line}, column {column_number} `{column}`: `{value}` is not {expected}")]
    BadValue {
        path: PathBuf,
        line: u64,
        column_number: usize,
        column: String,
        value: String,
        expected: String,
    },
    #[error(
        "{path}:{line}: time {value} is not after the previous record's {previous} (times must increase)"
    )]
    NonMonotonicTime {
        path: PathBuf,
        line: u64,
        value: String,
        previous: String,
    },
    #[error(
        "{path}:{line}: time {value} breaks the even step of {step_hours} h set by the first two records: expected {expected} (a gap or an uneven step)"
    )]
    UnevenStep {
        path: PathBuf,
        line: u64,
        value: String,
        expected: String,
        step_hours: f64,
    },
    #[error("{path} is {bytes} bytes, more than the {max} bytes a forcing file may hold")]
    TooLarge { path: PathBuf, bytes: u64, max: u64 },
    #[error(
        "{path}:{line}: the line is {bytes} bytes long, more than the {max} bytes a line may hold"
    )]
    LineTooLong {
        path: PathBuf,
        line: u64,
        bytes: usize,
        max: usize,
    },
    #[error(
        "{path}:{line}: column {column_number} holds {bytes} bytes, more than the {max} bytes a field may hold"
    )]
    FieldTooLong {
        path: PathBuf,
        line: u64,
        column_number: usize,
        bytes: usize,
        max: usize,
    },
    #[error(
        "{path}:{line}: the header has {columns} columns, more than the {max} a forcing file may have"
    )]
    TooManyColumns {
        path: PathBuf,
        line: u64,
        columns: usize,
        max: usize,
    },
    #[error(
        "{path}:{line}: more than {max} records (hourly records for 300 years), the most a forcing file may hold"
    )]
    TooManyRecords {
        path: PathBuf,
        line: u64,
        max: usize,
    },
    #[error("{path}: no records after the header")]
    NoRecords { path: PathBuf },
    #[error(
        "{path}:{line}: station_altitude_m = `{value}` is not metres within {min}..={max}",
        min = STATION_ALTITUDE_RANGE_M.0,
        max = STATION_ALTITUDE_RANGE_M.1
    )]
    BadAltitude {
        path: PathBuf,
        line: u64,
        value: String,
    },
    #[error(
        "station altitude override for {path}: {value} is not metres within {min}..={max}",
        min = STATION_ALTITUDE_RANGE_M.0,
        max = STATION_ALTITUDE_RANGE_M.1
    )]
    BadAltitudeOverride { path: PathBuf, value: f64 },
}

/// Reads a forcing file, generic or snobal (by its header; module docs).
/// `station_altitude_override` replaces the altitude the file gives (or gives the one it lacks).
pub fn from_path(
    path: &Path,
    station_altitude_override: Option<f64>,
) -> Result<StationForcing, ForcingError> {
    let io = |source| ForcingError::Io {
        path: path.to_path_buf(),
        source,
    };
    use std::io::Read;
    let not_regular = || {
        io(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "not a regular file (a device, FIFO or folder)",
        ))
    };
    // A device or a FIFO is refused before it is opened (reading one would not end, or block),
    // and again on the open handle (the path may have been replaced in between).
    if !std::fs::metadata(path).map_err(io)?.is_file() {
        return Err(not_regular());
    }
    let file = std::fs::File::open(path).map_err(io)?;
    let meta = file.metadata().map_err(io)?;
    if !meta.is_file() {
        return Err(not_regular());
    }
    let too_large = |bytes| ForcingError::TooLarge {
        path: path.to_path_buf(),
        bytes,
        max: MAX_FILE_BYTES,
    };
    if meta.len() > MAX_FILE_BYTES {
        return Err(too_large(meta.len()));
    }
    let mut text = String::with_capacity(meta.len() as usize);
    // `take` bounds the read even if the file grows while it is read.
    file.take(MAX_FILE_BYTES + 1)
        .read_to_string(&mut text)
        .map_err(io)?;
    if text.len() as u64 > MAX_FILE_BYTES {
        return Err(too_large(text.len() as u64));
    }
    StationForcing::from_text(&text, path, station_altitude_override)
}

impl StationForcing {
    /// Parses the text of a forcing file; `path` is only used to name it in errors.
    pub fn from_text(
        text: &str,
        path: &Path,
        station_altitude_override: Option<f64>,
    ) -> Result<Self, ForcingError> {
        if let Some(v) = station_altitude_override
            && !in_range(v, STATION_ALTITUDE_RANGE_M)
        {
            return Err(ForcingError::BadAltitudeOverride {
                path: path.to_path_buf(),
                value: v,
            });
        }
        if text.len() as u64 > MAX_FILE_BYTES {
            return Err(ForcingError::TooLarge {
                path: path.to_path_buf(),
                bytes: text.len() as u64,
                max: MAX_FILE_BYTES,
            });
        }
        let table = table::Table::parse(text, path)?;
        let (records, times) = if table.is_snobal() {
            snobal::read(&table)?
        } else {
            generic::read(&table)?
        };
        let (start, step_hours) = match times {
            Some(times) => table.check_times(&times)?,
            None => (SNOBAL_DEFAULT_START, 1.0),
        };
        Ok(Self {
            station_altitude_m: station_altitude_override.or(table.station_altitude_m),
            step_hours,
            start,
            records,
        })
    }

    /// Length of the series, days.
    pub fn len_days(&self) -> f64 {
        self.records.len() as f64 * self.step_hours / 24.0
    }

    /// The record covering `hours_since_start` (record k covers `[k·step, (k+1)·step)`).
    /// Times before the start (or NaN) give the first record, times after the end the last.
    pub fn at_hour(&self, hours_since_start: f64) -> &ForcingRecord {
        let k = (hours_since_start / self.step_hours).floor();
        let last = self.records.len() - 1;
        let k = if k.is_nan() || k < 0.0 {
            0
        } else {
            (k as usize).min(last)
        };
        &self.records[k]
    }

    /// The series as a generic-format CSV (every column; module docs), which reads back to
    /// the same series.
    pub fn to_csv(&self) -> String {
        generic::write(self)
    }

    /// The time of record `index`.
    pub fn time_of(&self, index: usize) -> ForcingTime {
        self.start.plus_hours(index as f64 * self.step_hours)
    }
}

fn in_range(v: f64, (lo, hi): (f64, f64)) -> bool {
    v >= lo && v <= hi
}
