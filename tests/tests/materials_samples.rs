//! glTF sample models render as their READMEs intend, checked by probing pixel colours.
//!
//! Pixels are attributed to scene objects by tracing each pixel's centre ray through the same
//! camera the render uses: a pixel belongs to an object when it and its 8 neighbours all hit
//! that object (so edges and antialiasing are left out). Expected colours come from the
//! samples' READMEs and reference screenshots, never from the renderer's own texture code.

use aperture_accel::Ray;
use aperture_render::{
    build_accel, render, Camera, CameraSample, Environment, FilterKind, RenderOptions,
};
use aperture_scene::{LoadOptions, Scene};
use aperture_tests::probe::{gltf_json, node, node_names, pixel_hits, sample, Probe};
use glam::{Vec2, Vec3};
use std::collections::HashMap;
use std::path::Path;

/// Under a white sky of radiance 1, a Lambertian surface shows its albedo.
fn white_sky(width: u32, height: u32, spp: u32) -> RenderOptions {
    RenderOptions {
        width,
        height,
        spp,
        max_bounces: 1,
        filter: FilterKind::Box,
        env: Environment::Constant(Vec3::ONE),
        ..RenderOptions::default()
    }
}

fn load(path: &Path) -> Scene {
    aperture_scene::load(path, &LoadOptions::default()).unwrap()
}

/// TextureCoordinateTest: each quad samples its own corner of the texture (uv (0, 0) is the
/// image's top-left), so the quads show yellow (top left), orange (top right), blue (bottom
/// left) and green (bottom right), as in the reference screenshot. A flipped v would swap
/// top and bottom; a flipped u left and right.
#[test]
fn texture_coordinate_test_quadrants() {
    let Some(path) = sample("correctness/TextureCoordinateTest/TextureCoordinateTest.glb") else {
        return;
    };
    let scene = load(&path);
    let names = node_names(&path);
    let probe = Probe::new(&scene, &white_sky(96, 96, 8));
    let check = |name: &str, ok: &dyn Fn(Vec3) -> bool| {
        let (c, n) = probe.mean_of(&scene, node(&names, name));
        println!("{name}: mean {c} over {n} pixels");
        assert!(n > 30, "{name}: {n} pixels");
        assert!(ok(c), "{name}: {c}");
    };
    check("TopLeftObj", &|c| {
        c.x > 0.3 && c.y > 0.6 * c.x && c.z < 0.2 * c.x
    });
    check("TopRightObj", &|c| {
        c.x > 0.3 && c.y < 0.4 * c.x && c.z < 0.2 * c.x
    });
    check("BottomLeftObj", &|c| {
        c.z > 0.3 && c.x < 0.2 * c.z && c.y < 0.5 * c.z
    });
    check("BottomRightObj", &|c| {
        c.y > 0.3 && c.x < 0.2 * c.y && c.z < 0.2 * c.y
    });
}

/// MultiUVTest: the emissive texture reads `TEXCOORD_1`. In the dark (no lights, black sky) the
/// cube shows only emission; every interior pixel must match the emissive texture looked up at
/// the hit point's second UV set (nearest texel, decoded here from the glTF image), and match it
/// better than a lookup through the first set would.
#[test]
fn multi_uv_test_emission_uses_texcoord_1() {
    let Some(path) = sample("correctness/MultiUVTest/MultiUVTest.glb") else {
        return;
    };
    let scene = load(&path);
    let m = &scene.materials[0];
    let et = m.emissive_texture.expect("emissive texture");
    assert_eq!(et.tex_coord, 1);
    let opts = RenderOptions {
        width: 64,
        height: 36,
        spp: 4,
        max_bounces: 0,
        filter: FilterKind::Box,
        ..RenderOptions::default()
    };
    let accel = build_accel(&scene, Default::default());
    let film = render(&scene, &accel, &opts, &|_, _| {}).unwrap();
    assert_eq!(film.dropped_samples(), 0);
    let camera = Camera::new(&scene.cameras[0], opts.width, opts.height);
    // Decode the image ourselves (sRGB, nearest texel) as the reference.
    let json = gltf_json(&path);
    let image_index = json["textures"][et.texture as usize]["source"]
        .as_u64()
        .unwrap_or(1);
    let tex = &scene.textures[et.texture as usize];
    let aperture_scene::Texels::Rgba8(texels) = &tex.texels else {
        panic!("8-bit texture expected (image {image_index})");
    };
    let lookup = |uv: Vec2| {
        let x = ((uv.x.rem_euclid(1.0)) * tex.width as f32) as usize % tex.width as usize;
        let y = ((uv.y.rem_euclid(1.0)) * tex.height as f32) as usize % tex.height as usize;
        let t = texels[y * tex.width as usize + x];
        Vec3::new(t[0] as f32, t[1] as f32, t[2] as f32) / 255.0
    };
    let mesh = &scene.meshes[0];
    let (mut err1, mut err0, mut n) = (0.0f32, 0.0f32, 0);
    for y in 1..opts.height - 1 {
        for x in 1..opts.width - 1 {
            let ray = |x: u32, y: u32| {
                let s = CameraSample {
                    p_film: Vec2::new(x as f32 + 0.5, y as f32 + 0.5),
                    p_lens: Vec2::ZERO,
                };
                let r = camera.generate_ray(&s).unwrap();
                accel.intersect(&Ray::new(r.origin, r.dir))
            };
            let Some(hit) = ray(x, y) else { continue };
            let tri = mesh.indices[hit.triangle as usize].map(|i| i as usize);
            let bary = |v: &[Vec2]| {
                (1.0 - hit.u - hit.v) * v[tri[0]] + hit.u * v[tri[1]] + hit.v * v[tri[2]]
            };
            let (uv0, uv1) = (bary(&mesh.uv0), bary(&mesh.uv1));
            let p = film.pixel(x, y);
            // Compare in sRGB-encoded space against the stored texel; skip texel edges where
            // the 4 samples straddle two texels.
            let enc = |c: f32| {
                if c <= 0.0031308 {
                    12.92 * c
                } else {
                    1.055 * c.powf(1.0 / 2.4) - 0.055
                }
            };
            let got = Vec3::new(enc(p[0]), enc(p[1]), enc(p[2]));
            err1 += (got - lookup(uv1)).abs().max_element();
            err0 += (got - lookup(uv0)).abs().max_element();
            n += 1;
        }
    }
    let (e1, e0) = (err1 / n as f32, err0 / n as f32);
    println!("MultiUVTest: {n} pixels, mean error via uv1 {e1:.4}, via uv0 {e0:.4}");
    assert!(n > 200);
    assert!(e1 < 0.08, "{e1}");
    assert!(e1 < 0.5 * e0, "uv1 {e1} vs uv0 {e0}");
}

/// Big textured models render with every texture kind, and not one sample is NaN or infinite.
#[test]
fn textured_models_render_without_dropped_samples() {
    for rel in [
        "benchmark/FlightHelmet/FlightHelmet.gltf",
        "benchmark/ToyCar/ToyCar.glb",
        "benchmark/GlamVelvetSofa/GlamVelvetSofa.glb",
        "benchmark/StainedGlassLamp/StainedGlassLamp.gltf",
    ] {
        let Some(dir) = aperture_tests::samples_dir() else {
            return;
        };
        let path = dir.join(rel);
        let path = if path.is_file() {
            path
        } else {
            // Some folders hold the .glb or .gltf variant only.
            let stem = path.with_extension("");
            ["glb", "gltf"]
                .iter()
                .map(|e| stem.with_extension(e))
                .find(|p| p.is_file())
                .unwrap_or_else(|| panic!("{rel} missing"))
        };
        let scene = load(&path);
        let textured = scene
            .materials
            .iter()
            .filter(|m| {
                m.base_color_texture.is_some()
                    || m.metallic_roughness_texture.is_some()
                    || m.normal_texture.is_some()
                    || m.emissive_texture.is_some()
            })
            .count();
        let normal_mapped: Vec<_> = scene
            .materials
            .iter()
            .enumerate()
            .filter(|(_, m)| m.normal_texture.is_some())
            .map(|(i, _)| i as u32)
            .collect();
        // Every normal-mapped triangle has a tangent frame (given or MikkTSpace).
        for mesh in &scene.meshes {
            for (t, mid) in mesh.material_ids.iter().enumerate() {
                if normal_mapped.contains(mid) && !mesh.uv0.is_empty() {
                    for &v in &mesh.indices[t] {
                        assert!(
                            mesh.tangents[v as usize].truncate() != Vec3::ZERO,
                            "{rel}: no tangent"
                        );
                    }
                }
            }
        }
        let probe = Probe::new(&scene, &white_sky(40, 30, 4));
        let px = probe.film.to_rgba();
        assert!(px.iter().flatten().all(|c| c.is_finite()));
        let mut distinct: HashMap<[u32; 3], ()> = HashMap::new();
        for p in &px {
            distinct.insert([p[0].to_bits(), p[1].to_bits(), p[2].to_bits()], ());
        }
        println!(
            "{rel}: {textured} textured and {} normal-mapped materials, {} distinct pixels, warnings {:?}",
            normal_mapped.len(),
            distinct.len(),
            scene.stats.warnings
        );
        assert!(textured > 0, "{rel}: no texture");
        assert!(distinct.len() > 100, "{rel}: image too flat");
    }
}

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

/// UnlitTest: each object is one flat colour, #FF7F00 and #007FFF decoded from sRGB, whatever
/// the light.
#[test]
fn unlit_test_objects_are_flat_colours() {
    let Some(path) = sample("correctness/UnlitTest/UnlitTest.glb") else {
        return;
    };
    let scene = load(&path);
    let probe = Probe::new(&scene, &white_sky(96, 64, 4));
    let half = aperture_render::srgb_to_linear(127.0 / 255.0);
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

/// An equirectangular sky with a sharp horizon: bright above, dark below.
fn horizon_sky() -> Environment {
    Environment::Image(std::sync::Arc::new(aperture_render::EnvImage {
        width: 64,
        height: 32,
        texels: (0..64 * 32)
            .map(|i| {
                if i / 64 < 16 {
                    Vec3::new(1.0, 0.9, 0.8)
                } else {
                    Vec3::new(0.02, 0.03, 0.05)
                }
            })
            .collect(),
        rotation: 0.0,
        strength: 1.0,
        sampling: aperture_render::EnvSampling::Importance,
    }))
}

/// An orthographic camera looking down −Z at the whole scene, so every part of it is seen
/// from the same direction.
fn front_ortho(scene: &Scene, w: u32, h: u32) -> aperture_scene::Camera {
    let b = scene.bounds();
    let half = 0.5 * (b.max - b.min);
    let ymag = half.y.max(half.x * h as f32 / w as f32) * 1.05;
    aperture_scene::Camera {
        name: "front".into(),
        node: None,
        world_from_camera: glam::Affine3A::from_translation(Vec3::new(
            b.center().x,
            b.center().y,
            b.max.z + 5.0,
        )),
        projection: aperture_scene::Projection::Orthographic {
            xmag: ymag * w as f32 / h as f32,
            ymag,
        },
        dof: aperture_scene::Dof::default(),
    }
}

/// How far the normal-mapped cells differ from the real-geometry cells beside them: for each
/// pixel on curved geometry (geometric normal more than 10° off the view axis), the difference
/// to the pixel `s` to its right, where a flat (normal-mapped) quad must be; the best shift `s`
/// is searched, so the layout need not be known.
fn normal_map_mismatch(scene: &Scene) -> f32 {
    let (w, h) = (240u32, 200u32);
    let mut scene = scene.clone();
    scene.cameras = vec![front_ortho(&scene, w, h)];
    let opts = RenderOptions {
        width: w,
        height: h,
        spp: 16,
        max_bounces: 1,
        filter: FilterKind::Box,
        env: horizon_sky(),
        ..RenderOptions::default()
    };
    let accel = build_accel(&scene, Default::default());
    let film = render(&scene, &accel, &opts, &|_, _| {}).unwrap();
    assert_eq!(film.dropped_samples(), 0);
    let camera = Camera::new(&scene.cameras[0], w, h);
    let hits = pixel_hits(&accel, &camera, w, h);
    // Per pixel: None (background), Some(true) curved geometry, Some(false) flat.
    let curved: Vec<Option<bool>> = hits
        .iter()
        .map(|hit| {
            let (i, t) = (*hit)?;
            let inst = &scene.instances[i as usize];
            let n = inst.world_geometric_normal(&scene.meshes[inst.mesh as usize], t as usize)?;
            Some(n.z.abs() < 10f32.to_radians().cos())
        })
        .collect();
    let px = film.to_rgba();
    let lum = |i: usize| px[i][0] + px[i][1] + px[i][2];
    let n_curved = curved.iter().filter(|c| **c == Some(true)).count();
    assert!(n_curved > 500, "{n_curved} curved pixels");
    let mut best = f32::INFINITY;
    for s in 3..w / 4 {
        let (mut sum, mut n) = (0.0f32, 0usize);
        for y in 0..h {
            for x in 0..w - s {
                let i = (y * w + x) as usize;
                let j = i + s as usize;
                if curved[i] == Some(true) && curved[j] == Some(false) {
                    sum += (lum(i) - lum(j)).abs();
                    n += 1;
                }
            }
        }
        if 2 * n > n_curved {
            best = best.min(sum / n as f32);
        }
    }
    best
}

/// The same scene with the normal maps' green channel inverted (the DirectX convention):
/// the classic failure the README describes.
fn flip_normal_map_green(scene: &Scene) -> Scene {
    let mut s = scene.clone();
    let normal: Vec<u32> = s
        .materials
        .iter()
        .filter_map(|m| m.normal_texture.map(|t| t.texture))
        .collect();
    for t in normal {
        match &mut s.textures[t as usize].texels {
            aperture_scene::Texels::Rgba8(v) => v.iter_mut().for_each(|p| p[1] = 255 - p[1]),
            aperture_scene::Texels::Rgba32F(v) => v.iter_mut().for_each(|p| p[1] = 1.0 - p[1]),
        }
    }
    s
}

/// NormalTangentTest (MikkTSpace tangents) and NormalTangentMirrorTest (`TANGENT` given,
/// mirrored UVs): each normal-mapped cell reflects a horizon like the real geometry beside it.
/// The measure must be clearly better than for the same maps with green inverted.
#[test]
fn normal_tangent_tests_match_real_geometry() {
    for rel in [
        "correctness/NormalTangentTest/NormalTangentTest.glb",
        "correctness/NormalTangentMirrorTest/NormalTangentMirrorTest.glb",
    ] {
        let Some(path) = sample(rel) else { return };
        let scene = load(&path);
        let good = normal_map_mismatch(&scene);
        let flipped = normal_map_mismatch(&flip_normal_map_green(&scene));
        println!("{rel}: mismatch {good:.4}, with green inverted {flipped:.4}");
        assert!(good < 0.7 * flipped, "{rel}: {good} vs {flipped}");
    }
}

/// TextureEncodingTest: in each row (base colour, emissive, metallic-roughness) the spheres
/// textured by 1×1 images (plain, with a gamma chunk, with an ICC profile) look like the one
/// with the same value as a plain factor: base colour and emissive are decoded from sRGB,
/// metallic-roughness is linear, and image colour metadata is ignored. Each sphere is rendered
/// alone through an orthographic camera, so neighbours and viewing angle cannot tell them
/// apart; the metal row is lit by a horizon, whose reflection's contrast depends on roughness.
#[test]
fn texture_encoding_test_rows_match_their_factor_sphere() {
    let Some(path) = sample("correctness/TextureEncodingTest/TextureEncodingTest.glb") else {
        return;
    };
    let scene = load(&path);
    // Mean and standard deviation of luminance over the sphere of `node`, rendered alone.
    let stats = |node: u32, env: Environment| {
        let mut s = scene.clone();
        s.instances.retain(|i| i.node == node);
        s.cameras = vec![front_ortho(&s, 64, 64)];
        let probe = Probe::new(
            &s,
            &RenderOptions {
                env,
                ..white_sky(64, 64, 16)
            },
        );
        let px = probe.pixels_of(&s, node);
        assert!(px.len() > 500, "node {node}: {} pixels", px.len());
        let l: Vec<f32> = px
            .iter()
            .map(|&(x, y)| {
                let p = probe.film.pixel(x, y);
                p[0] + p[1] + p[2]
            })
            .collect();
        let mean = l.iter().sum::<f32>() / l.len() as f32;
        let var = l.iter().map(|v| (v - mean).powi(2)).sum::<f32>() / l.len() as f32;
        (mean, var.sqrt())
    };
    let white = Environment::Constant(Vec3::ONE);
    for (row, nodes, env) in [
        ("base colour", 1..5, white.clone()),
        ("emissive", 5..9, white),
        ("metal-rough", 9..13, horizon_sky()),
    ] {
        let st: Vec<(f32, f32)> = nodes.map(|n| stats(n, env.clone())).collect();
        println!("{row}: (mean, std) {st:?}");
        let (m0, s0) = st[0];
        for &(m, s) in &st[1..] {
            assert!((m - m0).abs() < 0.005 * m0, "{row}: mean {m} vs {m0}");
            assert!((s - s0).abs() < 0.02 * s0 + 1e-4, "{row}: std {s} vs {s0}");
        }
    }
}

/// TextureTransformTest: the offset quads show the green (U), blue (V) and cyan (UV) quadrants
/// of the UV texture, never its yellow "not supported" quadrant; and the arrows, rotated, scaled
/// and transformed by all three, point at their green "correct" markers. The markers are taken
/// out of the scene, and the arrow's tip must be nearer the correct marker than the "not
/// supported" or "error" ones.
#[test]
fn texture_transform_test_offsets_and_arrows() {
    let Some(path) = sample("correctness/TextureTransformTest/TextureTransformTest.gltf") else {
        return;
    };
    let names = node_names(&path);
    let json = gltf_json(&path);
    // World position of each node: the parents here only translate.
    let translation = |i: usize| {
        json["nodes"][i]["translation"]
            .as_array()
            .map_or(Vec3::ZERO, |t| {
                Vec3::new(
                    t[0].as_f64().unwrap() as f32,
                    t[1].as_f64().unwrap() as f32,
                    t[2].as_f64().unwrap() as f32,
                )
            })
    };
    let mut world = vec![Vec3::ZERO; names.len()];
    for (p, n) in json["nodes"].as_array().unwrap().iter().enumerate() {
        world[p] += translation(p);
        for c in n["children"].as_array().into_iter().flatten() {
            let c = c.as_u64().unwrap() as usize;
            world[c] += translation(p);
        }
    }
    let full = load(&path);
    let mut scene = full.clone();
    let markers: Vec<u32> = (0..names.len() as u32)
        .filter(|&n| names[n as usize].contains(" - "))
        .collect();
    scene.instances.retain(|i| !markers.contains(&i.node));
    let (w, h) = (330u32, 220u32);
    // Frame the full scene (markers included) so both renders share one camera.
    let camera = front_ortho(&full, w, h);
    scene.cameras = vec![camera.clone()];
    let probe = Probe::new(&scene, &white_sky(w, h, 8));

    for (quad, ok) in [
        (
            "Offset U",
            &(|c: Vec3| c.y > 2.0 * c.x && c.y > 2.0 * c.z) as &dyn Fn(Vec3) -> bool,
        ),
        ("Offset V", &|c: Vec3| c.z > 2.0 * c.x && c.z > 2.0 * c.y),
        ("Offset UV", &|c: Vec3| c.y > 2.0 * c.x && c.z > 2.0 * c.x),
    ] {
        let (c, n) = probe.mean_of(&scene, node(&names, quad));
        println!("{quad}: mean {c} over {n} pixels");
        assert!(n > 200, "{quad}: {n} pixels");
        assert!(ok(c), "{quad}: {c}");
    }

    // World point to pixel through the orthographic camera.
    let aperture_scene::Projection::Orthographic { xmag, ymag } = camera.projection else {
        unreachable!()
    };
    let centre = Vec3::from(camera.world_from_camera.translation);
    let pixel = |p: Vec3| {
        let x = (p.x - centre.x) / xmag * 0.5 * w as f32 + 0.5 * w as f32;
        let y = (centre.y - p.y) / ymag * 0.5 * h as f32 + 0.5 * h as f32;
        (x as i64, y as i64)
    };
    // Distance in pixels from a marker to the nearest dark (arrow) pixel of the quad's
    // material: the arrow points at the correct marker, so its tip is nearest to it.
    let nearest_dark = |quad: &str, marker: &str| {
        let id = full
            .materials
            .iter()
            .position(|m| m.name.as_deref() == Some(quad))
            .unwrap() as u32;
        let (mx, my) = pixel(world[node(&names, marker) as usize]);
        let mut best = f32::INFINITY;
        for y in 0..h {
            for x in 0..w {
                if probe.materials[(y * w + x) as usize] != Some(id) {
                    continue;
                }
                let p = probe.film.pixel(x, y);
                if p[0] + p[1] + p[2] < 0.3 {
                    let d = ((x as i64 - mx) as f32).hypot((y as i64 - my) as f32);
                    best = best.min(d);
                }
            }
        }
        best
    };
    for (quad, correct, wrong) in [
        (
            "Rotation",
            "Rotation - Correct",
            &["Rotation - Not Supported", "Rotation - Error"][..],
        ),
        ("Scale", "Scale - Correct", &["Scale - Not Supported"][..]),
    ] {
        let c = nearest_dark(quad, correct);
        for bad in wrong {
            let b = nearest_dark(quad, bad);
            println!("{correct}: arrow {c:.1} px away; {bad}: {b:.1} px");
            assert!(c < 0.6 * b, "{correct} {c} vs {bad} {b}");
        }
    }
    // "All" has a single marker: the arrow's tip is there.
    let all = nearest_dark("All", "All - Correct");
    println!("All - Correct: arrow {all:.1} px away");
    // The tip stops short of the marker by about the marker's size (0.1 of a 1-unit quad).
    let px_per_unit = w as f32 / (2.0 * xmag);
    assert!(all < 0.15 * px_per_unit, "{all} px");
}
