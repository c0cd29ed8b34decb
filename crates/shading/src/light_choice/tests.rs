use super::*;
use crate::light_bounds::LightBounds;
use aperture_scene::LightKind;

/// A small deterministic generator (the tests need many arbitrary configurations).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
    fn vec(&mut self, scale: f32) -> Vec3 {
        Vec3::new(self.next() - 0.5, self.next() - 0.5, self.next() - 0.5) * 2.0 * scale
    }
    fn unit(&mut self) -> Vec3 {
        loop {
            let v = self.vec(1.0);
            if v.length_squared() > 1e-3 && v.length_squared() <= 1.0 {
                return v.normalize();
            }
        }
    }
}

fn point(position: Vec3, intensity: f32) -> Light {
    Light {
        name: None,
        kind: LightKind::Point,
        position,
        direction: Vec3::NEG_Y,
        intensity: Vec3::splat(intensity),
    }
}

/// Whether any point of a grid over the triangle lights `p` (normal `n`, one-sided unless
/// `two_sided`): both cosines (the emitter's two-sided) away from zero.
fn can_light(tri: &[Vec3; 3], p: Vec3, n: Vec3, two_sided: bool) -> bool {
    let ng = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalize();
    (0..=8).any(|i| {
        (0..=8 - i).any(|j| {
            let (b1, b2) = (i as f32 / 8.0, j as f32 / 8.0);
            let q = tri[0] * (1.0 - b1 - b2) + tri[1] * b1 + tri[2] * b2;
            let wi = (q - p).normalize();
            let cos_r = if two_sided {
                n.dot(wi).abs()
            } else {
                n.dot(wi)
            };
            ng.dot(wi).abs() > 1e-3 && cos_r > 1e-3
        })
    })
}

#[test]
fn emitter_importance_is_zero_only_where_no_emitter_can_light() {
    let mut rng = Lcg(7);
    let (mut lit, mut zero) = (0, 0);
    for case in 0..400 {
        // One to three triangles near each other, sometimes coplanar (a panel).
        let centre = rng.vec(3.0);
        let count = 1 + case % 3;
        let normal = rng.unit();
        let tris: Vec<[Vec3; 3]> = (0..count)
            .map(|_| {
                let mut t = [
                    centre + rng.vec(0.5),
                    centre + rng.vec(0.5),
                    centre + rng.vec(0.5),
                ];
                if case % 2 == 0 {
                    // Flattened onto the plane through `centre` with `normal`.
                    for v in &mut t {
                        *v -= normal * normal.dot(*v - centre);
                    }
                }
                t
            })
            .collect();
        let Some(b) = LightBounds::emitters(tris.iter().map(|t| (*t, 1.0))) else {
            panic!("case {case}: no bounds");
        };
        for _ in 0..20 {
            let p = centre + rng.vec(2.5);
            let n = rng.unit();
            let two_sided = rng.next() < 0.3;
            let importance = b.importance(p, n, two_sided);
            assert!(importance >= 0.0 && importance.is_finite(), "{importance}");
            if tris.iter().any(|t| can_light(t, p, n, two_sided)) {
                assert!(
                    importance > 0.0,
                    "case {case}: {p} (normal {n}, two-sided {two_sided}) can be lit"
                );
                lit += 1;
            } else if importance == 0.0 {
                zero += 1;
            }
        }
    }
    // Both kinds occur, and the bound is zero for a good share of the points that nothing
    // lights (it is not trivially positive everywhere).
    assert!(lit > 1000 && zero > 300, "{lit} lit, {zero} zero");
}

#[test]
fn emitter_importance_falls_with_distance_and_angle() {
    // A downward-facing square panel of side 1 at y = 3.
    let q = [
        Vec3::new(-0.5, 3.0, -0.5),
        Vec3::new(0.5, 3.0, -0.5),
        Vec3::new(0.5, 3.0, 0.5),
        Vec3::new(-0.5, 3.0, 0.5),
    ];
    let b = LightBounds::emitters([([q[0], q[2], q[1]], 1.0), ([q[0], q[3], q[2]], 1.0)]).unwrap();
    let up = Vec3::Y;
    let near = b.importance(Vec3::new(0.0, 2.0, 0.0), up, false);
    let far = b.importance(Vec3::new(0.0, -7.0, 0.0), up, false);
    let aside = b.importance(Vec3::new(6.0, 0.0, 0.0), up, false);
    assert!(
        near > far && far > 0.0 && aside > 0.0,
        "{near} {far} {aside}"
    );
    // Facing away from the panel: nothing.
    assert_eq!(b.importance(Vec3::new(0.0, 0.0, 0.0), -up, false), 0.0);
    // Level with it, far away: little (the bound leaves a margin for its cone).
    let level = b.importance(Vec3::new(40.0, 3.0, 0.0), up, true);
    let under = b.importance(Vec3::new(0.0, -37.0, 0.0), up, true);
    assert!(level < 0.05 * under, "{level} {under}");
    // Two-sided receivers take light from behind.
    assert!(b.importance(Vec3::new(0.0, 0.0, 0.0), -up, true) > 0.0);
}

#[test]
fn punctual_importance_is_the_irradiance_on_the_lit_side() {
    let l = point(Vec3::new(0.0, 2.0, 0.0), 8.0);
    let p = Vec3::ZERO;
    // 8 / 2² at normal incidence, luminance of grey is the grey.
    let e = punctual_importance(&l, p, Vec3::Y, false);
    assert!((e - 2.0).abs() < 1e-5, "{e}");
    assert_eq!(punctual_importance(&l, p, -Vec3::Y, false), 0.0);
    assert!((punctual_importance(&l, p, -Vec3::Y, true) - 2.0).abs() < 1e-5);
    let tilted = Vec3::new(1.0, 1.0, 0.0).normalize();
    let e = punctual_importance(&l, p, tilted, false);
    assert!(
        (e - 2.0 * std::f32::consts::FRAC_1_SQRT_2).abs() < 1e-5,
        "{e}"
    );
}

#[test]
fn picks_follow_the_importances() {
    let lights = [
        point(Vec3::new(0.0, 2.0, 0.0), 8.0),
        point(Vec3::new(3.0, 1.0, 0.0), 1.0),
        // Below the receiver: it can light nothing and is never picked.
        point(Vec3::new(0.0, -2.0, 0.0), 100.0),
    ];
    let panel = [
        Vec3::new(-1.0, 3.0, -1.0),
        Vec3::new(1.0, 3.0, -1.0),
        Vec3::new(0.0, 3.0, 1.0),
    ];
    let bounds = LightBounds::emitters([(panel, 4.0)]).unwrap();
    let cands = Candidates {
        lights: &lights,
        emitters: Some(&bounds),
    };
    assert!(cands.choose());
    let (p, n) = (Vec3::ZERO, Vec3::Y);
    let w = [
        punctual_importance(&lights[0], p, n, false),
        punctual_importance(&lights[1], p, n, false),
        0.0,
        bounds.importance(p, n, false),
    ];
    let total: f32 = w.iter().sum();
    let runs = 10_000;
    let mut count = [0u32; 4];
    let mut u_sum = [0.0f64; 4];
    for k in 0..runs {
        let u = (k as f32 + 0.5) / runs as f32;
        let c = cands.pick(p, n, false, u);
        let slot = match c.pick {
            Some(Pick::Punctual(i)) => i,
            Some(Pick::Emitters) => 3,
            Some(Pick::Triangle(_)) => panic!("the exhaustive choice picks the emitters as one"),
            None => panic!("u = {u}: nothing picked"),
        };
        assert!((c.probability - w[slot] / total).abs() < 1e-6);
        assert!((c.emitters - w[3] / total).abs() < 1e-6);
        assert!((0.0..1.0).contains(&c.u));
        count[slot] += 1;
        u_sum[slot] += f64::from(c.u);
    }
    for slot in 0..4 {
        let expected = w[slot] / total * runs as f32;
        assert!(
            (count[slot] as f32 - expected).abs() <= 1.0,
            "slot {slot}: {} picks, {expected} expected",
            count[slot]
        );
        if count[slot] > 100 {
            // The leftover number is uniform again within each pick.
            let mean = u_sum[slot] / f64::from(count[slot]);
            assert!((mean - 0.5).abs() < 0.01, "slot {slot}: mean u {mean}");
        }
    }
    assert_eq!(count[2], 0);
    // A point no light reaches picks nothing.
    let dark = cands.pick(Vec3::new(0.0, 10.0, 0.0), Vec3::Y, false, 0.5);
    assert_eq!(dark.pick, None);
    assert_eq!(dark.emitters, 0.0);
}

#[test]
fn one_candidate_is_no_choice() {
    let lights = [point(Vec3::Y, 1.0)];
    let none = Candidates {
        lights: &lights,
        emitters: None,
    };
    assert!(!none.choose());
    let bounds = LightBounds::emitters([([Vec3::ZERO, Vec3::X, Vec3::Z], 1.0)]).unwrap();
    let emitters_alone = Candidates {
        lights: &[],
        emitters: Some(&bounds),
    };
    assert!(!emitters_alone.choose());
    assert!(Candidates {
        lights: &lights,
        emitters: Some(&bounds),
    }
    .choose());
}

/// The emitters' bound gives, bit for bit, what it gave before it became the light tree's
/// [`LightBounds`] (issue 58; the exhaustive choice's images are pinned by `bit_identity`):
/// outside and inside its sphere, one- and two-sided, and nothing for a NaN normal.
#[test]
fn emitter_importance_is_as_before_the_one_bound_type() {
    let tris = [
        (
            [
                Vec3::new(-0.5, 3.0, -0.5),
                Vec3::new(0.5, 3.0, 0.5),
                Vec3::new(0.5, 3.0, -0.5),
            ],
            2.0,
        ),
        (
            [
                Vec3::new(-0.5, 3.0, -0.5),
                Vec3::new(-0.5, 3.1, 0.5),
                Vec3::new(0.5, 3.0, 0.5),
            ],
            1.5,
        ),
    ];
    let b = LightBounds::emitters(tris).unwrap();
    let n = Vec3::new(0.3, 0.9, -0.2).normalize();
    let far = Vec3::new(2.0, 1.0, -1.0);
    let near = Vec3::new(0.1, 3.02, 0.2);
    for (p, n, two_sided, bits) in [
        (Vec3::ZERO, Vec3::Y, false, 0x3ec0a2eb),
        (far, n, false, 0x3e36b7a1),
        (far, -n, true, 0x3e36b7a1),
        (near, n, false, 0x40dee2b5),
        (Vec3::new(0.0, 3.05, 0.0), Vec3::NAN, false, 0),
        (Vec3::new(9.0, 3.0, 0.0), Vec3::X, true, 0x3c094dbf),
    ] {
        let got = b.importance(p, n, two_sided);
        assert_eq!(got.to_bits(), bits, "{p} {n} {two_sided}: {got}");
    }
}
