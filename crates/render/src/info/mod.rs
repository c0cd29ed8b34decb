//! What a scene contains and how the renderer reads it, as one JSON object: the report of
//! `aperture info --json` and of Python's `scene.info()` (the keys are SPEC §2's).

pub mod materials;
pub mod memory;
pub mod motion;
pub mod prescription;
#[cfg(test)]
mod tests;

use aperture_scene::{LightKind, Projection, Scene};
use aperture_shading::Convention;
use serde_json::{json, Value};

/// Counts that are not stored on the scene directly.
struct Counts {
    point: usize,
    spot: usize,
    directional: usize,
    emissive_drawn: usize,
    degenerate: usize,
}

fn counts(s: &Scene) -> Counts {
    let kind = |f: fn(&LightKind) -> bool| s.lights.iter().filter(|l| f(&l.kind)).count();
    let emissive = |ids: &[u32]| {
        ids.iter()
            .filter(|&&id| {
                s.materials
                    .get(id as usize)
                    .is_some_and(|m| m.is_emissive())
            })
            .count()
    };
    // Per mesh with its own materials, and per material set (each counted once).
    let per_mesh: Vec<usize> = s.meshes.iter().map(|m| emissive(&m.material_ids)).collect();
    let per_set: Vec<usize> = s.material_sets.iter().map(|m| emissive(m)).collect();
    let emissive_drawn = s
        .instances
        .iter()
        .map(|i| match i.materials {
            0 => per_mesh.get(i.mesh as usize).copied().unwrap_or(0),
            k => per_set.get(k as usize - 1).copied().unwrap_or(0),
        })
        .sum();
    // Degenerate triangles are what the BVH builder leaves out: counted as it counts them,
    // without building (a report traces no ray).
    let degenerate = crate::frame_accel::accel_input_counts(s).degenerate_triangles;
    Counts {
        point: kind(|k| matches!(k, LightKind::Point)),
        spot: kind(|k| matches!(k, LightKind::Spot { .. })),
        directional: kind(|k| matches!(k, LightKind::Directional)),
        emissive_drawn,
        degenerate,
    }
}

/// An f32 as the shortest decimal that reads back to it (0.7, not 0.699999988079071).
pub(crate) fn f(x: f32) -> Value {
    json!(x.to_string().parse::<f64>().unwrap_or(f64::from(x)))
}

fn v3(v: glam::Vec3) -> Value {
    json!([f(v.x), f(v.y), f(v.z)])
}

/// A point of the scene in the file's coordinates: the loader may have moved the origin
/// (`Scene::world_origin`) to keep far-away scenes precise; users know the file's numbers.
fn file_point(origin: glam::DVec3, p: glam::Vec3) -> Value {
    if origin == glam::DVec3::ZERO {
        return v3(p);
    }
    let q = origin + p.as_dvec3();
    json!([q.x, q.y, q.z])
}

fn camera_json(s: &Scene, i: usize) -> Value {
    let (c, origin) = (&s.cameras[i], s.world_origin);
    let (projection, yfov, aspect, xmag, ymag) = match c.projection {
        Projection::Perspective { yfov, aspect_ratio } => {
            ("perspective", Some(yfov), aspect_ratio, None, None)
        }
        Projection::Orthographic { xmag, ymag } => {
            ("orthographic", None, None, Some(xmag), Some(ymag))
        }
    };
    let d = &c.dof;
    json!({
        "name": c.name,
        "node": c.node,
        "index": c.index,
        "select": s.camera_selector(i),
        "projection": projection,
        "yfov": yfov.map(f),
        "aspect_ratio": aspect.map(f),
        "xmag": xmag.map(f),
        "ymag": ymag.map(f),
        // The automatic camera is framed once, on the stored pose (SPEC §3), whatever the time.
        "framed_on": c.node.is_none().then_some("stored pose"),
        "position": file_point(origin, c.world_from_camera.translation.into()),
        "direction": v3((-c.world_from_camera.matrix3.z_axis).into()),
        "dof": {
            "enabled": d.enabled,
            "aperture_radius": f(d.aperture_radius),
            "focus_distance": f(d.focus_distance),
            "lens_mm": f(d.lens_mm),
            "sensor_width": f(d.sensor_width),
            "sensor_height": f(d.sensor_height),
            "sensor_fit": format!("{:?}", d.sensor_fit).to_uppercase(),
            "blades": d.blades,
            "rotation": f(d.rotation),
            "ratio": f(d.ratio),
            "focus_object": d.focus_object,
            "vignetting": f(d.lens_options.vignetting),
            "distortion": {
                "k1": f(d.lens_options.distortion.k1),
                "k2": f(d.lens_options.distortion.k2),
                "k3": f(d.lens_options.distortion.k3),
                "p1": f(d.lens_options.distortion.p1),
                "p2": f(d.lens_options.distortion.p2),
            },
            "prescription": prescription::json(d),
            "aperture_image": d.lens_options.aperture_image.as_ref().map(|i| i.source.clone()),
            "chromatic_lateral": f(d.lens_options.chromatic.lateral),
            "chromatic_longitudinal": f(d.lens_options.chromatic.longitudinal),
        },
    })
}

/// World-space bounds of each drawing node's geometry (every instance it places), by node index.
fn node_bounds(s: &Scene) -> Vec<Value> {
    let mut by_node: std::collections::BTreeMap<u32, aperture_scene::Bounds> = Default::default();
    for inst in &s.instances {
        let Some(mesh) = s.meshes.get(inst.mesh as usize) else {
            continue;
        };
        let b = by_node
            .entry(inst.node)
            .or_insert(aperture_scene::Bounds::EMPTY);
        for p in &mesh.positions {
            b.include(inst.world_from_object.transform_point3(*p));
        }
    }
    by_node
        .into_iter()
        .filter(|(_, b)| !b.is_empty())
        .map(|(node, b)| {
            json!({
                "node": node,
                "min": file_point(s.world_origin, b.min),
                "max": file_point(s.world_origin, b.max),
            })
        })
        .collect()
}

/// The report of `scene` (`aperture info --json` prints it; Python's `scene.info()` returns
/// it): counts, bounds, extensions, what transmission and single-sided faces mean under the
/// `transmission` and `sides` conventions, animations and cameras. `motion` is
/// [`motion::motion_json`]'s, added by whoever knows the frame.
pub fn report(s: &Scene, transmission: Convention, sides: Convention) -> Value {
    let c = counts(s);
    let b = s.bounds();
    let bounds = if b.is_empty() {
        json!({"min": null, "max": null})
    } else {
        json!({
            "min": file_point(s.world_origin, b.min),
            "max": file_point(s.world_origin, b.max),
        })
    };
    json!({
        "nodes": s.stats.nodes,
        "meshes": s.meshes.len(),
        "instances": s.instances.len(),
        "primitives": s.stats.primitives,
        "triangles": {
            "unique": s.unique_triangle_count(),
            "drawn": s.drawn_triangle_count(),
            "emissive_drawn": c.emissive_drawn,
            "degenerate": c.degenerate,
        },
        "materials": s.materials.len(),
        "textures": s.textures.len(),
        "lights": {"point": c.point, "spot": c.spot, "directional": c.directional},
        "bounds": bounds,
        "node_bounds": node_bounds(s),
        "world_origin": [s.world_origin.x, s.world_origin.y, s.world_origin.z],
        "hidden_nodes": s.stats.hidden_nodes,
        "keyed_visibility_nodes": s.stats.keyed_visibility_nodes,
        "extensions": extensions_json(&s.stats.extensions),
        "skipped": {
            "primitives": s.stats.skipped_primitives,
            "features": s.stats.skipped_features,
        },
        "warnings": s.stats.warnings,
        "generator": s.stats.generator,
        "transmission": materials::transmission_json(s, transmission),
        "single_sided": materials::sides_json(s, sides),
        "variants": s.stats.variants,
        "variant": s.stats.variant,
        "time": s.stats.time.map(f),
        "animations": s
            .stats
            .animations
            .iter()
            .map(|a| json!({
                "index": a.index,
                "name": a.name,
                "start": f(a.start),
                "end": f(a.end),
                "duration": f(a.end - a.start.min(0.0)),
                "channels": a.channels,
                "selected": a.selected,
            }))
            .collect::<Vec<_>>(),
        "cameras": (0..s.cameras.len())
            .map(|i| camera_json(s, i))
            .collect::<Vec<_>>(),
    })
}

/// Each extension the file uses: its name, what aperture does with it, and why when ignored.
fn extensions_json(used: &[(String, aperture_scene::ExtensionStatus)]) -> Value {
    use aperture_scene::ExtensionStatus;
    let row = |(name, status): &(String, ExtensionStatus)| match status {
        ExtensionStatus::Supported => json!({"name": name, "status": "supported"}),
        ExtensionStatus::Ignored => json!({"name": name, "status": "ignored",
            "why": "optional and not implemented: the file renders without it"}),
    };
    Value::Array(used.iter().map(row).collect())
}
