//! Geometry shared by the accel crate's integration tests.
// Each test binary uses its own part of these.
#![allow(dead_code)]

use aperture_accel::{MeshInput, Ray};
use glam::Vec3;

/// Positions and triangles of one mesh.
pub type Geometry = (Vec<Vec3>, Vec<[u32; 3]>);

/// The accel's view of `meshes`.
pub fn mesh_inputs(meshes: &[Geometry]) -> Vec<MeshInput<'_>> {
    meshes
        .iter()
        .map(|(p, t)| MeshInput {
            positions: p,
            indices: t,
        })
        .collect()
}

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
    (p, grid_indices(n))
}

/// The triangles of an `n × n` grid of `(n + 1)²` vertices, row by row.
pub fn grid_indices(n: u32) -> Vec<[u32; 3]> {
    let mut t = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let a = j * (n + 1) + i;
            t.push([a, a + 1, a + n + 2]);
            t.push([a, a + n + 2, a + n + 1]);
        }
    }
    t
}

/// 80 × 60 rays from just in front of z = 1 towards −z, fanning over the grid.
pub fn view_rays() -> Vec<Ray> {
    let mut out = Vec::new();
    for j in 0..60 {
        for i in 0..80 {
            let d = Vec3::new(i as f32 / 80.0 - 0.5, j as f32 / 60.0 - 0.5, -1.0).normalize();
            out.push(Ray::new(Vec3::new(0.01, 0.02, 1.0), d));
        }
    }
    out
}
