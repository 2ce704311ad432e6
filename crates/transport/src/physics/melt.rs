//! Degree-day melt (Jubert 2018, Section 5.5.6, Eq. 5.48): `M = C_M (T_a − T_b)`, mm of
//! snow depth per day, zero when the air is colder than `T_b`.

/// Melt rate, m of snow depth per second, for a melt factor `c_m` (mm °C⁻¹ d⁻¹), air
/// temperature `t_air_c` and reference temperature `t_base_c` (°C) (Eq. 5.48).
pub fn melt_rate(c_m: f64, t_air_c: f64, t_base_c: f64) -> f64 {
    (c_m * (t_air_c - t_base_c)).max(0.0) * 1e-3 / 86_400.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn degree_day_melt_matches_hand_value() {
        // Table 7.I: 3.2 mm/°C/day at +10 °C → 32 mm/day = 0.032 / 86400 m/s = 3.7037e-7
        assert!((melt_rate(3.2, 10.0, 0.0) - 3.703_704e-7).abs() < 1e-12);
        assert_eq!(melt_rate(3.2, -5.0, 0.0), 0.0);
    }
}
