//! Sampler evaluation: STEP, LINEAR, CUBICSPLINE, clamping and slerp.

use super::*;

fn sampler(times: &[f32], values: &[f32], width: usize, i: Interpolation) -> Sampler {
    Sampler {
        times: times.to_vec(),
        values: values.to_vec(),
        width,
        interpolation: i,
    }
}

#[test]
fn step_linear_and_clamping() {
    let s = sampler(&[1.0, 2.0], &[10.0, 20.0], 1, Interpolation::Linear);
    assert_eq!(s.sample(0.0, false), [10.0]);
    assert_eq!(s.sample(1.25, false), [12.5]);
    assert_eq!(s.sample(5.0, false), [20.0]);
    let s = sampler(&[1.0, 2.0], &[10.0, 20.0], 1, Interpolation::Step);
    assert_eq!(s.sample(1.99, false), [10.0]);
    assert_eq!(s.sample(2.0, false), [20.0]);
}

#[test]
fn cubic_spline_hits_keys_and_follows_tangents() {
    // Keys 0 -> 1 over one second with out-tangent 0 and in-tangent 0: smoothstep.
    let s = sampler(
        &[0.0, 1.0],
        &[0.0, 0.0, 0.0, 0.0, 1.0, 0.0],
        1,
        Interpolation::CubicSpline,
    );
    assert_eq!(s.sample(0.0, false), [0.0]);
    assert!((s.sample(0.5, false)[0] - 0.5).abs() < 1e-12);
    assert!((s.sample(0.25, false)[0] - (3.0 * 0.0625 - 2.0 * 0.015625)).abs() < 1e-12);
}

#[test]
fn slerp_takes_the_short_way_at_constant_speed() {
    let a = DQuat::IDENTITY;
    let b = DQuat::from_rotation_y(std::f64::consts::FRAC_PI_2);
    let h = slerp(a, -b, 0.5);
    let want = DQuat::from_rotation_y(std::f64::consts::FRAC_PI_4);
    assert!(h.dot(want).abs() > 1.0 - 1e-12, "{h:?}");
}

#[test]
fn bool_keys_step_and_keep_the_values_of_cubic_splines() {
    let mut out = Animations::default();
    // Two CUBICSPLINE keys: in-tangent, value, out-tangent each.
    let keys = [0.0, 1.0, 0.0, 9.0, 0.0, 9.0];
    let at = "animations[0].channels[1]";
    let (v, i) = bool_keys(&keys, Interpolation::CubicSpline, at, &mut out);
    assert_eq!((v, i), (vec![1.0, 0.0], Interpolation::Step));
    assert!(out.warnings[0].starts_with(at), "{:?}", out.warnings);
    let (v, _) = bool_keys(&[1.0, 0.0], Interpolation::Step, at, &mut out);
    assert_eq!(v, [1.0, 0.0]);
    assert_eq!(out.warnings.len(), 1, "STEP is what a bool is keyed with");
}
