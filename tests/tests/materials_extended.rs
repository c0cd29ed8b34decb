//! Real files with the extended materials (issue 14), checked where a number can say what the
//! eye sees: glass shows what is behind it, clear coat shows its texture, velvet brightens at
//! grazing angles, every material extension of the Khronos test files renders without a
//! warning and without a non-finite sample, and variants switch materials.
//!
//! Pixels are attributed to objects by their centre rays (`aperture_tests::probe`).

use aperture_imageio::Image;
use aperture_output as output;
use aperture_render::{build_accel, render, Camera, PassSet, RenderOptions};
use aperture_scene::{LoadOptions, Scene};
use aperture_shading::Environment;
use aperture_tests::probe::{node, node_names, sample, Probe};
use glam::{Vec2, Vec3};
use std::path::Path;

fn load(path: &Path) -> Scene {
    aperture_scene::load(path, &LoadOptions::default()).unwrap()
}

fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

fn sky(width: u32, height: u32, spp: u32) -> RenderOptions {
    RenderOptions {
        width,
        height,
        spp,
        env: Environment::Constant(Vec3::new(0.8, 0.85, 0.9)),
        ..RenderOptions::default()
    }
}

/// Luminances of a node's interior pixels.
fn lums(p: &Probe, scene: &Scene, node: u32) -> Vec<f32> {
    p.pixels_of(scene, node)
        .iter()
        .map(|&(x, y)| {
            let c = p.film.pixel(x, y);
            luminance(Vec3::new(c[0], c[1], c[2]))
        })
        .collect()
}

/// GlassVaseFlowers: the left vase is alpha-blended grey glass, the right one transmissive
/// glass with a volume. The stems in the right one show through it as in the left one: in each
/// vase's bowl (the upper two thirds of its pixels), the share of pixels darker than half the
/// bowl's median (stems and leaves against the glass) agrees within 30 %. Before issue 14 the
/// right vase was white porcelain with nothing dark in it.
#[test]
fn glass_vase_shows_the_stems_inside() {
    let Some(path) = sample("benchmark/GlassVaseFlowers/GlassVaseFlowers.glb") else {
        return;
    };
    let scene = load(&path);
    let names = node_names(&path);
    let p = Probe::new(&scene, &sky(320, 180, 32));
    let dark = |n: &str| {
        let px = p.pixels_of(&scene, node(&names, n));
        let (y0, y1) = px
            .iter()
            .fold((u32::MAX, 0), |(a, b), &(_, y)| (a.min(y), b.max(y)));
        let cut = y0 + (y1 - y0) * 2 / 3;
        let mut l: Vec<f32> = px
            .iter()
            .filter(|&&(_, y)| y <= cut)
            .map(|&(x, y)| {
                let c = p.film.pixel(x, y);
                luminance(Vec3::new(c[0], c[1], c[2]))
            })
            .collect();
        assert!(l.len() > 300, "{n}: {} pixels", l.len());
        l.sort_by(f32::total_cmp);
        let median = l[l.len() / 2];
        l.iter().filter(|&&v| v < 0.5 * median).count() as f32 / l.len() as f32
    };
    let (left, right) = (dark("GlassAlpha"), dark("GlassTransmission"));
    println!("dark-pixel share in the bowls: left vase {left:.3}, right vase {right:.3}");
    assert!(left > 0.05, "the left vase shows stems: {left}");
    assert!((right - left).abs() <= 0.3 * left, "{right} vs {left}");
}

/// ToyCar: the windows (green transmissive glass without a volume: thin-walled) show the dark
/// cabin behind them; as opaque panels (the material without transmission) they are pale.
#[test]
fn toy_car_cabin_shows_through_the_windows() {
    let Some(path) = sample("benchmark/ToyCar/ToyCar.gltf") else {
        return;
    };
    let scene = load(&path);
    let names = node_names(&path);
    let glass = node(&names, "Glass");
    let o = sky(320, 180, 16);
    let windows = |s: &Scene| {
        let l = lums(&Probe::new(s, &o), s, glass);
        assert!(l.len() > 100, "{} window pixels", l.len());
        l.iter().sum::<f32>() / l.len() as f32
    };
    let seen = windows(&scene);
    let mut opaque = scene.clone();
    for m in &mut opaque.materials {
        m.transmission = None;
    }
    let panels = windows(&opaque);
    println!("ToyCar windows: mean luminance {seen:.3} transmissive, {panels:.3} as opaque panels");
    assert!(seen < 0.6 * panels, "{seen} vs {panels}");
}

/// TextureTransformMultiTest: in every clear-coat cell the coat's texture draws a checkmark.
/// The contrast inside a cell (the spread between its brighter and darker pixels) is at least
/// half the base-colour row's; before issue 14 the cells were flat dark squares.
#[test]
fn clear_coat_cells_show_their_checkmarks() {
    let Some(path) = sample("correctness/TextureTransformMultiTest/TextureTransformMultiTest.glb")
    else {
        return;
    };
    let scene = load(&path);
    let names = node_names(&path);
    let p = Probe::new(&scene, &sky(480, 270, 32));
    let contrast = |n: &str| {
        let mut l = lums(&p, &scene, node(&names, n));
        assert!(l.len() > 50, "{n}: {} pixels", l.len());
        l.sort_by(f32::total_cmp);
        let q = |f: f32| l[((l.len() - 1) as f32 * f) as usize];
        (q(0.9) - q(0.1)) / q(0.5).max(1e-3)
    };
    let base = ["BaseColorUV0", "BaseColorUV1", "BaseColorSample"]
        .map(contrast)
        .iter()
        .sum::<f32>()
        / 3.0;
    for row in ["Clearcoat", "ClearcoatRough", "ClearcoatNormal"] {
        for cell in ["UV0", "UV1", "Sample"] {
            let c = contrast(&format!("{row}{cell}"));
            println!("{row}{cell}: contrast {c:.3} (base colour row {base:.3})");
            assert!(c >= 0.5 * base, "{row}{cell}: {c} vs base colour {base}");
        }
    }
}

/// Mean luminance of a node's pixels seen at grazing angles (view cosine below 0.35) and face
/// on (above 0.75), the cosine from the Normal pass.
fn grazing_and_face_on(scene: &Scene, fabric: &[u32], width: u32, height: u32) -> (f32, f32) {
    let o = RenderOptions {
        passes: PassSet::parse("Normal").unwrap(),
        ..sky(width, height, 32)
    };
    let accel = build_accel(scene, Default::default());
    let film = render(scene, &accel, &o, &|_, _| {}).unwrap();
    assert_eq!(film.dropped_samples(), 0);
    let image: Image = output::film_to_image(&film, scene, &o, false, 0.0).unwrap();
    let normal = &image.layer("Normal").unwrap().data;
    let cam = Camera::new(&scene.cameras[0], width, height);
    let hits = aperture_tests::probe::pixel_hits(&accel, &cam, width, height);
    let (mut g, mut f) = ((0.0f32, 0usize), (0.0f32, 0usize));
    for y in 0..height {
        for x in 0..width {
            let i = (y * width + x) as usize;
            let Some((inst, _)) = hits[i] else { continue };
            if !fabric.contains(&scene.instances[inst as usize].node) {
                continue;
            }
            let n = Vec3::from_slice(&normal[3 * i..3 * i + 3]);
            let Some(r) = cam.centre_ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5)) else {
                continue;
            };
            let cos = n.dot(-r.dir).abs();
            let px = image.rgba[i];
            let l = luminance(Vec3::new(px[0], px[1], px[2]));
            if cos < 0.35 {
                g = (g.0 + l, g.1 + 1);
            } else if cos > 0.75 {
                f = (f.0 + l, f.1 + 1);
            }
        }
    }
    assert!(
        g.1 > 30 && f.1 > 30,
        "grazing {} face-on {} pixels",
        g.1,
        f.1
    );
    (g.0 / g.1 as f32, f.0 / f.1 as f32)
}

/// Velvet (GlamVelvetSofa's fabric, SheenCloth): the sheen makes grazing angles brighter than
/// the fabric seen face on; without the sheen they are not.
#[test]
fn sheen_brightens_grazing_angles() {
    for (rel, fabric) in [
        (
            "benchmark/GlamVelvetSofa/GlamVelvetSofa.glb",
            "GlamVelvetSofa_fabric",
        ),
        ("materials/SheenCloth/SheenCloth.gltf", ""),
    ] {
        let Some(path) = sample(rel) else { return };
        let scene = load(&path);
        let names = node_names(&path);
        let nodes: Vec<u32> = if fabric.is_empty() {
            (0..names.len() as u32).collect()
        } else {
            vec![node(&names, fabric)]
        };
        let (g, f) = grazing_and_face_on(&scene, &nodes, 240, 240);
        let mut plain = scene.clone();
        for m in &mut plain.materials {
            m.sheen = None;
        }
        let (pg, pf) = grazing_and_face_on(&plain, &nodes, 240, 240);
        println!("{rel}: grazing {g:.3} face-on {f:.3}; without sheen {pg:.3} / {pf:.3}");
        assert!(g > f, "{rel}: grazing {g} vs face-on {f}");
        if !fabric.is_empty() {
            // The sofa's velvet: the sheen is what brightens its grazing angles most.
            assert!(g / f > 1.2 * (pg / pf), "{rel}: {} vs {}", g / f, pg / pf);
        }
    }
}

/// Every Khronos test file of an extension aperture implements loads without a warning about
/// a material extension, renders without a non-finite sample, and a file that requires clear
/// coat loads.
#[test]
fn extension_test_files_render_without_warnings() {
    for rel in [
        "materials/TransmissionTest/TransmissionTest.glb",
        "materials/TransmissionRoughnessTest/TransmissionRoughnessTest.glb",
        "materials/AttenuationTest/AttenuationTest.glb",
        "materials/ClearCoatTest/ClearCoatTest.glb",
        "materials/ClearCoatCarPaint/ClearCoatCarPaint.glb",
        "materials/SheenChair/SheenChair.gltf",
        "materials/SheenCloth/SheenCloth.gltf",
        "materials/AnisotropyStrengthTest/AnisotropyStrengthTest.glb",
        "materials/AnisotropyRotationTest/AnisotropyRotationTest.glb",
        "materials/SpecularTest/SpecularTest.glb",
        "materials/IridescenceLamp/IridescenceLamp.gltf",
        "materials/GlassBrokenWindow/GlassBrokenWindow.glb",
        "materials/GlassHurricaneCandleHolder/GlassHurricaneCandleHolder.glb",
        "benchmark/GlamVelvetSofa/GlamVelvetSofa.glb",
        "benchmark/ToyCar/ToyCar.gltf",
    ] {
        let Some(path) = sample(rel) else { return };
        let scene = load(&path);
        let material_warnings: Vec<_> = scene
            .stats
            .warnings
            .iter()
            .filter(|w| w.contains("KHR_materials") || w.contains("EXT_texture"))
            .collect();
        assert!(material_warnings.is_empty(), "{rel}: {material_warnings:?}");
        let film = aperture_tests::render_checked(&scene, &sky(48, 32, 4));
        assert!(
            film.to_rgba().iter().any(|p| p[0] > 0.0),
            "{rel} rendered black"
        );
    }
}

/// KHR_materials_variants: `--variant` draws the variant's materials, by name or index, and
/// an unknown one is an error naming the file's variants.
#[test]
fn variants_switch_materials() {
    let Some(path) = sample("benchmark/GlamVelvetSofa/GlamVelvetSofa.glb") else {
        return;
    };
    let fabric_material = |variant: Option<&str>| {
        let scene = aperture_scene::load(
            &path,
            &LoadOptions {
                variant: variant.map(str::to_owned),
                ..LoadOptions::default()
            },
        )
        .unwrap();
        let names = node_names(&path);
        let fabric = node(&names, "GlamVelvetSofa_fabric");
        let inst = scene.instances.iter().find(|i| i.node == fabric).unwrap();
        let id = scene.instance_materials(inst)[0];
        (
            scene.materials[id as usize]
                .name
                .clone()
                .unwrap_or_default(),
            scene.stats.variants.len(),
        )
    };
    // The primitive's own material is the navy one; variant 0, "Champagne", maps another.
    let (default, n) = fabric_material(None);
    assert_eq!(n, 5);
    assert_eq!(default, "GlamVelvetSofa_fabric_navy");
    assert_eq!(
        fabric_material(Some("Champagne")).0,
        "GlamVelvetSofa_fabric_champagne"
    );
    assert_eq!(fabric_material(Some("3")).0, "GlamVelvetSofa_fabric_black");
    let err = aperture_scene::load(
        &path,
        &LoadOptions {
            variant: Some("Plaid".into()),
            ..LoadOptions::default()
        },
    )
    .unwrap_err();
    assert!(
        matches!(err, aperture_scene::Error::NoSuchVariant { .. })
            && err.to_string().contains("Pale Pink"),
        "{err}"
    );
}
