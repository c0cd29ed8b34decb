//! View transforms: scene-referred linear Rec.709 to display-encoded sRGB values in [0, 1].
//!
//! Every function here is total: NaN becomes 0 and infinities are clipped, so whatever the
//! renderer produced, the result is a valid display value.

use crate::options::ViewTransform;

/// Below this linear value the sRGB curve is a straight line (IEC 61966-2-1).
pub const SRGB_LINEAR_CUTOFF: f32 = 0.003_130_8;

/// The sRGB opto-electronic transfer function, the exact piecewise form: `12.92 v` up to
/// 0.0031308, `1.055 v^(1/2.4) − 0.055` above. Defined for v in [0, 1]; not clipped here.
pub fn srgb_oetf(linear: f32) -> f32 {
    srgb_oetf_f64(f64::from(linear)) as f32
}

fn srgb_oetf_f64(v: f64) -> f64 {
    if v <= f64::from(SRGB_LINEAR_CUTOFF) {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// The inverse of [`srgb_oetf`] (decoding sRGB-encoded values to linear), in f32: the one
/// implementation of the project, which the renderer's texture lookups use too.
pub fn srgb_eotf(encoded: f32) -> f32 {
    if encoded <= 0.04045 {
        encoded / 12.92
    } else {
        ((encoded + 0.055) / 1.055).powf(2.4)
    }
}

/// NaN to 0, infinities to the largest finite value, so later arithmetic stays finite.
pub(crate) fn sanitize(v: f32) -> f64 {
    if v.is_nan() {
        0.0
    } else {
        f64::from(v.clamp(f32::MIN, f32::MAX))
    }
}

/// `Standard`: clip to [0, 1], then the sRGB OETF.
pub fn standard(rgb: [f32; 3]) -> [f32; 3] {
    rgb.map(|c| srgb_oetf_f64(sanitize(c).clamp(0.0, 1.0)) as f32)
}

/// Applies `view` to one linear Rec.709 colour (straight, not premultiplied).
pub fn apply(view: ViewTransform, rgb: [f32; 3]) -> [f32; 3] {
    match view {
        ViewTransform::Standard => standard(rgb),
        ViewTransform::AgX => agx(rgb),
    }
}

type Mat3 = [[f64; 3]; 3];

fn mul(m: &Mat3, v: [f64; 3]) -> [f64; 3] {
    m.map(|row| row[0] * v[0] + row[1] * v[1] + row[2] * v[2])
}

// Rows. Rec.709 and Rec.2020 primaries, both D65 (ITU-R BT.2087-0; Filament and three.js
// round these to four decimals, which tints grey slightly).
const REC709_TO_REC2020: Mat3 = [
    [0.627_403_896, 0.329_283_039, 0.043_313_065],
    [0.069_097_289, 0.919_540_395, 0.011_362_316],
    [0.016_391_439, 0.088_013_308, 0.895_595_253],
];
const REC2020_TO_REC709: Mat3 = [
    [1.660_491, -0.587_641_1, -0.072_849_9],
    [-0.124_550_5, 1.132_899_9, -0.008_349_4],
    [-0.018_150_8, -0.100_578_9, 1.118_729_7],
];
// Blender's AgX inset (config.ocio, "AgX Log"), in Rec.2020: pulls colours towards the
// achromatic axis so highlights desaturate to white instead of skewing in hue.
const AGX_INSET: Mat3 = [
    [
        0.856_627_153_315_983,
        0.095_121_240_538_158_8,
        0.048_251_606_145_858_3,
    ],
    [
        0.137_318_972_929_847,
        0.761_241_990_602_591,
        0.101_439_036_467_562,
    ],
    [
        0.111_898_212_999_95,
        0.076_799_418_603_190_3,
        0.811_302_368_396_859,
    ],
];
// The outset that restores purity after the curve (inverse of AgX_LUT_Gen's outset).
const AGX_OUTSET: Mat3 = [
    [
        1.127_100_581_814_436_8,
        -0.110_606_643_096_603_23,
        -0.016_493_938_717_834_573,
    ],
    [
        -0.141_329_763_498_438_3,
        1.157_823_702_216_272,
        -0.016_493_938_717_834_257,
    ],
    [
        -0.141_329_763_498_438_26,
        -0.110_606_643_096_602_94,
        1.251_936_406_595_040_5,
    ],
];
/// Log2 range of AgX's encoding: 10 stops below and 6.5 above middle grey 0.18.
pub const AGX_MIN_EV: f64 = -12.473_93;
/// Upper end of [`AGX_MIN_EV`]'s range.
pub const AGX_MAX_EV: f64 = 4.026_069;

/// The 6th-degree polynomial fit of AgX's default-contrast sigmoid over [0, 1]
/// (fit published with Filament/three.js; mean squared error about 3.7e-6 against the curve).
pub fn agx_sigmoid(x: f64) -> f64 {
    let x2 = x * x;
    let x4 = x2 * x2;
    15.5 * x4 * x2 - 40.14 * x4 * x + 31.96 * x4 - 6.868 * x2 * x + 0.4298 * x2 + 0.1191 * x
        - 0.00232
}

/// Blender's AgX base view (no look), approximated the way Filament and three.js do: linear
/// Rec.709 → Rec.2020 → inset → log2 over [`AGX_MIN_EV`, `AGX_MAX_EV`] → polynomial sigmoid
/// → outset → 2.2 power (undoing the sigmoid's display encoding) → Rec.709 → clip → sRGB OETF.
///
/// Differences from Blender: Blender evaluates the sigmoid through a baked LUT and encodes
/// for the display without the round trip through 2.2 and the sRGB curve; the polynomial
/// fit (rms ≈ 0.002) and that round trip keep results within a few 8-bit code values of
/// Blender's over most of the range, largest in the deepest shadows. This has not been
/// compared against Blender renders here; treat the tolerance as an estimate.
pub fn agx(rgb: [f32; 3]) -> [f32; 3] {
    let v = mul(&REC709_TO_REC2020, rgb.map(sanitize));
    let v = mul(&AGX_INSET, v).map(|c| {
        let ev = c.max(1e-10).log2();
        agx_sigmoid(((ev - AGX_MIN_EV) / (AGX_MAX_EV - AGX_MIN_EV)).clamp(0.0, 1.0))
    });
    let v = mul(&AGX_OUTSET, v).map(|c| c.max(0.0).powf(2.2));
    mul(&REC2020_TO_REC709, v).map(|c| srgb_oetf_f64(c.clamp(0.0, 1.0)) as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn to_u8(v: f32) -> u8 {
        (v * 255.0 + 0.5).floor() as u8
    }

    #[test]
    fn srgb_known_points() {
        assert_eq!(srgb_oetf(0.0), 0.0);
        assert!((srgb_oetf(1.0) - 1.0).abs() < 1e-6);
        assert_eq!(to_u8(srgb_oetf(1.0)), 255);
        assert_eq!(to_u8(srgb_oetf(0.18)), 118);
        assert!((srgb_oetf(0.18) - 0.461_356).abs() < 1e-5);
        assert_eq!(to_u8(srgb_oetf(0.5)), 188);
        // The two pieces meet at the cut-off.
        let c = f64::from(SRGB_LINEAR_CUTOFF);
        let line = 12.92 * c;
        let curve = 1.055 * c.powf(1.0 / 2.4) - 0.055;
        assert!((line - curve).abs() < 1e-7, "{line} vs {curve}");
        let below = srgb_oetf(SRGB_LINEAR_CUTOFF);
        let above = srgb_oetf(SRGB_LINEAR_CUTOFF * (1.0 + 1e-6));
        assert!((above - below).abs() < 1e-6 && above >= below);
        // Linear piece really is linear.
        assert!((srgb_oetf(0.001) - 0.01292).abs() < 1e-8);
    }

    #[test]
    fn srgb_eotf_inverts_oetf() {
        for i in 0..=1000 {
            let v = i as f32 / 1000.0;
            assert!((srgb_eotf(srgb_oetf(v)) - v).abs() < 1e-6, "{v}");
        }
    }

    #[test]
    fn standard_clips_and_cleans() {
        assert_eq!(standard([-1.0, 2.0, f32::NAN]), [0.0, 1.0, 0.0]);
        assert_eq!(
            standard([f32::INFINITY, f32::NEG_INFINITY, 0.0]),
            [1.0, 0.0, 0.0]
        );
    }

    #[test]
    fn rec2020_matrices_are_inverse() {
        for i in 0..3 {
            let e = [0, 1, 2].map(|j| f64::from(u8::from(i == j)));
            let back = mul(&REC2020_TO_REC709, mul(&REC709_TO_REC2020, e));
            for j in 0..3 {
                assert!((back[j] - e[j]).abs() < 1e-6, "{i} {j}: {back:?}");
            }
        }
    }

    #[test]
    fn agx_keeps_grey_neutral_monotonic_and_bounded() {
        let mut last = -1.0f32;
        for i in 0..200 {
            let x = 2f32.powf(i as f32 / 10.0 - 14.0);
            let [r, g, b] = agx([x, x, x]);
            assert!(
                (r - g).abs() < 2e-3 && (g - b).abs() < 2e-3,
                "{x}: {r} {g} {b}"
            );
            assert!((0.0..=1.0).contains(&r));
            assert!(g >= last - 1e-6, "not monotonic at {x}");
            last = g;
        }
        // Black stays (nearly) black, huge values reach (nearly) white.
        assert!(agx([0.0; 3])[1] < 0.01);
        assert!(agx([1e6; 3])[1] > 0.98);
        // Middle grey lands mid-scale (Blender shows 0.18 at roughly 0.5 display).
        let mid = agx([0.18; 3])[1];
        assert!((0.4..0.6).contains(&mid), "{mid}");
    }

    #[test]
    fn agx_desaturates_bright_primaries_and_survives_bad_input() {
        let [r, g, b] = agx([100.0, 0.0, 0.0]);
        assert!(r > 0.9 && g > 0.3 && b > 0.3, "{r} {g} {b}");
        for bad in [
            [f32::NAN, 1.0, 0.0],
            [f32::INFINITY, f32::NEG_INFINITY, 0.0],
            [-5.0, -5.0, -5.0],
        ] {
            let out = agx(bad);
            assert!(
                out.iter().all(|c| (0.0..=1.0).contains(c)),
                "{bad:?} -> {out:?}"
            );
        }
    }
}
