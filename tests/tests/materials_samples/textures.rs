//! Texture coordinates, UV sets, encodings and KHR_texture_transform: each part of a texture
//! lands where the sample's README says.

use aperture_accel::Ray;
use aperture_render::{build_accel, render, Camera, CameraSample, FilterKind, RenderOptions};
use aperture_scene::Scene;
use aperture_shading::Environment;
use aperture_tests::probe::{gltf_json, node, node_names, sample, Probe};
use glam::{Vec2, Vec3};

use crate::{front_ortho, horizon_sky, load, white_sky};

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
                    time: 0.0,
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
    let world = node_world_positions(&gltf_json(&path), names.len());
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
    offset_quads_show_their_quadrant(&probe, &scene, &names);
    let arrows = Arrows {
        probe: &probe,
        full: &full,
        names: &names,
        world: &world,
        camera: &camera,
    };
    arrows_point_at_the_correct_markers(&arrows);
}

/// World position of each node of `json` (`count` nodes): the parents here only translate.
fn node_world_positions(json: &serde_json::Value, count: usize) -> Vec<Vec3> {
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
    let mut world = vec![Vec3::ZERO; count];
    for (p, n) in json["nodes"].as_array().unwrap().iter().enumerate() {
        world[p] += translation(p);
        for c in n["children"].as_array().into_iter().flatten() {
            let c = c.as_u64().unwrap() as usize;
            world[c] += translation(p);
        }
    }
    world
}

/// The offset quads show the green (U), blue (V) and cyan (UV) quadrants of the UV texture.
fn offset_quads_show_their_quadrant(probe: &Probe, scene: &Scene, names: &[String]) {
    for (quad, ok) in [
        (
            "Offset U",
            &(|c: Vec3| c.y > 2.0 * c.x && c.y > 2.0 * c.z) as &dyn Fn(Vec3) -> bool,
        ),
        ("Offset V", &|c: Vec3| c.z > 2.0 * c.x && c.z > 2.0 * c.y),
        ("Offset UV", &|c: Vec3| c.y > 2.0 * c.x && c.z > 2.0 * c.x),
    ] {
        let (c, n) = probe.mean_of(scene, node(names, quad));
        println!("{quad}: mean {c} over {n} pixels");
        assert!(n > 200, "{quad}: {n} pixels");
        assert!(ok(c), "{quad}: {c}");
    }
}

/// The render without markers and what is needed to find the arrows and the markers in it.
struct Arrows<'a> {
    probe: &'a Probe,
    /// The scene with its markers.
    full: &'a Scene,
    names: &'a [String],
    world: &'a [Vec3],
    camera: &'a aperture_scene::Camera,
}

impl Arrows<'_> {
    /// Half the orthographic view's width and height, in world units.
    fn mag(&self) -> (f32, f32) {
        let aperture_scene::Projection::Orthographic { xmag, ymag } = self.camera.projection else {
            unreachable!()
        };
        (xmag, ymag)
    }

    /// World point to pixel through the orthographic camera.
    fn pixel(&self, p: Vec3) -> (i64, i64) {
        let (w, h) = (self.probe.width, self.probe.height);
        let (xmag, ymag) = self.mag();
        let centre = Vec3::from(self.camera.world_from_camera.translation);
        let x = (p.x - centre.x) / xmag * 0.5 * w as f32 + 0.5 * w as f32;
        let y = (centre.y - p.y) / ymag * 0.5 * h as f32 + 0.5 * h as f32;
        (x as i64, y as i64)
    }

    /// Distance in pixels from a marker to the nearest dark (arrow) pixel of the quad's
    /// material: the arrow points at the correct marker, so its tip is nearest to it.
    fn nearest_dark(&self, quad: &str, marker: &str) -> f32 {
        let (w, h) = (self.probe.width, self.probe.height);
        let id = self
            .full
            .materials
            .iter()
            .position(|m| m.name.as_deref() == Some(quad))
            .unwrap() as u32;
        let (mx, my) = self.pixel(self.world[node(self.names, marker) as usize]);
        let mut best = f32::INFINITY;
        for y in 0..h {
            for x in 0..w {
                if self.probe.materials[(y * w + x) as usize] != Some(id) {
                    continue;
                }
                let p = self.probe.film.pixel(x, y);
                if p[0] + p[1] + p[2] < 0.3 {
                    let d = ((x as i64 - mx) as f32).hypot((y as i64 - my) as f32);
                    best = best.min(d);
                }
            }
        }
        best
    }
}

/// The arrows, rotated, scaled and transformed by all three, point at their green "correct"
/// markers rather than the "not supported" or "error" ones.
fn arrows_point_at_the_correct_markers(arrows: &Arrows) {
    for (quad, correct, wrong) in [
        (
            "Rotation",
            "Rotation - Correct",
            &["Rotation - Not Supported", "Rotation - Error"][..],
        ),
        ("Scale", "Scale - Correct", &["Scale - Not Supported"][..]),
    ] {
        let c = arrows.nearest_dark(quad, correct);
        for bad in wrong {
            let b = arrows.nearest_dark(quad, bad);
            println!("{correct}: arrow {c:.1} px away; {bad}: {b:.1} px");
            assert!(c < 0.6 * b, "{correct} {c} vs {bad} {b}");
        }
    }
    // "All" has a single marker: the arrow's tip is there.
    let all = arrows.nearest_dark("All", "All - Correct");
    println!("All - Correct: arrow {all:.1} px away");
    // The tip stops short of the marker by about the marker's size (0.1 of a 1-unit quad).
    let px_per_unit = arrows.probe.width as f32 / (2.0 * arrows.mag().0);
    assert!(all < 0.15 * px_per_unit, "{all} px");
}
