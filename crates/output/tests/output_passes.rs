//! The passes of SPEC §6 as a compositor reads them: light passes that add up to the beauty,
//! unit normals, depth that is not anti-aliased, Cryptomatte coverage that adds up to alpha,
//! windows and bands that change no pixel, and the EXR that carries it all.

mod common;

use aperture_imageio::{Image, MetaValue, SampleType};
use aperture_output::{self as output, ExrOptions};
use aperture_render::{
    build_accel, render, render_window, scene_camera, AdaptiveOptions, Pass, PassSet,
    RenderOptions, Window,
};
use aperture_scene::{Material, Scene};
use aperture_shading::{test_scenes, Environment};
use glam::{Affine3A, Vec3};

/// The glass scene's materials: a refractive glass with a volume, a thin-walled pane and a
/// coated velvet with sheen.
fn glass_materials() -> [Material; 3] {
    let transmission = Some(aperture_scene::Transmission {
        factor: 1.0,
        texture: None,
    });
    let glass = Material {
        name: Some("Glass".into()),
        base_color_factor: glam::Vec4::new(0.9, 0.95, 1.0, 1.0),
        metallic_factor: 0.0,
        roughness_factor: 0.1,
        transmission,
        volume: Some(aperture_scene::Volume {
            thickness_factor: 1.0,
            thickness_texture: None,
            attenuation_distance: 2.0,
            attenuation_color: Vec3::new(0.8, 0.9, 1.0),
        }),
        ..Material::default()
    };
    let pane = Material {
        name: Some("Pane".into()),
        base_color_factor: glam::Vec4::new(0.7, 1.0, 0.8, 1.0),
        metallic_factor: 0.0,
        roughness_factor: 0.0,
        transmission,
        ..Material::default()
    };
    let velvet = Material {
        name: Some("Velvet".into()),
        base_color_factor: glam::Vec4::new(0.5, 0.1, 0.1, 1.0),
        metallic_factor: 0.0,
        roughness_factor: 0.6,
        clearcoat: Some(aperture_scene::Clearcoat {
            factor: 0.7,
            texture: None,
            roughness_factor: 0.1,
            roughness_texture: None,
            normal_texture: None,
            normal_scale: 1.0,
        }),
        sheen: Some(aperture_scene::Sheen {
            color_factor: Vec3::new(0.9, 0.8, 0.7),
            color_texture: None,
            roughness_factor: 0.4,
            roughness_texture: None,
        }),
        ..Material::default()
    };
    [glass, pane, velvet]
}

/// [`test_scenes::passes`] with glass: a refractive ball (with a volume), a thin-walled pane and a
/// coated ball with sheen, so the Transmission passes fill.
fn glass_scene() -> Scene {
    let mut s = test_scenes::passes();
    let first = s.materials.len() as u32;
    s.materials.extend(glass_materials());
    let place = |mesh: aperture_scene::Mesh, scale: f32, t: Vec3| {
        (
            mesh,
            Affine3A::from_scale_rotation_translation(Vec3::splat(scale), glam::Quat::IDENTITY, t),
        )
    };
    let added = [
        place(
            test_scenes::icosphere(3, first),
            0.45,
            Vec3::new(-0.5, 0.45, 1.3),
        ),
        (
            test_scenes::quad(1.2, first + 1),
            Affine3A::from_rotation_translation(
                glam::Quat::from_rotation_x(std::f32::consts::FRAC_PI_2),
                Vec3::new(0.9, 0.6, 1.6),
            ),
        ),
        place(
            test_scenes::icosphere(3, first + 2),
            0.3,
            Vec3::new(-1.8, 0.3, 1.2),
        ),
    ];
    for (mesh, xf) in added {
        s.meshes.push(mesh.into());
        s.instances.push(aperture_scene::Instance {
            mesh: s.meshes.len() as u32 - 1,
            world_from_object: xf,
            node: s.instances.len() as u32,
            materials: 0,
        });
    }
    s.node_names
        .extend(["GlassBall", "Pane", "VelvetBall"].map(|n| Some(n.to_string())));
    s
}

fn opts(passes: PassSet) -> RenderOptions {
    RenderOptions {
        width: 48,
        height: 32,
        spp: 16,
        passes,
        env: Environment::Constant(Vec3::splat(0.3)),
        ..RenderOptions::default()
    }
}

fn image_of(scene: &Scene, o: &RenderOptions) -> Image {
    let accel = build_accel(scene, Default::default());
    let film = render(scene, &accel, o, &|_, _| {}).unwrap();
    assert_eq!(film.dropped_samples(), 0);
    output::film_to_image(&film, scene, o, false, 0.0).unwrap()
}

fn rgb(image: &Image, layer: &str, p: usize) -> Vec3 {
    let l = image
        .layer(layer)
        .unwrap_or_else(|| panic!("no layer {layer}"));
    let n = l.channels.len();
    Vec3::from_slice(&l.data[p * n..p * n + 3])
}

/// `(Direct + Indirect) × Color` summed over the lobes, plus Emission and Environment, is the
/// beauty, pixel by pixel; returns the passes' totals over the image: (lit pixels, Diffuse
/// Direct, Diffuse Indirect, Glossy Direct, Transmission Direct + Indirect, Transmission Color).
fn check_light_passes(image: &Image) -> (usize, f32, f32, f32, f32, f32) {
    let (mut lit, mut direct, mut indirect, mut glossy) = (0, 0.0, 0.0, 0.0);
    let (mut transmission, mut transmission_color) = (0.0, 0.0);
    for (p, px) in image.rgba.iter().enumerate() {
        let beauty = Vec3::new(px[0], px[1], px[2]);
        let mut sum = rgb(image, "Emission", p) + rgb(image, "Environment", p);
        for lobe in ["Diffuse", "Glossy", "Transmission"] {
            let colour = rgb(image, &format!("{lobe} Color"), p);
            let light = rgb(image, &format!("{lobe} Direct"), p)
                + rgb(image, &format!("{lobe} Indirect"), p);
            sum += light * colour;
        }
        let err = (sum - beauty).abs().max_element();
        assert!(
            err <= 1e-5 * beauty.max_element().max(1e-2),
            "pixel {p}: passes {sum} vs beauty {beauty}"
        );
        lit += usize::from(beauty.max_element() > 0.0);
        direct += rgb(image, "Diffuse Direct", p).max_element();
        indirect += rgb(image, "Diffuse Indirect", p).max_element();
        glossy += rgb(image, "Glossy Direct", p).max_element();
        transmission += (rgb(image, "Transmission Direct", p)
            + rgb(image, "Transmission Indirect", p))
        .max_element();
        transmission_color += rgb(image, "Transmission Color", p).max_element();
    }
    (
        lit,
        direct,
        indirect,
        glossy,
        transmission,
        transmission_color,
    )
}

#[test]
fn light_passes_add_up_to_the_beauty() {
    let scene = test_scenes::passes();
    let image = image_of(&scene, &opts(PassSet::all()));
    let (lit, direct, indirect, glossy, _, transmission_color) = check_light_passes(&image);
    // Not vacuous: the scene fills every kind of pass.
    assert!(lit > image.rgba.len() / 2 && direct > 0.0 && indirect > 0.0 && glossy > 0.0);
    assert!((0..image.rgba.len()).any(|p| rgb(&image, "Emission", p).max_element() > 1.0));
    assert!((0..image.rgba.len()).any(|p| rgb(&image, "Environment", p).max_element() > 0.2));
    // Nothing transmits here.
    assert_eq!(transmission_color, 0.0);
}

/// The same with a refractive glass ball, a thin pane and a coated, sheened ball: their
/// transmission fills the Transmission passes, and everything still adds up.
#[test]
fn light_passes_add_up_with_glass() {
    let scene = glass_scene();
    let image = image_of(&scene, &opts(PassSet::all()));
    let (lit, direct, indirect, glossy, transmission, colour) = check_light_passes(&image);
    assert!(lit > image.rgba.len() / 2 && direct > 0.0 && indirect > 0.0 && glossy > 0.0);
    assert!(
        transmission > 1.0 && colour > 1.0,
        "{transmission} {colour}"
    );
}

#[test]
fn normals_are_unit_on_flat_surfaces_and_camera_space_for_the_denoiser() {
    // The lit plane alone fills the view: one flat surface, seen from above.
    let mut scene = test_scenes::lit_plane(4.0);
    scene.cameras[0].dof.enabled = true;
    scene.cameras[0].dof.aperture_radius = 0.05;
    let o = RenderOptions {
        width: 24,
        height: 16,
        spp: 8,
        passes: PassSet::compositing(),
        ..RenderOptions::default()
    };
    let image = image_of(&scene, &o);
    let cam = scene_camera(&scene, &o).unwrap();
    let up_in_camera = cam.world_from_camera.matrix3.transpose() * glam::Vec3A::Y;
    let expected = Vec3::new(up_in_camera.x, up_in_camera.y, -up_in_camera.z);
    for p in 0..image.rgba.len() {
        assert_eq!(image.rgba[p][3], 1.0);
        let n = rgb(&image, "Normal", p);
        assert!((n - Vec3::Y).length() < 1e-5, "pixel {p}: {n}");
        let d = rgb(&image, "Denoising Normal", p);
        assert!(
            (d - expected).length() < 1e-5,
            "pixel {p}: {d} vs {expected}"
        );
        // A surface facing the camera points back at it: −z in Cycles' camera space.
        assert!(d.z < 0.0);
        let a = rgb(&image, "Denoising Albedo", p);
        assert!(a.min_element() > 0.3 && a.max_element() < 1.0, "{a}");
    }
}

#[test]
fn depth_is_the_centre_ray_and_never_a_blend() {
    let scene = test_scenes::passes();
    let o = opts(PassSet::parse("Depth,Position").unwrap());
    let image = image_of(&scene, &o);
    let cam = scene_camera(&scene, &o).unwrap();
    let depth = &image.layer("Depth").unwrap().data;
    let position = &image.layer("Position").unwrap().data;
    let eye = Vec3::from(cam.world_from_camera.translation);
    let forward = Vec3::from(cam.world_from_camera.matrix3 * glam::Vec3A::NEG_Z);
    let (mut background, mut surface) = (0, 0);
    for (p, &z) in depth.iter().enumerate() {
        let pos = Vec3::from_slice(&position[3 * p..3 * p + 3]);
        if z == aperture_render::DEPTH_BACKGROUND {
            background += 1;
            assert_eq!(pos, Vec3::ZERO);
            continue;
        }
        surface += 1;
        // Depth is the view-axis distance of the very point Position holds, which lies on
        // some surface of the scene (the ground, or a ball), not between two of them.
        assert!(((pos - eye).dot(forward) - z).abs() < 1e-4 * z, "pixel {p}");
        let on_ground = pos.y.abs() < 1e-4;
        let on_ball = scene.instances[1..].iter().any(|i| {
            let c = Vec3::from(i.world_from_object.translation);
            let r = i.world_from_object.matrix3.x_axis.length();
            ((pos - c).length() - r).abs() < 0.02 * r
        });
        assert!(on_ground || on_ball, "pixel {p}: {pos} is on no surface");
        // The ray through the pixel centre and the lens centre: on the pixel's centre line.
        let (x, y) = ((p % 48) as f32 + 0.5, (p / 48) as f32 + 0.5);
        let ray = cam.centre_ray(glam::Vec2::new(x, y)).unwrap();
        assert!((pos - ray.origin).normalize().dot(ray.dir) > 1.0 - 1e-6);
    }
    assert!(background > 10 && surface > 10, "{background} {surface}");
}

#[test]
fn cryptomatte_coverage_adds_up_to_alpha_and_names_the_objects() {
    let scene = test_scenes::passes();
    let image = image_of(&scene, &opts(PassSet::compositing()));
    let id = |name: &str| {
        f32::from_bits(aperture_render::cryptomatte::id_bits(
            aperture_render::cryptomatte::murmur3_32(name.as_bytes()),
        ))
    };
    let mut fractional = 0;
    for kind in ["CryptoObject", "CryptoMaterial"] {
        let names: &[&str] = if kind == "CryptoObject" {
            &["Ground", "Blue", "Gold", "Mirror", "Lamp"]
        } else {
            &["Ground", "Glossy", "Gold", "Mirror", "Lamp"]
        };
        for (p, px) in image.rgba.iter().enumerate() {
            let mut total = 0.0;
            let mut last = f32::INFINITY;
            for layer in 0..3 {
                let l = image.layer(&format!("{kind}{layer:02}")).unwrap();
                for rank in 0..2 {
                    let (i, c) = (l.data[4 * p + 2 * rank], l.data[4 * p + 2 * rank + 1]);
                    assert!(c <= last, "ranks in decreasing coverage");
                    last = c;
                    if c > 0.0 {
                        assert!(names.iter().any(|n| id(n) == i), "unknown id at {p}");
                        fractional += usize::from(c < 1.0);
                    }
                    total += c;
                }
            }
            assert!(
                (total - px[3]).abs() < 1e-6,
                "{kind} pixel {p}: {total} vs {}",
                px[3]
            );
        }
        // The manifest names every object, and the key is Blender's.
        let key = aperture_render::cryptomatte::layer_key(kind);
        let Some(MetaValue::Text(m)) = image.meta(&format!("cryptomatte/{key}/manifest")) else {
            panic!("no manifest for {kind}");
        };
        for n in names {
            assert!(m.contains(&format!("\"{n}\":")), "{m}");
        }
        assert_eq!(
            image.meta(&format!("cryptomatte/{key}/name")),
            Some(&MetaValue::Text(kind.into()))
        );
    }
    // Edges (and defocused ones) give fractional coverage.
    assert!(fractional > 20, "{fractional}");
}

/// Any window of the image, uniform or adaptive, gives exactly the pixels and passes of the
/// whole render there: what banded output and tiled farm renders rely on.
#[test]
fn windows_are_bit_identical_to_the_whole_render() {
    let scene = test_scenes::passes();
    let accel = build_accel(&scene, Default::default());
    for adaptive in [false, true] {
        let mut o = opts(PassSet::all());
        o.spp = 32;
        o.adaptive = adaptive.then_some(AdaptiveOptions {
            threshold: 0.05,
            min_spp: 4,
        });
        let camera = scene_camera(&scene, &o).unwrap();
        let whole = output::film_to_image(
            &render(&scene, &accel, &o, &|_, _| {}).unwrap(),
            &scene,
            &o,
            false,
            0.0,
        )
        .unwrap();
        let counts = &whole.layer("Debug Sample Count").map(|l| l.data.clone());
        if adaptive {
            let c = counts.as_ref().unwrap();
            assert!(c.contains(&4.0) && c.contains(&32.0), "adaptive varies");
        }
        for w in [
            Window {
                x0: 0,
                y0: 0,
                width: 48,
                height: 32,
            },
            Window {
                x0: 5,
                y0: 3,
                width: 17,
                height: 9,
            },
            Window {
                x0: 30,
                y0: 20,
                width: 18,
                height: 12,
            },
            Window {
                x0: 47,
                y0: 0,
                width: 1,
                height: 32,
            },
        ] {
            let film = render_window(&scene, &accel, &camera, &o, w, &|_, _| {}).unwrap();
            let part = output::film_to_image(&film, &scene, &o, false, 0.0).unwrap();
            for y in 0..w.height as usize {
                for x in 0..w.width as usize {
                    let (p, q) = (
                        y * w.width as usize + x,
                        (y + w.y0 as usize) * 48 + x + w.x0 as usize,
                    );
                    let bits = |v: &[f32]| v.iter().map(|f| f.to_bits()).collect::<Vec<_>>();
                    assert_eq!(
                        bits(&part.rgba[p]),
                        bits(&whole.rgba[q]),
                        "{w:?} ({x}, {y})"
                    );
                    for (a, b) in part.layers.iter().zip(&whole.layers) {
                        let n = a.channels.len();
                        assert_eq!(a.name, b.name);
                        assert_eq!(
                            bits(&a.data[p * n..(p + 1) * n]),
                            bits(&b.data[q * n..(q + 1) * n]),
                            "{} {w:?} ({x}, {y}) adaptive {adaptive}",
                            a.name
                        );
                    }
                }
            }
        }
    }
}

/// The streamed EXR, in one band or in many, holds what the film in memory holds, and the
/// header's camera, lens, hashes and times.
#[test]
fn streamed_exr_in_bands_equals_the_film() {
    let scene = test_scenes::passes();
    let accel = build_accel(&scene, Default::default());
    let mut o = opts(PassSet::all());
    o.height = 70;
    let film = render(&scene, &accel, &o, &|_, _| {}).unwrap();
    let expected = output::film_to_image(&film, &scene, &o, false, 0.0).unwrap();
    let dir = std::env::temp_dir().join(format!("aperture-output-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for band_bytes in [output::BAND_BYTES, 1] {
        let path = dir.join(format!("bands-{band_bytes}.exr"));
        let exr = ExrOptions {
            band_bytes,
            ..ExrOptions::default()
        };
        let calls = std::sync::atomic::AtomicUsize::new(0);
        let summary = common::write_exr(&scene, &o, &path, &exr, None, &|done, total| {
            assert!(done <= total);
            calls.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        })
        .unwrap();
        assert_eq!(summary.samples, 48 * 70 * 16);
        assert!(calls.into_inner() >= 3 * 2);
        let back = aperture_imageio::read_exr(&path).unwrap();
        std::fs::remove_file(&path).unwrap();
        assert!(
            back.rgba == expected.rgba,
            "beauty, bands of {band_bytes} bytes"
        );
        // The reader sorts layers by name.
        let mut layers = expected.layers.clone();
        layers.sort_by(|a, b| a.name.cmp(&b.name));
        assert_eq!(back.layers.len(), layers.len());
        for (b, e) in back.layers.iter().zip(&layers) {
            assert!(
                b == e,
                "layer {} / {}, bands of {band_bytes} bytes",
                b.name,
                e.name
            );
        }
        let keep = |m: &Vec<(String, MetaValue)>| {
            m.iter()
                .filter(|(k, _)| !matches!(k.as_str(), "capDate" | "aperture:renderTime"))
                .cloned()
                .collect::<Vec<_>>()
        };
        let mut e = keep(&expected.metadata);
        e.sort_by(|a, b| a.0.cmp(&b.0));
        assert_eq!(keep(&back.metadata), e);
        assert!(matches!(back.meta("aperture:renderTime"), Some(MetaValue::Float(t)) if *t > 0.0));
        assert_eq!(back.meta("aperture:spp"), Some(&MetaValue::Int(16)));
        assert_eq!(
            back.meta("aperture:camera"),
            Some(&MetaValue::Text("test camera".into()))
        );
        assert_eq!(
            back.meta("aperture:apertureRadius"),
            Some(&MetaValue::Float(0.05))
        );
        assert_eq!(back.meta("focus"), Some(&MetaValue::Float(6.0)));
        assert_eq!(
            back.meta("colorInteropID"),
            Some(&MetaValue::Text("lin_rec709_scene".into()))
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `--half` stores colour as half, clamped to its range (and counted), data as float32.
#[test]
fn half_clamps_colour_and_keeps_data_float() {
    let mut scene = test_scenes::passes();
    scene.materials[4].emissive_factor = Vec3::splat(1e6);
    let o = opts(PassSet::parse("default,Emission").unwrap());
    let path = std::env::temp_dir().join(format!("aperture-half-{}.exr", std::process::id()));
    let exr = ExrOptions {
        half: true,
        ..ExrOptions::default()
    };
    let summary = common::write_exr(&scene, &o, &path, &exr, None, &|_, _| {}).unwrap();
    let back = aperture_imageio::read_exr(&path).unwrap();
    std::fs::remove_file(&path).unwrap();
    assert!(summary.half_clamped > 0);
    assert_eq!(back.beauty_type, SampleType::F16);
    assert!(back
        .rgba
        .iter()
        .flatten()
        .all(|v| v.is_finite() && v.abs() <= 65504.0));
    assert!(back.rgba.iter().any(|p| p[0] == 65504.0));
    let kind = |n: &str| back.layer(n).unwrap().sample_type;
    assert_eq!(kind("Emission"), SampleType::F16);
    assert_eq!(kind("Denoising Albedo"), SampleType::F16);
    assert_eq!(kind("Depth"), SampleType::F32);
    assert_eq!(kind("Normal"), SampleType::F32);
    assert_eq!(kind("CryptoObject00"), SampleType::F32);
}

#[test]
fn passes_cost_nothing_in_the_beauty() {
    // The beauty is bit-identical with and without passes: the recording adds no arithmetic
    // to the radiance.
    let scene = test_scenes::passes();
    let a = image_of(&scene, &opts(PassSet::NONE));
    let b = image_of(&scene, &opts(PassSet::all()));
    assert_eq!(a.rgba, b.rgba);
    assert!(b.layer(Pass::GlossyIndirect.name()).is_some());
}
