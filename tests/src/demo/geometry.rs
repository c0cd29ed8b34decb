//! The demo's meshes: a UV sphere, a cube, a capped cylinder, a quad and the checkered ground.

use super::math::{add, scale, sin_cos, V3};

const PI: f64 = std::f64::consts::PI;

/// Triangle geometry with per-vertex normals.
#[derive(Default)]
pub(super) struct Geometry {
    pub(super) positions: Vec<[f32; 3]>,
    pub(super) normals: Vec<[f32; 3]>,
    pub(super) indices: Vec<u32>,
}

impl Geometry {
    fn vertex(&mut self, p: V3, n: V3) -> u32 {
        let i = self.positions.len() as u32;
        self.positions.push(p.map(|x| x as f32));
        self.normals.push(n.map(|x| x as f32));
        i
    }

    pub(super) fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// A unit-radius UV sphere centred at the origin, counter-clockwise from outside.
    pub(super) fn uv_sphere(segments: u32, rings: u32) -> Self {
        let mut g = Self::default();
        for ring in 0..=rings {
            let (st, ct) = sin_cos(PI * ring as f64 / rings as f64);
            for seg in 0..=segments {
                let (sp, cp) = sin_cos(2.0 * PI * seg as f64 / segments as f64);
                let n = [st * cp, ct, -st * sp];
                g.vertex(n, n);
            }
        }
        let row = segments + 1;
        for ring in 0..rings {
            for seg in 0..segments {
                let a = ring * row + seg;
                let (b, c, d) = (a + row, a + row + 1, a + 1);
                if ring != 0 {
                    g.indices.extend([a, b, d]);
                }
                if ring != rings - 1 {
                    g.indices.extend([d, b, c]);
                }
            }
        }
        g
    }

    /// An axis-aligned unit cube centred at the origin, flat-shaded.
    pub(super) fn cube() -> Self {
        let mut g = Self::default();
        // Each face: normal, and two tangent axes u, v with u × v = normal.
        let faces: [(V3, V3, V3); 6] = [
            ([1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]),
            ([-1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]),
            ([0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]),
            ([0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
            ([0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
            ([0.0, 0.0, -1.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
        ];
        for (n, u, v) in faces {
            let base = g.positions.len() as u32;
            for (su, sv) in [(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)] {
                let p = add(add(scale(n, 0.5), scale(u, su)), scale(v, sv));
                g.vertex(p, n);
            }
            g.indices
                .extend([base, base + 1, base + 2, base, base + 2, base + 3]);
        }
        g
    }

    /// A capped cylinder of radius 1 from y = 0 to y = 1: smooth sides, flat caps.
    pub(super) fn cylinder(segments: u32) -> Self {
        let mut g = Self::default();
        let ring: Vec<(f64, f64)> = (0..=segments)
            .map(|s| sin_cos(2.0 * PI * s as f64 / segments as f64))
            .collect();
        for &(s, c) in &ring {
            let n = [c, 0.0, -s];
            g.vertex([c, 0.0, -s], n);
            g.vertex([c, 1.0, -s], n);
        }
        for k in 0..segments {
            let (a, b, c, d) = (2 * k, 2 * k + 2, 2 * k + 3, 2 * k + 1);
            g.indices.extend([a, b, c, a, c, d]);
        }
        for (y, n) in [(1.0, [0.0, 1.0, 0.0]), (0.0, [0.0, -1.0, 0.0])] {
            let centre = g.vertex([0.0, y, 0.0], n);
            let first = g.positions.len() as u32;
            for &(s, c) in &ring[..segments as usize] {
                g.vertex([c, y, -s], n);
            }
            for k in 0..segments {
                let (a, b) = (first + k, first + (k + 1) % segments);
                if y > 0.5 {
                    g.indices.extend([centre, a, b]);
                } else {
                    g.indices.extend([centre, b, a]);
                }
            }
        }
        g
    }

    /// A unit quad in the XY plane facing +Z, centred at the origin.
    pub(super) fn quad() -> Self {
        let mut g = Self::default();
        let n = [0.0, 0.0, 1.0];
        for (x, y) in [(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)] {
            g.vertex([x, y, 0.0], n);
        }
        g.indices.extend([0, 1, 2, 0, 2, 3]);
        g
    }

    /// The checkered ground at y = 0: `(light tiles, dark tiles)`.
    pub(super) fn ground(x0: f64, x1: f64, z0: f64, z1: f64, tile: f64) -> (Self, Self) {
        let (mut light, mut dark) = (Self::default(), Self::default());
        let nx = ((x1 - x0) / tile).round() as i64;
        let nz = ((z1 - z0) / tile).round() as i64;
        for iz in 0..nz {
            for ix in 0..nx {
                let g = if (ix + iz) % 2 == 0 {
                    &mut light
                } else {
                    &mut dark
                };
                let (xa, xb) = (x0 + ix as f64 * tile, x0 + (ix + 1) as f64 * tile);
                let (za, zb) = (z0 + iz as f64 * tile, z0 + (iz + 1) as f64 * tile);
                let n = [0.0, 1.0, 0.0];
                let base = g.positions.len() as u32;
                // Seen from above (+Y), x right and −z forward: counter-clockwise.
                for (x, z) in [(xa, zb), (xb, zb), (xb, za), (xa, za)] {
                    g.vertex([x, 0.0, z], n);
                }
                g.indices
                    .extend([base, base + 1, base + 2, base, base + 2, base + 3]);
            }
        }
        (light, dark)
    }
}
