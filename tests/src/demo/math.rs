//! The demo's arithmetic: trigonometry from additions, multiplications, divisions and square
//! roots only (bit-identical on every platform), 3-vectors, quaternions, and rounded JSON numbers.

use serde_json::{json, Value};

const PI: f64 = std::f64::consts::PI;

/// `(sin x, cos x)` from a Taylor series after reduction to `[-π/4, π/4]`: bit-identical everywhere.
pub fn sin_cos(x: f64) -> (f64, f64) {
    let quadrant = (x / (PI / 2.0)).round();
    let r = x - quadrant * (PI / 2.0);
    let r2 = r * r;
    // Taylor series to the 19th power: the error at |r| = π/4 is below 1e-17.
    let (mut s, mut c) = (0.0, 0.0);
    let (mut ts, mut tc) = (r, 1.0);
    for k in 0..10 {
        s += ts;
        c += tc;
        let k2 = 2.0 * k as f64;
        ts *= -r2 / ((k2 + 2.0) * (k2 + 3.0));
        tc *= -r2 / ((k2 + 1.0) * (k2 + 2.0));
    }
    match (quadrant as i64).rem_euclid(4) {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

/// `atan x` by argument halving and a Taylor series: bit-identical everywhere.
pub fn atan(x: f64) -> f64 {
    // atan x = 2 atan(x / (1 + sqrt(1 + x²))); four halvings bring |x| ≤ 1 below tan(π/64).
    let mut y = x;
    for _ in 0..4 {
        y /= 1.0 + (1.0 + y * y).sqrt();
    }
    let y2 = y * y;
    let (mut sum, mut term) = (0.0, y);
    for k in 0..24 {
        sum += term / (2 * k + 1) as f64;
        term *= -y2;
    }
    16.0 * sum
}

/// A 3-vector.
pub(super) type V3 = [f64; 3];

/// `a + b`.
pub(super) fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// `a · s`.
pub(super) fn scale(a: V3, s: f64) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}

/// A unit quaternion `[x, y, z, w]`.
pub(super) type Quat = [f64; 4];

/// The rotation by `degrees` about the unit `axis`.
pub(super) fn quat_axis_angle(axis: V3, degrees: f64) -> Quat {
    let (s, c) = sin_cos(degrees.to_radians() / 2.0);
    [axis[0] * s, axis[1] * s, axis[2] * s, c]
}

/// The rotation `b`, then `a`.
pub(super) fn quat_mul(a: Quat, b: Quat) -> Quat {
    [
        a[3] * b[0] + a[0] * b[3] + a[1] * b[2] - a[2] * b[1],
        a[3] * b[1] - a[0] * b[2] + a[1] * b[3] + a[2] * b[0],
        a[3] * b[2] + a[0] * b[1] - a[1] * b[0] + a[2] * b[3],
        a[3] * b[3] - a[0] * b[0] - a[1] * b[1] - a[2] * b[2],
    ]
}

/// `v` rotated by `q`.
pub(super) fn quat_rotate(q: Quat, v: V3) -> V3 {
    // v' = v + 2w (u × v) + 2 u × (u × v), u = q.xyz
    let u = [q[0], q[1], q[2]];
    let cross = |a: V3, b: V3| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let t = scale(cross(u, v), 2.0);
    add(add(v, scale(t, q[3])), cross(u, t))
}

/// Rounds to 6 decimals so the JSON stays readable (and stays exactly what it says).
pub(super) fn r6(x: f64) -> f64 {
    let y = (x * 1e6).round() / 1e6;
    if y == 0.0 {
        0.0 // no "-0.0"
    } else {
        y
    }
}

/// A 3-vector as JSON, rounded by [`r6`].
pub(super) fn jv3(v: V3) -> Value {
    json!([r6(v[0]), r6(v[1]), r6(v[2])])
}

/// A quaternion as JSON, rounded by [`r6`].
pub(super) fn jq(q: Quat) -> Value {
    json!([r6(q[0]), r6(q[1]), r6(q[2]), r6(q[3])])
}
