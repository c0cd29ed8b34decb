//! Tests of the box test against its scalar reference.

use super::layout::nodes_from_cwbvh;
use super::*;
use glam::DVec3;
use obvhs::{aabb::Aabb, cwbvh::builder::build_cwbvh, BvhBuildParams};
use std::time::Duration;

/// Our nodes over `boxes` (obvhs' fast build).
fn tree(boxes: &[Aabb]) -> Vec<Node> {
    let cw = build_cwbvh(
        boxes,
        BvhBuildParams::fast_build(),
        &mut Duration::default(),
    );
    nodes_from_cwbvh(&cw.nodes, &cw.primitive_indices, boxes)
}

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
    let nodes = tree(&boxes);
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
        for node in &nodes {
            let (a, enter) = child_hits_scalar(node, &r, tmax);
            let bits = |e: [f32; 8]| e.map(f32::to_bits);
            let (fast, fast_enter) = child_hits(node, &r, tmax);
            assert_eq!((fast, bits(fast_enter)), (a, bits(enter)));
            // The ordered walk's test: the same hits and entries, obvhs' leaf bits.
            let ordered = child_hits_enter(node, &r, tmax);
            assert_eq!((ordered.hits, bits(ordered.enter)), (a, bits(enter)));
            let mask = hitmask_from_children(node, r.oct_inv4, a);
            assert_eq!(ordered.prims, mask & 0x00ff_ffff);
            assert_eq!(intersect_node(node, &r, tmax), mask);
            #[cfg(target_arch = "x86_64")]
            if std::arch::is_x86_feature_detected!("avx2")
                && std::arch::is_x86_feature_detected!("fma")
            {
                // SAFETY: AVX2 and FMA were detected.
                let full = unsafe { intersect_node_avx2(node, &r, tmax) };
                assert_eq!(full, mask);
                // SAFETY: AVX2 and FMA were detected.
                let ordered = unsafe { child_hits_enter_avx2(node, &r, tmax) };
                assert_eq!((ordered.hits, bits(ordered.enter)), (a, bits(enter)));
                assert_eq!(ordered.prims, mask & 0x00ff_ffff);
            }
            #[cfg(target_arch = "aarch64")]
            {
                assert_eq!(neon::intersect_node_neon(node, &r, tmax), mask);
                let ordered = neon::child_hits_enter_neon(node, &r, tmax);
                assert_eq!((ordered.hits, bits(ordered.enter)), (a, bits(enter)));
                assert_eq!(ordered.prims, mask & 0x00ff_ffff);
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
                    (-r.ninv).to_array().map(f32::to_bits),
                    want.to_array().map(f32::to_bits),
                    "{d}"
                );
                let neg = want.to_array().map(|i| i < 0.0);
                let bits = neg
                    .iter()
                    .enumerate()
                    .map(|(a, &n)| u32::from(n) << a)
                    .sum();
                assert_eq!(r.rows, Rows::new(bits), "{d}");
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
    let nodes = tree(&boxes);
    let root = &nodes[0];
    // A ray along +x through both boxes, starting at x = -5, over [tmin, tmax].
    let hits = |tmin: f32, tmax: f32| {
        let r = BoxRay::new(
            Vec3::new(-5.0, 0.0, 0.0),
            Vec3::X,
            tmin,
            (Vec3::splat(-1.0), Vec3::splat(11.0)),
        );
        child_hits(root, &r, tmax).0
    };
    let all = hits(0.0, f32::INFINITY);
    let late = hits(8.0, f32::INFINITY);
    let early = hits(0.0, 8.0);
    assert_eq!(all.count_ones(), 2);
    assert_eq!(late.count_ones(), 1);
    assert_eq!(early.count_ones(), 1);
    assert_ne!(late, early);
}

/// Whether the exact segment `[tmin, tmax]` of the ray `o + t d` (in `f64`) enters child
/// `slot` of `node`, its box grown by `grow` on every side.
fn segment_enters(
    node: &Node,
    slot: usize,
    (o, d): (DVec3, DVec3),
    (tmin, tmax): (f32, f32),
    grow: f64,
) -> bool {
    let (mut t0, mut t1) = (f64::from(tmin), f64::from(tmax));
    for a in 0..3 {
        let lo = f64::from(node.bounds[2 * a][slot]) - grow;
        let hi = f64::from(node.bounds[2 * a + 1][slot]) + grow;
        if d[a] == 0.0 {
            if o[a] < lo || o[a] > hi {
                t0 = f64::INFINITY;
            }
            continue;
        }
        let (x, y) = ((lo - o[a]) / d[a], (hi - o[a]) / d[a]);
        t0 = t0.max(x.min(y));
        t1 = t1.min(x.max(y));
    }
    t0 <= t1
}

/// Ray `i` of the grazing test: an origin near the boxes (far away now and then), aimed at a
/// corner of some box or in a random direction (now and then along an axis).
fn grazing_ray(s: &mut u64, i: usize, offset: Vec3A, scale: f32, boxes: &[Aabb]) -> (Vec3A, Vec3A) {
    let u = |s: &mut u64| Vec3A::new(lcg(s), lcg(s), lcg(s));
    let far = if i % 7 == 0 { 30.0 } else { 1.0 };
    let o = offset + (u(s) * 140.0 - 20.0) * scale * far;
    let d = if i % 2 == 0 {
        let b = &boxes[i % boxes.len()];
        let k = lcg(s);
        Vec3A::new(
            if k < 0.5 { b.min.x } else { b.max.x },
            if !(0.25..=0.75).contains(&k) {
                b.min.y
            } else {
                b.max.y
            },
            if lcg(s) < 0.5 { b.min.z } else { b.max.z },
        ) - o
    } else {
        let mut d = u(s) - 0.5;
        if i % 5 == 1 {
            d.y = 0.0;
            d.z = 0.0;
        }
        d
    };
    (o, d)
}

/// Wherever a ray's exact segment (in `f64`) enters a child's box, the test says so, and it says
/// so elsewhere only within twice its slack: scenes near and far from the origin and at several
/// scales, rays from inside and outside, along axes, and aimed exactly at box corners (grazing).
#[test]
fn never_misses_a_box_the_exact_ray_enters() {
    let mut s = 11u64;
    for (offset, scale) in [
        (0.0, 1.0),
        (1e5, 1.0),
        (-3e3, 1e-3),
        (0.0, 1e4),
        (7e6, 50.0),
    ] {
        let offset = Vec3A::splat(offset);
        let boxes: Vec<Aabb> = (0..300)
            .map(|_| {
                let c = Vec3A::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) * 100.0 * scale;
                let h = Vec3A::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) * 3.0 * scale;
                Aabb::new(offset + c - h, offset + c + h)
            })
            .collect();
        let nodes = tree(&boxes);
        let all = boxes.iter().fold(Aabb::empty(), |a, b| a.union(b));
        let bounds = (Vec3::from(all.min), Vec3::from(all.max));
        let (mut entered, mut loose) = (0, 0);
        for i in 0..400 {
            let (o, d) = grazing_ray(&mut s, i, offset, scale, &boxes);
            let (tmin, tmax) = if i % 3 == 0 {
                (0.0, f32::INFINITY)
            } else {
                (0.1, 0.9)
            };
            let r = BoxRay::new(o.into(), d.into(), tmin, bounds);
            // Twice the slack in space, with the two ulps of the origin's coordinates.
            let slack =
                2.0 * f64::from(reach(o, bounds) + 2.0 * f32::EPSILON * o.abs().max_element());
            let exact = (o.as_dvec3(), d.as_dvec3());
            for node in &nodes {
                let (hits, _) = child_hits_scalar(node, &r, tmax);
                for slot in 0..8 {
                    if node.child_meta[slot] == 0 {
                        continue;
                    }
                    let hit = hits & (1 << slot) != 0;
                    if segment_enters(node, slot, exact, (tmin, tmax), 0.0) {
                        entered += 1;
                        assert!(hit, "offset {offset} scale {scale} ray {i} slot {slot}");
                    } else if hit {
                        loose += 1;
                        assert!(
                            segment_enters(node, slot, exact, (tmin, tmax), slack),
                            "offset {offset} scale {scale} ray {i} slot {slot}"
                        );
                    }
                }
            }
        }
        assert!(
            entered > 500 && loose < entered,
            "entered {entered}, loose {loose}"
        );
    }
}

/// A ray's rows are its near planes then its far planes: the minimum rows on positive axes.
#[test]
fn rows_pick_near_then_far_planes() {
    let mut node = tree(&[Aabb::new(Vec3A::ZERO, Vec3A::ONE)])[0];
    for (k, row) in node.bounds.iter_mut().enumerate() {
        *row = [k as f32; 8];
    }
    for neg_bits in 0..8u32 {
        let got = Rows::new(neg_bits).planes(&node).map(|row| row[0] as usize);
        let near = |a: usize| 2 * a + (neg_bits as usize >> a & 1);
        let far = |a: usize| 2 * a + 1 - (neg_bits as usize >> a & 1);
        assert_eq!(got, [near(0), near(1), near(2), far(0), far(1), far(2)]);
    }
}

/// The slack covers what the triangle test accepts outside a triangle (module docs): rays aimed
/// just outside an edge or a vertex (by 1/2 to 64 ε M, along the triangle's plane), from near
/// and far, some grazing the plane, at scales from 1e-2 to 1e4. Wherever the test reports a hit,
/// the exact ray passes within a quarter of the slack of the triangle's box, `M` taken from that
/// box alone (the smallest `M` a tree holding the triangle can give).
#[test]
fn slack_covers_what_the_triangle_test_accepts() {
    use crate::triangle::intersect_triangle;
    use glam::DVec3;
    let mut s = 5u64;
    let r = |s: &mut u64| f64::from(lcg(s));
    let unit = |s: &mut u64| loop {
        let v = DVec3::new(r(s), r(s), r(s)) * 2.0 - 1.0;
        if (0.01..1.0).contains(&v.length_squared()) {
            break v.normalize();
        }
    };
    let eps = f64::from(f32::EPSILON);
    let (mut worst, mut outside) = (0.0f64, 0);
    for _ in 0..1_000_000 {
        let c = unit(&mut s) * 10f64.powf(r(&mut s) * 6.0 - 2.0);
        let l = 10f64.powf(r(&mut s) * 4.0 - 3.0) * c.length().max(1e-2);
        let p: [Vec3; 3] = std::array::from_fn(|_| (c + unit(&mut s) * l).as_vec3());
        let pd = p.map(|v| v.as_dvec3());
        let n = (pd[1] - pd[0]).cross(pd[2] - pd[0]);
        if n.length() < 1e-6 * l * l {
            continue;
        }
        let n = n.normalize();
        // A point of an edge (a vertex one time in five), and the way out of the triangle.
        let e = (r(&mut s) * 3.0) as usize % 3;
        let (a, b, other) = (pd[e], pd[(e + 1) % 3], pd[(e + 2) % 3]);
        let u = if r(&mut s) < 0.2 { 0.0 } else { r(&mut s) };
        let q0 = a + (b - a) * u;
        let mut out = n.cross((b - a).normalize());
        if out.dot(other - q0) > 0.0 {
            out = -out;
        }
        let mut from = unit(&mut s);
        if r(&mut s) < 0.3 {
            from = (from - n * from.dot(n) * (1.0 - 1e-3 * r(&mut s))).normalize();
        }
        let o = (q0 + from * l * 10f64.powf(r(&mut s) * 3.0)).as_vec3();
        let od = o.as_dvec3();
        let lo = pd.iter().fold(DVec3::INFINITY, |m, v| m.min(*v));
        let hi = pd.iter().fold(DVec3::NEG_INFINITY, |m, v| m.max(*v));
        let m = f64::from(reach(o.into(), (lo.as_vec3(), hi.as_vec3())) / SLACK);
        for f in [64.0, 16.0, 4.0, 1.0, 0.5] {
            let dir = (q0 + out * (f * eps * m) - od).normalize().as_vec3();
            let ray = crate::types::Ray {
                origin: o,
                dir,
                tmin: 0.0,
                tmax: f32::INFINITY,
                time: 0.0,
            };
            if intersect_triangle(&ray, p).is_none() {
                continue;
            }
            let grow = least_growth((lo, hi), od, dir.as_dvec3(), eps * m);
            if grow > 0.0 {
                outside += 1;
                worst = worst.max(grow / (eps * m));
            }
            break;
        }
    }
    let quarter = f64::from(SLACK / f32::EPSILON) / 4.0;
    assert!(
        outside > 100,
        "only {outside} accepted rays passed outside a box"
    );
    assert!(
        worst <= quarter,
        "the triangle test accepted a ray {worst:.2} ε M outside the triangle's box"
    );
}

/// The least growth of the box `(lo, hi)` that the exact ray from `o` along `d` (`t >= 0`)
/// enters (0 when it enters the box itself), to about `step / 2^40`.
fn least_growth(
    (lo, hi): (glam::DVec3, glam::DVec3),
    o: glam::DVec3,
    d: glam::DVec3,
    step: f64,
) -> f64 {
    let enters = |g: f64| {
        let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
        for k in 0..3 {
            let (x, y) = ((lo[k] - g - o[k]) / d[k], (hi[k] + g - o[k]) / d[k]);
            t0 = t0.max(x.min(y));
            t1 = t1.min(x.max(y));
        }
        t0 <= t1
    };
    if enters(0.0) {
        return 0.0;
    }
    let (mut below, mut above) = (0.0, step);
    while !enters(above) {
        (below, above) = (above, 2.0 * above);
    }
    for _ in 0..40 {
        let mid = 0.5 * (below + above);
        if enters(mid) {
            above = mid;
        } else {
            below = mid;
        }
    }
    above
}

/// Rays with NaN, infinite and zero components (and a NaN `tmax`): every path takes NaN slabs
/// as SSE's `maxps`/`minps` do (the second operand), so the same hits and entries bit for bit.
#[test]
fn nan_rays_match_the_scalar_reference() {
    let mut s = 11u64;
    let boxes: Vec<Aabb> = (0..200)
        .map(|_| {
            let c = Vec3A::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) * 10.0;
            Aabb::new(c - 0.5, c + 0.5)
        })
        .collect();
    let nodes = tree(&boxes);
    let odd = [
        0.0,
        -0.0,
        1.0,
        -2.0,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::NAN,
    ];
    let bits = |e: [f32; 8]| e.map(f32::to_bits);
    let mut nan_enters = 0;
    for (i, &a) in odd.iter().enumerate() {
        for &b in &odd {
            let o = Vec3::new(a, 5.0, b);
            let d = Vec3::new(b, a, 0.5);
            let tmax = [f32::INFINITY, 7.0, f32::NAN][i % 3];
            let r = BoxRay::new(o, d, 0.0, (Vec3::ZERO, Vec3::splat(10.0)));
            for node in &nodes {
                let (want, enter) = child_hits_scalar(node, &r, tmax);
                nan_enters += enter.iter().filter(|e| e.is_nan()).count();
                let (got, got_enter) = child_hits(node, &r, tmax);
                assert_eq!((got, bits(got_enter)), (want, bits(enter)), "{o} {d}");
                #[cfg(target_arch = "aarch64")]
                {
                    let mask = hitmask_from_children(node, r.oct_inv4, want);
                    assert_eq!(neon::intersect_node_neon(node, &r, tmax), mask, "{o} {d}");
                    let n = neon::child_hits_enter_neon(node, &r, tmax);
                    assert_eq!((n.hits, bits(n.enter)), (want, bits(enter)), "{o} {d}");
                }
            }
        }
    }
    assert!(nan_enters > 0, "no NaN slab was exercised");
}
