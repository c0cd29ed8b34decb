//! Value parsers for numeric command-line options, shared by every subcommand.

/// A finite number.
pub(crate) fn finite_f32(s: &str) -> Result<f32, String> {
    checked(s, "", |_| true)
}

/// A finite number > 0.
pub(crate) fn positive_f32(s: &str) -> Result<f32, String> {
    checked(s, " > 0", |v| v > 0.0)
}

/// A finite number ≥ 0.
pub(crate) fn non_negative_f32(s: &str) -> Result<f32, String> {
    checked(s, " ≥ 0", |v| v >= 0.0)
}

fn checked(s: &str, what: &str, ok: impl Fn(f32) -> bool) -> Result<f32, String> {
    let v: f32 = s.parse().map_err(|e| format!("{e}"))?;
    if v.is_finite() && ok(v) {
        Ok(v)
    } else {
        Err(format!("must be a finite number{what}, got {s}"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bounds_are_checked() {
        assert_eq!(positive_f32("2.5"), Ok(2.5));
        assert!(positive_f32("0").is_err());
        assert_eq!(non_negative_f32("0"), Ok(0.0));
        assert!(non_negative_f32("-1").is_err());
        assert!(finite_f32("inf").is_err() && finite_f32("x").is_err());
        assert_eq!(finite_f32("-3"), Ok(-3.0));
    }
}
