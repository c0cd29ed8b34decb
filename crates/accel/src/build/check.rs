//! Which triangles are kept: indices in range, three finite points not on one line.

use crate::triangle::Tri;
use crate::types::{InstanceInput, MeshInput};
use glam::{Affine3A, Vec3};

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
    // In f64 the edges of f32 points and their products are exact, so this is exactly "the
    // three points are collinear", without a tolerance that would depend on the scene's scale.
    let [a, b, c] = p.map(|v| v.as_dvec3());
    if (b - a).cross(c - a) == glam::DVec3::ZERO {
        return TriCheck::Degenerate;
    }
    TriCheck::Ok(p)
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
