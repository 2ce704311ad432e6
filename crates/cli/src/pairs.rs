//! `X,Y` pairs on the command line (map coordinates, wind vectors).

use anyhow::bail;

/// Parses `X,Y` as two finite numbers; errors name the flag and the value.
pub fn parse_xy(flag: &str, text: &str) -> anyhow::Result<(f64, f64)> {
    let parts: Vec<&str> = text.split(',').collect();
    let parsed = match parts.as_slice() {
        [x, y] => x
            .trim()
            .parse::<f64>()
            .ok()
            .zip(y.trim().parse::<f64>().ok()),
        _ => None,
    };
    match parsed {
        Some((x, y)) if x.is_finite() && y.is_finite() => Ok((x, y)),
        _ => bail!("{flag} {text:?}: expected two finite numbers X,Y"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pairs_parse_and_errors_name_flag_and_value() {
        assert_eq!(
            parse_xy("--at", " 631250.5, -12 ").unwrap(),
            (631250.5, -12.0)
        );
        for bad in ["1", "1,2,3", "a,2", "inf,2", "1,NaN", ""] {
            let e = parse_xy("--at", bad).unwrap_err().to_string();
            assert!(e.contains("--at") && e.contains(&format!("{bad:?}")), "{e}");
        }
    }
}
