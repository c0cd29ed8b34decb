//! `scene.info()`: what the posed scene contains, as a dict with the keys and values of
//! `aperture info --json` (which the command line builds itself; this is the part built from
//! the library's scene: counts, bounds, animations, variants and cameras).

use aperture_scene::{LightKind, Projection, Scene};
use serde_json::{json, Value};

/// An f32 as the shortest decimal that reads back to it (as `aperture info` prints it).
fn f(x: f32) -> Value {
    json!(x.to_string().parse::<f64>().unwrap_or(f64::from(x)))
}

fn v3(v: glam::Vec3) -> Value {
    json!([f(v.x), f(v.y), f(v.z)])
}

/// A point in the file's coordinates (the loader may have moved the origin).
fn file_point(origin: glam::DVec3, p: glam::Vec3) -> Value {
    if origin == glam::DVec3::ZERO {
        return v3(p);
    }
    let q = origin + p.as_dvec3();
    json!([q.x, q.y, q.z])
}

fn camera(s: &Scene, i: usize) -> Value {
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
        },
    })
}

/// The report of `s`.
pub(crate) fn report(s: &Scene) -> Value {
    let kind = |k: fn(&LightKind) -> bool| s.lights.iter().filter(|l| k(&l.kind)).count();
    let b = s.bounds();
    let bounds = match b.is_empty() {
        true => json!({"min": null, "max": null}),
        false => json!({
            "min": file_point(s.world_origin, b.min),
            "max": file_point(s.world_origin, b.max),
        }),
    };
    json!({
        "nodes": s.stats.nodes,
        "meshes": s.meshes.len(),
        "instances": s.instances.len(),
        "primitives": s.stats.primitives,
        "triangles": {
            "unique": s.unique_triangle_count(),
            "drawn": s.drawn_triangle_count(),
        },
        "materials": s.materials.len(),
        "textures": s.textures.len(),
        "lights": {
            "point": kind(|k| matches!(k, LightKind::Point)),
            "spot": kind(|k| matches!(k, LightKind::Spot { .. })),
            "directional": kind(|k| matches!(k, LightKind::Directional)),
        },
        "bounds": bounds,
        "world_origin": [s.world_origin.x, s.world_origin.y, s.world_origin.z],
        "hidden_nodes": s.stats.hidden_nodes,
        "warnings": s.stats.warnings,
        "generator": s.stats.generator,
        "variants": s.stats.variants,
        "variant": s.stats.variant,
        "time": s.stats.time.map(f),
        "animations": s.stats.animations.iter().map(|a| json!({
            "index": a.index,
            "name": a.name,
            "start": f(a.start),
            "end": f(a.end),
            "duration": f(a.end - a.start.min(0.0)),
            "channels": a.channels,
            "selected": a.selected,
        })).collect::<Vec<_>>(),
        "cameras": (0..s.cameras.len()).map(|i| camera(s, i)).collect::<Vec<_>>(),
    })
}
