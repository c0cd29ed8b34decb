//! `Accel::cover`: the boxes of the cut hold every triangle, whatever the scene's layout
//! (flattened, instanced, both), and stay within the budget.

use aperture_accel::{Accel, BvhQuality, FrameHints, InstanceInput};
use glam::{Affine3A, Quat, Vec3};

mod common;
use common::{grid, mesh_inputs};

/// The structures a scene may get: flattened, instanced, joined pieces, moving instances.
fn layouts(moving: &[bool]) -> [(&'static str, FrameHints<'_>); 4] {
    [
        ("flattened", FrameHints::STILL),
        (
            "instanced",
            FrameHints {
                flatten_shared_up_to: 0,
                ..FrameHints::STILL
            },
        ),
        (
            "joined pieces",
            FrameHints {
                join_from: 0,
                ..FrameHints::STILL
            },
        ),
        (
            "moving instances",
            FrameHints {
                moving,
                ..FrameHints::STILL
            },
        ),
    ]
}

#[test]
fn the_cut_holds_every_triangle() {
    let meshes = [grid(9, 0.2), grid(4, 0.2), grid(1, 0.2)];
    let inputs = mesh_inputs(&meshes);
    // A ground-like plate far larger than the rest, mesh 0 drawn three times, a lone quad.
    let place = |mesh: u32, scale: f32, angle: f32, at: Vec3| InstanceInput {
        mesh,
        world_from_object: Affine3A::from_scale_rotation_translation(
            Vec3::splat(scale),
            Quat::from_rotation_x(angle),
            at,
        ),
    };
    let instances = [
        place(1, 40.0, -std::f32::consts::FRAC_PI_2, Vec3::ZERO),
        place(0, 1.0, 0.3, Vec3::new(-3.0, 1.0, 2.0)),
        place(0, 0.5, 1.1, Vec3::new(4.0, 2.0, -6.0)),
        place(0, 2.0, -0.4, Vec3::new(0.0, 3.0, -12.0)),
        place(2, 0.3, 0.0, Vec3::new(1e3, 5.0, 0.0)),
    ];
    let moving = [false, true, true, false, false];
    let layouts = layouts(&moving);
    for (name, hints) in layouts {
        let accel = Accel::build_frame(&inputs, &instances, BvhQuality::Medium, hints, None);
        let root = accel.bounds().expect("geometry");
        let mut finer = false;
        for budget in [0, 1, 2, 5, 8, 16, 64, 400] {
            let cut = accel.cover(budget);
            assert!(
                !cut.is_empty() && cut.len() <= budget.max(1),
                "{name}: {budget}"
            );
            finer |= cut.len() > 1;
            for (k, inst) in instances.iter().enumerate() {
                let count = meshes[inst.mesh as usize].1.len() as u32;
                for t in 0..count {
                    let p = accel
                        .triangle_world(k as u32, t)
                        .expect("every triangle is kept");
                    // Instanced triangles come back through the inverse transform: a few ulps.
                    let tol = 1e-5 * (1.0 + p.iter().map(|v| v.abs().max_element()).sum::<f32>());
                    let inside = |(lo, hi): &(Vec3, Vec3)| {
                        p.iter()
                            .all(|v| v.cmpge(*lo - tol).all() && v.cmple(*hi + tol).all())
                    };
                    assert!(
                        cut.iter().any(inside),
                        "{name}, budget {budget}: instance {k} triangle {t} {p:?} in no box"
                    );
                }
            }
            // Every box lies inside the scene's bounds.
            for (lo, hi) in &cut {
                assert!(lo.cmpge(root.0).all() && hi.cmple(root.1).all(), "{name}");
            }
        }
        assert!(finer, "{name}: the cut never opened the root");
    }
}

#[test]
fn nothing_to_hit_no_boxes() {
    let accel = Accel::build(&[], &[], BvhQuality::Medium);
    assert!(accel.cover(16).is_empty());
}
