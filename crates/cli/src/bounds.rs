//! Ranges of the numeric flags, checked by clap before any work starts (exit 2 with a message
//! naming the flag and its value). Values the library also checks (scenario keys, avalanche
//! and cover parameters) are checked there as well, with the same ranges; these bound the
//! flags that size the work itself (days, hours, frames, threads, time budgets).

/// A parser for a finite number within `[lo, hi]`, or `(lo, hi]` when `open_low` (`unit`
/// for the message).
fn number_in(text: &str, lo: f64, hi: f64, open_low: bool, unit: &str) -> Result<f64, String> {
    let range = format!("{}{lo}, {hi}]{unit}", if open_low { "(" } else { "[" });
    let v: f64 = text
        .trim()
        .parse()
        .map_err(|_| format!("not a number (expected a value within {range})"))?;
    let above = if open_low { v > lo } else { v >= lo };
    if v.is_finite() && above && v <= hi {
        Ok(v)
    } else {
        Err(format!("must be within {range}"))
    }
}

fn number_within(text: &str, lo: f64, hi: f64, unit: &str) -> Result<f64, String> {
    number_in(text, lo, hi, false, unit)
}

/// A parser for a positive finite number at most `hi` (`(0, hi]`).
fn positive_up_to(text: &str, hi: f64, unit: &str) -> Result<f64, String> {
    number_in(text, 0.0, hi, true, unit)
}

/// A season's length, days: (0, 3650] (ten years).
pub fn season_days(text: &str) -> Result<f64, String> {
    positive_up_to(text, 3650.0, " days")
}

/// A memory budget, GiB: (0, 1048576] (a pebibyte); returned in bytes.
pub fn memory_budget(text: &str) -> Result<u64, String> {
    positive_up_to(text, 1_048_576.0, " GiB").map(|g| (g * f64::from(1u32 << 30)) as u64)
}

/// A day of the season: [0, 3650].
pub fn season_day(text: &str) -> Result<f64, String> {
    number_within(text, 0.0, 3650.0, " days")
}

/// Simulated hours of the physical transport: (0, 8760] (a year).
pub fn transport_hours(text: &str) -> Result<f64, String> {
    positive_up_to(text, 8760.0, " h")
}

/// A release thickness, metres: (0, 50].
pub fn release_thickness(text: &str) -> Result<f64, String> {
    positive_up_to(text, 50.0, " m")
}

/// A snow cover laid on a DEM, metres: [0, 50].
pub fn snow_cover(text: &str) -> Result<f64, String> {
    number_within(text, 0.0, 50.0, " m")
}

/// Simulated seconds of one avalanche: (0, 86400].
pub fn avalanche_seconds(text: &str) -> Result<f64, String> {
    positive_up_to(text, 86_400.0, " s")
}

/// Simulated seconds between avalanche playback frames: [0.01, 3600].
pub fn frame_interval(text: &str) -> Result<f64, String> {
    number_within(text, 0.01, 3600.0, " s")
}

/// A wall-clock time budget, seconds: (0, 86400].
pub fn wall_seconds(text: &str) -> Result<f64, String> {
    positive_up_to(text, 86_400.0, " s")
}

/// A cell size or voxel side, metres: (0, 100000].
pub fn metres(text: &str) -> Result<f64, String> {
    positive_up_to(text, 1e5, " m")
}

/// A latitude, degrees: [−90, 90].
pub fn latitude(text: &str) -> Result<f64, String> {
    number_within(text, -90.0, 90.0, " °")
}

/// Most frames of a time-lapse.
pub const MAX_FRAMES: usize = 1000;

/// Frames of a time-lapse: 0..=1000.
pub fn frames(text: &str) -> Result<usize, String> {
    count_within(text, 0, MAX_FRAMES)
}

/// Timed repetitions of a benchmark: 1..=1000.
pub fn repeats(text: &str) -> Result<usize, String> {
    count_within(text, 1, 1000)
}

/// Flakes of the precipitation map: 1..=100 000 000.
pub fn flakes(text: &str) -> Result<usize, String> {
    count_within(text, 1, 100_000_000)
}

/// Stable Fluids iterations: 1..=100 000.
pub fn wind_iterations(text: &str) -> Result<usize, String> {
    count_within(text, 1, 100_000)
}

/// Voxel layers of the wind grid: 1..=4096.
pub fn voxel_layers(text: &str) -> Result<usize, String> {
    count_within(text, 1, 4096)
}

/// Longest side of a preview image, pixels: 16..=16384.
pub fn image_side(text: &str) -> Result<usize, String> {
    count_within(text, 16, 16_384)
}

/// Worker threads: 1..=1024 here; [`check_threads`] then caps them at a multiple of the
/// machine's cores.
pub fn threads(text: &str) -> Result<usize, String> {
    count_within(text, 1, 1024)
}

/// Most worker threads per core.
pub const THREADS_PER_CORE: usize = 8;

/// Refuses more than [`THREADS_PER_CORE`] threads per core of this machine (at least 8).
pub fn check_threads(n: usize) -> Result<usize, String> {
    let cores = std::thread::available_parallelism().map_or(1, |c| c.get());
    let most = (cores * THREADS_PER_CORE).max(8);
    if n <= most {
        Ok(n)
    } else {
        Err(format!(
            "--threads {n}: at most {most} on this machine ({cores} cores, {THREADS_PER_CORE} threads per core)"
        ))
    }
}

fn count_within(text: &str, lo: usize, hi: usize) -> Result<usize, String> {
    let v: u64 = text
        .trim()
        .parse()
        .map_err(|_| format!("not a whole number (expected {lo}..={hi})"))?;
    if (lo as u64..=hi as u64).contains(&v) {
        Ok(v as usize)
    } else {
        Err(format!("must be within {lo}..={hi}"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_outside_their_range_are_refused_with_it() {
        assert!(season_day("nan").unwrap_err().contains("[0, 3650]"));
        assert!(season_days("0").is_err());
        assert!(season_days("1e999").is_err());
        assert_eq!(season_days("100"), Ok(100.0));
        assert!(wall_seconds("1e20").is_err());
        assert!(release_thickness("1e9").is_err());
        assert!(threads("99999999999").is_err());
        assert!(threads("0").is_err());
        assert_eq!(frames("0"), Ok(0));
        assert!(frames("1000000000").is_err());
        assert!(check_threads(1_000).is_err());
        assert_eq!(check_threads(2), Ok(2));
    }
}
