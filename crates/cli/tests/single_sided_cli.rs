//! Single-sided faces (issue 50): a red `doubleSided: false` quad seen from behind against a
//! white sky is invisible under glTF's meaning and red under Cycles' (`--single-sided`), `auto`
//! choosing by `asset.generator`; a double-sided quad is red under every mode. On the Khronos
//! TextureSettingsTest, the "single-sided" test cell shows its red ✗ only under `blender`.
//! The back of a culled single-sided emitter lights nothing, by light sampling either.

mod common;

use aperture_imageio::read_exr;
use common::{aperture, quad_glb, quad_json, sample, Scratch};
use serde_json::json;
use std::process::Command;

/// The quad (facing +Z) in red, seen from z = −3 looking along +Z (its back).
fn quad_from_behind(double_sided: bool, generator: Option<&str>) -> Vec<u8> {
    let mut doc = quad_json();
    if let Some(g) = generator {
        doc["asset"]["generator"] = json!(g);
    }
    doc["materials"] = json!([{"doubleSided": double_sided,
        "pbrMetallicRoughness": {"baseColorFactor": [1.0, 0.0, 0.0, 1.0], "metallicFactor": 0.0}}]);
    doc["meshes"] = json!([{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1,
        "material": 0}]}]);
    doc["cameras"] = json!([{"type": "perspective", "perspective": {"yfov": 0.3, "znear": 0.1}}]);
    doc["nodes"] = json!([{"mesh": 0},
        {"camera": 0, "translation": [0.0, 0.0, -3.0], "rotation": [0.0, 1.0, 0.0, 0.0]}]);
    doc["scenes"] = json!([{"nodes": [0, 1]}]);
    quad_glb(&doc)
}

/// A white floor (double-sided) and above it a single-sided emissive quad facing up, seen from
/// beside the floor below the quad: only the quad's back faces the floor and the camera.
fn emitter_facing_away() -> Vec<u8> {
    let mut doc = quad_json();
    doc["materials"] = json!([
        {"doubleSided": true, "pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0],
            "metallicFactor": 0.0}},
        {"doubleSided": false, "emissiveFactor": [1.0, 1.0, 1.0],
            "pbrMetallicRoughness": {"baseColorFactor": [0.0, 0.0, 0.0, 1.0], "metallicFactor": 0.0}}
    ]);
    let prim = |m: usize| {
        json!({"primitives": [{"attributes": {"POSITION": 0}, "indices": 1,
        "material": m}]})
    };
    doc["meshes"] = json!([prim(0), prim(1)]);
    doc["cameras"] = json!([{"type": "perspective", "perspective": {"yfov": 1.0, "znear": 0.1}}]);
    // −90° about x: the quad's +z normal turns to +y.
    let up = [
        -std::f64::consts::FRAC_1_SQRT_2,
        0.0,
        0.0,
        std::f64::consts::FRAC_1_SQRT_2,
    ];
    doc["nodes"] = json!([
        {"mesh": 0, "rotation": up, "scale": [5.0, 5.0, 1.0]},
        {"mesh": 1, "rotation": up, "translation": [0.0, 1.0, 0.0]},
        {"camera": 0, "translation": [0.0, 0.5, 3.0]}]);
    doc["scenes"] = json!([{"nodes": [0, 1, 2]}]);
    quad_glb(&doc)
}

#[test]
fn back_of_a_single_sided_emitter_lights_nothing() {
    let dir = Scratch::new("single-sided-emitter");
    let file = emitter_facing_away();
    let args = |mode| {
        [
            "--single-sided",
            mode,
            "--env",
            "0,0,0",
            "--max-bounces",
            "0",
        ]
    };
    let gltf = mean(&dir, &file, "gltf", &args("gltf"));
    let blender = mean(&dir, &file, "blender", &args("blender"));
    // Culled, nothing is lit and nothing emits towards the camera; both sides shown, the
    // quad's back glows and lights the floor.
    assert_eq!(gltf, [0.0; 3], "light sampling met the culled back");
    assert!(blender[1] > 0.05, "{blender:?}");
}

/// The mean colour of a render of `file` with `args`.
fn mean(dir: &Scratch, file: &[u8], name: &str, args: &[&str]) -> [f32; 3] {
    let scene = dir.path(&format!("{name}.glb"));
    std::fs::write(&scene, file).unwrap();
    let out = dir.path(&format!("{name}.exr"));
    let status = Command::new(aperture())
        .arg("render")
        .arg(&scene)
        .arg("-o")
        .arg(&out)
        .args(["--width", "8", "--height", "8", "--spp", "4", "--quiet"])
        .args(args)
        .status()
        .unwrap();
    assert!(status.success(), "{name} {args:?}");
    let img = read_exr(&out).unwrap();
    let n = img.rgba.len() as f32;
    let sum = img
        .rgba
        .iter()
        .fold([0.0; 3], |a, p| [a[0] + p[0], a[1] + p[1], a[2] + p[2]]);
    sum.map(|c| c / n)
}

/// Green is what tells the sky (white) from the quad (red, no green).
fn sees_quad(rgb: [f32; 3]) -> bool {
    rgb[1] < 0.5 && rgb[0] > 0.05
}

#[test]
fn back_of_a_single_sided_quad_under_each_mode() {
    let dir = Scratch::new("single-sided");
    let blender = Some("Khronos glTF Blender I/O v4.2.70");
    let cases = [
        // (double-sided, generator, --single-sided, the quad is seen)
        (false, None, "auto", false),
        (false, None, "gltf", false),
        (false, None, "blender", true),
        (false, blender, "auto", true),
        (false, blender, "gltf", false),
        (true, None, "auto", true),
        (true, None, "gltf", true),
        (true, blender, "blender", true),
    ];
    for (k, (double, generator, mode, seen)) in cases.into_iter().enumerate() {
        let rgb = mean(
            &dir,
            &quad_from_behind(double, generator),
            &format!("case{k}"),
            &["--single-sided", mode, "--env", "1,1,1"],
        );
        assert_eq!(
            sees_quad(rgb),
            seen,
            "doubleSided {double}, generator {generator:?}, --single-sided {mode}: {rgb:?}"
        );
    }
}

#[test]
fn info_says_which_meaning_applies() {
    let dir = Scratch::new("single-sided-info");
    let scene = dir.path("q.glb");
    std::fs::write(&scene, quad_from_behind(false, None)).unwrap();
    let out = Command::new(aperture())
        .arg("info")
        .arg(&scene)
        .output()
        .unwrap();
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        text.contains("single-sided faces: gltf (the file names no asset.generator); 1 single-sided material(s), their backs invisible to every ray"),
        "{text}"
    );
}

/// The share of strongly red pixels in the "single-sided" test cell of TextureSettingsTest
/// (rendered 480 × 270 from its automatic camera, the cell at x 238–258, y 70–92).
fn red_share(dir: &Scratch, mode: &str) -> Option<f32> {
    let scene = sample("correctness/TextureSettingsTest/TextureSettingsTest.glb")?;
    let out = dir.path(&format!("tst-{mode}.exr"));
    let status = Command::new(aperture())
        .arg("render")
        .arg(&scene)
        .arg("-o")
        .arg(&out)
        .args([
            "--width", "480", "--height", "270", "--spp", "4", "--env", "1,1,1",
        ])
        .args(["--quiet", "--single-sided", mode])
        .status()
        .unwrap();
    assert!(status.success());
    let img = read_exr(&out).unwrap();
    let (mut red, mut all) = (0, 0);
    for y in 70..92 {
        for x in 238..258 {
            let p = img.rgba[y * img.width as usize + x];
            all += 1;
            if p[0] > 0.4 && p[1] < 0.2 && p[2] < 0.2 {
                red += 1;
            }
        }
    }
    Some(red as f32 / all as f32)
}

#[test]
fn texture_settings_test_single_sided_marker() {
    let dir = Scratch::new("single-sided-khronos");
    let (Some(gltf), Some(blender)) = (red_share(&dir, "gltf"), red_share(&dir, "blender")) else {
        return;
    };
    // Both sides shown: the ✗ in front covers the cell; culled: the ✓ behind it shows (with a
    // faint reflection of the ✗'s front, which faces it). Measured: 0.105 and 0.005.
    assert!(blender > 0.05, "the ✗ should show under blender: {blender}");
    assert!(gltf < 0.25 * blender, "gltf {gltf} vs blender {blender}");
}

/// A white floor lit by a point light through a single-sided quad between them whose back
/// faces the floor, seen from between floor and quad (the quad's back in view); `with_quad`
/// false leaves the quad out of the scene.
fn floor_under_a_one_way_quad(with_quad: bool) -> Vec<u8> {
    let mut doc = quad_json();
    doc["extensionsUsed"] = json!(["KHR_lights_punctual"]);
    doc["extensions"] = json!({"KHR_lights_punctual": {"lights": [
        {"type": "point", "color": [1.0, 0.9, 0.8], "intensity": 40.0}]}});
    doc["materials"] = json!([
        {"doubleSided": true, "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1.0],
            "metallicFactor": 0.0, "roughnessFactor": 0.6}},
        {"doubleSided": false, "pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.1, 0.1, 1.0],
            "metallicFactor": 0.0}}
    ]);
    let prim = |m: usize| json!({"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": m}]});
    doc["meshes"] = json!([prim(0), prim(1)]);
    doc["cameras"] = json!([{"type": "perspective", "perspective": {"yfov": 1.2, "znear": 0.1}}]);
    // −90° about x: the quad's +z normal turns to +y (the floor's front, the quad's front up).
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let up = [-h, 0.0, 0.0, h];
    doc["nodes"] = json!([
        {"mesh": 0, "rotation": up, "scale": [5.0, 5.0, 1.0]},
        {"mesh": 1, "rotation": up, "translation": [0.0, 1.0, 0.0], "scale": [1.5, 1.5, 1.0]},
        {"camera": 0, "translation": [0.0, 0.6, 3.0]},
        {"translation": [0.0, 3.0, 0.0], "extensions": {"KHR_lights_punctual": {"light": 0}}}]);
    let nodes = if with_quad {
        json!([0, 1, 2, 3])
    } else {
        json!([0, 2, 3])
    };
    doc["scenes"] = json!([{"nodes": nodes}]);
    quad_glb(&doc)
}

/// Under glTF's meaning a culled back is not there for any ray: camera rays see the sky
/// through it, shadow rays from the floor reach the light through it, bounces leave through
/// it. The image equals the render without the quad bit for bit (the immediate and the
/// deferred shadow rays both pass it); with both sides seen it shadows the floor.
#[test]
fn a_culled_back_is_absent_for_camera_shadow_and_bounce_rays() {
    let dir = Scratch::new("single-sided-absent");
    let render = |name: &str, with_quad: bool, mode: &str| {
        let scene = dir.path(&format!("{name}.glb"));
        std::fs::write(&scene, floor_under_a_one_way_quad(with_quad)).unwrap();
        let out = dir.path(&format!("{name}.exr"));
        let status = Command::new(aperture())
            .arg("render")
            .arg(&scene)
            .arg("-o")
            .arg(&out)
            .args(["--width", "24", "--height", "16", "--spp", "8", "--quiet"])
            .args([
                "--env",
                "0.2,0.3,0.4",
                "--max-bounces",
                "3",
                "--single-sided",
                mode,
            ])
            .status()
            .unwrap();
        assert!(status.success(), "{name}");
        read_exr(&out).unwrap()
    };
    let culled = render("culled", true, "gltf");
    let absent = render("absent", false, "gltf");
    let both = render("both", true, "blender");
    let bits = |i: &aperture_imageio::Image| -> Vec<u32> {
        i.rgba.iter().flatten().map(|v| v.to_bits()).collect()
    };
    assert_eq!(
        bits(&culled),
        bits(&absent),
        "the culled quad changed the image"
    );
    let sum = |i: &aperture_imageio::Image| i.rgba.iter().map(|p| p[0] + p[1] + p[2]).sum::<f32>();
    assert!(
        sum(&both) < 0.9 * sum(&absent),
        "seen from both sides the quad should shadow the floor: {} vs {}",
        sum(&both),
        sum(&absent)
    );
}
