//! Instances moving within the shutter: each ray meets an instance where it is at the ray's
//! time, and still instances are untouched by time.

use aperture_accel::{
    Accel, BvhQuality, FrameHints, InstanceInput, MeshInput, MotionTransform, Ray,
};
use glam::{Affine3A, Vec3};

/// A unit square in the plane z = 0 (two triangles), facing +Z.
fn square() -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let p = vec![
        Vec3::new(-0.5, -0.5, 0.0),
        Vec3::new(0.5, -0.5, 0.0),
        Vec3::new(0.5, 0.5, 0.0),
        Vec3::new(-0.5, 0.5, 0.0),
    ];
    (p, vec![[0, 1, 2], [0, 2, 3]])
}

#[test]
fn a_moving_instance_is_met_where_it_is_at_the_ray_time() {
    let (p, i) = square();
    let meshes = [MeshInput {
        positions: &p,
        indices: &i,
    }];
    // Instance 0 moves from x = -4 to x = 4 at z = -5; instance 1 stays at x = 0, z = -10.
    let start = Affine3A::from_translation(Vec3::new(-4.0, 0.0, -5.0));
    let end = Affine3A::from_translation(Vec3::new(4.0, 0.0, -5.0));
    let still = Affine3A::from_translation(Vec3::new(0.0, 0.0, -10.0));
    let instances = [
        InstanceInput {
            mesh: 0,
            world_from_object: start,
        },
        InstanceInput {
            mesh: 0,
            world_from_object: still,
        },
    ];
    let motion = [MotionTransform::new(&[start, end]), None];
    for single in [false, true] {
        let hints = FrameHints {
            motion: if single { &motion[..1] } else { &motion },
            ..FrameHints::STILL
        };
        let n = if single { 1 } else { 2 };
        let accel = Accel::build_frame(&meshes, &instances[..n], BvhQuality::Medium, hints, None);
        for k in 0..=16 {
            let time = k as f32 / 16.0;
            let x = -4.0 + 8.0 * time;
            // A ray down −Z at the moving square's centre at this time meets it at t = 5.
            let ray = Ray {
                time,
                ..Ray::new(Vec3::new(x, 0.0, 0.0), Vec3::NEG_Z)
            };
            let hit = accel.intersect(&ray).expect("the moving square");
            assert_eq!(hit.instance, 0, "time {time}");
            assert!((hit.t - 5.0).abs() < 1e-4, "time {time}: t = {}", hit.t);
            assert!(accel.occluded(&ray));
            // Where it was at the other end of the interval it is not.
            let away = Ray {
                time: 1.0 - time,
                ..ray
            };
            if (time - 0.5).abs() > 0.1 {
                let h = accel.intersect(&away);
                assert!(h.is_none_or(|h| h.instance != 0), "time {time}");
            }
            let mut batch = [None; 2];
            accel.intersect_batch(&[ray, away], &mut batch);
            assert_eq!(batch[0], accel.intersect(&ray));
            assert_eq!(batch[1], accel.intersect(&away));
        }
        if !single {
            // The still square ignores time.
            for time in [0.0, 0.3, 1.0] {
                let ray = Ray {
                    time,
                    ..Ray::new(Vec3::new(0.0, 0.3, -6.0), Vec3::NEG_Z)
                };
                let hit = accel.intersect(&ray).expect("the still square");
                assert_eq!((hit.instance, hit.t), (1, 4.0));
            }
        }
    }
}
