//! Unlit and emissive materials and a point light, each seen in a dark or plain world.

use aperture_render::{FilterKind, RenderOptions};
use aperture_tests::probe::{sample, Probe};
use glam::Vec3;

use crate::{load, white_sky};

/// UnlitTest: each object is one flat colour, #FF7F00 and #007FFF decoded from sRGB, whatever
/// the light.
#[test]
fn unlit_test_objects_are_flat_colours() {
    let Some(path) = sample("correctness/UnlitTest/UnlitTest.glb") else {
        return;
    };
    let scene = load(&path);
    let probe = Probe::new(&scene, &white_sky(96, 64, 4));
    let half = aperture_shading::srgb_to_linear(127.0 / 255.0);
    for (name, want) in [
        ("Orange", Vec3::new(1.0, half, 0.0)),
        ("Blue", Vec3::new(0.0, half, 1.0)),
    ] {
        let px = probe.material_pixels(&scene, name);
        assert!(px.len() > 100, "{name}: {} pixels", px.len());
        let mean = px.iter().sum::<Vec3>() / px.len() as f32;
        // Flat: no shading at all across the object.
        let spread = px
            .iter()
            .map(|c| (*c - mean).abs().max_element())
            .fold(0.0f32, f32::max);
        println!(
            "{name}: {} pixels, mean {mean} (want {want}), spread {spread}",
            px.len()
        );
        assert!(spread < 1e-4, "{name}: spread {spread}");
        assert!((mean - want).abs().max_element() < 0.01, "{name}: {mean}");
    }
}

/// EmissiveStrengthTest: cubes of emissive colour [0.1, 0.5, 0.9] with strengths 1, 2, 4, 8
/// and 16: in the dark their faces are that many times brighter.
#[test]
fn emissive_strength_test_scales_radiance() {
    let Some(path) = sample("correctness/EmissiveStrengthTest/EmissiveStrengthTest.glb") else {
        return;
    };
    let scene = load(&path);
    let opts = RenderOptions {
        width: 480,
        height: 180,
        spp: 2,
        max_bounces: 0,
        filter: FilterKind::Box,
        ..RenderOptions::default()
    };
    let probe = Probe::new(&scene, &opts);
    let median_blue = |name: &str| {
        let mut v: Vec<f32> = probe
            .material_pixels(&scene, name)
            .iter()
            .map(|c| c.z)
            .collect();
        assert!(v.len() > 10, "{name}: {} pixels", v.len());
        v.sort_by(f32::total_cmp);
        v[v.len() / 2]
    };
    let one = median_blue("Emit1");
    assert!((one - 0.9).abs() < 0.1, "{one}");
    for (name, k) in [
        ("Emit2", 2.0),
        ("Emit4", 4.0),
        ("Emit8", 8.0),
        ("Emit16", 16.0),
    ] {
        let r = median_blue(name) / one;
        println!("{name}: {r:.3} × Emit1");
        assert!((r - k).abs() < 0.1 * k, "{name}: {r} vs {k}");
    }
}

/// Cubes-PointLight: in a black world the point light alone lights the cubes: each shows lit
/// faces, in its own colour.
#[test]
fn cubes_point_light_lights_the_cubes() {
    let Some(path) = sample("correctness/Cubes-PointLight/Cubes.glb") else {
        return;
    };
    let scene = load(&path);
    assert_eq!(scene.lights.len(), 1);
    let opts = RenderOptions {
        width: 240,
        height: 160,
        spp: 4,
        max_bounces: 2,
        filter: FilterKind::Box,
        ..RenderOptions::default()
    };
    let probe = Probe::new(&scene, &opts);
    for name in ["Material.001", "Material.002", "Material.003"] {
        let px = probe.material_pixels(&scene, name);
        // 79.6 cd is 0.117 W/sr (SPEC §4): a few metres away that is a few thousandths.
        let lit = px.iter().filter(|c| c.max_element() > 1e-4).count();
        println!("{name}: {} pixels, {lit} lit", px.len());
        assert!(px.len() > 20, "{name}");
        // The light sits above the cubes: their tops and some sides are lit, the rest dark.
        assert!(lit >= 10, "{name}: {lit} lit pixels");
        let sum: Vec3 = px.iter().sum();
        let base = scene
            .materials
            .iter()
            .find(|m| m.name.as_deref() == Some(name))
            .unwrap()
            .base_color_factor
            .truncate();
        // The dominant channel of the lit colour is the base colour's.
        assert_eq!(
            sum.max_position(),
            base.max_position(),
            "{name}: {sum} vs {base}"
        );
    }
}
