//! The bokeh image and chromatic aberration (issue 61) through the camera and the renderer: a
//! constant image and zero aberration change no bit, the lens points follow the image, red's
//! image grows and blue's shrinks by the stated scale, each channel focuses where stated.

use aperture_render::camera::{Camera, CameraSample};
use aperture_render::{Frame, RenderOptions};
use aperture_scene::{ApertureImage, Chromatic, Dof, LensOptions, Projection};
use aperture_shading::test_scenes;
use glam::{Affine3A, Vec2, Vec3};
use std::sync::Arc;

fn scene_camera(dof: Dof) -> aperture_scene::Camera {
    aperture_scene::Camera {
        name: "bokeh".into(),
        node: None,
        index: None,
        world_from_camera: Affine3A::from_translation(Vec3::new(0.5, -1.0, 3.0)),
        projection: Projection::Perspective {
            yfov: 0.8,
            aspect_ratio: None,
        },
        dof,
    }
}

fn dof(options: LensOptions, blades: u32, rotation: f32) -> Dof {
    Dof {
        enabled: true,
        aperture_radius: 0.2,
        focus_distance: 3.0,
        blades,
        rotation,
        lens_options: options,
        ..Dof::default()
    }
}

/// A `w × h` image whose texel `(x, y)` (y down) transmits `f(x, y)`.
fn image(w: u32, h: u32, f: impl Fn(u32, u32) -> f32) -> LensOptions {
    let lum = (0..w * h).map(|i| f(i % w, i / w)).collect();
    LensOptions {
        aperture_image: Some(Arc::new(
            ApertureImage::new("test".into(), w, h, lum).unwrap(),
        )),
        ..LensOptions::default()
    }
}

fn grid(n: u32) -> impl Iterator<Item = Vec2> {
    (0..n * n).map(move |i| {
        Vec2::new(
            ((i % n) as f32 + 0.37) / n as f32,
            ((i / n) as f32 + 0.61) / n as f32,
        )
    })
}

fn sample(p_film: Vec2, p_lens: Vec2) -> CameraSample {
    CameraSample {
        p_film,
        p_lens,
        time: 0.0,
    }
}

fn render(options: LensOptions, blades: u32, spp: u32) -> Vec<[f32; 4]> {
    let mut scene = test_scenes::balls();
    let d = &mut scene.cameras[0].dof;
    (d.lens_options, d.blades, d.aperture_radius) = (options, blades, 0.2);
    let frame = Frame::still(scene, Default::default());
    let opts = RenderOptions {
        width: 24,
        height: 16,
        spp,
        ..Default::default()
    };
    let film = frame.render(&opts, &|_, _| {}).expect("a render");
    (0..16)
        .flat_map(|y| (0..24).map(move |x| (x, y)))
        .map(|(x, y)| film.pixel(x, y))
        .collect()
}

fn bits(v: &[[f32; 4]]) -> Vec<u32> {
    v.iter().flatten().map(|x| x.to_bits()).collect()
}

#[test]
fn a_constant_image_and_zero_aberration_render_the_plain_lens_bit_for_bit() {
    for blades in [0, 6] {
        let plain = render(LensOptions::default(), blades, 4);
        let white = image(7, 5, |_, _| 1.0);
        assert_eq!(bits(&plain), bits(&render(white, blades, 4)), "{blades}");
        let grey = image(3, 3, |_, _| 0.4);
        assert_eq!(bits(&plain), bits(&render(grey, blades, 4)), "{blades}");
        let zero = LensOptions {
            chromatic: Chromatic {
                lateral: 0.0,
                longitudinal: -0.0,
            },
            ..LensOptions::default()
        };
        assert_eq!(bits(&plain), bits(&render(zero, blades, 4)), "{blades}");
        // And they do change the image when they are not neutral.
        let half = image(8, 8, |x, _| if x >= 4 { 1.0 } else { 0.0 });
        assert_ne!(bits(&plain), bits(&render(half, blades, 4)));
        let ca = LensOptions {
            chromatic: Chromatic {
                lateral: 0.02,
                longitudinal: 0.05,
            },
            ..LensOptions::default()
        };
        assert_ne!(bits(&plain), bits(&render(ca, blades, 4)));
    }
}

#[test]
fn lens_points_lie_where_the_image_is_bright() {
    // The right half of the image lit: points on the right of the lens; turned a quarter, on
    // top; with six blades, inside the hexagon too; always in the aperture, always focused.
    let half = image(16, 16, |x, _| if x >= 8 { 1.0 } else { 0.0 });
    let quarter = std::f32::consts::FRAC_PI_2;
    for (blades, rotation) in [(0, 0.0), (0, quarter), (6, 0.0), (5, 0.3)] {
        let cam = Camera::new(&scene_camera(dof(half.clone(), blades, rotation)), 64, 48);
        let film = Vec2::new(20.0, 30.0);
        let ps = cam.screen_point(film);
        let (s, c) = rotation.sin_cos();
        for u in grid(40) {
            let r = cam.generate_ray_camera_space(&sample(film, u)).unwrap();
            let o = r.origin.truncate() / 0.2;
            // Back in the image's frame: x ≥ 0 is its lit half.
            let x = c * o.x + s * o.y;
            assert!(x >= -1e-5, "{blades} {rotation}: {o}");
            assert!(o.length() <= 1.0 + 1e-5, "{o} outside the aperture");
            if blades >= 3 {
                let n = blades as f32;
                let apothem = (std::f32::consts::PI / n).cos();
                for k in 0..blades {
                    let a = rotation + std::f32::consts::TAU * k as f32 / n;
                    let d = o.dot(Vec2::new(a.cos(), a.sin()));
                    assert!(d <= apothem * (1.0 + 1e-5), "{o} outside blade {k}");
                }
            }
            let hit = r.origin + r.dir * ((-3.0 - r.origin.z) / r.dir.z);
            let want = Vec3::new(ps.x * 3.0, ps.y * 3.0, -3.0);
            assert!(hit.distance(want) < 1e-4, "{hit} vs {want}");
        }
    }
}

#[test]
fn lens_points_follow_the_image_density() {
    // Two columns transmitting 0.25 and 0.75 over the round stop: 3/4 of the points on the right,
    // and within each half uniform by area (left/right of x = ±0.5 inside the disc);
    // chi-square of four cells, 3 degrees of freedom, 0.999 quantile 16.3.
    let two = image(2, 1, |x, _| if x == 0 { 0.25 } else { 0.75 });
    let cam = Camera::new(&scene_camera(dof(two, 0, 0.0)), 64, 48);
    let film = Vec2::new(32.0, 24.0);
    // Area of the unit disc with x in [0, 0.5] and in [0.5, 1].
    let inner = 0.5 * (1.0 - 0.25f64).sqrt() + (0.5f64).asin();
    let outer = std::f64::consts::FRAC_PI_2 - inner;
    let half = std::f64::consts::FRAC_PI_2;
    let want = [
        0.25 * outer / half,
        0.25 * inner / half,
        0.75 * inner / half,
        0.75 * outer / half,
    ];
    let n = 200;
    let mut counts = [0usize; 4];
    for u in grid(n) {
        let r = cam.generate_ray_camera_space(&sample(film, u)).unwrap();
        let x = r.origin.x / 0.2;
        counts[((x + 1.0) * 2.0).clamp(0.0, 3.0) as usize] += 1;
    }
    let total = (n * n) as f64;
    let chi2: f64 = (counts.iter().zip(want))
        .map(|(&c, w)| (c as f64 - total * w).powi(2) / (total * w))
        .sum();
    assert!(
        chi2 < 16.3,
        "{counts:?} against {want:?}: chi-square {chi2}"
    );
}

#[test]
fn the_image_combines_with_vignetting() {
    // At a corner the barrel clips the image's points too.
    let mut options = image(16, 16, |x, y| 0.2 + (x * y) as f32 / 225.0);
    options.vignetting = 1.0;
    let cam = Camera::new(&scene_camera(dof(options, 0, 0.0)), 64, 48);
    let corner = Vec2::ZERO;
    let ps = cam.screen_point(corner);
    let barrel = -ps / ps.length() * 0.2;
    for u in grid(32) {
        let o = (cam.generate_ray_camera_space(&sample(corner, u)))
            .unwrap()
            .origin
            .truncate();
        assert!(o.length() <= 0.2 * (1.0 + 1e-5), "{o} outside the aperture");
        assert!(
            o.distance(barrel) <= 0.2 * (1.0 + 1e-4),
            "{o} outside the barrel"
        );
    }
}

fn chromatic(lateral: f32, longitudinal: f32, radius: f32) -> Camera {
    let d = Dof {
        aperture_radius: radius,
        ..dof(
            LensOptions {
                chromatic: Chromatic {
                    lateral,
                    longitudinal,
                },
                ..LensOptions::default()
            },
            0,
            0.0,
        )
    };
    Camera::new(&scene_camera(d), 64, 48)
}

#[test]
fn lateral_aberration_scales_red_out_and_blue_in() {
    // A pinhole-sized lens: the direction a film point sees in each channel. Red sees at film
    // point p what green sees at p / (1 + lateral): its image is 1 + lateral times as large.
    let lateral = 0.01;
    let cam = chromatic(lateral, 0.0, 0.0);
    let plain = chromatic(0.0, 0.0, 0.0);
    let centre = Vec2::new(32.0, 24.0);
    for film in [
        Vec2::new(3.0, 5.0),
        Vec2::new(60.0, 40.0),
        Vec2::new(50.0, 24.0),
    ] {
        let s = sample(film, Vec2::splat(0.5));
        assert_eq!(cam.generate_ray_channel(&s, 1), plain.generate_ray(&s));
        for (channel, scale) in [(0, 1.0 + lateral), (2, 1.0 - lateral)] {
            let got = cam.generate_ray_channel(&s, channel).unwrap().dir;
            let q = centre + (film - centre) / scale;
            let want = plain
                .generate_ray(&sample(q, Vec2::splat(0.5)))
                .unwrap()
                .dir;
            assert!(
                got.distance(want) < 1e-6,
                "{channel} {film}: {got} vs {want}"
            );
        }
    }
    // Depth and Vector stay green's.
    assert_eq!(cam.centre_ray(centre), plain.centre_ray(centre));
}

#[test]
fn longitudinal_aberration_moves_each_channels_focal_plane() {
    let cam = chromatic(0.0, 0.1, 0.2);
    let film = Vec2::new(20.0, 30.0);
    let ps = cam.screen_point(film);
    for (channel, f) in [(0, 3.3), (1, 3.0), (2, 2.7)] {
        // Every lens point's ray meets the centre ray at the channel's focus distance.
        for u in grid(8) {
            let r = cam
                .generate_ray_camera_space_channel(&sample(film, u), channel)
                .unwrap();
            let hit = r.origin + r.dir * ((-f - r.origin.z) / r.dir.z);
            let want = Vec3::new(ps.x * f, ps.y * f, -f);
            assert!(hit.distance(want) < 1e-4, "{channel}: {hit} vs {want}");
        }
    }
}

#[test]
fn chromatic_aberration_keeps_the_image_unbiased() {
    // Each path carries one channel at three times its weight: the image's mean colour is the
    // plain lens's, within the noise of 64 samples a pixel.
    let mean = |v: &[[f32; 4]]| -> Vec3 {
        v.iter().map(|p| Vec3::new(p[0], p[1], p[2])).sum::<Vec3>() / v.len() as f32
    };
    let plain = mean(&render(LensOptions::default(), 0, 64));
    let ca = LensOptions {
        chromatic: Chromatic {
            lateral: 0.003,
            longitudinal: 0.01,
        },
        ..LensOptions::default()
    };
    let got = mean(&render(ca, 0, 64));
    let rel = (got - plain).abs() / plain;
    assert!(rel.max_element() < 0.04, "{got} vs {plain}");
}
