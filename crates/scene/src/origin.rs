//! The world origin a scene is expressed relative to, and meshes recentred on their bounds, so
//! scenes far from the file's origin keep their float32 precision.

use glam::{DAffine3, DVec3};

use crate::types::SceneStats;

/// Moves a mesh whose vertices sit far from its own origin (farther than its size) to be centred
/// on its bounds, and returns the offset to add back in front of every instance transform.
///
/// Why: vertex coordinates near 1e6 have f32 spacing 0.0625 and every ray transformed into that
/// object space inherits that error. The subtraction is done in f64 and the stored f32 values
/// are exact multiples of their spacing, so the recentred vertices lose nothing that the file
/// held.
pub(crate) fn recentre(mesh: &mut crate::types::Mesh) -> DVec3 {
    let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for p in &mesh.positions {
        lo = lo.min(p.as_dvec3());
        hi = hi.max(p.as_dvec3());
    }
    if !(lo.is_finite() && hi.is_finite()) {
        return DVec3::ZERO;
    }
    let centre = 0.5 * (lo + hi);
    if centre.length() <= (hi - lo).length() {
        return DVec3::ZERO;
    }
    for p in &mut mesh.positions {
        *p = (p.as_dvec3() - centre).as_vec3();
    }
    centre
}

/// The world point the loaded scene is expressed relative to (see [`Scene::world_origin`]): the
/// centre of the drawn geometry's bounds when that centre is farther from the file's origin than
/// the geometry is large (a scene placed at geographic coordinates, say), else the file's
/// origin, so scenes modelled around the origin keep the coordinates their files give.
///
/// The geometry's centre, rather than a camera's position, because a file has any number of
/// cameras (or none) and the bounds are what every camera looks at.
pub(crate) fn world_origin(
    meshes: &[std::sync::Arc<crate::types::Mesh>],
    placed: &[(u32, DAffine3, u32)],
    stats: &mut SceneStats,
) -> DVec3 {
    // Per mesh, once (a mesh may be placed thousands of times): object-space bounds and the
    // shortest edge.
    let per_mesh: Vec<Option<(DVec3, DVec3, f64)>> = meshes
        .iter()
        .map(|m| {
            let (mut mlo, mut mhi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
            for p in &m.positions {
                mlo = mlo.min(p.as_dvec3());
                mhi = mhi.max(p.as_dvec3());
            }
            (mlo.is_finite() && mhi.is_finite()).then(|| (mlo, mhi, shortest_edge(m)))
        })
        .collect();
    let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for (mesh, world, _) in placed {
        let Some(&Some((mlo, mhi, _))) = per_mesh.get(*mesh as usize) else {
            continue;
        };
        for k in 0..8 {
            let corner = DVec3::select(
                glam::BVec3::new(k & 1 != 0, k & 2 != 0, k & 4 != 0),
                mhi,
                mlo,
            );
            let w = world.transform_point3(corner);
            lo = lo.min(w);
            hi = hi.max(w);
        }
    }
    if !(lo.is_finite() && hi.is_finite()) {
        return DVec3::ZERO;
    }
    let centre = 0.5 * (lo + hi);
    let size = (hi - lo).length();
    let origin = if centre.length() > size {
        centre
    } else {
        DVec3::ZERO
    };
    // What recentring cannot fix: a scene so large around its own centre that f32 positions at
    // its edge are coarse next to its smallest triangles.
    let reach = (hi - origin).abs().max((lo - origin).abs()).max_element();
    let spacing = reach * f64::from(f32::EPSILON);
    let detail = placed
        .iter()
        .filter_map(|(mesh, world, _)| {
            let (_, _, edge) = (*per_mesh.get(*mesh as usize)?)?;
            let shrink = [
                world.matrix3.x_axis,
                world.matrix3.y_axis,
                world.matrix3.z_axis,
            ]
            .map(|c| c.length())
            .into_iter()
            .fold(f64::INFINITY, f64::min);
            Some(edge * shrink)
        })
        .filter(|d| *d > 0.0)
        .fold(f64::INFINITY, f64::min);
    if spacing * MIN_STEPS_PER_EDGE > detail {
        stats.warnings.push(format!(
            "the scene reaches {reach:.3e} units from its centre, where float32 positions are \
             {spacing:.1e} apart, yet its shortest triangle edge is {detail:.1e}: such details \
             are distorted or cracked (docs/accuracy.md, float32 limits)"
        ));
    }
    if size > 0.0 && size < MIN_EXTENT {
        stats.warnings.push(format!(
            "the scene is only {size:.1e} units across: below {MIN_EXTENT:.0e} squared distances \
             and light falloff near float32's smallest normal numbers change the image; model it \
             in smaller units (docs/accuracy.md, float32 limits)"
        ));
    }
    origin
}

/// Smallest scene diagonal accepted silently. Measured (docs/accuracy.md): the stress scene
/// scaled to 8.6e-8 units across renders its unscaled image (same-seed rmse 0.0000 × the
/// seed-to-seed rmse); at 8.6e-10 across it drifts (0.135).
const MIN_EXTENT: f64 = 1e-8;

/// A triangle edge shorter than this many f32 steps at the scene's edge is reported: vertices
/// round by up to half a step, so such an edge may change length by more than 1/16.
const MIN_STEPS_PER_EDGE: f64 = 16.0;

/// The shortest non-zero edge of a mesh's triangles, in object space (infinity if none).
fn shortest_edge(mesh: &crate::types::Mesh) -> f64 {
    let p = |i: u32| mesh.positions.get(i as usize).map(|v| v.as_dvec3());
    mesh.indices
        .iter()
        .flat_map(|&[a, b, c]| [(a, b), (b, c), (c, a)])
        .filter_map(|(a, b)| Some(p(a)?.distance(p(b)?)))
        .filter(|d| *d > 0.0)
        .fold(f64::INFINITY, f64::min)
}
