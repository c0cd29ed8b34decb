//! Geometry shared by the accel crate's integration tests.

use glam::Vec3;

/// Positions and triangles of one mesh.
pub type Geometry = (Vec<Vec3>, Vec<[u32; 3]>);

/// A grid of `n × n` quads in the plane z = 0, spanning [-1, 1]², bumped by `bump`.
pub fn grid(n: u32, bump: f32) -> Geometry {
    let mut p = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (
                i as f32 / n as f32 * 2.0 - 1.0,
                j as f32 / n as f32 * 2.0 - 1.0,
            );
            p.push(Vec3::new(x, y, bump * (3.0 * x).sin() * (2.0 * y).cos()));
        }
    }
    let mut t = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let a = j * (n + 1) + i;
            t.push([a, a + 1, a + n + 2]);
            t.push([a, a + n + 2, a + n + 1]);
        }
    }
    (p, t)
}
