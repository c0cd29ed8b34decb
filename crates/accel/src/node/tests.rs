//! Tests of the box test against its scalar reference.

use super::*;
use obvhs::{aabb::Aabb, cwbvh::builder::build_cwbvh, BvhBuildParams};
use std::time::Duration;

fn lcg(s: &mut u64) -> f32 {
    *s = s
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    (*s >> 40) as f32 / (1u64 << 24) as f32
}

#[test]
fn simd_matches_scalar_reference() {
    let mut s = 7u64;
    let boxes: Vec<Aabb> = (0..500)
        .map(|_| {
            let c = Vec3A::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) * 100.0;
            let h = Vec3A::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) * 3.0;
            Aabb::new(c - h, c + h)
        })
        .collect();
    let bvh = build_cwbvh(
        &boxes,
        BvhBuildParams::fast_build(),
        &mut Duration::default(),
    );
    let mut nonzero = 0;
    for i in 0..2000 {
        let o = Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) * 120.0 - 10.0;
        let mut d = Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) - 0.5;
        if i % 5 == 0 {
            d.y = 0.0; // exercises the clamped reciprocal
        }
        let r = BoxRay::new(
            o,
            d,
            if i % 3 == 0 { 5.0 } else { 0.0 },
            (Vec3::splat(-10.0), Vec3::splat(110.0)),
        );
        let tmax = if i % 4 == 0 { 50.0 } else { f32::INFINITY };
        for node in &bvh.nodes {
            let a = child_hits_fast(node, &r, tmax);
            assert_eq!(a, child_hits_reference(node, &r, tmax));
            // The ordered walk's test: the same hits, the scalar entries, obvhs' leaf bits.
            let f = frame(node, &r);
            let ordered = child_hits_enter(node, &r, tmax);
            assert_eq!(ordered.hits, a);
            let enter = child_hits_scalar(node, &r, &f, tmax).1;
            assert_eq!(ordered.enter.map(f32::to_bits), enter.map(f32::to_bits));
            let mask = hitmask_from_children(node, r.oct_inv4, a);
            assert_eq!(ordered.prims, mask & 0x00ff_ffff);
            #[cfg(target_arch = "x86_64")]
            if std::arch::is_x86_feature_detected!("avx2")
                && std::arch::is_x86_feature_detected!("fma")
            {
                let (fused, fused_enter) = child_hits_scalar_with::<true>(node, &r, &f, tmax);
                // SAFETY: AVX2 and FMA were detected.
                assert_eq!(fused, unsafe { child_hits_avx2(node, &r, &f, tmax) });
                // SAFETY: AVX2 and FMA were detected.
                let full = unsafe { intersect_node_avx2(node, &r, tmax) };
                assert_eq!(full, hitmask_from_children(node, r.oct_inv4, fused));
                // SAFETY: AVX2 and FMA were detected.
                let ordered = unsafe { child_hits_enter_avx2(node, &r, tmax) };
                assert_eq!(ordered.hits, fused);
                assert_eq!(
                    ordered.enter.map(f32::to_bits),
                    fused_enter.map(f32::to_bits)
                );
                assert_eq!(ordered.prims, full & 0x00ff_ffff);
            }
            nonzero += (a != 0) as usize;
        }
    }
    assert!(nonzero > 100);
}

#[test]
fn lane_wise_setup_matches_per_axis() {
    let vals = [
        0.0f32,
        -0.0,
        1e-30,
        -1e-30,
        1e-45,
        0.5,
        -3.0,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::NAN,
        -f32::NAN,
    ];
    for &x in &vals {
        for &y in &vals {
            for &z in &vals {
                let d = Vec3::new(x, y, z);
                let r = BoxRay::new(Vec3::ZERO, d, 0.0, (Vec3::ZERO, Vec3::ONE));
                let want = BoxRay::inv_reference(d);
                assert_eq!(
                    r.inv.to_array().map(f32::to_bits),
                    want.to_array().map(f32::to_bits),
                    "{d}"
                );
                let neg = want.to_array().map(|i| i < 0.0);
                assert_eq!(r.neg, neg, "{d}");
                let oct = (if neg[0] { 0 } else { 0x0404_0404 })
                    | (if neg[1] { 0 } else { 0x0202_0202 })
                    | (if neg[2] { 0 } else { 0x0101_0101 });
                assert_eq!(r.oct_inv4, oct, "{d}");
            }
        }
    }
}

#[test]
fn honours_tmin() {
    // obvhs' own test ignores tmin; this one must reject boxes entirely before it.
    let boxes = vec![
        Aabb::new(Vec3A::new(0.0, -1.0, -1.0), Vec3A::new(1.0, 1.0, 1.0)),
        Aabb::new(Vec3A::new(10.0, -1.0, -1.0), Vec3A::new(11.0, 1.0, 1.0)),
    ];
    let bvh = build_cwbvh(
        &boxes,
        BvhBuildParams::fast_build(),
        &mut Duration::default(),
    );
    let root = &bvh.nodes[0];
    // A ray along +x through both boxes, starting at x = -5, over [tmin, tmax].
    let hits = |tmin: f32, tmax: f32| {
        let r = BoxRay::new(
            Vec3::new(-5.0, 0.0, 0.0),
            Vec3::X,
            tmin,
            (Vec3::splat(-1.0), Vec3::splat(11.0)),
        );
        child_hits_fast(root, &r, tmax)
    };
    let all = hits(0.0, f32::INFINITY);
    let late = hits(8.0, f32::INFINITY);
    let early = hits(0.0, 8.0);
    assert_eq!(all.count_ones(), 2);
    assert_eq!(late.count_ones(), 1);
    assert_eq!(early.count_ones(), 1);
    assert_ne!(late, early);
}
