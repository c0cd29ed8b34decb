//! The world-space BVH built per instance and joined (`FrameHints::join_from`, issue 59)
//! answers every query as the one-build tree does: the same hits (the same triangle, instance,
//! `t` and barycentrics, bit for bit), the same occlusion, the same counts, through every
//! query path (one ray, batches, the packets of `intersect_many`).

use aperture_accel::{Accel, BvhQuality, FrameHints, Hit, InstanceInput, MeshInput, Ray};
use glam::{Affine3A, Quat, Vec3};

mod common;
use common::{grid, mesh_inputs};

/// A few meshes drawn once each, overlapping (a floor under tilted plates, one plate through
/// another), a lone triangle and a mesh whose triangles are all degenerate.
fn scene() -> (Vec<common::Geometry>, Vec<InstanceInput>) {
    let mut lone = grid(1, 0.0);
    lone.1.truncate(1);
    let flat_line = (
        vec![Vec3::ZERO, Vec3::X, Vec3::X * 2.0],
        vec![[0, 1, 2], [2, 1, 0]],
    );
    let meshes = vec![
        grid(24, 0.0),
        grid(9, 0.3),
        grid(12, 0.5),
        lone,
        flat_line,
        grid(5, 0.2),
        grid(7, 0.1),
    ];
    let place = |mesh: u32, scale: Vec3, angle: f32, at: Vec3| InstanceInput {
        mesh,
        world_from_object: Affine3A::from_scale_rotation_translation(
            scale,
            Quat::from_rotation_x(angle),
            at,
        ),
    };
    let instances = vec![
        place(
            0,
            Vec3::splat(20.0),
            -std::f32::consts::FRAC_PI_2,
            Vec3::ZERO,
        ),
        place(1, Vec3::ONE, 0.3, Vec3::new(-1.0, 1.0, 0.0)),
        place(2, Vec3::splat(1.5), 1.1, Vec3::new(-0.5, 1.2, 0.3)),
        place(3, Vec3::splat(0.7), 0.0, Vec3::new(2.0, 0.5, -1.0)),
        place(4, Vec3::ONE, 0.0, Vec3::new(0.0, 2.0, 0.0)),
        place(5, Vec3::new(1.0, 2.0, 0.5), 0.0, Vec3::new(3.0, 1.0, 1.0)),
        place(6, Vec3::splat(3.0), 0.7, Vec3::new(-4.0, 2.0, -5.0)),
    ];
    (meshes, instances)
}

/// Rays from a few eyes towards a fan of directions over the scene.
fn rays() -> Vec<Ray> {
    let eyes = [
        Vec3::new(0.3, 6.0, 9.0),
        Vec3::new(-7.0, 3.0, 2.0),
        Vec3::new(1.0, 0.8, 0.2),
    ];
    let mut out = Vec::new();
    for eye in eyes {
        for j in 0..48 {
            for i in 0..64 {
                // Off the grids' lattice: no ray meets an edge or a vertex exactly (where two
                // trees may report either triangle).
                let target = Vec3::new(
                    i as f32 * 0.1637 - 5.0 + 0.0131 * j as f32,
                    j as f32 * 0.0839 - 0.5,
                    0.0071 * i as f32,
                );
                out.push(Ray::new(eye, target - eye - Vec3::Z * 2.0));
            }
        }
    }
    out
}

/// The structure over `inputs` placed by `instances`, joined from `join_from` triangles.
fn build(
    inputs: &[MeshInput],
    instances: &[InstanceInput],
    quality: BvhQuality,
    join_from: usize,
) -> Accel {
    let hints = FrameHints {
        join_from,
        ..FrameHints::STILL
    };
    Accel::build_frame(inputs, instances, quality, hints, None)
}

fn key(h: &Option<Hit>) -> Option<(u32, u32, u32, u32, u32)> {
    h.map(|h| {
        (
            h.instance,
            h.triangle,
            h.t.to_bits(),
            h.u.to_bits(),
            h.v.to_bits(),
        )
    })
}

#[test]
fn joined_pieces_answer_as_one_build() {
    let (meshes, instances) = scene();
    let inputs = mesh_inputs(&meshes);
    let with = |join_from| build(&inputs, &instances, BvhQuality::Medium, join_from);
    let (one, joined) = (with(usize::MAX), with(0));
    let rays = rays();
    let mut hits = 0;
    for r in &rays {
        let a = one.intersect(r);
        assert_eq!(key(&a), key(&joined.intersect(r)), "{r:?}");
        assert_eq!(one.occluded(r), joined.occluded(r), "{r:?}");
        hits += usize::from(a.is_some());
    }
    // Every instance with triangles is hit somewhere, and some rays miss.
    assert!(hits > rays.len() / 2 && hits < rays.len(), "{hits}");
    let mut seen: Vec<u32> = rays
        .iter()
        .filter_map(|r| joined.intersect(r).map(|h| h.instance))
        .collect();
    seen.sort_unstable();
    seen.dedup();
    assert_eq!(seen, [0, 1, 2, 3, 5, 6], "instances hit");

    let (mut a, mut b) = (vec![None; rays.len()], vec![None; rays.len()]);
    one.intersect_many(&rays, &mut a);
    joined.intersect_many(&rays, &mut b);
    assert!(a.iter().zip(&b).all(|(x, y)| key(x) == key(y)));
    let (mut a, mut b) = (vec![false; rays.len()], vec![false; rays.len()]);
    one.occluded_batch(&rays, &mut a);
    joined.occluded_batch(&rays, &mut b);
    assert_eq!(a, b);

    let (s1, s2) = (one.stats(), joined.stats());
    assert_eq!(s1.unique_triangles, s2.unique_triangles);
    assert_eq!(s1.degenerate_triangles, s2.degenerate_triangles);
    assert_eq!(s1.degenerate_triangles, 2, "the two of mesh 4");
    assert_eq!(s1.triangle_bytes, s2.triangle_bytes);
    // The joined tree is one world-space tree as well, a few levels deeper at most.
    assert_eq!((s1.blas_count, s2.blas_count), (1, 1));
    assert!(s2.max_blas_depth >= s1.max_blas_depth.min(3), "{s2:?}");
    // Each triangle is still found where it was placed.
    for (k, inst) in instances.iter().enumerate() {
        for t in 0..meshes[inst.mesh as usize].1.len() as u32 {
            assert_eq!(
                one.triangle_world(k as u32, t),
                joined.triangle_world(k as u32, t)
            );
        }
    }
}

#[test]
fn small_sets_keep_one_build() {
    let (meshes, instances) = scene();
    let inputs = mesh_inputs(&meshes);
    let drawn: usize = instances
        .iter()
        .map(|i| meshes[i.mesh as usize].1.len())
        .sum();
    let build = |join_from| build(&inputs, &instances, BvhQuality::Fast, join_from).stats();
    // One more triangle than the set draws: one build, the same tree as never joining.
    let (below, never, at) = (build(drawn + 1), build(usize::MAX), build(drawn));
    assert_eq!((below.joined_pieces, never.joined_pieces), (0, 0));
    assert_eq!(below.bvh_nodes, never.bvh_nodes);
    // At the threshold it joins the six instances with triangles (mesh 4 has none).
    assert_eq!(at.joined_pieces, 6);
    assert_eq!(at.unique_triangles, never.unique_triangles);
}

#[test]
fn overlapping_pieces_keep_one_build() {
    // Eight plates over the same square, a hair apart: every ray through one enters all, so
    // a tree over their boxes would walk all eight (`OVERLAP_LIMIT`).
    let meshes: Vec<common::Geometry> = (0..8).map(|k| grid(6, 0.1 + 0.01 * k as f32)).collect();
    let inputs = mesh_inputs(&meshes);
    // Plate k moved by k steps.
    let row = |step: Vec3| -> Vec<InstanceInput> {
        (0..8)
            .map(|k| InstanceInput {
                mesh: k,
                world_from_object: Affine3A::from_translation(step * k as f32),
            })
            .collect()
    };
    let stats = build(&inputs, &row(Vec3::Z * 0.001), BvhQuality::Medium, 0).stats();
    assert_eq!(stats.joined_pieces, 0);
    assert_eq!(stats.unique_triangles, 8 * 6 * 6 * 2);
    // Spread out side by side, the same plates are joined.
    let stats = build(&inputs, &row(Vec3::X * 2.0), BvhQuality::Medium, 0).stats();
    assert_eq!(stats.joined_pieces, 8);
}
