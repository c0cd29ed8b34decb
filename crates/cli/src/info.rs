//! `aperture info`: what a scene contains and how its cameras resolve.

use std::path::PathBuf;

use aperture_render::info;
use aperture_scene::LoadOptions;
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
    /// Also report the memory each stage holds: the file, the meshes by attribute, the
    /// decoded textures and the BVH (nodes, triangle store); decodes the textures and builds
    /// the BVH (medium quality) as `render` would, which info otherwise skips.
    #[arg(long)]
    pub memory: bool,
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

/// The report as text: one section after another.
fn print_text(path: &std::path::Path, r: &Value) {
    println!("{}", path.display());
    print_counts(r);
    print_skipped_and_warnings(r);
    crate::info_materials::print_materials(r);
    print_time(r);
    crate::info_motion::print_motion(r);
    print_cameras(r);
    crate::info_memory::print_memory(r);
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
/// The `lens:` line of the bokeh image and chromatic aberration, when either is set.
fn print_bokeh_chromatic(d: &Value) {
    let (lat, lon) = (&d["chromatic_lateral"], &d["chromatic_longitudinal"]);
    let chromatic = [lat, lon]
        .iter()
        .any(|v| v.as_f64().is_some_and(|v| v != 0.0));
    if let Some(image) = d["aperture_image"].as_str() {
        println!("      lens: aperture image {image:?}");
    }
    if chromatic {
        println!("      lens: chromatic lateral {lat}, longitudinal {lon}");
    }
}

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
        let k = &d["distortion"];
        let distorted = ["k1", "k2", "k3", "p1", "p2"]
            .iter()
            .any(|c| k[c].as_f64().is_some_and(|v| v != 0.0));
        if d["vignetting"].as_f64().is_some_and(|v| v != 0.0) || distorted {
            println!(
                "      lens: vignetting {}, distortion k1 {} k2 {} k3 {} p1 {} p2 {}",
                d["vignetting"], k["k1"], k["k2"], k["k3"], k["p1"], k["p2"]
            );
        }
        crate::info_prescription::print(&d["prescription"]);
        print_bokeh_chromatic(d);
    }
}

/// Runs `aperture info`.
pub fn run(args: InfoArgs) -> anyhow::Result<()> {
    let options = LoadOptions {
        scene: args.scene_index,
        // Counts need no texels; the memory report measures them.
        skip_textures: !args.memory,
        time: args.when.seconds(),
        animation: args.when.selection(),
        variant: args.materials.variant.clone(),
        ..LoadOptions::default()
    };
    let loaded = aperture_scene::Animated::load(&args.scene, &options)
        .and_then(|a| a.scene_at(options.time).map(|s| (a, s)));
    let (animated, s) = loaded
        .map_err(|e| anyhow::anyhow!(e).context(format!("loading {}", args.scene.display())))?;
    let m = &args.materials;
    let mut r = info::report(&s, m.transmission, m.single_sided);
    let when = (options.time, args.when.fps);
    r["motion"] = info::motion::motion_json(&args.motion.overrides(), &animated, &s, when)?;
    if args.memory {
        let quality = aperture_accel::BvhQuality::Medium;
        let accel = aperture_render::build_accel(&s, quality);
        r["memory"] = info::memory::memory_json(&info::memory::MemoryInputs {
            scene: &s,
            file_bytes: std::fs::metadata(&args.scene).ok().map(|m| m.len()),
            textures_decoded: true,
            accel: Some((accel.stats(), quality)),
        });
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&r)?);
    } else {
        print_text(&args.scene, &r);
    }
    Ok(())
}
