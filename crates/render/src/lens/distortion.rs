//! Brown–Conrady distortion exactly as OpenCV's `projectPoints` applies it (`k1, k2, p1, p2,
//! k3`; `k4…k6` and the thin-prism terms zero), on screen points: normalised image coordinates
//! with the principal point at the image centre and y up (OpenCV's y points down, so y is
//! flipped on the way in and out). Worked in `f64`.

use super::Distortion;
use glam::Vec2;

/// OpenCV's forward model at `(x, y)` (y down): the distorted point and the Jacobian
/// `[[∂xd/∂x, ∂xd/∂y], [∂yd/∂x, ∂yd/∂y]]`.
fn forward(d: &Distortion, x: f64, y: f64) -> ((f64, f64), [[f64; 2]; 2]) {
    let [k1, k2, k3, p1, p2] = [d.k1, d.k2, d.k3, d.p1, d.p2].map(f64::from);
    let r2 = x * x + y * y;
    let radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
    let dradial = k1 + r2 * (2.0 * k2 + 3.0 * k3 * r2);
    let xd = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x);
    let yd = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y;
    let cross = 2.0 * x * y * dradial + 2.0 * p1 * x + 2.0 * p2 * y;
    let j = [
        [
            radial + 2.0 * x * x * dradial + 2.0 * p1 * y + 6.0 * p2 * x,
            cross,
        ],
        [
            cross,
            radial + 2.0 * y * y * dradial + 6.0 * p1 * y + 2.0 * p2 * x,
        ],
    ];
    ((xd, yd), j)
}

/// Where direction `p` (y up) lands on the distorted film.
pub(super) fn distort(d: &Distortion, p: Vec2) -> Vec2 {
    let ((xd, yd), _) = forward(d, f64::from(p.x), -f64::from(p.y));
    Vec2::new(xd as f32, -yd as f32)
}

/// The direction (y up) that lands on film point `q`: Newton's method on the forward model
/// from `q` (quadratic, a handful of steps where OpenCV's fixed-point `undistortPoints` needs
/// many). `None` when it does not converge onto the model's one-to-one branch (positive
/// Jacobian): past the fold of a strong barrel distortion no direction images there.
pub(super) fn undistort(d: &Distortion, q: Vec2) -> Option<Vec2> {
    let (qx, qy) = (f64::from(q.x), -f64::from(q.y));
    let (mut x, mut y) = (qx, qy);
    for _ in 0..24 {
        let ((xd, yd), j) = forward(d, x, y);
        let (ex, ey) = (xd - qx, yd - qy);
        let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
        if det.is_nan() || det <= 0.0 {
            return None;
        }
        let sx = (j[1][1] * ex - j[0][1] * ey) / det;
        let sy = (j[0][0] * ey - j[1][0] * ex) / det;
        x -= sx;
        y -= sy;
        if sx.abs() + sy.abs() <= 1e-13 * (1.0 + x.abs() + y.abs()) {
            let p = Vec2::new(x as f32, -y as f32);
            return p.is_finite().then_some(p);
        }
    }
    None
}
