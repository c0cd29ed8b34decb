//! The thin-lens camera's tests: focus, aperture shapes, orientation, and properties.

use super::*;
use aperture_scene::Dof;

fn scene_camera(radius: f32, blades: u32, focus: f32) -> aperture_scene::Camera {
    test_scene_camera(Dof {
        enabled: true,
        aperture_radius: radius,
        focus_distance: focus,
        blades,
        rotation: 0.2,
        ..Dof::default()
    })
}

fn grid(n: u32) -> impl Iterator<Item = Vec2> {
    (0..n * n).map(move |i| {
        Vec2::new(
            ((i % n) as f32 + 0.37) / n as f32,
            ((i / n) as f32 + 0.61) / n as f32,
        )
    })
}

#[test]
fn focal_plane_point_is_the_same_for_every_lens_sample() {
    for blades in [0, 6] {
        for ortho in [false, true] {
            let mut sc = scene_camera(0.1, blades, 4.0);
            if ortho {
                sc.projection = Projection::Orthographic {
                    xmag: 2.0,
                    ymag: 1.5,
                };
            }
            let cam = Camera::new(&sc, 64, 48);
            let p_film = Vec2::new(13.3, 40.2);
            let pin = Camera {
                aperture: Aperture::Pinhole,
                ..cam
            }
            .generate_ray_camera_space(&CameraSample {
                p_film,
                p_lens: Vec2::ZERO,
                time: 0.0,
            })
            .unwrap();
            let target = pin.origin + pin.dir * (4.0 / -pin.dir.z);
            let mut origins = Vec::new();
            for p_lens in grid(8) {
                let r = cam
                    .generate_ray_camera_space(&CameraSample {
                        p_film,
                        p_lens,
                        time: 0.0,
                    })
                    .unwrap();
                let t = (-4.0 - r.origin.z) / r.dir.z;
                let hit = r.origin + t * r.dir;
                assert!(hit.distance(target) < 1e-5, "{hit} vs {target}");
                origins.push(r.origin);
            }
            // And the lens samples really differ (so the check above means something).
            let spread = origins
                .iter()
                .map(|o| o.distance(origins[0]))
                .fold(0.0f32, f32::max);
            assert!(spread > 0.1, "{spread}");
        }
    }
}

#[test]
fn primary_rays_start_inside_the_aperture() {
    // Disc with squeeze: (x·ratio)² + y² ≤ R².
    let mut sc = scene_camera(0.2, 0, 3.0);
    sc.dof.ratio = 2.0;
    let cam = Camera::new(&sc, 32, 32);
    let mut max_x: f32 = 0.0;
    for p_lens in grid(32) {
        let o = cam
            .generate_ray_camera_space(&CameraSample {
                p_film: Vec2::new(16.0, 16.0),
                p_lens,
                time: 0.0,
            })
            .unwrap()
            .origin;
        assert!(o.z == 0.0);
        assert!((o.x * 2.0).hypot(o.y) <= 0.2 * (1.0 + 1e-5));
        max_x = max_x.max(o.x.abs());
    }
    assert!(max_x > 0.09 && max_x <= 0.1 + 1e-6, "{max_x}");
    // Hexagon: inside every edge's half-plane.
    let sc = scene_camera(0.2, 6, 3.0);
    let cam = Camera::new(&sc, 32, 32);
    let corners: Vec<Vec2> = (0..6).map(|k| polygon_corner(k, 6, 0.2) * 0.2).collect();
    for p_lens in grid(32) {
        let o = cam
            .generate_ray_camera_space(&CameraSample {
                p_film: Vec2::new(3.0, 29.0),
                p_lens,
                time: 0.0,
            })
            .unwrap()
            .origin
            .truncate();
        for k in 0..6 {
            let (a, b) = (corners[k], corners[(k + 1) % 6]);
            assert!((b - a).perp_dot(o - a) >= -1e-6, "{o} outside edge {k}");
        }
    }
}

#[test]
fn zero_radius_is_a_pinhole() {
    let cam = Camera::new(&scene_camera(0.0, 6, 3.0), 16, 16);
    assert_eq!(cam.aperture, Aperture::Pinhole);
    let mut sc = scene_camera(0.3, 0, 3.0);
    sc.dof.enabled = false;
    assert_eq!(Camera::new(&sc, 16, 16).aperture, Aperture::Pinhole);
}

#[test]
fn image_plane_orientation() {
    let mut sc = scene_camera(0.0, 0, 1.0);
    sc.world_from_camera = Affine3A::IDENTITY;
    let cam = Camera::new(&sc, 40, 20);
    let top_left = cam
        .generate_ray(&CameraSample {
            p_film: Vec2::ZERO,
            p_lens: Vec2::ZERO,
            time: 0.0,
        })
        .unwrap();
    assert!(top_left.dir.x < 0.0 && top_left.dir.y > 0.0 && top_left.dir.z < 0.0);
    // Vertical half-angle is yfov/2, horizontal follows the aspect.
    let top = cam
        .generate_ray(&CameraSample {
            p_film: Vec2::new(20.0, 0.0),
            p_lens: Vec2::ZERO,
            time: 0.0,
        })
        .unwrap();
    assert!((top.dir.y / -top.dir.z - (0.4f32).tan()).abs() < 1e-6);
    assert!((top_left.dir.x / top_left.dir.z - 2.0 * (0.4f32).tan()).abs() < 1e-5);
}

mod properties {
    //! Property-based checks over the whole parameter space the loader lets through.
    use super::*;
    use proptest::prelude::*;

    /// Lens parameters: radius from 0 (pinhole) over twelve decades, focus from 1e-3 to 1e6,
    /// round or 3 to 16 blades, any rotation, squeeze 0.1 to 10.
    fn dof() -> impl Strategy<Value = Dof> {
        (
            prop_oneof![Just(None), (-9.0f32..2.0f32).prop_map(Some)],
            -3.0f32..6.0f32,
            prop_oneof![Just(0u32), 3u32..=16],
            -10.0f32..10.0,
            -1.0f32..1.0f32,
        )
            .prop_map(|(log_r, log_f, blades, rotation, log_ratio)| Dof {
                enabled: true,
                aperture_radius: log_r.map_or(0.0, |l| 10f32.powf(l)),
                focus_distance: 10f32.powf(log_f),
                blades,
                rotation,
                ratio: 10f32.powf(log_ratio),
                ..Dof::default()
            })
    }

    fn camera(dof: Dof, ortho: bool, yfov: f32) -> Camera {
        let mut sc = scene_camera(0.0, 0, 1.0);
        sc.dof = dof;
        if ortho {
            sc.projection = Projection::Orthographic {
                xmag: 2.0,
                ymag: 1.5,
            };
        } else {
            sc.projection = Projection::Perspective {
                yfov,
                aspect_ratio: None,
            };
        }
        Camera::new(&sc, 64, 48)
    }

    /// Lens samples in `[0, 1)²`, edges included.
    fn unit() -> impl Strategy<Value = f32> {
        prop_oneof![Just(0.0f32), Just(1.0 - f32::EPSILON / 2.0), 0.0f32..1.0]
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(512))]

        /// Every sample gives a finite unit ray from a point of the aperture (in the lens
        /// plane, inside the squeezed disc or polygon), in camera and world space.
        #[test]
        fn rays_are_finite_unit_and_start_on_the_aperture(
            dof in dof(),
            ortho in any::<bool>(),
            yfov in 0.01f32..3.1,
            fx in 0.0f32..=64.0, fy in 0.0f32..=48.0,
            lx in unit(), ly in unit(),
        ) {
            let cam = camera(dof.clone(), ortho, yfov);
            let s = CameraSample { p_film: Vec2::new(fx, fy), p_lens: Vec2::new(lx, ly), time: 0.0 };
            let r = cam.generate_ray_camera_space(&s).expect("a ray");
            prop_assert!(r.origin.is_finite() && r.dir.is_finite());
            prop_assert!((r.dir.length() - 1.0).abs() < 1e-5);
            prop_assert!(r.dir.z < 0.0, "{}", r.dir);
            let w = cam.generate_ray(&s).expect("a world ray");
            prop_assert!(w.origin.is_finite() && (w.dir.length() - 1.0).abs() < 1e-5);

            // Position on the lens, with the screen offset of orthographic cameras removed.
            let lens = if ortho {
                r.origin.truncate() - cam.screen_point(s.p_film)
            } else {
                r.origin.truncate()
            };
            prop_assert_eq!(r.origin.z, 0.0);
            let radius = dof.aperture_radius;
            // Unsqueezed, the point is inside the radius-R circle (all polygons are too);
            // tolerance: a few roundings of R, plus the orthographic screen offset's.
            let tol = 1e-5 * radius + if ortho { 1e-5 * 3.0 } else { 0.0 };
            let unsqueezed = Vec2::new(lens.x * dof.ratio, lens.y);
            prop_assert!(unsqueezed.length() <= radius + tol, "{unsqueezed} vs {radius}");
            if dof.blades >= 3 && radius > 0.0 {
                // Inside every edge's half-plane of the blade polygon.
                let n = dof.blades;
                for k in 0..n {
                    let a = polygon_corner(k, n, dof.rotation) * radius;
                    let b = polygon_corner((k + 1) % n, n, dof.rotation) * radius;
                    let side = (b - a).perp_dot(unsqueezed - a) / (b - a).length();
                    prop_assert!(side >= -tol, "outside edge {} by {}", k, -side);
                }
            }
        }

        /// The thin-lens rule: all rays of one film point meet at the same point of the
        /// focal plane, the one the pinhole ray through that film point reaches.
        #[test]
        fn the_focal_plane_point_does_not_depend_on_the_lens_sample(
            dof in dof(),
            ortho in any::<bool>(),
            yfov in 0.01f32..3.1,
            fx in 0.0f32..=64.0, fy in 0.0f32..=48.0,
            lx in unit(), ly in unit(),
        ) {
            let cam = camera(dof.clone(), ortho, yfov);
            let f = dof.focus_distance;
            let p_film = Vec2::new(fx, fy);
            let pin = Camera { aperture: Aperture::Pinhole, ..cam }
                .generate_ray_camera_space(&CameraSample { p_film, p_lens: Vec2::ZERO, time: 0.0 })
                .expect("a pinhole ray");
            let target = pin.origin + pin.dir * (f / -pin.dir.z);
            let r = cam
                .generate_ray_camera_space(&CameraSample { p_film, p_lens: Vec2::new(lx, ly), time: 0.0 })
                .expect("a ray");
            let hit = r.origin + r.dir * ((-f - r.origin.z) / r.dir.z);
            // Rounding: relative 1e-5 of the distances involved (focal point and lens
            // offset; direction normalisation and division each cost a few ulps).
            let scale = target.length() + r.origin.length();
            prop_assert!(
                hit.distance(target) <= 1e-5 * scale,
                "{} vs {} (scale {})", hit, target, scale
            );
        }
    }
}
