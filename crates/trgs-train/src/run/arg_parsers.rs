//! clap's parsers of `train`'s values, shared with the other commands of `trgs`: each refuses
//! with the value and what was expected.

/// `WxH` with both sides at least 16 pixels (`--demo-size`).
pub fn parse_image_size(v: &str) -> Result<(u32, u32), String> {
    let bad = || format!("{v:?}: expected WxH, e.g. 1600x1200, each side at least 16");
    let (w, h) = v.split_once(['x', 'X']).ok_or_else(bad)?;
    let (w, h) =
        (w.trim().parse::<u32>().map_err(|_| bad())?, h.trim().parse::<u32>().map_err(|_| bad())?);
    if w < 16 || h < 16 {
        return Err(bad());
    }
    Ok((w, h))
}

/// A finite number above 0 (`--downscale`).
pub fn parse_positive(v: &str) -> Result<f64, String> {
    parse_number(v, |f| f > 0.0, "a number above 0")
}

/// A finite number 0 or above (`--prune-scale`).
pub fn parse_non_negative(v: &str) -> Result<f64, String> {
    parse_number(v, |f| f >= 0.0, "a number 0 or above")
}

/// A share above 0 and at most 1 (`--grow-fraction`).
pub fn parse_positive_share(v: &str) -> Result<f64, String> {
    parse_number(v, |f| f > 0.0 && f <= 1.0, "a share above 0 and at most 1")
}

/// `v` as a finite number that `accept`s, or an error naming `v` and what was `expected`.
fn parse_number(v: &str, accept: impl Fn(f64) -> bool, expected: &str) -> Result<f64, String> {
    match v.parse::<f64>() {
        Ok(f) if f.is_finite() && accept(f) => Ok(f),
        _ => Err(format!("{v:?}: expected {expected}")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_are_checked_and_refusals_name_them() {
        assert_eq!(parse_image_size("1600x1200"), Ok((1600, 1200)));
        assert!(parse_image_size("1600").is_err() && parse_image_size("8x8").is_err());
        assert!(parse_positive("0").is_err() && parse_positive("2.5") == Ok(2.5));
        assert!(parse_non_negative("0") == Ok(0.0) && parse_non_negative("-1").is_err());
        assert!(parse_non_negative("inf").is_err() && parse_non_negative("nan").is_err());
        assert_eq!(parse_positive_share("1"), Ok(1.0));
        assert!(parse_positive_share("0").is_err() && parse_positive_share("1.5").is_err());
        assert_eq!(parse_positive("x"), Err("\"x\": expected a number above 0".into()));
    }
}
