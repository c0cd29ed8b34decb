//! Edits of a camera's bokeh image and lens prescription (issue 61, SPEC §9): `aperture_image`
//! and `lens_prescription` set by [`Edit::CameraKey`], then the cameras refreshed, pose what a
//! cold load of the file storing the value poses; a bad value or an unreadable file is refused
//! naming the camera and the key, and leaves the document as it was.

use aperture_scene::{Animated, Edit, LoadOptions, Scene, Touched};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

/// A greyscale PNG of `w` × `h` texels, `f(x, y)` each.
fn png(w: u32, h: u32, f: impl Fn(u32, u32) -> u8) -> Vec<u8> {
    let img = image::GrayImage::from_fn(w, h, |x, y| image::Luma([f(x, y)]));
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png).unwrap();
    out.into_inner()
}

const LENS: &str = "# a test lens\n 30 4 1.6 20\n -60 2 1 20\n0 10 0 12\n";

/// A fresh folder with a bokeh image (`half.png`), a black one, a lens file and a texture.
fn folder(name: &str) -> PathBuf {
    let dir =
        std::env::temp_dir().join(format!("aperture-lens-edits-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("half.png"),
        png(4, 2, |x, _| if x >= 2 { 255 } else { 0 }),
    )
    .unwrap();
    std::fs::write(dir.join("black.png"), png(2, 2, |_, _| 0)).unwrap();
    std::fs::write(
        dir.join("ring.png"),
        png(3, 3, |x, y| if x == 1 && y == 1 { 0 } else { 200 }),
    )
    .unwrap();
    std::fs::write(dir.join("lens.dat"), LENS).unwrap();
    dir
}

/// Two cameras (the second names texture 1 as its bokeh image), on nodes 0 and 1; node 0's
/// extras may carry keys of its own.
fn doc(camera0: Value, node0: Value) -> Value {
    let perspective = json!({"yfov": 0.5, "znear": 0.1});
    json!({
        "asset": {"version": "2.0"},
        "cameras": [
            {"type": "perspective", "name": "Cam", "perspective": perspective,
             "extras": camera0},
            {"type": "perspective", "name": "Other", "perspective": perspective,
             "extras": {"aperture_image": 1, "aperture_fstop": 2.8}}
        ],
        "images": [{"uri": "ring.png"}, {"uri": "half.png"}],
        "textures": [{"source": 0}, {"source": 1}],
        "nodes": [
            {"camera": 0, "translation": [0, 0, 3], "extras": node0},
            {"camera": 1, "translation": [1, 0, 3]}
        ],
        "scenes": [{"nodes": [0, 1]}]
    })
}

fn write(dir: &Path, name: &str, doc: &Value) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, serde_json::to_vec(doc).unwrap()).unwrap();
    path
}

fn posed(path: &Path) -> Scene {
    Animated::load(path, &LoadOptions::default())
        .unwrap()
        .scene_at(None)
        .unwrap()
}

/// `edit` applied to the file `base` stores, the cameras refreshed: what it touched, and the
/// scene. A reload is done as a session does it (the file loaded again with the edit).
fn edited(base: &Path, edit: &Edit) -> (Touched, Scene) {
    let mut doc = Animated::load(base, &LoadOptions::default()).unwrap();
    let mut scene = doc.scene_at(None).unwrap();
    let touched = doc.edit(edit).unwrap();
    match touched {
        Touched::Cameras => doc.refresh(&mut scene, touched).unwrap(),
        _ => {
            let again =
                Animated::load_edited(base, &LoadOptions::default(), std::slice::from_ref(edit));
            scene = again.unwrap().scene_at(None).unwrap();
        }
    }
    (touched, scene)
}

fn key(key: &str, value: Value) -> Edit {
    Edit::CameraKey {
        camera: 0,
        key: key.into(),
        value,
    }
}

#[test]
fn an_edited_bokeh_image_poses_as_a_cold_load() {
    let dir = folder("image");
    let base = write(
        &dir,
        "base.gltf",
        &doc(json!({"aperture_fstop": 2}), json!({})),
    );
    let cases = [
        // A path: read by the edit, in place.
        (json!("half.png"), Touched::Cameras),
        // A texture another camera already uses: in place.
        (json!(1), Touched::Cameras),
        // A texture not loaded with the file: read by loading it again.
        (json!(0), Touched::Reload),
    ];
    for (value, want) in cases {
        let (touched, warm) = edited(&base, &key("aperture_image", value.clone()));
        assert_eq!(touched, want, "{value}");
        let cold_doc = doc(
            json!({"aperture_fstop": 2, "aperture_image": value}),
            json!({}),
        );
        let cold = posed(&write(&dir, "cold.gltf", &cold_doc));
        assert_eq!(warm.cameras, cold.cameras, "{value}");
        assert!(warm.cameras[0].dof.lens_options.aperture_image.is_some());
        // The edit as a session replays it when loading again.
        let replayed = Animated::load_edited(
            &base,
            &LoadOptions::default(),
            &[key("aperture_image", value.clone())],
        );
        assert_eq!(
            replayed.unwrap().scene_at(None).unwrap().cameras,
            cold.cameras
        );
    }
}

#[test]
fn removing_the_image_and_the_nodes_key_poses_as_a_cold_load() {
    let dir = folder("remove");
    // The node's key wins over the camera's: the edit removes it from the node.
    let base = write(
        &dir,
        "base.gltf",
        &doc(
            json!({"aperture_image": "half.png"}),
            json!({"aperture_image": "ring.png"}),
        ),
    );
    assert!(posed(&base).cameras[0]
        .dof
        .lens_options
        .aperture_image
        .is_some());
    let (touched, warm) = edited(&base, &key("aperture_image", Value::Null));
    assert_eq!(touched, Touched::Cameras);
    let cold = posed(&write(&dir, "cold.gltf", &doc(json!({}), json!({}))));
    assert_eq!(warm.cameras, cold.cameras);
    assert!(warm.cameras[0].dof.lens_options.aperture_image.is_none());
    // Set on the camera, it replaces the node's too.
    let (_, warm) = edited(&base, &key("aperture_image", json!("half.png")));
    let cold_doc = doc(json!({"aperture_image": "half.png"}), json!({}));
    assert_eq!(
        warm.cameras,
        posed(&write(&dir, "cold.gltf", &cold_doc)).cameras
    );
}

#[test]
fn an_image_path_is_read_again_by_the_edit() {
    let dir = folder("again");
    // Not the texture's image (a texture's is the file's, read once with it).
    std::fs::copy(dir.join("half.png"), dir.join("spot.png")).unwrap();
    let base = write(
        &dir,
        "base.gltf",
        &doc(json!({"aperture_image": "spot.png"}), json!({})),
    );
    let mut document = Animated::load(&base, &LoadOptions::default()).unwrap();
    let mut scene = document.scene_at(None).unwrap();
    assert!(!scene.cameras[0]
        .dof
        .lens_options
        .aperture_image
        .clone()
        .unwrap()
        .is_constant());
    std::fs::write(dir.join("spot.png"), png(2, 2, |_, _| 255)).unwrap();
    let touched = document
        .edit(&key("aperture_image", json!("spot.png")))
        .unwrap();
    document.refresh(&mut scene, touched).unwrap();
    assert_eq!(scene.cameras, posed(&base).cameras);
    let image = scene.cameras[0].dof.lens_options.aperture_image.clone();
    assert!(image.unwrap().is_constant(), "the new file's image");
}

#[test]
fn an_edited_prescription_poses_as_a_cold_load() {
    let dir = folder("lens");
    let base = write(
        &dir,
        "base.gltf",
        &doc(json!({"aperture_fstop": 4}), json!({})),
    );
    let rows = json!([[30, 4, 1.6, 20], [-60, 2, 1, 20], [0, 10, 0, 12]]);
    for value in [json!("lens.dat"), rows] {
        let (touched, warm) = edited(&base, &key("lens_prescription", value.clone()));
        assert_eq!(touched, Touched::Cameras);
        let cold_doc = doc(
            json!({"aperture_fstop": 4, "lens_prescription": value}),
            json!({}),
        );
        let cold = posed(&write(&dir, "cold.gltf", &cold_doc));
        assert_eq!(warm.cameras, cold.cameras, "{value}");
        assert_eq!(
            warm.cameras[0]
                .dof
                .prescription
                .as_ref()
                .unwrap()
                .surfaces
                .len(),
            3
        );
    }
    // Removed: the thin lens again.
    let with = doc(json!({"lens_prescription": "lens.dat"}), json!({}));
    let (_, warm) = edited(
        &write(&dir, "with.gltf", &with),
        &key("lens_prescription", Value::Null),
    );
    let cold = posed(&write(&dir, "cold.gltf", &doc(json!({}), json!({}))));
    assert_eq!(warm.cameras, cold.cameras);
    assert!(warm.cameras[0].dof.prescription.is_none());
}

#[test]
fn bad_values_are_refused_naming_camera_and_key_and_change_nothing() {
    let dir = folder("bad");
    let base = write(
        &dir,
        "base.gltf",
        &doc(json!({"aperture_image": "half.png"}), json!({})),
    );
    let before = posed(&base).cameras;
    let cases = [
        ("aperture_image", json!("missing.png"), "missing.png"),
        ("aperture_image", json!("../half.png"), "../half.png"),
        ("aperture_image", json!("black.png"), "black"),
        ("aperture_image", json!(""), "expected an image path"),
        ("aperture_image", json!(-1), "texture index"),
        ("aperture_image", json!(true), "expected an image path"),
        ("lens_prescription", json!("nowhere.dat"), "nowhere.dat"),
        ("lens_prescription", json!([[30, 4, 1.6]]), "row 0"),
        ("lens_prescription", json!([[30, 4, 1.6, "x"]]), "row 0"),
        ("lens_prescription", json!(7), "expected a lens file"),
    ];
    let mut document = Animated::load(&base, &LoadOptions::default()).unwrap();
    let mut scene = document.scene_at(None).unwrap();
    for (k, value, want) in cases {
        let e = document
            .edit(&key(k, value.clone()))
            .expect_err(&value.to_string());
        let e = e.to_string();
        assert!(e.contains("\"Cam\""), "{value}: {e}");
        assert!(e.contains(&format!("cameras.extras.{k}")), "{value}: {e}");
        assert!(e.contains(want), "{value}: {e}");
        document.refresh(&mut scene, Touched::Cameras).unwrap();
        assert_eq!(scene.cameras, before, "{value} changed the document");
    }
    // A texture the file does not have: the reload refuses it, naming it.
    let e = Animated::load_edited(
        &base,
        &LoadOptions::default(),
        &[key("aperture_image", json!(9))],
    )
    .expect_err("no texture 9")
    .to_string();
    assert!(
        e.contains("cameras.extras.aperture_image") && e.contains("textures[9]"),
        "{e}"
    );
}
