//! The image warp of the bokeh image (`aperture_image`): points where the image is bright, in
//! proportion to its texels (chi-square), and the rejection helper deterministic in its numbers.

use aperture_shading::warp_image::ImageDistribution;
use aperture_shading::warp_lens::first_inside;
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

#[test]
fn a_bright_half_gets_every_point() {
    // 8 × 6, the right half lit.
    let (w, h) = (8, 6);
    let weights: Vec<f32> = (0..w * h)
        .map(|i| if i % w >= w / 2 { 1.0 } else { 0.0 })
        .collect();
    let d = ImageDistribution::new(w, h, &weights).expect("some light");
    for u in numbers(3, 20_000)
        .into_iter()
        .chain([Vec2::ZERO, Vec2::splat(1.0 - f32::EPSILON)])
    {
        let p = d.sample(u);
        assert!(
            p.x >= 0.5 && p.x < 1.0 && p.y >= 0.0 && p.y < 1.0,
            "{u} -> {p}"
        );
        assert_eq!(d.pdf(p), 2.0);
    }
    assert!(ImageDistribution::new(w, h, &vec![0.0; w * h]).is_none());
    assert!(ImageDistribution::new(w, h, &[1.0; 3]).is_none());
}

#[test]
fn texels_are_drawn_in_proportion_to_their_weight() {
    // A 5 × 4 image of uneven weights (one black texel); chi-square of the texel counts for
    // three seeds, 19 degrees of freedom: 0.999 quantile 43.8.
    let (w, h) = (5usize, 4usize);
    let weights: Vec<f32> = (0..w * h)
        .map(|i| {
            if i == 7 {
                0.0
            } else {
                1.0 + (i * 7 % 11) as f32
            }
        })
        .collect();
    let total: f32 = weights.iter().sum();
    let d = ImageDistribution::new(w, h, &weights).expect("some light");
    for seed in [5, 6, 7] {
        let n = 100_000;
        let mut counts = vec![0usize; w * h];
        for u in numbers(seed, n) {
            let p = d.sample(u);
            let (x, y) = ((p.x * w as f32) as usize, (p.y * h as f32) as usize);
            counts[y * w + x] += 1;
        }
        assert_eq!(counts[7], 0, "a black texel was drawn");
        let chi2: f64 = counts
            .iter()
            .zip(&weights)
            .filter(|(_, &wt)| wt > 0.0)
            .map(|(&c, &wt)| {
                let e = n as f64 * f64::from(wt / total);
                (c as f64 - e).powi(2) / e
            })
            .sum();
        assert!(chi2 < 43.8, "seed {seed}: chi-square {chi2}");
    }
}

#[test]
fn the_warp_keeps_strata_inside_a_texel() {
    // Within one texel the warp is linear: equal steps of u.x are equal steps of x.
    let d = ImageDistribution::new(2, 1, &[1.0, 3.0]).expect("some light");
    let a = d.sample(Vec2::new(0.3, 0.5));
    let b = d.sample(Vec2::new(0.4, 0.5));
    let c = d.sample(Vec2::new(0.5, 0.5));
    assert!(((b.x - a.x) - (c.x - b.x)).abs() < 1e-6, "{a} {b} {c}");
    assert!(
        a.x >= 0.5,
        "u.x = 0.3 lies past the first texel's 0.25 of the mass: {a}"
    );
}

#[test]
fn rejection_is_a_pure_function_of_its_numbers() {
    let inside = |p: Vec2| p.x > 0.9;
    for u in numbers(9, 500) {
        let a = first_inside(u, |v| v, inside);
        let b = first_inside(u, |v| v, inside);
        assert_eq!(a, b);
        if a.1 {
            assert!(a.0.x > 0.9);
        }
    }
    // A point already inside is itself.
    assert_eq!(
        first_inside(Vec2::new(0.95, 0.1), |v| v, inside),
        (Vec2::new(0.95, 0.1), true)
    );
}
