//! `aperture info`: what a scene contains and how its cameras resolve.

use std::path::PathBuf;

use crate::material_args::MaterialArgs;
use aperture_accel::BvhQuality;
use aperture_scene::{LightKind, LoadOptions, Projection, Scene};
use serde_json::{json, Value};

/// Arguments of `aperture info`.
#[derive(clap::Args)]
pub struct InfoArgs {
    /// The .gltf or .glb file.
    pub scene: PathBuf,
    /// Which glTF scene to describe (default: the file's `scene`, else the first).
    #[arg(long = "scene", value_name = "N")]
    pub scene_index: Option<usize>,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
    /// Time, frame and animation (SPEC §7): bounds, lights and cameras as posed then.
    #[command(flatten)]
    pub when: crate::time_args::TimeArgs,
    /// Motion blur, as `render` would pose it (SPEC §7).
    #[command(flatten)]
    pub motion: crate::motion_args::MotionArgs,
    /// Transmission and variants, as `render` would interpret them.
    #[command(flatten)]
    pub materials: crate::material_args::MaterialArgs,
}

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
    // Degenerate triangles are what the BVH builder leaves out, so ask it.
    let degenerate = aperture_render::build_accel(s, BvhQuality::Fast)
        .stats()
        .degenerate_triangles;
    Counts {
        point: kind(|k| matches!(k, LightKind::Point)),
        spot: kind(|k| matches!(k, LightKind::Spot { .. })),
        directional: kind(|k| matches!(k, LightKind::Directional)),
        emissive_drawn,
        degenerate,
    }
}

/// An f32 as the shortest decimal that reads back to it (0.7, not 0.699999988079071).
fn f(x: f32) -> Value {
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

fn report(s: &Scene, materials: &MaterialArgs) -> Value {
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
        "transmission": crate::info_materials::transmission_json(s, materials.transmission),
        "single_sided": crate::info_materials::sides_json(s, materials.single_sided),
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

/// The report as text: one section after another.
fn print_text(path: &std::path::Path, r: &Value) {
    println!("{}", path.display());
    print_counts(r);
    print_skipped_and_warnings(r);
    crate::info_materials::print_materials(r);
    print_time(r);
    crate::info_motion::print_motion(r);
    print_cameras(r);
}

/// A JSON string ("" when missing).
fn str_of(v: &Value) -> &str {
    v.as_str().unwrap_or_default()
}

/// A JSON count (0 when missing).
fn count(v: &Value) -> u64 {
    v.as_u64().unwrap_or(0)
}

/// Nodes, meshes, triangles, materials, lights, bounds and the world origin.
fn print_counts(r: &Value) {
    let t = &r["triangles"];
    let l = &r["lights"];
    println!(
        "  nodes {}  meshes {}  instances {}  primitives {}",
        count(&r["nodes"]),
        count(&r["meshes"]),
        count(&r["instances"]),
        count(&r["primitives"])
    );
    println!(
        "  triangles: {} unique, {} drawn, {} emissive (drawn), {} degenerate",
        count(&t["unique"]),
        count(&t["drawn"]),
        count(&t["emissive_drawn"]),
        count(&t["degenerate"])
    );
    println!(
        "  materials {}  textures {}  lights: {} point, {} spot, {} directional",
        count(&r["materials"]),
        count(&r["textures"]),
        count(&l["point"]),
        count(&l["spot"]),
        count(&l["directional"])
    );
    println!(
        "  bounds: min {} max {}",
        r["bounds"]["min"], r["bounds"]["max"]
    );
    if r["world_origin"] != json!([0.0, 0.0, 0.0]) {
        println!(
            "  rendered relative to {} (far from the file's origin; kept precise in f64)",
            r["world_origin"]
        );
    }
}

/// What the loader left out, and its warnings.
fn print_skipped_and_warnings(r: &Value) {
    let skipped = &r["skipped"];
    for e in r["extensions"].as_array().into_iter().flatten() {
        let why = e["why"]
            .as_str()
            .map_or(String::new(), |w| format!(" ({w})"));
        println!(
            "  extension: {} {}{why}",
            str_of(&e["name"]),
            str_of(&e["status"])
        );
    }
    if count(&r["hidden_nodes"]) > 0 {
        println!(
            "  hidden: {} node(s) (KHR_node_visibility; not drawn, not lights)",
            count(&r["hidden_nodes"])
        );
    }
    if count(&r["keyed_visibility_nodes"]) > 0 {
        println!(
            "  keyed visibility: {} node(s) (KHR_animation_pointer; shown and hidden per frame)",
            count(&r["keyed_visibility_nodes"])
        );
    }
    if count(&skipped["primitives"]) > 0 {
        println!(
            "  skipped: {} non-triangle primitive(s)",
            count(&skipped["primitives"])
        );
    }
    for f in skipped["features"].as_array().into_iter().flatten() {
        println!("  skipped: {}", f.as_str().unwrap_or_default());
    }
    for w in r["warnings"].as_array().into_iter().flatten() {
        println!("  warning: {}", w.as_str().unwrap_or_default());
    }
}

/// The time the scene is posed at, and its animations.
fn print_time(r: &Value) {
    match r["time"].as_f64() {
        Some(t) => println!("  posed at {t} s"),
        None => println!("  posed as stored (no time given)"),
    }
    for a in r["animations"].as_array().into_iter().flatten() {
        println!(
            "  animation {} {}: {} s to {} s, {} channel(s){}",
            a["index"],
            a["name"]
                .as_str()
                .map_or("(unnamed)".into(), |n| format!("{n:?}")),
            a["start"],
            a["end"],
            a["channels"],
            if a["selected"] == json!(true) {
                ""
            } else {
                " (not played)"
            }
        );
    }
}

/// Each camera: its projection and depth of field.
fn print_cameras(r: &Value) {
    let cams = r["cameras"].as_array().cloned().unwrap_or_default();
    println!("  cameras: {}", cams.len());
    for c in &cams {
        let d = &c["dof"];
        let node = match (c["index"].as_u64(), c["node"].as_u64()) {
            (Some(n), Some(j)) => format!(
                "--camera {}: cameras[{n}] on node {j}",
                c["select"].as_str().unwrap_or_default()
            ),
            _ => format!(
                "automatic, framed on the {}",
                c["framed_on"].as_str().unwrap_or("stored pose")
            ),
        };
        let proj = match c["projection"].as_str() {
            Some("perspective") => format!(
                "perspective yfov {:.2}° aspect {}",
                c["yfov"].as_f64().unwrap_or(0.0).to_degrees(),
                c["aspect_ratio"]
            ),
            _ => format!("orthographic xmag {} ymag {}", c["xmag"], c["ymag"]),
        };
        println!("    {} ({node}): {proj}", c["name"]);
        println!(
            "      dof {}: aperture radius {} m, focus {} m{}, lens {} mm, sensor {}x{} mm {}, blades {}, rotation {}, ratio {}",
            if d["enabled"].as_bool() == Some(true) { "on" } else { "off" },
            d["aperture_radius"],
            d["focus_distance"],
            match d["focus_object"].as_str() {
                Some(o) => format!(" (on {o:?})"),
                None => String::new(),
            },
            d["lens_mm"],
            d["sensor_width"],
            d["sensor_height"],
            d["sensor_fit"].as_str().unwrap_or_default(),
            d["blades"],
            d["rotation"],
            d["ratio"],
        );
    }
}

/// Runs `aperture info`.
pub fn run(args: InfoArgs) -> anyhow::Result<()> {
    let options = LoadOptions {
        scene: args.scene_index,
        // Counts need no texels.
        skip_textures: true,
        time: args.when.seconds(),
        animation: args.when.selection(),
        variant: args.materials.variant.clone(),
        ..LoadOptions::default()
    };
    let loaded = aperture_scene::Animated::load(&args.scene, &options)
        .and_then(|a| a.scene_at(options.time).map(|s| (a, s)));
    let (animated, s) = loaded
        .map_err(|e| anyhow::anyhow!(e).context(format!("loading {}", args.scene.display())))?;
    let mut r = report(&s, &args.materials);
    let when = (options.time, args.when.fps);
    r["motion"] = crate::info_motion::motion_json(&args.motion, &animated, &s, when)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&r)?);
    } else {
        print_text(&args.scene, &r);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use aperture_scene::{Camera, Dof, Instance, Light, Material, Mesh};
    use glam::{Affine3A, Vec3};

    /// Two instances of a two-triangle mesh whose second triangle is emissive.
    fn scene() -> Scene {
        let mesh = Mesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z],
            normals: vec![Vec3::Z; 4],
            indices: vec![[0, 1, 2], [0, 2, 3]],
            material_ids: vec![0, 1],
            ..Mesh::default()
        };
        let glow = Material {
            emissive_factor: Vec3::ONE,
            ..Material::default()
        };
        let light = |kind| Light {
            name: None,
            kind,
            position: Vec3::ZERO,
            direction: Vec3::NEG_Z,
            intensity: Vec3::ONE,
        };
        Scene {
            meshes: vec![mesh],
            instances: vec![
                Instance {
                    mesh: 0,
                    world_from_object: Affine3A::IDENTITY,
                    node: 0,
                    materials: 0,
                },
                Instance {
                    mesh: 0,
                    world_from_object: Affine3A::from_translation(Vec3::new(2.0, 0.0, 0.0)),
                    node: 1,
                    materials: 0,
                },
            ],
            materials: vec![Material::default(), glow],
            lights: vec![
                light(LightKind::Point),
                light(LightKind::Point),
                light(LightKind::Directional),
            ],
            cameras: vec![Camera {
                name: "Cam".into(),
                node: Some(2),
                index: Some(0),
                world_from_camera: Affine3A::IDENTITY,
                projection: Projection::Perspective {
                    yfov: 0.7,
                    aspect_ratio: Some(1.5),
                },
                dof: Dof {
                    enabled: true,
                    aperture_radius: 0.25,
                    focus_object: Some("Target".into()),
                    ..Dof::default()
                },
            }],
            ..Scene::default()
        }
    }

    #[test]
    fn json_report_has_the_documented_keys_and_counts() {
        let r = report(&scene(), &Default::default());
        assert_eq!(r["triangles"]["unique"], 2);
        assert_eq!(r["triangles"]["drawn"], 4);
        assert_eq!(r["triangles"]["emissive_drawn"], 2);
        assert_eq!(r["lights"]["point"], 2);
        assert_eq!(r["lights"]["spot"], 0);
        assert_eq!(r["lights"]["directional"], 1);
        assert_eq!(r["bounds"]["min"], json!([0.0, 0.0, 0.0]));
        assert_eq!(r["bounds"]["max"], json!([3.0, 1.0, 1.0]));
        let c = &r["cameras"][0];
        assert_eq!(c["name"], "Cam");
        assert_eq!(c["node"], 2);
        assert_eq!(c["projection"], "perspective");
        assert_eq!(c["yfov"], 0.7);
        assert_eq!(c["aspect_ratio"], 1.5);
        assert_eq!(c["framed_on"], Value::Null, "a file's camera is not framed");
        let d = &c["dof"];
        assert_eq!(d["enabled"], true);
        assert_eq!(d["aperture_radius"], 0.25);
        assert_eq!(d["focus_distance"], 10.0);
        assert_eq!(d["focus_object"], "Target");
        for key in ["lens_mm", "blades", "rotation", "ratio"] {
            assert!(d.get(key).is_some_and(|v| !v.is_null()), "{key}");
        }
    }

    /// A recentred scene reports bounds and cameras in the file's coordinates.
    #[test]
    fn extensions_are_listed_with_what_aperture_does_with_them() {
        use aperture_scene::ExtensionStatus;
        let mut s = scene();
        s.stats.extensions = vec![
            ("KHR_node_visibility".into(), ExtensionStatus::Supported),
            ("KHR_xmp".into(), ExtensionStatus::Ignored),
        ];
        s.stats.hidden_nodes = 3;
        s.stats.keyed_visibility_nodes = 2;
        let r = report(&s, &Default::default());
        assert_eq!(r["extensions"][0]["name"], "KHR_node_visibility");
        assert_eq!(r["extensions"][0]["status"], "supported");
        assert!(r["extensions"][0].get("why").is_none());
        assert_eq!(r["extensions"][1]["status"], "ignored");
        assert!(r["extensions"][1]["why"]
            .as_str()
            .unwrap()
            .contains("optional"));
        assert_eq!(r["hidden_nodes"], 3);
        assert_eq!(r["keyed_visibility_nodes"], 2);
    }

    #[test]
    fn recentred_scenes_report_file_coordinates() {
        let mut s = scene();
        s.world_origin = glam::DVec3::new(1e6, -2e6, 0.5);
        let r = report(&s, &Default::default());
        assert_eq!(r["world_origin"], json!([1e6, -2e6, 0.5]));
        assert_eq!(r["bounds"]["min"], json!([1e6, -2e6, 0.5]));
        assert_eq!(r["bounds"]["max"], json!([1e6 + 3.0, -2e6 + 1.0, 1.5]));
        assert_eq!(r["cameras"][0]["position"], json!([1e6, -2e6, 0.5]));
        assert_eq!(
            report(&scene(), &Default::default())["world_origin"],
            json!([0.0, 0.0, 0.0])
        );
    }

    /// The automatic camera says it is framed on the stored pose (issue 58), in JSON and text.
    #[test]
    fn the_automatic_camera_says_what_it_is_framed_on() {
        let mut s = scene();
        s.cameras[0].node = None;
        s.cameras[0].index = None;
        let r = report(&s, &Default::default());
        assert_eq!(r["cameras"][0]["framed_on"], "stored pose");
    }

    #[test]
    fn empty_scene_has_null_bounds() {
        let r = report(&Scene::default(), &Default::default());
        assert_eq!(r["bounds"]["min"], Value::Null);
        assert_eq!(r["triangles"]["drawn"], 0);
    }
}
