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
/// A finite number from 0 to 1.
pub(crate) fn unit_f32(s: &str) -> Result<f32, String> {
    checked(s, " from 0 to 1", |v| (0.0..=1.0).contains(&v))
}

/// A chromatic aberration number: finite, from −0.5 to 0.5.
pub(crate) fn chromatic_f32(s: &str) -> Result<f32, String> {
    checked(s, " from -0.5 to 0.5", |v| (-0.5..=0.5).contains(&v))
}

/// Brown–Conrady coefficients `K1[,K2[,K3[,P1[,P2]]]]` (OpenCV's, in this order; the ones left
/// out are 0), each a finite number.
pub(crate) fn distortion(s: &str) -> Result<[f32; 5], String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() > 5 {
        return Err(format!(
            "at most five coefficients (k1,k2,k3,p1,p2), got {}",
            parts.len()
        ));
    }
    let mut out = [0.0; 5];
    for (o, p) in out.iter_mut().zip(&parts) {
        *o = finite_f32(p).map_err(|e| format!("{p:?}: {e}"))?;
    }
    Ok(out)
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
        assert_eq!(unit_f32("1"), Ok(1.0));
        assert!(unit_f32("1.01").is_err() && unit_f32("-0.1").is_err());
        assert_eq!(chromatic_f32("-0.01"), Ok(-0.01));
        assert!(chromatic_f32("0.6").is_err() && chromatic_f32("nan").is_err());
    }

    #[test]
    fn distortion_takes_one_to_five_coefficients() {
        assert_eq!(distortion("-0.2"), Ok([-0.2, 0.0, 0.0, 0.0, 0.0]));
        assert_eq!(
            distortion("-0.2, 0.05,0,0.01,-0.01"),
            Ok([-0.2, 0.05, 0.0, 0.01, -0.01])
        );
        assert!(distortion("1,2,3,4,5,6").is_err());
        assert!(distortion("0.1,nan").is_err());
        assert!(distortion("").is_err());
    }
}
