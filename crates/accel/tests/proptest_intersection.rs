//! Property-based tests of triangle intersection through the public [`Accel`] API (issue 6,
//! part 3): random triangles at random scales and offsets, random instance transforms.
//!
//! Tolerances. A triangle of size `s` whose coordinates reach `m` is stored with rounding
//! `m · 2⁻²⁴`; the strategies keep `m / s ≤ 100`, so barycentrics are exact to about
//! `100 · 2⁻²⁴ ≈ 6e-6` per rounding. A few roundings (the ray transform, the edge functions)
//! stay well inside 1e-3, the margin the aimed-at points keep from the edges.

use aperture_accel::{Accel, BvhQuality, InstanceInput, MeshInput, Ray};
use glam::{Affine3A, Quat, Vec3};
use proptest::prelude::*;

/// A point in the cube `[-1, 1]³`.
fn unit_point() -> impl Strategy<Value = Vec3> {
    (-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

/// Size `s` from 1e-2 to 1e3 and an offset of up to 100 `s`.
fn placement() -> impl Strategy<Value = (f32, Vec3)> {
    (-2.0f32..3.0, unit_point(), 0.0f32..100.0)
        .prop_map(|(log_s, dir, k)| (10f32.powf(log_s), dir * 10f32.powf(log_s) * k))
}

/// A triangle of size about `s` whose angles are not too thin (area at least 5% of its
/// bounding square), so "a point 1e-3 inside" is meaningfully inside.
fn triangle() -> impl Strategy<Value = [Vec3; 3]> {
    (unit_point(), unit_point(), unit_point(), placement())
        .prop_filter("fat enough", |(a, b, c, _)| {
            let area = 0.5 * (*b - *a).cross(*c - *a).length();
            let side = (*b - *a)
                .length()
                .max((*c - *a).length())
                .max((*c - *b).length());
            area > 0.05 * side * side
        })
        .prop_map(|(a, b, c, (s, o))| [a * s + o, b * s + o, c * s + o])
}

/// Barycentrics `(u, v)` at least 1e-2 inside every edge.
fn interior() -> impl Strategy<Value = (f32, f32)> {
    (0.01f32..0.98, 0.01f32..0.98).prop_filter("inside", |(u, v)| u + v <= 0.99)
}

fn build(tris: &[[Vec3; 3]], world_from_object: Affine3A) -> Accel {
    let positions: Vec<Vec3> = tris.iter().flatten().copied().collect();
    let indices: Vec<[u32; 3]> = (0..tris.len() as u32)
        .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
        .collect();
    Accel::build(
        &[MeshInput {
            positions: &positions,
            indices: &indices,
        }],
        &[InstanceInput {
            mesh: 0,
            world_from_object,
        }],
        BvhQuality::default(),
    )
}

/// A rigid motion with uniform scale 0.1 to 10 and a translation of up to 100 `size` (so the
/// world coordinates stay within a few hundred triangle sizes, see the tolerances above).
fn transform(size: f32) -> impl Strategy<Value = Affine3A> {
    (unit_point(), -3.0f32..3.0, -1.0f32..1.0, unit_point()).prop_filter_map(
        "axis",
        move |(axis, angle, log_s, t)| {
            let axis = axis.try_normalize()?;
            Some(Affine3A::from_scale_rotation_translation(
                Vec3::splat(10f32.powf(log_s)),
                Quat::from_axis_angle(axis, angle),
                t * 100.0 * size,
            ))
        },
    )
}

/// A triangle and a transform that suits its size.
fn placed_triangle() -> impl Strategy<Value = ([Vec3; 3], Affine3A)> {
    triangle().prop_flat_map(|t| {
        let size = (t[1] - t[0]).length().max((t[2] - t[0]).length());
        (Just(t), transform(size))
    })
}

/// The origin of a ray towards `p` on a triangle with unit normal `n` and size `size`: one to
/// three sizes away and at least one size off the plane, so the ray meets the plane at 15° or
/// more.
fn origin_towards(p: Vec3, n: Vec3, size: f32, from: Vec3) -> Vec3 {
    let side = if from.dot(n) >= 0.0 { 1.0 } else { -1.0 };
    p + size * (2.0 * from + n * side)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// A ray aimed at an interior point hits the triangle there: `t` (the ray's direction is
    /// the unnormalised vector to the point, so `t = 1`) and the barycentrics match. From the
    /// other side too (both sides are hit).
    #[test]
    fn a_ray_aimed_inside_hits_with_matching_barycentrics(
        (tri, xf) in placed_triangle(),
        (u, v) in interior(),
        from in unit_point(),
    ) {
        let [a, b, c] = tri;
        let size = (b - a).length().max((c - a).length());
        let p = a + u * (b - a) + v * (c - a);
        // The origin 1 to 3 triangle sizes away, off the plane.
        let n = (b - a).cross(c - a).normalize();
        let origin = origin_towards(p, n, size, from);
        let accel = build(&[tri], xf);
        let wp = xf.transform_point3(p);
        let wo = xf.transform_point3(origin);
        let hit = accel.intersect(&Ray::new(wo, wp - wo));
        prop_assert!(hit.is_some(), "missed");
        let hit = hit.unwrap();
        prop_assert!((hit.t - 1.0).abs() < 1e-3, "t = {}", hit.t);
        prop_assert!((hit.u - u).abs() < 1e-3 && (hit.v - v).abs() < 1e-3,
            "({}, {}) vs ({u}, {v})", hit.u, hit.v);
        prop_assert_eq!((hit.instance, hit.triangle), (0, 0));
        // The same ray pointed away misses.
        prop_assert!(accel.intersect(&Ray::new(wo, wo - wp)).is_none());
        // And a segment that stops short of the triangle is not occluded.
        let short = Ray { tmax: 0.99, ..Ray::new(wo, wp - wo) };
        prop_assert!(!accel.occluded(&short));
    }

    /// Watertightness: a ray aimed at any point of the edge two coplanar triangles share hits
    /// one of them, never slips between.
    #[test]
    fn a_ray_aimed_at_a_shared_edge_hits_one_of_its_triangles(
        (tri, xf) in placed_triangle(),
        d in unit_point(),
        // Not at the corners: around a shared vertex the two triangles cover only two
        // wedges, and the rounded aim point may lie outside both.
        s in 0.01f32..=0.99,
        from in unit_point(),
    ) {
        let [a, b, c] = tri;
        let size = (b - a).length().max((c - a).length());
        // The second triangle shares the edge a-b, with its apex on the other side of it, in
        // the same plane. (With a fold, a ray aimed at the rounded edge point may pass an ulp
        // outside the convex side of the fold and rightly miss both: only the exact edge is
        // guaranteed, and f32 cannot aim at it.)
        let n = (b - a).cross(c - a).normalize();
        let away = (c - a) - (b - a) * (c - a).dot(b - a) / (b - a).length_squared();
        let apex = a + (0.5 + 0.4 * d.y) * (b - a) - away * (0.3 + 0.7 * d.x.abs());
        let accel = build(&[[a, b, c], [b, a, apex]], xf);
        let p = a + s * (b - a);
        let origin = origin_towards(p, n, size, from);
        let (wp, wo) = (xf.transform_point3(p), xf.transform_point3(origin));
        let ray = Ray::new(wo, wp - wo);
        let hit = accel.intersect(&ray);
        prop_assert!(hit.is_some(), "slipped through the edge at s = {s}");
        prop_assert!(accel.occluded(&ray));
    }

    /// The BVH finds exactly the hit that testing every triangle finds.
    #[test]
    fn closest_hit_equals_brute_force(
        tris in prop::collection::vec(triangle(), 1..40),
        rays in prop::collection::vec((unit_point(), unit_point()), 16),
        xf in transform(1.0),
    ) {
        let accel = build(&tris, xf);
        // Rays through the middle of the soup's bounds, from well outside and inside.
        let (lo, hi) = tris.iter().flatten().fold(
            (Vec3::INFINITY, Vec3::NEG_INFINITY),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        );
        let (centre, half) = (0.5 * (lo + hi), 0.5 * (hi - lo));
        for (o, t) in rays {
            let origin = xf.transform_point3(centre + 2.0 * half * o);
            let target = xf.transform_point3(centre + half * t);
            let ray = Ray::new(origin, target - origin);
            let fast = accel.intersect(&ray);
            let slow = accel.intersect_brute_force(&ray);
            prop_assert_eq!(
                fast.map(|h| (h.t, h.instance, h.triangle)),
                slow.map(|h| (h.t, h.instance, h.triangle))
            );
            prop_assert_eq!(accel.occluded(&ray), slow.is_some());
            // The any hit that says which: present exactly when something is hit, no closer
            // than the closest hit, and a point of its triangle on the ray.
            let any = accel.occluder(&ray);
            prop_assert_eq!(any.is_some(), slow.is_some());
            if let (Some(a), Some(s)) = (any, slow) {
                prop_assert!(a.t >= s.t && a.t <= ray.tmax, "{a:?} against the closest {s:?}");
                let p = accel.triangle_world(a.instance, a.triangle).expect("its triangle");
                let on_triangle = (1.0 - a.u - a.v) * p[0] + a.u * p[1] + a.v * p[2];
                let on_ray = ray.origin + a.t * ray.dir;
                let scale = 1.0 + on_ray.length() + ray.origin.length();
                prop_assert!(
                    (on_triangle - on_ray).length() <= 1e-4 * scale,
                    "{a:?}: {on_triangle} on the triangle, {on_ray} on the ray"
                );
            }
        }
    }
}
