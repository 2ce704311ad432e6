//! `X,Y` pairs on the command line (map coordinates, wind vectors).

use anyhow::{Context, bail};

/// Parses `X,Y` as two finite numbers; errors name the flag, the value and the bad part.
pub fn parse_xy(flag: &str, text: &str) -> anyhow::Result<(f64, f64)> {
    let num = |s: &str| -> anyhow::Result<f64> {
        let v: f64 = s
            .trim()
            .parse()
            .with_context(|| format!("{flag} {text:?}: {s:?} is not a number"))?;
        if !v.is_finite() {
            bail!("{flag} {text:?}: {s:?} is not finite");
        }
        Ok(v)
    };
    match text.split(',').collect::<Vec<_>>().as_slice() {
        [x, y] => Ok((num(x)?, num(y)?)),
        _ => bail!("{flag} {text:?}: expected two numbers X,Y"),
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
