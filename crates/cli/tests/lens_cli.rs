//! The thin lens's options (issue 61) from the command line: `--aperture-vignetting` and
//! `--distortion` render what the file's `aperture_vignetting` and `distortion_*` keys render,
//! bit for bit, as do `--aperture-image`, `--chromatic-lateral` and `--chromatic-longitudinal`
//! for `aperture_image` and `chromatic_*`, and `info` shows the file's values.

mod common;

use aperture_imageio::read_exr;
use common::{aperture, quad_glb, quad_json, Scratch};
use serde_json::{json, Value};
use std::process::Command;

/// A lit quad seen slightly off axis by a camera with depth of field, whose `extras` add `lens`.
fn scene(lens: Value) -> Vec<u8> {
    let mut doc = quad_json();
    doc["materials"] = json!([{"pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.5, 0.2, 1.0],
        "metallicFactor": 0.0}}]);
    doc["meshes"] = json!([{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1,
        "material": 0}]}]);
    let mut extras = json!({"use_dof": true, "aperture_radius": 0.2, "focus_distance": 2.5});
    for (k, v) in lens.as_object().unwrap() {
        extras[k] = v.clone();
    }
    doc["cameras"] = json!([{"type": "perspective", "extras": extras,
        "perspective": {"yfov": 0.9, "znear": 0.1}}]);
    doc["nodes"] = json!([{"mesh": 0, "scale": [2.0, 2.0, 1.0]},
        {"camera": 0, "translation": [0.3, 0.2, 3.0]}]);
    doc["scenes"] = json!([{"nodes": [0, 1]}]);
    quad_glb(&doc)
}

fn render(dir: &Scratch, name: &str, file: &[u8], args: &[&str]) -> Vec<u32> {
    let path = dir.path(&format!("{name}.glb"));
    std::fs::write(&path, file).unwrap();
    let out = dir.path(&format!("{name}.exr"));
    let status = Command::new(aperture())
        .arg("render")
        .arg(&path)
        .arg("-o")
        .arg(&out)
        .args(["--width", "32", "--height", "24", "--spp", "4", "--quiet"])
        .args(["--env", "0.3,0.3,0.3", "--passes", "none"])
        .args(args)
        .status()
        .unwrap();
    assert!(status.success(), "{name} {args:?}");
    let img = read_exr(&out).unwrap();
    img.rgba.iter().flatten().map(|v| v.to_bits()).collect()
}

#[test]
fn flags_render_what_the_files_keys_render() {
    let dir = Scratch::new("lens-cli");
    let keys = json!({"aperture_vignetting": 0.6, "distortion_k1": -0.3, "distortion_k2": 0.05,
        "distortion_p1": 0.01});
    let from_file = render(&dir, "file", &scene(keys), &[]);
    let plain = scene(json!({}));
    let from_flags = render(
        &dir,
        "flags",
        &plain,
        &[
            "--aperture-vignetting",
            "0.6",
            "--distortion",
            "-0.3,0.05,0,0.01",
        ],
    );
    let ideal = render(&dir, "ideal", &plain, &[]);
    assert_ne!(from_file, ideal, "the lens keys should change the image");
    assert_eq!(from_file, from_flags);
    // The flags win over the file: zero gives the ideal thin lens back.
    let keys = json!({"aperture_vignetting": 0.6, "distortion_k1": -0.3});
    let zeroed = render(
        &dir,
        "zeroed",
        &scene(keys),
        &["--aperture-vignetting", "0", "--distortion", "0"],
    );
    assert_eq!(zeroed, ideal);
}

#[test]
fn bad_flags_are_refused_and_info_shows_the_keys() {
    let dir = Scratch::new("lens-cli-info");
    let path = dir.path("lens.glb");
    std::fs::write(
        &path,
        scene(json!({"aperture_vignetting": 0.25, "distortion_k1": -0.125})),
    )
    .unwrap();
    for bad in [
        ["--aperture-vignetting", "1.5"],
        ["--distortion", "1,2,3,4,5,6"],
        ["--distortion", "0.1,inf"],
    ] {
        let out = Command::new(aperture())
            .arg("render")
            .arg(&path)
            .args(["-o", dir.path("bad.exr").to_str().unwrap()])
            .args(bad)
            .output()
            .unwrap();
        assert!(!out.status.success(), "{bad:?} was accepted");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(bad[0]), "{bad:?}: {err}");
    }
    let out = Command::new(aperture())
        .arg("info")
        .arg(&path)
        .output()
        .unwrap();
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        text.contains("lens: vignetting 0.25, distortion k1 -0.125 k2 0.0 k3 0.0"),
        "{text}"
    );
    let out = Command::new(aperture())
        .args(["info", "--json"])
        .arg(&path)
        .output()
        .unwrap();
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    let d = &v["cameras"][0]["dof"];
    assert_eq!(d["vignetting"], 0.25, "{d}");
    assert_eq!(d["distortion"]["k1"], -0.125, "{d}");
}

/// A 16 × 16 greyscale PNG of a star-ish cross: bright texels where `|x − 7.5|` or `|y − 7.5|`
/// is small.
fn cross_png() -> Vec<u8> {
    let img = image::GrayImage::from_fn(16, 16, |x, y| {
        let (dx, dy) = ((x as f32 - 7.5).abs(), (y as f32 - 7.5).abs());
        image::Luma([if dx < 2.5 || dy < 2.5 { 255 } else { 20 }])
    });
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png).unwrap();
    out.into_inner()
}

#[test]
fn bokeh_image_and_chromatic_flags_render_what_the_keys_render() {
    let dir = Scratch::new("lens-cli-bokeh");
    std::fs::write(dir.path("cross.png"), cross_png()).unwrap();
    let keys = json!({"aperture_image": "cross.png", "chromatic_lateral": 0.02,
        "chromatic_longitudinal": -0.05});
    let from_file = render(&dir, "bokeh-file", &scene(keys), &[]);
    let plain = scene(json!({}));
    let image = dir.path("cross.png");
    let from_flags = render(
        &dir,
        "bokeh-flags",
        &plain,
        &[
            "--aperture-image",
            image.to_str().unwrap(),
            "--chromatic-lateral",
            "0.02",
            "--chromatic-longitudinal",
            "-0.05",
        ],
    );
    let ideal = render(&dir, "bokeh-ideal", &plain, &[]);
    assert_ne!(from_file, ideal, "the keys should change the image");
    assert_eq!(from_file, from_flags);
    // Zero aberration on the command line: the image alone, as the file's image alone.
    let image_only = render(
        &dir,
        "bokeh-image-only",
        &scene(json!({"aperture_image": "cross.png"})),
        &[],
    );
    let zeroed = render(
        &dir,
        "bokeh-zeroed",
        &scene(json!({"aperture_image": "cross.png", "chromatic_lateral": 0.02})),
        &["--chromatic-lateral", "0"],
    );
    assert_eq!(zeroed, image_only);
}

#[test]
fn bad_bokeh_and_chromatic_flags_are_refused_and_info_shows_them() {
    let dir = Scratch::new("lens-cli-bokeh-info");
    std::fs::write(dir.path("cross.png"), cross_png()).unwrap();
    let keys = json!({"aperture_image": "cross.png", "chromatic_lateral": 0.02,
        "chromatic_longitudinal": -0.05});
    let path = dir.path("bokeh.glb");
    std::fs::write(&path, scene(keys)).unwrap();
    for bad in [
        ["--chromatic-lateral", "0.9"],
        ["--chromatic-longitudinal", "nan"],
    ] {
        let out = Command::new(aperture())
            .arg("render")
            .arg(&path)
            .args(["-o", dir.path("bad.exr").to_str().unwrap()])
            .args(bad)
            .output()
            .unwrap();
        assert!(!out.status.success(), "{bad:?} was accepted");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(bad[0]), "{bad:?}: {err}");
    }
    let out = Command::new(aperture())
        .arg("render")
        .arg(&path)
        .args(["-o", dir.path("bad.exr").to_str().unwrap()])
        .args([
            "--aperture-image",
            dir.path("nowhere.png").to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("nowhere.png"),
        "{err}"
    );
    let out = Command::new(aperture())
        .arg("info")
        .arg(&path)
        .output()
        .unwrap();
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        text.contains("lens: aperture image \"cross.png\""),
        "{text}"
    );
    assert!(
        text.contains("lens: chromatic lateral 0.02, longitudinal -0.05"),
        "{text}"
    );
    let out = Command::new(aperture())
        .args(["info", "--json"])
        .arg(&path)
        .output()
        .unwrap();
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    let d = &v["cameras"][0]["dof"];
    assert_eq!(d["aperture_image"], "cross.png", "{d}");
    assert_eq!(d["chromatic_lateral"], 0.02, "{d}");
}
