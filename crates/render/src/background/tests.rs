use super::*;
use crate::camera::CameraModel;
use crate::camera::{Aperture, CameraSample};
use glam::{Affine3A, Quat, Vec2};

/// A small deterministic generator (xorshift).
struct Rng(u64);

impl Rng {
    fn f(&mut self) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
    fn range(&mut self, a: f32, b: f32) -> f32 {
        a + (b - a) * self.f()
    }
}

/// Whether the segment from `o` along `d` (`t ≥ 0`) meets the box, in `f64`.
fn meets(o: Vec3, d: Vec3, lo: Vec3, hi: Vec3) -> bool {
    let (o, d, lo, hi) = (o.as_dvec3(), d.as_dvec3(), lo.as_dvec3(), hi.as_dvec3());
    let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
    for a in 0..3 {
        if d[a] == 0.0 {
            if o[a] < lo[a] || o[a] > hi[a] {
                return false;
            }
            continue;
        }
        let (u, v) = ((lo[a] - o[a]) / d[a], (hi[a] - o[a]) / d[a]);
        t0 = t0.max(u.min(v));
        t1 = t1.min(u.max(v));
    }
    t0 <= t1
}

fn camera(rng: &mut Rng, aperture: Aperture, width: u32, height: u32) -> Camera {
    let rot = Quat::from_euler(
        glam::EulerRot::YXZ,
        rng.range(-3.0, 3.0),
        rng.range(-0.7, 0.7),
        rng.range(-0.3, 0.3),
    );
    let pos = Vec3::new(
        rng.range(-5.0, 5.0),
        rng.range(-5.0, 5.0),
        rng.range(-5.0, 5.0),
    );
    let tan_half_y = rng.range(0.1, 1.2);
    Camera {
        world_from_camera: Affine3A::from_rotation_translation(rot, pos),
        model: CameraModel::ThinLens {
            tan_half_x: tan_half_y * width as f32 / height as f32,
            tan_half_y,
        },
        aperture,
        focus_distance: rng.range(0.5, 20.0),
        width,
        height,
        lens: crate::lens::Lens::IDEAL,
        realistic: None,
    }
}

#[test]
fn rays_of_pixels_outside_never_meet_the_box() {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let (mut culled, mut kept) = (0usize, 0usize);
    for case in 0..300 {
        let radius = [0.0, 0.05, 0.4, 1.5][case % 4];
        let aperture = match case % 3 {
            _ if radius == 0.0 => Aperture::Pinhole,
            0 => Aperture::Disc { radius, ratio: 1.0 },
            1 => Aperture::Disc { radius, ratio: 0.6 },
            _ => Aperture::Polygon {
                radius,
                blades: 5,
                rotation: 0.3,
                ratio: 1.4,
            },
        };
        let (width, height) = (24, 18);
        let cam = camera(&mut rng, aperture, width, height);
        // A box somewhere in front of (or around) the camera.
        let at = cam.world_from_camera.transform_point3(Vec3::new(
            rng.range(-4.0, 4.0),
            rng.range(-3.0, 3.0),
            rng.range(-12.0, 1.0),
        ));
        let half = Vec3::new(
            rng.range(0.05, 2.0),
            rng.range(0.05, 2.0),
            rng.range(0.05, 2.0),
        );
        let (lo, hi) = (at - half, at + half);
        let filter_half = [0.5, 0.75][case % 2];
        let rect = box_pixels(&cam, lo, hi, filter_half);
        let (k, c) = check_left_out(&mut rng, &cam, rect, (lo, hi), filter_half, 24, case);
        (kept, culled) = (kept + k, culled + c);
    }
    // Both kinds occur, so the test checks something either way.
    assert!(
        culled > 10_000 && kept > 10_000,
        "culled {culled}, kept {kept}"
    );
}

#[test]
fn chromatic_channels_stay_inside_the_union_of_their_windows() {
    // Each channel is a thin lens of its own (image scaled by 1 ± lateral, focus by
    // 1 ± longitudinal): no channel's ray of a pixel outside meets the box.
    let mut rng = Rng(0x51_7cc1_b727_220a);
    let (mut culled, mut kept) = (0usize, 0usize);
    for case in 0..240 {
        let radius = [0.0, 0.05, 0.4][case % 3];
        let aperture = match radius {
            0.0 => Aperture::Pinhole,
            _ => Aperture::Disc { radius, ratio: 1.0 },
        };
        let mut cam = camera(&mut rng, aperture, 24, 18);
        let lateral = [0.004, -0.02, 0.3, 0.0][case % 4];
        let longitudinal = [0.03, 0.0, -0.45, 0.2][(case / 4) % 4];
        cam.lens.chromatic = Some(crate::lens::Chromatic {
            lateral,
            longitudinal,
        })
        .filter(|c| !c.is_zero());
        let at = cam.world_from_camera.transform_point3(Vec3::new(
            rng.range(-4.0, 4.0),
            rng.range(-3.0, 3.0),
            rng.range(-12.0, 1.0),
        ));
        let half = Vec3::new(
            rng.range(0.05, 1.5),
            rng.range(0.05, 1.5),
            rng.range(0.05, 1.5),
        );
        let (lo, hi) = (at - half, at + half);
        let rect = box_pixels(&cam, lo, hi, 0.5);
        let (k, c) = check_left_out(&mut rng, &cam, rect, (lo, hi), 0.5, 24, case);
        (kept, culled) = (kept + k, culled + c);
    }
    assert!(
        culled > 10_000 && kept > 5_000,
        "culled {culled}, kept {kept}"
    );
}

#[test]
fn the_rectangle_holds_the_pixels_that_see_the_box() {
    // Pixels whose centre ray meets the box are all inside, however the rectangle is cut.
    let mut rng = Rng(7);
    for _ in 0..200 {
        let cam = Camera {
            model: CameraModel::ThinLens {
                tan_half_x: 0.96,
                tan_half_y: 0.6,
            },
            focus_distance: rng.range(4.0, 8.0),
            ..camera(
                &mut rng,
                Aperture::Disc {
                    radius: 0.2,
                    ratio: 1.0,
                },
                32,
                20,
            )
        };
        let at = cam
            .world_from_camera
            .transform_point3(Vec3::new(0.0, 0.0, -6.0));
        let (lo, hi) = (at - Vec3::splat(0.7), at + Vec3::splat(0.7));
        let rect = box_pixels(&cam, lo, hi, 0.5);
        let mut seen = 0;
        for y in 0..20 {
            for x in 0..32 {
                let r = cam
                    .centre_ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5))
                    .expect("a ray");
                if meets(r.origin, r.dir, lo, hi) {
                    seen += 1;
                    assert!(rect.contains(x, y), "({x}, {y}) sees the box, {rect:?}");
                }
            }
        }
        assert!(seen > 0);
        // And the bound is tight enough to matter: a box of 1.4 at distance 6 (in focus
        // or nearly) leaves most of a view 7.2 high outside.
        let area = (rect.x1 - rect.x0 + 1) * (rect.y1 - rect.y0 + 1);
        assert!(area < 32 * 20 / 2, "{rect:?}");
    }
}

#[test]
fn no_bound_where_none_holds() {
    let mut rng = Rng(11);
    let cam = camera(
        &mut rng,
        Aperture::Disc {
            radius: 0.1,
            ratio: 1.0,
        },
        8,
        6,
    );
    let all = PixelRect::all(8, 6);
    // A box around the camera.
    let p: Vec3 = cam.world_from_camera.translation.into();
    assert_eq!(box_pixels(&cam, p - Vec3::ONE, p + Vec3::ONE, 0.5), all);
    // Orthographic cameras are not bounded here.
    let ortho = Camera {
        model: CameraModel::Orthographic {
            half_x: 1.0,
            half_y: 1.0,
        },
        ..cam
    };
    let far = cam
        .world_from_camera
        .transform_point3(Vec3::new(0.0, 0.0, -50.0));
    assert_eq!(box_pixels(&ortho, far, far + Vec3::ONE, 0.5), all);
    // No geometry: no pixel sees any.
    assert_eq!(scene_pixels(&cam, &[], 0.5).count(), 0);
}

/// The pixels of `cam` inside `rect` and outside it (kept, culled), checking that `rays` rays
/// of every pixel outside miss the box `lo..hi`.
fn check_left_out(
    rng: &mut Rng,
    cam: &Camera,
    rect: PixelRect,
    (lo, hi): (Vec3, Vec3),
    filter_half: f32,
    rays: usize,
    case: usize,
) -> (usize, usize) {
    let (mut kept, mut culled) = (0, 0);
    for y in 0..cam.height {
        for x in 0..cam.width {
            if rect.contains(x, y) {
                kept += 1;
                continue;
            }
            culled += 1;
            for _ in 0..rays {
                // Under chromatic aberration, any channel's ray.
                let channel = match cam.lens.chromatic {
                    Some(_) => ((rng.f() * 3.0) as usize).min(2),
                    None => 1,
                };
                let r = cam
                    .generate_ray_channel(&sample_in(rng, x, y, filter_half), channel)
                    .expect("a perspective camera makes rays");
                assert!(
                    !meets(r.origin, r.dir, lo, hi),
                    "case {case}: pixel ({x}, {y}) outside {rect:?} meets the box"
                );
            }
        }
    }
    (kept, culled)
}

/// Film and lens points over pixel `(x, y)`'s filter support and the whole aperture square.
fn sample_in(rng: &mut Rng, x: u32, y: u32, filter_half: f32) -> CameraSample {
    let off = Vec2::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)) * filter_half;
    CameraSample {
        p_film: Vec2::new(x as f32 + 0.5, y as f32 + 0.5) + off,
        p_lens: Vec2::new(rng.f(), rng.f()),
        time: 0.0,
    }
}

#[test]
fn grounds_and_walls_through_the_lens_plane() {
    // Flat boxes reaching behind the camera (a ground under it, a wall beside it): the rays of
    // pixels outside never meet them, and the view above a ground's far edge is outside.
    let mut rng = Rng(0x2545_f491_4f6c_dd1d);
    let (mut culled, mut kept, mut skies) = (0usize, 0usize, 0usize);
    for case in 0..400 {
        let radius = [0.0, 0.05, 0.3][case % 3];
        let aperture = if radius == 0.0 {
            Aperture::Pinhole
        } else {
            Aperture::Disc { radius, ratio: 1.0 }
        };
        let (width, height) = (32, 24);
        let pitch = rng.range(-0.35, 0.1);
        let height_above = rng.range(0.2, 3.0);
        let cam = Camera {
            world_from_camera: Affine3A::from_rotation_translation(
                Quat::from_euler(glam::EulerRot::YXZ, rng.range(-3.0, 3.0), pitch, 0.0),
                Vec3::new(rng.range(-2.0, 2.0), height_above, rng.range(-2.0, 2.0)),
            ),
            model: CameraModel::ThinLens {
                tan_half_x: 0.5,
                tan_half_y: 0.375,
            },
            aperture,
            focus_distance: rng.range(0.5, 20.0),
            width,
            height,
            lens: crate::lens::Lens::IDEAL,
            realistic: None,
        };
        let extent = rng.range(5.0, 60.0);
        let (lo, hi) = if case % 4 == 3 {
            // A wall at x = 3 spanning the camera's surroundings.
            (
                Vec3::new(3.0, -extent, -extent),
                Vec3::new(3.0, extent, extent),
            )
        } else {
            (
                Vec3::new(-extent, 0.0, -extent),
                Vec3::new(extent, 0.0, extent),
            )
        };
        let rect = box_pixels(&cam, lo, hi, 0.5);
        let before = culled;
        let (k, c) = check_left_out(&mut rng, &cam, rect, (lo, hi), 0.5, 16, case);
        (kept, culled) = (kept + k, culled + c);
        // A camera level with the ground (pitch above −0.2, so the horizon is in view) sees
        // sky above a large ground's far edge.
        if case % 4 != 3 && pitch > -0.2 && extent > 20.0 && culled > before {
            skies += 1;
        }
    }
    assert!(
        culled > 20_000 && kept > 20_000 && skies > 40,
        "culled {culled}, kept {kept}, skies {skies}"
    );
}

/// A scene as a BVH cuts it: a ground reaching behind the camera, objects on it, one far away.
fn cut_scene() -> aperture_accel::Accel {
    use aperture_accel::{BvhQuality, InstanceInput, MeshInput};
    let (mut p, mut t) = (Vec::new(), Vec::new());
    for j in 0..=8u32 {
        for i in 0..=8u32 {
            let (u, v) = (i as f32 / 4.0 - 1.0, j as f32 / 4.0 - 1.0);
            p.push(Vec3::new(u, 0.3 * (3.0 * u).sin() * v.cos(), v));
        }
    }
    for j in 0..8 {
        for i in 0..8 {
            let a = j * 9 + i;
            t.push([a, a + 1, a + 10]);
            t.push([a, a + 10, a + 9]);
        }
    }
    let ground = [
        Vec3::new(-30.0, 0.0, -30.0),
        Vec3::new(30.0, 0.0, -30.0),
        Vec3::new(30.0, 0.0, 30.0),
        Vec3::new(-30.0, 0.0, 30.0),
    ];
    let meshes = [
        MeshInput {
            positions: &p,
            indices: &t,
        },
        MeshInput {
            positions: &ground,
            indices: &[[0, 1, 2], [0, 2, 3]],
        },
    ];
    let at = |mesh: u32, s: f32, x: f32, y: f32, z: f32| InstanceInput {
        mesh,
        world_from_object: Affine3A::from_scale_rotation_translation(
            Vec3::splat(s),
            Quat::from_rotation_y(x + z),
            Vec3::new(x, y, z),
        ),
    };
    let instances = [
        at(1, 1.0, 0.0, 0.0, 0.0),
        at(0, 1.0, -2.0, 1.0, -6.0),
        at(0, 0.5, 1.5, 0.5, -3.0),
        at(0, 2.0, 4.0, 3.0, -15.0),
        at(0, 1.0, -8.0, 6.0, -25.0),
    ];
    aperture_accel::Accel::build(&meshes, &instances, BvhQuality::Medium)
}

/// A random thin-lens camera above the cut scene's ground; aperture radius by `case`.
fn cut_camera(rng: &mut Rng, case: usize) -> Camera {
    let (width, height) = (48, 32);
    Camera {
        world_from_camera: Affine3A::from_rotation_translation(
            Quat::from_euler(
                glam::EulerRot::YXZ,
                rng.range(-0.4, 0.4),
                rng.range(-0.3, 0.05),
                0.0,
            ),
            Vec3::new(
                rng.range(-1.0, 1.0),
                rng.range(0.8, 2.5),
                rng.range(4.0, 8.0),
            ),
        ),
        model: CameraModel::ThinLens {
            tan_half_x: 0.6,
            tan_half_y: 0.4,
        },
        aperture: Aperture::Disc {
            radius: [0.0, 0.1, 0.4][case % 3],
            ratio: 1.0,
        },
        focus_distance: rng.range(2.0, 12.0),
        width,
        height,
        lens: crate::lens::Lens::IDEAL,
        realistic: None,
    }
}

#[test]
fn pixels_outside_the_cut_see_no_triangle() {
    // Every ray of a pixel outside the union of the cut's rectangles misses everything.
    use aperture_accel::Ray;
    let accel = cut_scene();
    let mut rng = Rng(99);
    let (mut culled, mut total) = (0usize, 0usize);
    for case in 0..24 {
        let cam = cut_camera(&mut rng, case);
        let (width, height) = (cam.width, cam.height);
        let boxes = accel.cover(64);
        let mask = scene_pixels(&cam, &boxes, 0.5);
        for y in 0..height {
            for x in 0..width {
                total += 1;
                if mask.contains(x, y) {
                    continue;
                }
                culled += 1;
                for _ in 0..16 {
                    let r = cam
                        .generate_ray(&sample_in(&mut rng, x, y, 0.5))
                        .expect("a ray");
                    let hit = accel.intersect(&Ray::new(r.origin, r.dir));
                    assert!(hit.is_none(), "case {case}: ({x}, {y}) hits {hit:?}");
                }
            }
        }
        // The root's box alone (the camera stands inside it) bounds nothing.
        let root = accel.bounds().expect("geometry");
        assert!(scene_pixels(&cam, &[root], 0.5).is_all(), "case {case}");
    }
    // The sky above the ground's far edge, between the objects, is outside.
    assert!(culled * 8 > total, "culled {culled} of {total}");
}
