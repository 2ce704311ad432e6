//! Placeholder of the station forcing reader (replaced by the reader on its branch).

/// One record.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ForcingRecord {
    pub air_temperature_c: f32,
    pub precipitation_mm: f32,
    pub wind_speed_m_s: f32,
    pub wind_from_deg: Option<f32>,
    pub shortwave_in_w_m2: Option<f32>,
    pub net_shortwave_w_m2: Option<f32>,
    pub relative_humidity: Option<f32>,
}

/// A series.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StationForcing {
    pub start: ForcingTime,
    pub station_altitude_m: Option<f64>,
    pub step_hours: f64,
    pub records: Vec<ForcingRecord>,
}

impl StationForcing {
    /// Days covered.
    pub fn len_days(&self) -> f64 {
        self.records.len() as f64 * self.step_hours / 24.0
    }
    /// The record covering an hour.
    pub fn at_hour(&self, hours: f64) -> &ForcingRecord {
        let k = (hours / self.step_hours).floor().max(0.0) as usize;
        &self.records[k.min(self.records.len() - 1)]
    }
}

/// Start time of a record.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ForcingTime {
    pub year: i32,
    pub month: u32,
    pub day: u32,
    pub hour: u32,
}

/// A reading error.
#[derive(Debug, thiserror::Error)]
#[error("forcing {0}")]
pub struct ForcingError(String);

/// Reads a file.
pub fn from_path(
    path: &std::path::Path,
    _station_altitude: Option<f64>,
) -> Result<StationForcing, ForcingError> {
    Err(ForcingError(path.display().to_string()))
}
