//! The checkmark samples: every "Test" cell shows its green mark and no red X.

use aperture_tests::probe::{sample, Probe};
use glam::Vec3;

use crate::{load, white_sky};

/// Strongly red: the colour of every failure mark in the checkmark tests.
fn is_red(c: Vec3) -> bool {
    c.x > 0.15 && c.y < 0.35 * c.x && c.z < 0.35 * c.x
}

/// Strongly green: the colour of their success marks.
fn is_green(c: Vec3) -> bool {
    c.y > 0.15 && c.x < 0.5 * c.y && c.z < 0.5 * c.y
}

/// TextureSettingsTest: every "Test" cell shows a green check (or a solid green box for the
/// clamp tests) and no red X: repeat, mirrored repeat and clamp-to-edge in s and t, and the
/// double-sided polygon. The single-sided cell is not checked: SPEC §5 shades both sides of
/// every surface (a path tracer has no back-face culling), so its red X is expected.
#[test]
fn texture_settings_test_wrap_modes() {
    let Some(path) = sample("correctness/TextureSettingsTest/TextureSettingsTest.glb") else {
        return;
    };
    let scene = load(&path);
    let probe = Probe::new(&scene, &white_sky(200, 200, 4));
    for name in [
        "TextureMirrorMaterialS",
        "TextureMirrorMaterialT",
        "TextureRepeatMaterialS",
        "TextureRepeatMaterialT",
        "TextureClampMaterialS",
        "TextureClampMaterialT",
        "DoubleSidedMaterial",
    ] {
        let px = probe.material_pixels(&scene, name);
        let red = px.iter().filter(|&&c| is_red(c)).count();
        let green = px.iter().filter(|&&c| is_green(c)).count();
        println!("{name}: {} pixels, {green} green, {red} red", px.len());
        assert!(px.len() > 50, "{name}: {} pixels", px.len());
        assert_eq!(red, 0, "{name}: a red failure mark is visible");
        assert!(green * 5 > px.len(), "{name}: too little green ({green})");
    }
}

/// AlphaBlendModeTest: MASK cuts at each cutoff and BLEND blends, so every hidden red X stays
/// hidden and the green check marks show; nowhere in the image is there a red mark.
#[test]
fn alpha_blend_mode_test_shows_no_red_marks() {
    let Some(path) = sample("correctness/AlphaBlendModeTest/AlphaBlendModeTest.glb") else {
        return;
    };
    let scene = load(&path);
    let probe = Probe::new(&scene, &white_sky(640, 240, 4));
    let px: Vec<Vec3> = probe
        .film
        .to_rgba()
        .iter()
        .map(|p| Vec3::new(p[0], p[1], p[2]))
        .collect();
    let red = px.iter().filter(|&&c| is_red(c)).count();
    let green = px.iter().filter(|&&c| is_green(c)).count();
    println!("AlphaBlendModeTest: {green} green, {red} red pixels");
    assert!(red <= 2, "{red} red pixels");
    assert!(green > 20, "{green} green pixels");
    // The blended and cut boxes show the marble behind them: their alpha ramps end in holes.
    for name in ["MatBlend", "MatCutoff25", "MatCutoffDefault", "MatCutoff75"] {
        assert!(!probe.material_pixels(&scene, name).is_empty(), "{name}");
    }
}

/// VertexColorTest: the top row's checks are multiplied by red, green and blue vertex colours,
/// which zero the other channels; if they were ignored, cyan, magenta and yellow X's would show.
#[test]
fn vertex_color_test_zeroes_the_other_channels() {
    let Some(path) = sample("correctness/VertexColorTest/VertexColorTest.glb") else {
        return;
    };
    let scene = load(&path);
    let probe = Probe::new(&scene, &white_sky(160, 120, 4));
    let px = probe.material_pixels(&scene, "VC_Checks_Mat");
    // Two strong channels and a weak third: a secondary colour.
    let secondary = |c: Vec3| {
        let v = c.to_array();
        let strong = v.iter().filter(|&&x| x > 0.3).count();
        let weak = v.iter().filter(|&&x| x < 0.1).count();
        strong == 2 && weak == 1
    };
    let bad = px.iter().filter(|&&c| secondary(c)).count();
    let prim = px
        .iter()
        .filter(|&&c| {
            is_red(c) || is_green(c) || (c.z > 0.15 && c.x < 0.35 * c.z && c.y < 0.35 * c.z)
        })
        .count();
    println!(
        "VertexColorTest: {} pixels, {prim} primary, {bad} secondary",
        px.len()
    );
    assert!(px.len() > 500);
    assert!(bad * 100 < px.len(), "{bad} cyan/magenta/yellow pixels");
    assert!(prim * 10 > px.len(), "{prim} primary-coloured pixels");
}
