//! The barrel-clipped lens warps (optical vignetting): inside both discs, uniform over their
//! intersection, and the unclipped lens unchanged.

use aperture_shading::warp::{concentric_disc, uniform_polygon};
use aperture_shading::warp_lens::{clipped_by_disc, disc_in_disc};
use glam::Vec2;

/// Fixed-seed uniform numbers (xorshift64*).
fn numbers(seed: u64, n: usize) -> Vec<Vec2> {
    let mut x = seed;
    let mut next = move || {
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        (x.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 40) as f32 / (1u64 << 24) as f32
    };
    (0..n).map(|_| Vec2::new(next(), next())).collect()
}

/// Clip configurations: (centre, radius), from a sliver to a lens nearly the whole disc.
const CASES: [([f32; 2], f32); 5] = [
    ([0.5, 0.0], 1.0),
    ([-0.7, 0.6], 1.0),
    ([0.0, -1.6], 1.0),
    ([0.3, 0.4], 0.9),
    ([1.2, 0.9], 1.4),
];

#[test]
fn an_unclipped_lens_is_unchanged_bit_for_bit() {
    for u in numbers(1, 2000) {
        let plain = concentric_disc(u);
        assert_eq!(disc_in_disc(u, Vec2::ZERO, 1.0), Some(plain));
        assert_eq!(disc_in_disc(u, Vec2::new(0.1, -0.2), 1.3), Some(plain));
    }
}

#[test]
fn samples_lie_in_both_discs() {
    for (c, r) in CASES {
        let c = Vec2::from(c);
        for u in numbers(2, 20_000).into_iter().chain([
            Vec2::ZERO,
            Vec2::ONE * (1.0 - f32::EPSILON),
            Vec2::new(0.0, 0.999),
        ]) {
            let p = disc_in_disc(u, c, r).expect("the discs meet");
            assert!(p.is_finite(), "{u}");
            assert!(p.length() <= 1.0 + 1e-5, "{p} outside the lens ({c}, {r})");
            assert!(
                p.distance(c) <= r * (1.0 + 1e-5),
                "{p} outside the barrel ({c}, {r})"
            );
        }
    }
    assert_eq!(
        disc_in_disc(Vec2::splat(0.5), Vec2::new(2.5, 0.0), 1.0),
        None
    );
}

/// Chi-square of the warp's histogram on an 8×8 grid over `[-1,1]²` against each cell's share
/// of the intersection's area (by a 1200² midpoint quadrature), 200 000 samples, 3 seeds.
#[test]
fn density_is_uniform_over_the_intersection() {
    const G: usize = 8;
    const Q: usize = 1200;
    for (c, r) in CASES {
        let c = Vec2::from(c);
        let inside = |p: Vec2| p.length() <= 1.0 && p.distance(c) <= r;
        let cell = |p: Vec2| {
            let i = (((p + 1.0) * 0.5 * G as f32).floor()).clamp(Vec2::ZERO, Vec2::splat(7.0));
            i.y as usize * G + i.x as usize
        };
        let mut area = [0f64; G * G];
        for j in 0..Q {
            for i in 0..Q {
                let p = Vec2::new(
                    (i as f32 + 0.5) / Q as f32 * 2.0 - 1.0,
                    (j as f32 + 0.5) / Q as f32 * 2.0 - 1.0,
                );
                if inside(p) {
                    area[cell(p)] += 1.0;
                }
            }
        }
        let total: f64 = area.iter().sum();
        for seed in [3, 4, 5] {
            let n = 200_000;
            let mut count = [0f64; G * G];
            for u in numbers(seed, n) {
                count[cell(disc_in_disc(u, c, r).unwrap())] += 1.0;
            }
            let (mut chi2, mut dof) = (0.0, 0);
            for k in 0..G * G {
                let want = area[k] / total * n as f64;
                if want >= 20.0 {
                    chi2 += (count[k] - want).powi(2) / want;
                    dof += 1;
                } else {
                    assert!(count[k] <= want + 5.0 * want.sqrt() + 5.0, "cell {k}");
                }
            }
            // p ≈ 1e-6 for the degrees of freedom here (≤ 63): mean dof, sd sqrt(2 dof).
            let limit = dof as f64 + 7.0 * (2.0 * dof as f64).sqrt();
            println!("centre {c} radius {r} seed {seed}: chi2 {chi2:.1} over {dof} cells");
            assert!(
                chi2 < limit,
                "chi2 {chi2} >= {limit} ({c}, {r}, seed {seed})"
            );
        }
    }
}

#[test]
fn a_clipped_polygon_stays_in_both_shapes_and_is_deterministic() {
    let hexagon = |u: Vec2| uniform_polygon(u, 6, 0.3);
    let (c, r) = (Vec2::new(0.6, 0.5), 1.0);
    for u in numbers(6, 5000) {
        let p = clipped_by_disc(u, hexagon, c, r);
        assert!(p.distance(c) <= r * (1.0 + 1e-6));
        assert!(p.length() <= 1.0 + 1e-6);
        assert_eq!(p, clipped_by_disc(u, hexagon, c, r));
    }
}

/// The area left of a chord of the two discs' intersection, in `f64`, from the formula of a
/// circle's segment (independent of the warp's code): the unit disc, and the disc of radius `r`
/// at distance `d` along +s.
fn area_left(s: f64, d: f64, r: f64) -> f64 {
    let seg = |rho: f64, x: f64| {
        let q = (x / rho).clamp(-1.0, 1.0);
        rho * rho * (q.asin() + q * (1.0 - q * q).sqrt() + std::f64::consts::FRAC_PI_2)
    };
    let chord = (d * d + 1.0 - r * r) / (2.0 * d);
    if s <= chord {
        seg(r, s - d)
    } else {
        seg(r, chord - d) + seg(1.0, s) - seg(1.0, chord)
    }
}

/// The warp inverts the area exactly (to the `f32` result's resolution): a point's chord
/// coordinate along the line of centres has `u.x` of the intersection's area to its left.
#[test]
fn the_chord_splits_the_area_as_u_says() {
    for (c, r) in CASES {
        let c = Vec2::from(c);
        let (d, r64) = (f64::from(c.length()), f64::from(r));
        let e = (c / c.length()).as_dvec2();
        let total = area_left(1.0, d, r64);
        let mut worst = 0f64;
        for u in numbers(9, 20_000) {
            let p = disc_in_disc(u, c, r).unwrap().as_dvec2();
            let s = p.dot(e);
            // The area's derivative is the chord's length: compare in `s`, where `f32`
            // rounding of the point (about 6e-8) is the scale.
            let err = (area_left(s, d, r64) / total - f64::from(u.x)).abs() * total;
            let h = {
                let a = 1.0 - s * s;
                let b = r64 * r64 - (s - d) * (s - d);
                a.min(b).max(0.0).sqrt()
            };
            worst = worst.max(err / (2.0 * h).max(1e-3));
        }
        println!("({c}, {r}): worst chord error {worst:e}");
        assert!(worst < 4e-7, "({c}, {r}): worst chord error {worst:e}");
    }
}
