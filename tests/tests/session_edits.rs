//! A render session (SPEC §9): after any sequence of edits, a render equals a cold load of the
//! file that already had the edited values, bit for bit (every pass); progressive passes add up
//! to the one-shot render; a camera edit builds nothing.
//!
//! The file is the demo scene (`tests/src/demo.rs`): every edit is made twice, on a live
//! session and on the glTF JSON, which is then written and loaded cold.

use aperture_output::film_to_image;
use aperture_render::film::Window;
use aperture_render::{Film, FrameSpec, PassSet, Progressive, RenderOptions, Session, TILE};
use aperture_scene::{Edit, LoadOptions, Touched};
use aperture_tests::demo;
use proptest::prelude::*;
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

/// A scratch file for this test process.
fn scratch(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("aperture-session-{}-{name}", std::process::id()))
}

/// The demo's JSON (with `KHR_node_visibility` declared, so nodes can be hidden) and buffer.
fn demo_document() -> (Value, Vec<u8>) {
    let d = demo::build();
    let mut json = d.json;
    json["extensionsUsed"]
        .as_array_mut()
        .expect("the demo lists extensions")
        .push(json!("KHR_node_visibility"));
    (json, d.bin)
}

fn write_glb(json: &Value, bin: &[u8], name: &str) -> PathBuf {
    let path = scratch(name);
    std::fs::write(&path, demo::to_glb(json, bin)).expect("scratch file");
    path
}

fn opts() -> RenderOptions {
    RenderOptions {
        width: 40,
        height: 24,
        spp: 2,
        passes: PassSet::all(),
        ..RenderOptions::default()
    }
}

/// Every beauty and pass value of a film, as bits.
fn bits(film: &Film, session: &mut Session, opts: &RenderOptions) -> Vec<u32> {
    let frame = session.frame(&FrameSpec::default()).expect("frame");
    let image = film_to_image(film, frame.scene(), opts, false, 0.0).expect("image");
    let mut out: Vec<u32> = image.rgba.iter().flatten().map(|v| v.to_bits()).collect();
    for layer in &image.layers {
        out.extend(layer.data.iter().map(|v| v.to_bits()));
    }
    out
}

fn render(session: &mut Session, opts: &RenderOptions) -> Vec<u32> {
    outcome(session, opts).expect("render")
}

/// A render's bits, or the error that stopped it (an edit may make a frame invalid, e.g. a
/// focus object moved behind the camera; a cold load of that file must then fail the same way).
fn outcome(session: &mut Session, opts: &RenderOptions) -> Result<Vec<u32>, String> {
    let frame = session
        .frame(&FrameSpec::default())
        .map_err(|e| e.to_string())?;
    let film = frame.render(opts, &|_, _| {}).map_err(|e| e.to_string())?;
    Ok(bits(&film, session, opts))
}

/// One edit, as the session takes it and as it changes the file.
#[derive(Debug, Clone)]
enum Change {
    /// A node's matrix: translated and scaled.
    Matrix(usize, [f32; 3], f32),
    /// A node's translation through its pointer.
    Translation(usize, [f32; 3]),
    /// A material's base colour.
    BaseColor(usize, [f32; 4]),
    /// A material's roughness.
    Roughness(usize, f32),
    /// The sun's intensity and colour.
    Sun(f32, [f32; 3]),
    /// The camera's f-stop.
    Fstop(f32),
    /// The camera's focus object removed, its focus distance set.
    FocusDistance(f32),
    /// A node hidden or shown.
    Visible(usize, bool),
}

fn f32s<const N: usize>(v: [f32; N]) -> Vec<f64> {
    v.iter().map(|&x| f64::from(x)).collect()
}

impl Change {
    fn edit(&self) -> Edit {
        let pointer = |path: String, value: Vec<f64>| Edit::Pointer { path, value };
        match self {
            Change::Matrix(node, t, s) => Edit::NodeMatrix {
                node: *node,
                matrix: matrix(*t, *s),
            },
            Change::Translation(n, t) => pointer(format!("/nodes/{n}/translation"), f32s(*t)),
            Change::BaseColor(m, c) => pointer(
                format!("/materials/{m}/pbrMetallicRoughness/baseColorFactor"),
                f32s(*c),
            ),
            Change::Roughness(m, r) => pointer(
                format!("/materials/{m}/pbrMetallicRoughness/roughnessFactor"),
                f32s([*r]),
            ),
            Change::Sun(..) => unreachable!("two edits"),
            Change::Fstop(f) => Edit::CameraKey {
                camera: 0,
                key: "aperture_fstop".into(),
                value: json!(f64::from(*f)),
            },
            Change::FocusDistance(_) => unreachable!("two edits"),
            Change::Visible(node, visible) => Edit::NodeVisible {
                node: *node,
                visible: *visible,
            },
        }
    }

    /// The session edits of this change.
    fn edits(&self) -> Vec<Edit> {
        match self {
            Change::Sun(i, c) => vec![
                Edit::Pointer {
                    path: "/extensions/KHR_lights_punctual/lights/0/intensity".into(),
                    value: f32s([*i]),
                },
                Edit::Pointer {
                    path: "/extensions/KHR_lights_punctual/lights/0/color".into(),
                    value: f32s(*c),
                },
            ],
            Change::FocusDistance(d) => vec![
                Edit::CameraKey {
                    camera: 0,
                    key: "focus_object".into(),
                    value: Value::Null,
                },
                Edit::CameraKey {
                    camera: 0,
                    key: "focus_distance".into(),
                    value: json!(f64::from(*d)),
                },
            ],
            c => vec![c.edit()],
        }
    }

    /// The same change made to the file.
    fn apply(&self, doc: &mut Value) {
        let num = |x: f32| json!(f64::from(x));
        let arr = |v: &[f32]| Value::Array(v.iter().map(|&x| num(x)).collect());
        match self {
            Change::Matrix(n, t, s) => {
                let node = doc["nodes"][*n].as_object_mut().expect("node");
                for k in ["translation", "rotation", "scale"] {
                    node.remove(k);
                }
                node.insert("matrix".into(), arr(matrix(*t, *s).as_flattened()));
            }
            Change::Translation(n, t) => {
                let node = doc["nodes"][*n].as_object_mut().expect("node");
                if let Some(m) = node.remove("matrix") {
                    // A matrix node keyed by TRS is decomposed first (as the session does).
                    let cols: Vec<f32> = m
                        .as_array()
                        .expect("matrix")
                        .iter()
                        .map(|v| v.as_f64().expect("number") as f32)
                        .collect();
                    let m = glam::DMat4::from_cols_slice(
                        &cols.iter().map(|&x| f64::from(x)).collect::<Vec<_>>(),
                    );
                    let (s, r, _) = glam::DAffine3::from_mat4(m).to_scale_rotation_translation();
                    node.insert("scale".into(), arr(&s.as_vec3().to_array()));
                    node.insert("rotation".into(), arr(&r.as_quat().to_array()));
                }
                node.insert("translation".into(), arr(t));
            }
            Change::BaseColor(m, c) => {
                doc["materials"][*m]["pbrMetallicRoughness"]["baseColorFactor"] = arr(c);
            }
            Change::Roughness(m, r) => {
                doc["materials"][*m]["pbrMetallicRoughness"]["roughnessFactor"] = num(*r);
            }
            Change::Sun(i, c) => {
                let light = &mut doc["extensions"]["KHR_lights_punctual"]["lights"][0];
                light["intensity"] = num(*i);
                light["color"] = arr(c);
            }
            Change::Fstop(f) => doc["cameras"][0]["extras"]["aperture_fstop"] = num(*f),
            Change::FocusDistance(d) => {
                let extras = doc["cameras"][0]["extras"].as_object_mut().expect("extras");
                extras.remove("focus_object");
                extras.insert("focus_distance".into(), num(*d));
            }
            Change::Visible(n, v) => {
                doc["nodes"][*n]["extensions"]["KHR_node_visibility"] = json!({ "visible": v });
            }
        }
    }
}

/// A column-major matrix: scale `s`, then translation `t`.
fn matrix(t: [f32; 3], s: f32) -> [[f32; 4]; 4] {
    [
        [s, 0.0, 0.0, 0.0],
        [0.0, s, 0.0, 0.0],
        [0.0, 0.0, s, 0.0],
        [t[0], t[1], t[2], 1.0],
    ]
}

fn change(nodes: usize, materials: usize) -> impl Strategy<Value = Change> {
    let n = 0..nodes;
    let m = 0..materials;
    let t = prop::array::uniform3(-2.0f32..2.0);
    prop_oneof![
        (n.clone(), t.clone(), 0.5f32..1.5).prop_map(|(n, t, s)| Change::Matrix(n, t, s)),
        (n.clone(), t).prop_map(|(n, t)| Change::Translation(n, t)),
        (m.clone(), prop::array::uniform4(0.0f32..1.0)).prop_map(|(m, c)| Change::BaseColor(m, c)),
        (m, 0.0f32..1.0).prop_map(|(m, r)| Change::Roughness(m, r)),
        (100.0f32..5000.0, prop::array::uniform3(0.2f32..1.0)).prop_map(|(i, c)| Change::Sun(i, c)),
        (0.7f32..16.0).prop_map(Change::Fstop),
        (0.5f32..20.0).prop_map(Change::FocusDistance),
        (n, any::<bool>()).prop_map(|(n, v)| Change::Visible(n, v)),
    ]
}

fn counts() -> (usize, usize) {
    let (json, _) = demo_document();
    let n = |k: &str| json[k].as_array().map_or(0, Vec::len);
    (n("nodes"), n("materials"))
}

fn load(path: &Path) -> Session {
    Session::load(path, &LoadOptions::default()).expect("loads")
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 10, ..ProptestConfig::default() })]

    /// Edits on a live session (rendered between edits, so each edit meets a built frame)
    /// equal a cold load of the edited file, bit for bit, in every pass.
    #[test]
    fn edits_equal_a_cold_load_of_the_edited_file(
        changes in prop::collection::vec(change(counts().0, counts().1), 1..5)
    ) {
        let (mut doc, bin) = demo_document();
        let base = write_glb(&doc, &bin, "base.glb");
        let mut session = load(&base);
        let o = opts();
        let small = RenderOptions { width: 8, height: 6, spp: 1, ..o.clone() };
        render(&mut session, &small);
        for c in &changes {
            for e in c.edits() {
                session.edit(e).expect("edit");
            }
            c.apply(&mut doc);
            // An invalid intermediate frame is allowed: a later edit may make it valid again.
            let _ = outcome(&mut session, &small);
        }
        let edited = write_glb(&doc, &bin, "edited.glb");
        let mut cold = load(&edited);
        let (live, want) = (outcome(&mut session, &o), outcome(&mut cold, &o));
        std::fs::remove_file(&base).ok();
        std::fs::remove_file(&edited).ok();
        match (&live, &want) {
            (Ok(l), Ok(w)) => prop_assert!(l == w, "{changes:?}: the edited session differs from a cold load"),
            _ => prop_assert_eq!(live, want, "{:?}: live and cold loads end differently", changes),
        }
    }
}

/// The case CI's random search found: the focus object (node 4) moved behind the camera. The
/// live session and a cold load of the edited file both refuse the frame, with one message.
#[test]
fn a_focus_object_behind_the_camera_fails_live_as_it_fails_cold() {
    let (mut doc, bin) = demo_document();
    let base = write_glb(&doc, &bin, "behind-base.glb");
    let mut session = load(&base);
    let o = opts();
    render(&mut session, &o);
    let c = Change::Translation(4, [0.0, 0.0, 0.907_355_84]);
    for e in c.edits() {
        session.edit(e).expect("edit");
    }
    c.apply(&mut doc);
    let edited = write_glb(&doc, &bin, "behind-edited.glb");
    let live = outcome(&mut session, &o);
    let cold = outcome(&mut load(&edited), &o);
    std::fs::remove_file(&base).ok();
    std::fs::remove_file(&edited).ok();
    let error = live
        .as_ref()
        .expect_err("the focus point is behind the camera");
    assert!(error.contains("not in front of the camera"), "{error}");
    assert_eq!(live, cold);
    // The session stays usable: moving the node back renders the first image again.
    let back = Change::Translation(4, node_translation(&demo_document().0, 4));
    for e in back.edits() {
        session.edit(e).expect("edit");
    }
    let first = render(
        &mut load(&write_glb(&demo_document().0, &bin, "behind-again.glb")),
        &o,
    );
    assert_eq!(render(&mut session, &o), first);
    std::fs::remove_file(scratch("behind-again.glb")).ok();
}

/// A node's translation in the document (zero when it has none).
fn node_translation(doc: &Value, node: usize) -> [f32; 3] {
    let t = &doc["nodes"][node]["translation"];
    std::array::from_fn(|i| t[i].as_f64().unwrap_or(0.0) as f32)
}

/// Progressive passes (1, 1, 2, 4 samples) reach the one-shot 8-sample render bit for bit,
/// for the whole image and for a window that cuts tiles, every pass included.
#[test]
fn progressive_passes_equal_the_one_shot_render() {
    let (doc, bin) = demo_document();
    let path = write_glb(&doc, &bin, "progressive.glb");
    let mut session = load(&path);
    let o = RenderOptions { spp: 8, ..opts() };
    let window = Window {
        x0: 5,
        y0: 3,
        width: TILE + 3,
        height: 17,
    };
    for w in [Window::whole(o.width, o.height), window] {
        let frame = session.frame(&FrameSpec::default()).expect("frame");
        let camera = frame.camera(&o).expect("camera");
        let once = frame
            .render_window(&camera, &o, w, &|_, _| {})
            .expect("render");
        let mut p = Progressive::new(frame, &o, w).expect("progressive");
        let mut totals = Vec::new();
        while let Some(n) = p.next_pass(frame, &|_, _| {}).expect("pass") {
            totals.push(n);
        }
        assert_eq!(totals, [1, 2, 4, 8]);
        let film = p.into_film();
        assert_eq!(
            bits(&film, &mut session, &o),
            bits(&once, &mut session, &o),
            "{w:?}"
        );
    }
    std::fs::remove_file(&path).ok();
}

/// A camera edit touches the cameras alone: the frame keeps its BVH (nothing is built), and
/// the image changes.
#[test]
fn a_camera_edit_builds_nothing() {
    let (doc, bin) = demo_document();
    let path = write_glb(&doc, &bin, "camera.glb");
    let mut session = load(&path);
    let o = opts();
    let before = render(&mut session, &o);
    let built = session.frame(&FrameSpec::default()).expect("frame").times();
    let fstop = Edit::CameraKey {
        camera: 0,
        key: "aperture_fstop".into(),
        value: json!(8.0),
    };
    assert_eq!(session.edit(fstop).expect("edit"), Touched::Cameras);
    let after = render(&mut session, &o);
    assert_eq!(
        session.frame(&FrameSpec::default()).expect("frame").times(),
        built,
        "the frame was not built again"
    );
    assert_ne!(before, after, "f/8 renders another image than f/1.4");
    std::fs::remove_file(&path).ok();
}

#[test]
fn another_image_size_shares_the_frame_unless_motion_or_vector_follow_the_view() {
    let (doc, bin) = demo_document();
    let path = write_glb(&doc, &bin, "view.glb");
    let mut session = load(&path);
    let at = |view: (usize, u32, u32), time: Option<f64>, vector: bool| FrameSpec {
        view,
        time,
        vector,
        ..FrameSpec::default()
    };
    let mut times = |spec: FrameSpec| session.frame(&spec).expect("frame").times();
    // A viewport's small first image and its full passes: one frame, built once.
    let full = times(at((0, 1920, 1080), None, false));
    assert_eq!(
        times(at((0, 120, 68), None, false)),
        full,
        "built again for 120 x 68"
    );
    // The Vector pass follows the view's size: another size is another frame.
    let vector = times(at((0, 1920, 1080), Some(0.0), true));
    assert_ne!(
        vector, full,
        "the Vector pass at a time needs its own frame"
    );
    assert_eq!(times(at((0, 1920, 1080), Some(0.0), true)), vector);
    assert_ne!(
        times(at((0, 120, 68), Some(0.0), true)),
        vector,
        "kept for another view"
    );
    std::fs::remove_file(&path).ok();
}

/// Edits that name what the file does not have are refused with the place they name.
#[test]
fn bad_edits_are_refused() {
    let (doc, bin) = demo_document();
    let path = write_glb(&doc, &bin, "bad.glb");
    let mut session = load(&path);
    let bad = [
        Edit::NodeMatrix {
            node: 9999,
            matrix: matrix([0.0; 3], 1.0),
        },
        Edit::NodeMatrix {
            node: 0,
            matrix: matrix([f32::NAN, 0.0, 0.0], 1.0),
        },
        Edit::Pointer {
            path: "/materials/0/pbrMetallicRoughness/baseColorFactor".into(),
            value: vec![1.0],
        },
        Edit::Pointer {
            path: "/materials/0/nonsense".into(),
            value: vec![1.0],
        },
        Edit::Pointer {
            path: "/extensions/KHR_lights_punctual/lights/0/intensity".into(),
            value: vec![f64::NAN],
        },
        Edit::CameraKey {
            camera: 7,
            key: "aperture_fstop".into(),
            value: json!(2.0),
        },
    ];
    for e in bad {
        let err = session.edit(e.clone()).expect_err("refused");
        assert!(!err.to_string().is_empty(), "{e:?}");
    }
    assert!(session.edits().is_empty(), "a refused edit is not kept");
    std::fs::remove_file(&path).ok();
}
