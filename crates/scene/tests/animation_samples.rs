//! SPEC §7 on the glTF samples: the stored pose (morph weights, skins) and poses at given times,
//! each checked against an independent evaluation written from the glTF specification
//! (`common/reference.rs`), or against the numbers the files are built to show.

mod common;

use std::path::Path;

use aperture_scene::{load, Animated, LoadOptions, Scene};
use common::reference;

fn at(time: Option<f32>) -> LoadOptions {
    LoadOptions {
        skip_textures: true,
        time,
        ..LoadOptions::default()
    }
}

fn scene(path: &Path, time: Option<f32>) -> Scene {
    load(path, &at(time)).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Bounds of a posed scene in the file's coordinates, as f64.
fn bounds(s: &Scene) -> ([f64; 3], [f64; 3]) {
    let b = s.bounds();
    let o = s.world_origin;
    (
        [
            o.x + b.min.x as f64,
            o.y + b.min.y as f64,
            o.z + b.min.z as f64,
        ],
        [
            o.x + b.max.x as f64,
            o.y + b.max.y as f64,
            o.z + b.max.z as f64,
        ],
    )
}

/// Asserts two bounds agree within `rel` of the box's size.
fn assert_bounds_close(
    name: &str,
    got: ([f64; 3], [f64; 3]),
    want: ([f64; 3], [f64; 3]),
    rel: f64,
) {
    let size = (0..3)
        .map(|i| want.1[i] - want.0[i])
        .fold(0.0, f64::max)
        .max(1e-9);
    for i in 0..3 {
        for (g, w) in [(got.0[i], want.0[i]), (got.1[i], want.1[i])] {
            assert!(
                (g - w).abs() <= rel * size,
                "{name}: bounds {got:?}, reference {want:?} (axis {i}: {g} vs {w}, tolerance {} )",
                rel * size
            );
        }
    }
}

#[test]
fn simple_morph_uses_the_files_weights() {
    let Some(dir) = common::samples_dir() else {
        return;
    };
    let path = dir.join("correctness/SimpleMorph/SimpleMorph.gltf");
    let s = scene(&path, None);
    let b = s.bounds();
    println!("SimpleMorph stored pose: bounds {b:?}");
    // mesh.weights [0.5, 0.5]: the apex (0.5 at rest) rises by 0.5 × 2 to 1.5.
    assert_eq!(b.max.y, 1.5);
    assert_bounds_close(
        "SimpleMorph",
        bounds(&s),
        reference::bounds(&reference::Doc::open(&path), None),
        1e-6,
    );
}

#[test]
fn recursive_skeletons_spread_their_branches() {
    let Some(dir) = common::samples_dir() else {
        return;
    };
    let path = dir.join("correctness/RecursiveSkeletons/RecursiveSkeletons.glb");
    let s = scene(&path, None);
    let b = s.bounds();
    println!("RecursiveSkeletons stored pose: bounds {b:?}");
    // Unposed, every skinned copy collapses onto one bar within ±5 of the axis.
    assert!(
        b.min.x < -5.0 && b.max.x > 5.0 && b.min.z < -5.0 && b.max.z > 5.0,
        "{b:?}"
    );
    assert_bounds_close(
        "RecursiveSkeletons",
        bounds(&s),
        reference::bounds(&reference::Doc::open(&path), None),
        1e-5,
    );
}

#[test]
fn walking_characters_move_between_times() {
    let Some(dir) = common::samples_dir() else {
        return;
    };
    for (file, lo, hi) in [
        // Cesium Man: about 1.5 m tall, walking in place near the origin (Y up).
        (
            "animation/CesiumMan/CesiumMan.glb",
            [-1.0, -0.1, -1.0],
            [1.0, 1.7, 1.0],
        ),
        // The fox: about 1.3 units tall (cm-scale skeleton), 2.5 long, near the origin.
        (
            "animation/Fox/Fox.glb",
            [-100.0, -5.0, -150.0],
            [100.0, 150.0, 150.0],
        ),
    ] {
        let path = dir.join(file);
        let doc = reference::Doc::open(&path);
        let mut seen = Vec::new();
        for t in [0.0f32, 1.0] {
            let s = scene(&path, Some(t));
            let got = bounds(&s);
            println!("{file} at {t} s: bounds {got:?}");
            for i in 0..3 {
                assert!(
                    got.0[i] >= lo[i] && got.1[i] <= hi[i],
                    "{file} at {t}: {got:?} outside {lo:?}..{hi:?}"
                );
            }
            assert_bounds_close(file, got, reference::bounds(&doc, Some(t as f64)), 1e-5);
            seen.push(got);
        }
        assert_ne!(seen[0], seen[1], "{file}: the same bounds at 0 s and 1 s");
    }
}

#[test]
fn posed_bounds_equal_the_reference_at_three_times() {
    let Some(dir) = common::samples_dir() else {
        return;
    };
    for file in [
        "animation/MorphStressTest/MorphStressTest.glb",
        "animation/AnimatedMorphSphere/AnimatedMorphSphere.glb",
        "animation/MorphPrimitivesTest/MorphPrimitivesTest.glb",
        "animation/RiggedSimple/RiggedSimple.glb",
        "animation/RiggedFigure/RiggedFigure.glb",
        "animation/BoxAnimated/BoxAnimated.glb",
        "animation/AnimatedCube/AnimatedCube.gltf",
    ] {
        let path = dir.join(file);
        let doc = reference::Doc::open(&path);
        // One load, posed three times (the --frames path), and a fresh load at each time.
        let animated = Animated::load(&path, &at(None)).unwrap();
        for t in [0.3f32, 0.9, 1.7] {
            let want = reference::bounds(&doc, Some(t as f64));
            let got = bounds(&animated.scene_at(Some(t)).unwrap());
            println!("{file} at {t} s: {got:?} (reference {want:?})");
            assert_bounds_close(file, got, want, 1e-5);
            assert_eq!(
                got,
                bounds(&scene(&path, Some(t))),
                "{file}: scene_at and load differ"
            );
        }
    }
}

#[test]
fn interpolation_test_follows_the_sampler_formulas() {
    let Some(dir) = common::samples_dir() else {
        return;
    };
    let path = dir.join("correctness/InterpolationTest/InterpolationTest.glb");
    let doc = reference::Doc::open(&path);
    let mut checked = 0;
    for t in [0.5f32, 1.25, 2.0] {
        let s = scene(&path, Some(t));
        let (local, _) = reference::locals(&doc, Some(t as f64));
        let world = reference::worlds(&doc, &local);
        for inst in &s.instances {
            let want = world[inst.node as usize];
            let m = glam::DMat4::from(glam::DAffine3::from_mat4(
                glam::Mat4::from(inst.world_from_object).as_dmat4(),
            ));
            let got = m.to_cols_array();
            // The loader's f64 composition, rounded to f32 once: within 1e-6 of the formula.
            for k in 0..16 {
                assert!(
                    (got[k] - want[k]).abs() <= 1e-6 * want[k].abs().max(1.0),
                    "node {} at {t}: matrix {got:?} vs formula {want:?}",
                    inst.node
                );
            }
            checked += 1;
        }
    }
    println!("InterpolationTest: {checked} cube transforms equal the glTF formulas");
    // Nine animated cubes (STEP, LINEAR, CUBICSPLINE × T, R, S) and one static reference.
    assert_eq!(checked, 3 * 10);
}

#[test]
fn one_load_shares_static_meshes_across_times() {
    let Some(dir) = common::samples_dir() else {
        return;
    };
    let path = dir.join("animation/BoxAnimated/BoxAnimated.glb");
    let a = Animated::load(&path, &at(None)).unwrap();
    assert!(a.is_animated());
    let (s0, s1) = (
        a.scene_at(Some(0.0)).unwrap(),
        a.scene_at(Some(1.0)).unwrap(),
    );
    // No skin or morph target: every mesh is static; only instance transforms move.
    assert_eq!(a.static_mesh_count(), s0.meshes.len());
    assert_eq!(s0.meshes[0].positions, s1.meshes[0].positions);
    assert_ne!(s0.instances, s1.instances);
    assert!(!a.moving_nodes().is_empty());
    let info = a.animations();
    assert_eq!(info.len(), 1);
    assert!(info[0].end > 3.0, "{info:?}");

    // A skinned character: its mesh deforms per pose, after the static ones.
    let a = Animated::load(&dir.join("animation/CesiumMan/CesiumMan.glb"), &at(None)).unwrap();
    let s = a.scene_at(Some(0.5)).unwrap();
    assert_eq!(a.static_mesh_count(), 0);
    assert_eq!(s.meshes.len(), 1);
}
