//! A season's station forcing, set up the same way by every front end (`snowscape run
//! --forcing`, a scenario's `forcing` key, Python's `Winter(..., forcing=...)` and a resume):
//! the file read ([`snowscape_season::forcing::from_path`]), its station altitude required, and
//! the scenario's calendar taken from the record (day 0 is the record's first hour; the season
//! cannot outlast the record).

use snowscape_season::forcing::{ForcingError, StationForcing, from_path};
use snowscape_season::scenario::Scenario;
use std::path::{Path, PathBuf};

/// Why a station forcing cannot drive a season.
#[derive(Debug, thiserror::Error)]
pub enum StationError {
    /// The file cannot be read or parsed (the reader's message names the file, the line and
    /// the value).
    #[error("{source}")]
    Read {
        path: PathBuf,
        #[source]
        source: Box<ForcingError>,
    },
    /// Neither the file nor the caller gives the station's altitude.
    #[error(
        "{path}: the station altitude is unknown; give it (--station-altitude M, station_altitude=M, the scenario's station_altitude_m or `# station_altitude_m = M` in the file)"
    )]
    UnknownAltitude { path: PathBuf },
}

/// The forcing file of a season: `given` (a flag or argument) or else the scenario's
/// `forcing`, a relative path read from the scenario file's folder (`scenario_file`).
pub fn forcing_path(
    given: Option<&Path>,
    scenario: &Scenario,
    scenario_file: Option<&Path>,
) -> Option<PathBuf> {
    match (given, &scenario.forcing) {
        (Some(p), _) => Some(p.to_path_buf()),
        (None, Some(p)) if p.is_relative() => Some(
            scenario_file
                .and_then(|s| s.parent())
                .map_or(p.clone(), |d| d.join(p)),
        ),
        (None, Some(p)) => Some(p.clone()),
        (None, None) => None,
    }
}

/// Reads the forcing at `path` for `scenario` (its `station_altitude_m` unless the file
/// states one) and sets the scenario's calendar from it: the start date is the record's first
/// day; the length is the record's, or `days` when given and within the record; the
/// scenario records the forcing's absolute path (what a resume reads again).
pub fn adopt_station_forcing(
    scenario: &mut Scenario,
    path: &Path,
    days: Option<f64>,
) -> Result<StationForcing, StationError> {
    let f = read_station_forcing(scenario, path)?;
    scenario.start_date = format!(
        "{:04}-{:02}-{:02}",
        f.start.year, f.start.month, f.start.day
    );
    let record_days = f.len_days();
    scenario.days = match days {
        Some(d) if d <= record_days => d,
        _ => record_days,
    };
    scenario.forcing = Some(std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf()));
    Ok(f)
}

/// The forcing a resolved scenario names (`forcing`, as [`adopt_station_forcing`] recorded
/// it), read again for a resume; `None` without one.
pub fn resumed_station_forcing(
    scenario: &Scenario,
) -> Result<Option<StationForcing>, StationError> {
    scenario
        .forcing
        .as_deref()
        .map(|p| read_station_forcing(scenario, p))
        .transpose()
}

fn read_station_forcing(scenario: &Scenario, path: &Path) -> Result<StationForcing, StationError> {
    let f = from_path(path, scenario.station_altitude_m).map_err(|source| StationError::Read {
        path: path.to_path_buf(),
        source: Box::new(source),
    })?;
    if f.station_altitude_m.is_none() {
        return Err(StationError::UnknownAltitude {
            path: path.to_path_buf(),
        });
    }
    Ok(f)
}
