//! Sample values as pure functions of (pixel, sample index, dimension, seed).
//!
//! Every primary sample draws one 4-D point: the pixel pair in dimensions 0–1 (the best
//! stratified pair of a Sobol sequence) and the lens pair in dimensions 2–3 of the *same* point,
//! so pixel and lens are stratified jointly (SPEC §2). Each path vertex then draws its own two
//! 4-D dimension sets. Pixels are decorrelated by hashing (pixel, seed) into the sequence's seed,
//! so neighbouring pixels show noise rather than structure.

pub(crate) mod pixel_run;

use sobol_burley::parts::Int4;

/// Which sequence generates sample values (`--sampler`; the first paragraph of each value's
/// comment is its help there).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum SamplerKind {
    /// Owen-scrambled Sobol.
    ///
    /// Burley 2020; stratified in every 4-D dimension set.
    #[default]
    Sobol,
    /// Independent uniform numbers, for comparison.
    ///
    /// From a counter-based hash.
    Random,
}

/// The largest sample count per pixel the Sobol sampler supports (its index is 16 bits).
pub const MAX_SPP: u32 = 1 << 16;

/// 4-D dimension sets the Sobol tables hold; later sets reuse them under another scramble seed.
const SOBOL_SETS: u32 = sobol_burley::NUM_DIMENSION_SETS_4D;

/// The dimension set of [`SampleStream::time`].
pub const TIME_SET: u32 = 1 << 22;

/// A 32-bit integer hash with good avalanche (the "lowbias32" finaliser by Chris Wellons).
#[inline]
pub(crate) fn hash_u32(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb_352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846c_a68b);
    x ^= x >> 16;
    x
}

/// SplitMix64's finaliser: the counter-based generator of the random sampler.
#[inline]
fn mix_u64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// Maps the top 24 bits of `x` to a float in `[0, 1)`: every value is exactly representable, so
/// the result never rounds up to 1.
#[inline]
fn u32_to_unit(x: u32) -> f32 {
    (x >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
}

/// The per-pixel seed: decorrelates pixels while keeping each pixel's sequence a pure function of
/// (pixel, seed).
pub fn pixel_seed(x: u32, y: u32, seed: u32) -> u32 {
    pixel_seed_in_row(x, row_seed(y, seed))
}

/// The part of [`pixel_seed`] that depends on the row `y` and the render's `seed` only: hashed
/// once for a row's pixels.
#[inline]
pub(crate) fn row_seed(y: u32, seed: u32) -> u32 {
    hash_u32(y.wrapping_add(0x9e37_79b9) ^ hash_u32(seed.wrapping_add(0x85eb_ca6b)))
}

/// [`pixel_seed`] of column `x` given its row's [`row_seed`].
#[inline]
pub(crate) fn pixel_seed_in_row(x: u32, row_seed: u32) -> u32 {
    hash_u32(x ^ row_seed)
}

impl SamplerKind {
    /// Dimensions `4·set .. 4·set + 4` of sample `index` of the pixel whose seed is `pixel_seed`.
    ///
    /// Sobol: at most [`MAX_SPP`] samples per pixel; sets past the tables' 64 are padded by
    /// re-scrambling (Burley's padding), so each set is stratified within itself.
    pub fn sample_4d(self, pixel_seed: u32, index: u32, set: u32) -> [f32; 4] {
        match self {
            Self::Sobol => {
                let (set, seed) = sobol_set(pixel_seed, set);
                sobol_burley::sample_4d(index, set, seed)
            }
            Self::Random => random_4d(pixel_seed, index, set),
        }
    }

    /// The first dimension of [`SamplerKind::sample_4d`], computing nothing else: a path's
    /// wavelength value and a sample's time (each one number of its own set).
    pub fn sample_1d(self, pixel_seed: u32, index: u32, set: u32) -> f32 {
        match self {
            Self::Sobol => {
                let (set, seed) = sobol_set(pixel_seed, set);
                sobol_burley::sample(index, 4 * set, seed)
            }
            Self::Random => {
                let (a, _) = random_words(pixel_seed, index, set);
                u32_to_unit(a as u32)
            }
        }
    }

    /// The first two dimensions of [`SamplerKind::sample_4d`], computing nothing else: what a
    /// pinhole camera draws.
    pub fn sample_2d(self, pixel_seed: u32, index: u32, set: u32) -> [f32; 2] {
        match self {
            Self::Sobol => {
                let (set, seed) = sobol_set(pixel_seed, set);
                [
                    sobol_burley::sample(index, 4 * set, seed),
                    sobol_burley::sample(index, 4 * set + 1, seed),
                ]
            }
            Self::Random => {
                let (a, _) = random_words(pixel_seed, index, set);
                [u32_to_unit(a as u32), u32_to_unit((a >> 32) as u32)]
            }
        }
    }
}

/// The random sampler's four values of one dimension set.
#[inline]
fn random_4d(pixel_seed: u32, index: u32, set: u32) -> [f32; 4] {
    let (a, b) = random_words(pixel_seed, index, set);
    [
        u32_to_unit(a as u32),
        u32_to_unit((a >> 32) as u32),
        u32_to_unit(b as u32),
        u32_to_unit((b >> 32) as u32),
    ]
}

/// `sobol_burley::sample_4d(index, set, seed)` with its first step, the Owen shuffle of the
/// sample index (`shuffled_rev`, which depends on the index and seed only), done by the
/// caller: a path draws up to 14 sets of one sample under one seed, so the shuffle is done once
/// per sample instead of once per set; the Sobol point comes from [`sobol_by_nibbles`]. The
/// same bits (`cached_shuffle_matches_the_crate` checks it).
#[inline]
fn sobol_4d_shuffled(shuffled_rev: u32, set: u32, seed: u32) -> [f32; 4] {
    let sobol = sobol_by_nibbles(&nibble_tables()[set as usize], shuffled_rev);
    sobol_scrambled(sobol, set_scramble(set, seed))
}

/// The Owen scramble (hashed) of dimension set `set` under `seed`, as `sobol_burley::sample_4d`
/// derives it: the same for every sample of a pixel.
#[inline]
fn set_scramble(set: u32, seed: u32) -> sobol_burley::parts::Int4 {
    use sobol_burley::parts::{hash_int4, Int4};
    let seed: Int4 = [seed.wrapping_mul(0x9c8f_2d3b); 4].into();
    let ds: Int4 = [set; 4].into();
    hash_int4(seed ^ ds ^ [0x912f_69ba, 0x174f_18ab, 0x691e_72ca, 0xb40c_c1b8].into())
}

/// The last steps of `sobol_burley::sample_4d`: the Sobol point of the shuffled index,
/// Owen-scrambled by its set's hashed `scramble`, as floats.
#[inline]
fn sobol_scrambled(sobol: Int4, scramble: Int4) -> [f32; 4] {
    sobol_burley::parts::owen_scramble_int4_rev(sobol, scramble)
        .reverse_bits()
        .to_f32_norm()
}

/// `sobol_burley::parts::sobol_int4_rev(index_rev, set)` by four lookups in set `set`'s table
/// `t`: the point is the XOR of the direction vectors of the top 16 index bits, so
/// XORing each nibble's precomputed share gives the same bits as the crate's loop over the set
/// bits, at a quarter of its instructions (`nibble_tables_match_the_crate` checks it).
#[inline]
fn sobol_by_nibbles(t: &NibbleTable, index_rev: u32) -> Int4 {
    let nibble = |k: usize| ((index_rev >> (28 - 4 * k)) & 15) as usize;
    t[0][nibble(0)] ^ t[1][nibble(1)] ^ t[2][nibble(2)] ^ t[3][nibble(3)]
}

/// One table set's share of the Sobol point per nibble of the top 16 index bits (most
/// significant first) and per value of that nibble.
type NibbleTable = [[Int4; 16]; 4];

/// Per table set, per nibble of the top 16 index bits (most significant first), the Sobol
/// point of each of its 16 values alone: 64 KiB, built once.
fn nibble_tables() -> &'static [NibbleTable] {
    use sobol_burley::parts::sobol_int4_rev;
    static TABLES: std::sync::OnceLock<Vec<NibbleTable>> = std::sync::OnceLock::new();
    TABLES.get_or_init(|| {
        (0..SOBOL_SETS)
            .map(|set| {
                std::array::from_fn(|k| {
                    std::array::from_fn(|v| sobol_int4_rev((v as u32) << (28 - 4 * k), set))
                })
            })
            .collect()
    })
}

/// The Owen-shuffled, bit-reversed sample index of `sobol_burley::sample_4d` for `seed`.
#[inline]
fn sobol_shuffle(index: u32, seed: u32) -> u32 {
    sobol_shuffle_rev(index.reverse_bits(), shuffle_scramble(seed))
}

/// The Owen-shuffled, bit-reversed sample index of `sobol_burley::sample_4d`, given the
/// bit-reversed index and the pixel's [`shuffle_scramble`].
#[inline]
fn sobol_shuffle_rev(index_rev: u32, scramble: u32) -> u32 {
    sobol_burley::parts::owen_scramble_rev(index_rev, scramble)
}

/// The hashed seed of [`sobol_shuffle`]: the same for every sample of a pixel.
#[inline]
fn shuffle_scramble(seed: u32) -> u32 {
    sobol_burley::parts::hash(seed ^ 0x79c6_8e4a)
}

/// The table set and scramble seed of dimension set `set`.
fn sobol_set(pixel_seed: u32, set: u32) -> (u32, u32) {
    if set < SOBOL_SETS {
        (set, pixel_seed)
    } else {
        (
            set % SOBOL_SETS,
            hash_u32(pixel_seed ^ hash_u32(set / SOBOL_SETS)),
        )
    }
}

/// The random sampler's two 64-bit words for one dimension set: a hash of the counter
/// (pixel seed, index, set), so the values are a pure function of it.
fn random_words(pixel_seed: u32, index: u32, set: u32) -> (u64, u64) {
    let key = ((pixel_seed as u64) << 32) | index as u64;
    let base = mix_u64(key ^ mix_u64(set as u64 ^ 0x5851_f42d_4c95_7f2d));
    (mix_u64(base), mix_u64(base ^ 0xd6e8_feb8_6659_fd93))
}

/// The dimensions of one primary sample: which sequence, which pixel, which sample.
#[derive(Debug, Clone, Copy)]
pub struct SampleStream {
    kind: SamplerKind,
    pixel_seed: u32,
    index: u32,
    /// [`sobol_shuffle`] of (index, pixel seed): shared by every table set of the sample.
    shuffled_rev: u32,
}

/// The values every path vertex draws: its scattering.
#[derive(Debug, Clone, Copy)]
pub struct BounceSample {
    /// BSDF lobe choice.
    pub lobe: f32,
    /// BSDF direction sample.
    pub bsdf: [f32; 2],
    /// Russian roulette.
    pub rr: f32,
}

/// The values a path vertex draws only in scenes that need them: lights to choose between,
/// emissive triangles to sample, alpha-cut surfaces to pass.
#[derive(Debug, Clone, Copy)]
pub struct VertexLightSample {
    /// Which light to sample, then (what the choice leaves of it) which emissive triangle.
    pub light_pick: f32,
    /// Where on it.
    pub light: [f32; 2],
    /// Stochastic alpha (coverage) decisions.
    pub alpha: f32,
}

impl SampleStream {
    /// The stream of sample `index` in the pixel `(x, y)`.
    pub fn new(kind: SamplerKind, x: u32, y: u32, index: u32, seed: u32) -> Self {
        Self::for_pixel(kind, pixel_seed(x, y, seed), index)
    }

    /// [`SampleStream::new`] given the pixel's [`pixel_seed`]: for callers that draw several
    /// samples of one pixel and hash it once.
    #[inline]
    pub fn for_pixel(kind: SamplerKind, pixel_seed: u32, index: u32) -> Self {
        Self {
            kind,
            pixel_seed,
            index,
            shuffled_rev: sobol_shuffle(index, pixel_seed),
        }
    }

    /// [`SamplerKind::sample_4d`] of this sample, the shuffle reused for the table sets.
    #[inline]
    fn set_4d(&self, set: u32) -> [f32; 4] {
        match self.kind {
            SamplerKind::Sobol if set < SOBOL_SETS => {
                sobol_4d_shuffled(self.shuffled_rev, set, self.pixel_seed)
            }
            kind => kind.sample_4d(self.pixel_seed, self.index, set),
        }
    }

    /// The pixel pair alone (dimensions 0–1), for a pinhole camera.
    pub fn pixel(&self) -> [f32; 2] {
        self.kind.sample_2d(self.pixel_seed, self.index, 0)
    }

    /// The camera's 4-D point: pixel pair (dimensions 0–1), lens pair (dimensions 2–3).
    pub fn camera(&self) -> [f32; 4] {
        self.set_4d(0)
    }

    /// The scattering values of path vertex `k` (0 = the camera ray's hit): dimension set
    /// `1 + 2k`, so no two vertices share a dimension.
    #[inline]
    pub fn bounce(&self, k: u32) -> BounceSample {
        let a = self.set_4d(1 + 2 * k);
        BounceSample {
            lobe: a[0],
            bsdf: [a[1], a[2]],
            rr: a[3],
        }
    }

    /// The light and alpha values of path vertex `k`: dimension set `2 + 2k`. Drawn apart from
    /// [`SampleStream::bounce`] so that scenes without emitters, a light choice or alpha skip
    /// its cost (a twelfth of a diffuse render's time); each value is the same either way.
    pub fn vertex_light(&self, k: u32) -> VertexLightSample {
        let b = self.set_4d(2 + 2 * k);
        VertexLightSample {
            light_pick: b[0],
            light: [b[1], b[2]],
            alpha: b[3],
        }
    }

    /// The environment light's pair at path vertex `k`: dimension set `2^20 + k`, far above the
    /// bounce sets, so drawing it changes no other value of the stream.
    pub fn environment(&self, k: u32) -> [f32; 2] {
        self.kind
            .sample_2d(self.pixel_seed, self.index, (1 << 20) + k)
    }

    /// The value choosing a path's wavelength at path vertex `k` (dispersion): dimension set
    /// `2^21 + k`, far above every other set.
    pub fn wavelength(&self, k: u32) -> f32 {
        self.kind
            .sample_1d(self.pixel_seed, self.index, (1 << 21) + k)
    }

    /// The sample's time in the shutter, normalised to `[0, 1)` (motion blur, SPEC §7):
    /// dimension set `2^22`, far above every other set. Its Sobol index shuffle and scramble
    /// come from another seed than the camera set's, so time is stratified on its own and
    /// independent of the pixel and lens dimensions.
    pub fn time(&self) -> f32 {
        self.kind.sample_1d(self.pixel_seed, self.index, TIME_SET)
    }

    /// An extra value for the `n`-th repeated decision at vertex `k` (alpha pass-through after
    /// the first), hashed so it stays a pure function of the sample.
    pub fn extra(&self, k: u32, n: u32) -> f32 {
        let h = hash_u32(
            self.pixel_seed ^ hash_u32(self.index ^ hash_u32(k.wrapping_mul(0x2545_f491) ^ n)),
        );
        u32_to_unit(h)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn points(kind: SamplerKind, n: u32, seed: u32) -> Vec<[f32; 4]> {
        let ps = pixel_seed(3, 7, seed);
        (0..n).map(|i| kind.sample_4d(ps, i, 0)).collect()
    }

    #[test]
    fn values_are_deterministic_and_in_unit_interval() {
        for kind in [SamplerKind::Sobol, SamplerKind::Random] {
            let a = points(kind, 64, 11);
            let b = points(kind, 64, 11);
            assert_eq!(a, b);
            assert!(a.iter().flatten().all(|v| (0.0..1.0).contains(v)));
            // Another seed and another pixel give other values.
            assert_ne!(a, points(kind, 64, 12));
            let other: Vec<_> = (0..64)
                .map(|i| kind.sample_4d(pixel_seed(4, 7, 11), i, 0))
                .collect();
            assert_ne!(a, other);
        }
    }

    #[test]
    fn one_and_two_d_values_are_the_first_of_four() {
        for kind in [SamplerKind::Sobol, SamplerKind::Random] {
            for set in [0, 3, 70, TIME_SET, (1 << 21) + 2] {
                for index in [0, 7, 1000] {
                    let a = kind.sample_4d(99, index, set);
                    assert_eq!(kind.sample_2d(99, index, set), [a[0], a[1]]);
                    assert_eq!(kind.sample_1d(99, index, set).to_bits(), a[0].to_bits());
                }
            }
        }
    }

    #[test]
    fn cached_shuffle_matches_the_crate() {
        for (x, y, seed) in [(0, 0, 0), (3, 7, 11), (319, 239, 1234)] {
            for index in [0, 1, 5, 63, 1000, MAX_SPP - 1] {
                let s = SampleStream::new(SamplerKind::Sobol, x, y, index, seed);
                let ps = pixel_seed(x, y, seed);
                assert_eq!(s.camera(), sobol_burley::sample_4d(index, 0, ps));
                for k in [0, 5, 31, 40] {
                    let (b, l) = (s.bounce(k), s.vertex_light(k));
                    let (sa, sb) = (1 + 2 * k, 2 + 2 * k);
                    let want_a = SamplerKind::Sobol.sample_4d(ps, index, sa);
                    let want_b = SamplerKind::Sobol.sample_4d(ps, index, sb);
                    let got_a = [b.lobe, b.bsdf[0], b.bsdf[1], b.rr];
                    let got_b = [l.light_pick, l.light[0], l.light[1], l.alpha];
                    assert_eq!(got_a.map(f32::to_bits), want_a.map(f32::to_bits));
                    assert_eq!(got_b.map(f32::to_bits), want_b.map(f32::to_bits));
                }
            }
        }
    }

    #[test]
    fn nibble_tables_match_the_crate() {
        use sobol_burley::parts::sobol_int4_rev;
        let bits = |v: sobol_burley::parts::Int4| v.to_f32_norm().map(f32::to_bits);
        let mut x = 0x9e37_79b9u32;
        for set in 0..SOBOL_SETS {
            let table = &nibble_tables()[set as usize];
            for index_rev in [
                0,
                u32::MAX,
                0xffff_0000,
                0x8000_0000,
                0x0001_0000,
                0x1234_5678,
            ] {
                let want = bits(sobol_int4_rev(index_rev, set));
                assert_eq!(bits(sobol_by_nibbles(table, index_rev)), want);
            }
            for _ in 0..64 {
                x = hash_u32(x);
                let want = bits(sobol_int4_rev(x, set));
                assert_eq!(
                    bits(sobol_by_nibbles(table, x)),
                    want,
                    "set {set}, index {x:#x}"
                );
            }
        }
    }

    #[test]
    fn padded_dimension_sets_differ_from_the_tables() {
        let ps = pixel_seed(0, 0, 0);
        let s = SamplerKind::Sobol;
        assert_ne!(s.sample_4d(ps, 5, 1), s.sample_4d(ps, 5, 1 + SOBOL_SETS));
    }

    /// True when the points, binned into `cx × cy` equal cells along dimensions (`i`, `j`), put
    /// the same number of points into every cell.
    fn stratified(pts: &[[f32; 4]], i: usize, j: usize, cx: usize, cy: usize) -> bool {
        let mut count = vec![0usize; cx * cy];
        for p in pts {
            let a = (p[i] * cx as f32) as usize;
            let b = (p[j] * cy as f32) as usize;
            count[b * cx + a] += 1;
        }
        let want = pts.len() / (cx * cy);
        count.iter().all(|&c| c == want)
    }

    /// The quality parameter `t` of a 2-D projection of `2^m` points: the smallest `t` such that
    /// every elementary interval of area `2^(t−m)` (all `2^k × 2^(m−t−k)` grids) holds exactly
    /// `2^t` points. `t = 0` is perfect stratification; independent points have `t` close to `m`.
    fn t_value(pts: &[[f32; 4]], i: usize, j: usize) -> u32 {
        let m = pts.len().trailing_zeros();
        (0..=m)
            .find(|&t| (0..=m - t).all(|k| stratified(pts, i, j, 1 << k, 1 << (m - t - k))))
            .unwrap_or(m)
    }

    /// Every 2-D projection of the camera's 4-D set is stratified for power-of-two counts: the
    /// pixel pair perfectly (a (0,m,2)-net: every elementary interval of area 1/n holds one
    /// point), every other pair in every elementary interval of area 4/n (t ≤ 2), and every 1-D
    /// projection in n strata. (t = 0 for all six pairs is impossible for any 4-D set: at n = 4
    /// it would need four mutually orthogonal balanced binary columns of length 4, and at most
    /// three exist.)
    #[test]
    fn sobol_every_2d_projection_is_stratified_for_power_of_two_spp() {
        for m in 1u32..=10 {
            let n = 1u32 << m;
            for seed in [0, 1, 1234] {
                let pts = points(SamplerKind::Sobol, n, seed);
                for i in 0..4 {
                    assert!(stratified(&pts, i, i, n as usize, 1), "1-D dim {i}, n {n}");
                    for j in i + 1..4 {
                        let t = t_value(&pts, i, j);
                        let bound = if (i, j) == (0, 1) { 0 } else { 2 };
                        assert!(t <= bound, "dims ({i},{j}), n {n}, seed {seed}: t = {t}");
                    }
                }
            }
        }
    }

    #[test]
    fn random_sampler_is_not_stratified() {
        // The check above must be able to fail: independent values miss strata.
        let pts = points(SamplerKind::Random, 256, 0);
        assert!(!stratified(&pts, 0, 1, 16, 16));
        assert!(t_value(&pts, 0, 1) > 2 && t_value(&pts, 2, 3) > 2);
    }

    #[test]
    fn bounces_use_distinct_dimensions() {
        let s = SampleStream::new(SamplerKind::Sobol, 1, 2, 3, 4);
        let a = s.bounce(0);
        let b = s.bounce(1);
        assert_ne!(a.bsdf, b.bsdf);
        assert_ne!(s.camera()[0], a.lobe);
    }
}
