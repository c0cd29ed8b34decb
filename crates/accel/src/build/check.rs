//! Which triangles are kept: indices in range, three finite points not on one line.

use crate::triangle::Tri;
use crate::types::{InstanceInput, MeshInput};
use glam::{Affine3A, Vec3, Vec3Swizzles};

/// Why a triangle is left out.
#[derive(Debug, Clone, Copy, PartialEq)]
enum TriCheck {
    Ok([Vec3; 3]),
    OutOfRange,
    Degenerate,
}

fn check_triangle(positions: &[Vec3], tri: [u32; 3]) -> TriCheck {
    let mut p = [Vec3::ZERO; 3];
    for k in 0..3 {
        match positions.get(tri[k] as usize) {
            Some(v) => p[k] = *v,
            None => return TriCheck::OutOfRange,
        }
    }
    classify(p)
}

fn classify(p: [Vec3; 3]) -> TriCheck {
    if !(p[0].is_finite() && p[1].is_finite() && p[2].is_finite()) {
        return TriCheck::Degenerate;
    }
    if clearly_not_collinear(p) || !exactly_collinear(p) {
        TriCheck::Ok(p)
    } else {
        TriCheck::Degenerate
    }
}

/// The three points are on one line. In f64 the edges of f32 points and their products are
/// exact, so this is exact, without a tolerance that would depend on the scene's scale.
fn exactly_collinear(p: [Vec3; 3]) -> bool {
    let [a, b, c] = p.map(|v| v.as_dvec3());
    (b - a).cross(c - a) == glam::DVec3::ZERO
}

/// True when the cross product of the edges, computed in f32, is too far from 0 for its
/// rounding to explain (then the exact test in [`classify`] would find them not collinear
/// too); false leaves the triangle to that test. Most triangles end here.
///
/// Each edge and product is rounded once and the difference once more, so a component is off
/// by less than 4 units in the last place of the products' sum (2^-22 of it); 2^-16 leaves
/// room, and the floor of 1e-30 (about 2^-100) keeps the products out of the subnormals,
/// where that bound fails.
/// An infinite or NaN product fails the comparison, so it goes on to the exact test.
fn clearly_not_collinear(p: [Vec3; 3]) -> bool {
    let (e1, e2) = (p[1] - p[0], p[2] - p[0]);
    let lhs = e1.yzx() * e2.zxy();
    let rhs = e1.zxy() * e2.yzx();
    let cross = lhs - rhs;
    let room = (lhs.abs() + rhs.abs()) * (1.0 / 65536.0);
    let big = cross.abs().cmpgt(room) & room.cmpgt(Vec3::splat(1e-30));
    big.any()
}

/// Per mesh: validity counts, and the kept triangles if a bottom-level BVH is to be built.
pub(super) struct Checked {
    pub(super) shared: Vec<(Tri, u32)>,
    pub(super) kept: usize,
    pub(super) degenerate: usize,
    pub(super) out_of_range: usize,
}

/// The triangles of `mesh` checked; kept ones are collected when `keep`.
pub(super) fn check_mesh(mesh: &MeshInput<'_>, keep: bool) -> Checked {
    let mut c = Checked {
        shared: Vec::new(),
        kept: 0,
        degenerate: 0,
        out_of_range: 0,
    };
    for (i, tri) in mesh.indices.iter().enumerate() {
        match check_triangle(mesh.positions, *tri) {
            TriCheck::Ok(p) => {
                c.kept += 1;
                if keep {
                    c.shared.push((Tri { p, prim: i as u32 }, 0));
                }
            }
            TriCheck::OutOfRange => c.out_of_range += 1,
            TriCheck::Degenerate => c.degenerate += 1,
        }
    }
    c
}

/// One placed instance's kept triangles in world space, and how many of its triangles only
/// become degenerate there (rounding).
pub(super) struct Kept {
    pub(super) tris: Vec<Tri>,
    pub(super) degenerate: usize,
}

/// The triangles of `mesh` placed by `inst` and checked in world space ([`Kept`]).
pub(super) fn world_triangles(mesh: &MeshInput<'_>, inst: &InstanceInput) -> Kept {
    let world: Vec<Vec3> = mesh
        .positions
        .iter()
        .map(|p| inst.world_from_object.transform_point3(*p))
        .collect();
    let mut kept = Kept {
        tris: Vec::with_capacity(mesh.indices.len()),
        degenerate: 0,
    };
    for (i, tri) in mesh.indices.iter().enumerate() {
        match check_triangle(&world, *tri) {
            TriCheck::Ok(p) => kept.tris.push(Tri { p, prim: i as u32 }),
            TriCheck::Degenerate
                if check_triangle(mesh.positions, *tri) != TriCheck::Degenerate =>
            {
                kept.degenerate += 1
            }
            _ => {}
        }
    }
    kept
}

/// The flattened instances' triangles in world space, tagged with the instance, and how many
/// triangles only become degenerate there (rounding).
pub(super) fn flatten(
    meshes: &[MeshInput<'_>],
    flat: &[(u32, InstanceInput)],
) -> (Vec<(Tri, u32)>, usize) {
    let mut tris: Vec<(Tri, u32)> = Vec::new();
    let mut degenerate = 0;
    for (id, inst) in flat {
        let kept = world_triangles(&meshes[inst.mesh as usize], inst);
        tris.extend(kept.tris.into_iter().map(|t| (t, *id)));
        degenerate += kept.degenerate;
    }
    (tris, degenerate)
}

/// How many triangles of `mesh` only become degenerate placed by `world_from_object` (what
/// [`flatten`] counts for an instance), without storing any: each triangle's points are
/// moved as it is checked.
pub(super) fn world_degenerate(mesh: &MeshInput<'_>, world_from_object: &Affine3A) -> usize {
    let degenerate = |tri: &[u32; 3]| {
        let TriCheck::Ok(p) = check_triangle(mesh.positions, *tri) else {
            return false;
        };
        classify(p.map(|v| world_from_object.transform_point3(v))) == TriCheck::Degenerate
    };
    mesh.indices.iter().filter(|t| degenerate(t)).count()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Triangles from far apart to nearly and exactly collinear, at scales from 1e-20 to 1e20.
    fn triangles() -> Vec<[Vec3; 3]> {
        let mut s = 7u32;
        let mut next = || {
            s = s.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (s >> 8) as f32 / (1u32 << 24) as f32 - 0.5
        };
        let mut out = Vec::new();
        for i in 0..30_000 {
            let scale = 10f32.powi(i % 41 - 20);
            let a = Vec3::new(next(), next(), next()) * scale;
            let d = Vec3::new(next(), next(), next()) * scale;
            let off = Vec3::new(next(), next(), next()) * scale * 10f32.powi(-(i % 9));
            let t = next() * 4.0;
            let c = match i % 3 {
                0 => a + d * t,                    // on the line, but for the rounding of `a + d t`
                1 => a + d * t + off,              // near it
                _ => a + d * 0.5 * (i % 5) as f32, // exactly on it where 0.5 k is exact
            };
            out.push([a, a + d, c]);
        }
        out
    }

    /// The f32 filter never calls collinear points not collinear; it settles every ordinary
    /// triangle (points apart by more than a ten-thousandth of the edges, scales 1e-12 to 1e12).
    #[test]
    fn the_filter_agrees_with_the_exact_test() {
        let mut collinear = 0;
        for p in triangles() {
            if exactly_collinear(p) {
                collinear += 1;
                assert!(!clearly_not_collinear(p), "{p:?}");
            }
        }
        assert!(collinear > 1_000, "{collinear} collinear");
        let mut ordinary_seen = 0;
        for (i, p) in triangles().into_iter().enumerate() {
            let scale = 10f32.powi(i as i32 % 41 - 20);
            let ordinary = i % 3 == 1 && i % 9 < 4 && (1e-12..=1e12).contains(&scale);
            let edges = (p[1] - p[0]).cross(p[2] - p[0]).length();
            if ordinary && edges > 1e-4 * (p[1] - p[0]).length() * (p[2] - p[0]).length() {
                assert!(clearly_not_collinear(p), "{p:?}");
                ordinary_seen += 1;
            }
        }
        assert!(ordinary_seen > 500, "{ordinary_seen} ordinary triangles");
    }
}
