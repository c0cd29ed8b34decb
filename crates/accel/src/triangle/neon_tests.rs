//! The NEON path of the triangle test (`sheared` with `AVX` on aarch64) against the scalar one,
//! bit for bit.

use super::{intersect, sheared, Tri, TriRay};
use crate::test_util::mix;
use glam::Vec3;

/// A test value for counter `k`: uniform in `[-1, 1)`, now and then an exact zero of either
/// sign, a tie, a tiny, huge, infinite or NaN one.
fn value(k: u32) -> f32 {
    const ODD: [f32; 8] = [0.0, -0.0, 1.0, -1.0, 1e-30, 3e30, f32::INFINITY, f32::NAN];
    if mix(k ^ 0x55) % 6 == 0 {
        ODD[mix(k) as usize % ODD.len()]
    } else {
        (mix(k) >> 8) as f32 / (1u32 << 23) as f32 - 1.0
    }
}

#[test]
fn neon_vertices_and_hits_match_the_scalar_test() {
    let bits = |h: Option<(f32, f32, f32)>| h.map(|h| [h.0, h.1, h.2].map(f32::to_bits));
    let mut hits = 0;
    for case in 0..20_000u32 {
        let k = case * 32;
        let v = |j: u32| Vec3::new(value(k + 3 * j), value(k + 3 * j + 1), value(k + 3 * j + 2));
        let tri = Tri {
            p: [v(0), v(1), v(2)],
            prim: 0,
        };
        let origin = v(3) + Vec3::new(0.0, 0.0, 2.0);
        // Mostly aimed at the triangle, now and then anywhere.
        let target = if mix(k + 20) % 4 == 0 {
            v(4)
        } else {
            (tri.p[0] + tri.p[1] + tri.p[2]) / 3.0
        };
        let r = TriRay::new(origin, target - origin);
        for j in 0..3 {
            let (n, s) = (sheared::<true>(&r, &tri, j), sheared::<false>(&r, &tri, j));
            // The sign of a zero may differ (`sheared`'s docs), and a NaN's payload (the
            // compiler may swap the operands of a sum), nothing else.
            let same = |a: f32, b: f32| {
                a.to_bits() == b.to_bits() || (a == 0.0 && b == 0.0) || (a.is_nan() && b.is_nan())
            };
            assert!(
                same(n.x, s.x) && same(n.y, s.y) && same(n.z, s.z),
                "case {case} vertex {j}: {n} vs {s}"
            );
        }
        let tmax = [f32::INFINITY, 1.0, 1e3][case as usize % 3];
        let want = intersect::<false>(&r, &tri, 1e-4, tmax);
        assert_eq!(
            bits(intersect::<true>(&r, &tri, 1e-4, tmax)),
            bits(want),
            "case {case}"
        );
        hits += u32::from(want.is_some());
    }
    assert!(hits > 2_000, "hits {hits}");
}
