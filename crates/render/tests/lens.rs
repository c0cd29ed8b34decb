//! The thin lens's options of issue 61 through the camera: neutral values change no bit, the
//! barrel clips the aperture only off axis, and distortion matches OpenCV's model.

use aperture_render::camera::{Camera, CameraSample};
use aperture_render::motion::raster_of;
use aperture_render::{Frame, RenderOptions};
use aperture_scene::{Distortion, Dof, LensOptions, Projection};
use aperture_shading::test_scenes;
use glam::{Affine3A, Vec2, Vec3};

fn scene_camera(dof: Dof) -> aperture_scene::Camera {
    aperture_scene::Camera {
        name: "lens".into(),
        node: None,
        index: None,
        world_from_camera: Affine3A::from_translation(Vec3::new(0.5, -1.0, 3.0))
            * Affine3A::from_rotation_y(0.3),
        projection: Projection::Perspective {
            yfov: 0.8,
            aspect_ratio: None,
        },
        dof,
    }
}

fn lens_dof(options: LensOptions, blades: u32) -> Dof {
    Dof {
        enabled: true,
        aperture_radius: 0.2,
        focus_distance: 3.0,
        blades,
        rotation: 0.2,
        lens_options: options,
        ..Dof::default()
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

fn render(options: LensOptions) -> Vec<[f32; 4]> {
    let mut scene = test_scenes::balls();
    scene.cameras[0].dof.lens_options = options;
    let frame = Frame::still(scene, Default::default());
    let opts = RenderOptions {
        width: 24,
        height: 16,
        spp: 4,
        ..Default::default()
    };
    let film = frame.render(&opts, &|_, _| {}).expect("a render");
    (0..16)
        .flat_map(|y| (0..24).map(move |x| (x, y)))
        .map(|(x, y)| film.pixel(x, y))
        .collect()
}

#[test]
fn neutral_lens_options_render_the_plain_thin_lens_bit_for_bit() {
    let plain = render(LensOptions::default());
    let zero = Distortion {
        k1: -0.0,
        ..Distortion::default()
    };
    let neutral = render(LensOptions {
        vignetting: 0.0,
        distortion: zero,
        ..LensOptions::default()
    });
    let bits = |v: &[[f32; 4]]| -> Vec<u32> { v.iter().flatten().map(|x| x.to_bits()).collect() };
    assert_eq!(bits(&plain), bits(&neutral));
    // And the options do change the image when they are not neutral.
    let strong = render(LensOptions {
        vignetting: 1.0,
        distortion: Distortion { k1: -0.2, ..zero },
        ..LensOptions::default()
    });
    assert_ne!(bits(&plain), bits(&strong));
}

#[test]
fn vignetting_leaves_the_axis_alone_and_clips_the_corners_by_the_barrel() {
    for blades in [0, 6] {
        let plain = Camera::new(
            &scene_camera(lens_dof(LensOptions::default(), blades)),
            64,
            48,
        );
        let options = LensOptions {
            vignetting: 1.0,
            ..LensOptions::default()
        };
        let cam = Camera::new(&scene_camera(lens_dof(options, blades)), 64, 48);
        let centre = Vec2::new(32.0, 24.0);
        for u in grid(16) {
            let a = plain.generate_ray_camera_space(&sample(centre, u));
            assert_eq!(a, cam.generate_ray_camera_space(&sample(centre, u)), "{u}");
        }
        // At a corner the barrel (radius R) is R·v off centre, away from the corner.
        let corner = Vec2::new(0.0, 0.0);
        let ps = cam.screen_point(corner);
        let barrel = -ps / ps.length() * 0.2;
        let mut clipped = 0;
        for u in grid(32) {
            let r = cam.generate_ray_camera_space(&sample(corner, u)).unwrap();
            let o = r.origin.truncate();
            assert!(o.length() <= 0.2 * (1.0 + 1e-5), "{o} outside the aperture");
            assert!(
                o.distance(barrel) <= 0.2 * (1.0 + 1e-5),
                "{o} outside the barrel"
            );
            // Still the thin lens: every ray meets the focal plane where the centre ray does.
            let hit = r.origin + r.dir * ((-3.0 - r.origin.z) / r.dir.z);
            let want = Vec3::new(ps.x * 3.0, ps.y * 3.0, -3.0);
            assert!(hit.distance(want) < 1e-4, "{hit} vs {want}");
            let p = plain.generate_ray_camera_space(&sample(corner, u)).unwrap();
            clipped += usize::from(p.origin.truncate().distance(barrel) > 0.2);
        }
        assert!(
            clipped > 100,
            "the plain lens would have {clipped} points outside"
        );
    }
}

/// Pixel grid of the distortion tests: a 320 × 240 image, borders included.
fn pixels() -> impl Iterator<Item = Vec2> {
    (0..=16).flat_map(|j| (0..=16).map(move |i| Vec2::new(i as f32 * 20.0, j as f32 * 15.0)))
}

const CV: [f64; 5] = [-0.28, 0.09, -0.012, 0.0012, -0.0018]; // k1, k2, k3, p1, p2

fn distorted_camera() -> (Camera, f64, f64) {
    let d = Distortion {
        k1: CV[0] as f32,
        k2: CV[1] as f32,
        k3: CV[2] as f32,
        p1: CV[3] as f32,
        p2: CV[4] as f32,
    };
    let dof = Dof {
        lens_options: LensOptions {
            vignetting: 0.0,
            distortion: d,
            ..LensOptions::default()
        },
        ..Dof::default()
    };
    let cam = Camera::new(&scene_camera(dof), 320, 240);
    let (tx, ty) = cam.model.tan_half().unwrap();
    // OpenCV's camera matrix: focal lengths in pixels, principal point at the centre.
    (cam, 160.0 / f64::from(tx), 120.0 / f64::from(ty))
}

/// OpenCV's `projectPoints` distortion of normalised `(x, y)` (y down).
fn cv_distort(x: f64, y: f64) -> (f64, f64) {
    let [k1, k2, k3, p1, p2] = CV;
    let r2 = x * x + y * y;
    let radial = 1.0 + k1 * r2 + k2 * r2 * r2 + k3 * r2 * r2 * r2;
    (
        x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x),
        y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y,
    )
}

/// OpenCV's `undistortPoints` iteration (`cvUndistortPointsInternal`, k4…k6 = 0), run to
/// convergence rather than its default 5 steps.
fn cv_undistort(x0: f64, y0: f64) -> (f64, f64) {
    let [k1, k2, k3, p1, p2] = CV;
    let (mut x, mut y) = (x0, y0);
    for _ in 0..200 {
        let r2 = x * x + y * y;
        let icdist = 1.0 / (1.0 + ((k3 * r2 + k2) * r2 + k1) * r2);
        let dx = 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x);
        let dy = p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y;
        x = (x0 - dx) * icdist;
        y = (y0 - dy) * icdist;
    }
    (x, y)
}

#[test]
fn distortion_round_trips_with_opencv_within_1e4_pixel() {
    let (cam, fx, fy) = distorted_camera();
    let mut worst = (0.0f64, 0.0f64);
    for p_film in pixels() {
        let r = cam
            .generate_ray_camera_space(&sample(p_film, Vec2::ZERO))
            .unwrap();
        assert_eq!(r.origin, Vec3::ZERO);
        // The ray's normalised coordinates, OpenCV's way round (y down).
        let (x, y) = (
            f64::from(r.dir.x / -r.dir.z),
            -f64::from(r.dir.y / -r.dir.z),
        );
        let (u, v) = (f64::from(p_film.x), f64::from(p_film.y));
        let (xd, yd) = cv_distort(x, y);
        let forward = (fx * xd + 160.0 - u).hypot(fy * yd + 120.0 - v);
        let (xu, yu) = cv_undistort((u - 160.0) / fx, (v - 120.0) / fy);
        let back = (fx * (xu - x)).hypot(fy * (yu - y));
        worst = (worst.0.max(forward), worst.1.max(back));
        // The Vector pass's projection (through the centre ray) lands back on the pixel.
        let c = cam.centre_ray(p_film).unwrap();
        let q = raster_of(&cam, c.origin + 5.0 * c.dir).unwrap();
        assert!(q.distance(p_film) < 2e-3, "{q} vs {p_film}");
    }
    println!(
        "worst: projectPoints {:.2e} px, undistortPoints {:.2e} px",
        worst.0, worst.1
    );
    assert!(worst.0 < 1e-4 && worst.1 < 1e-4, "{worst:?}");
}

#[test]
fn zero_distortion_is_the_identity_exactly() {
    let plain = Camera::new(&scene_camera(Dof::default()), 320, 240);
    let zero = Dof {
        lens_options: LensOptions {
            vignetting: 0.0,
            distortion: Distortion {
                k1: 0.0,
                k2: -0.0,
                ..Distortion::default()
            },
            ..LensOptions::default()
        },
        ..Dof::default()
    };
    let cam = Camera::new(&scene_camera(zero), 320, 240);
    for p_film in pixels() {
        let s = sample(p_film, Vec2::splat(0.3));
        assert_eq!(plain.generate_ray(&s), cam.generate_ray(&s));
        assert_eq!(plain.centre_ray(p_film), cam.centre_ray(p_film));
    }
}
