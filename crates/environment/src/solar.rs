//! Solar position for the precompute: the sampling schedule of a range of days. The
//! declination, hour angle and sun vector are [`snowscape_terrain::solar`]'s (re-exported here),
//! the one solar geometry of every crate.
//!
//! The sampling schedule covers a range of days (every `day_step`-th day) and, per day,
//! `samples_per_hour` instants per hour at the centre of each sub-interval of solar time; the
//! samples with the sun above the horizon are kept, each weighted by its duration in hours.

pub use snowscape_terrain::solar::{DeclinationModel, declination, hour_angle, sun_vector};

/// One sun position of the sampling schedule.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SunSample {
    /// Unit vector towards the sun `[east, north, up]` (up > 0).
    pub direction: [f64; 3],
    /// Duration this sample stands for, hours.
    pub weight_h: f64,
}

impl SunSample {
    /// A sample from elevation and azimuth (degrees; azimuth clockwise from north).
    pub fn from_angles(elevation_deg: f64, azimuth_deg: f64, weight_h: f64) -> Self {
        let (se, ce) = elevation_deg.to_radians().sin_cos();
        let (sa, ca) = azimuth_deg.to_radians().sin_cos();
        Self {
            direction: [ce * sa, ce * ca, se],
            weight_h,
        }
    }
    /// Elevation above the horizon, degrees.
    pub fn elevation_deg(&self) -> f64 {
        self.direction[2].clamp(-1.0, 1.0).asin().to_degrees()
    }
    /// Azimuth clockwise from north, degrees in [0, 360).
    pub fn azimuth_deg(&self) -> f64 {
        self.direction[0]
            .atan2(self.direction[1])
            .to_degrees()
            .rem_euclid(360.0)
    }
}

/// The days of the schedule: `num_days` days from `start_day` every `day_step`, wrapping
/// from 365 to 1.
pub fn schedule_days(start_day: u32, num_days: u32, day_step: u32) -> Vec<u32> {
    (0..num_days)
        .step_by(day_step.max(1) as usize)
        .map(|j| (start_day - 1 + j) % 365 + 1)
        .collect()
}

/// The sun positions above the horizon on `day`, `samples_per_hour` per hour of solar time.
pub fn day_samples(
    latitude_deg: f64,
    day: u32,
    samples_per_hour: u32,
    model: DeclinationModel,
) -> Vec<SunSample> {
    let dec = declination(day, model);
    let n = 24 * samples_per_hour;
    let dt = 1.0 / samples_per_hour as f64;
    (0..n)
        .map(|k| sun_vector(latitude_deg, dec, hour_angle((k as f64 + 0.5) * dt)))
        .filter(|v| v[2] > 0.0)
        .map(|direction| SunSample {
            direction,
            weight_h: dt,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solstice_noon_elevation_at_45n() {
        // Winter solstice (day 355): δ ≈ −23.44°, noon elevation = 90 − 45 − 23.44.
        let d = declination(355, DeclinationModel::Spencer).to_degrees();
        assert!((d + 23.44).abs() < 0.1, "{d}");
        let v = sun_vector(45.0, d.to_radians(), hour_angle(12.0));
        let s = SunSample {
            direction: v,
            weight_h: 1.0,
        };
        assert!((s.elevation_deg() - 21.56).abs() < 0.1);
        assert!((s.azimuth_deg() - 180.0).abs() < 1e-6);
        // Summer solstice with Cooper.
        let d = declination(172, DeclinationModel::Cooper).to_degrees();
        assert!((d - 23.45).abs() < 0.05, "{d}");
    }

    #[test]
    fn morning_sun_is_in_the_east_and_day_length_is_right() {
        let dec = declination(80, DeclinationModel::Spencer); // near equinox
        let v = sun_vector(45.0, dec, hour_angle(8.0));
        assert!(v[0] > 0.0 && v[2] > 0.0);
        // Equinox: ~12 h of sun at any latitude; winter solstice at 45N: ~8.7 h.
        let hours = |day| {
            day_samples(45.0, day, 4, DeclinationModel::Spencer)
                .iter()
                .map(|s| s.weight_h)
                .sum::<f64>()
        };
        assert!((hours(80) - 12.0).abs() < 0.3, "{}", hours(80));
        assert!((hours(355) - 8.7).abs() < 0.3, "{}", hours(355));
        // Unit vectors.
        for s in day_samples(45.0, 200, 2, DeclinationModel::Cooper) {
            let n: f64 = s.direction.iter().map(|c| c * c).sum();
            assert!((n - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn days_wrap_around_new_year() {
        assert_eq!(schedule_days(360, 10, 3), vec![360, 363, 1, 4]);
        assert_eq!(schedule_days(1, 1, 7), vec![1]);
    }
}
