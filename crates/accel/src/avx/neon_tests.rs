//! The NEON versions of AVX's intrinsics ([`super::neon`]) against the instructions'
//! definitions, lane by lane and bit for bit, on values with NaNs, infinities and signed zeros.

use super::neon::*;
use crate::test_util::{awkward, mix};

/// Eight floats from a counter: ordinary values, zeros of both signs, infinities and NaNs.
fn lanes(k: u32) -> [f32; 8] {
    std::array::from_fn(|i| awkward(k * 8 + i as u32, 2.0))
}

fn get(v: __m256) -> [f32; 8] {
    let mut out = [0.0; 8];
    // SAFETY: the store writes the eight floats of `out`.
    unsafe { _mm256_storeu_ps(out.as_mut_ptr(), v) };
    out
}

fn put(v: [f32; 8]) -> __m256 {
    // SAFETY: the load reads the eight floats of `v`.
    unsafe { _mm256_loadu_ps(v.as_ptr()) }
}

/// SSE's definitions, lane by lane, as Intel's manual gives them.
fn maxps(a: f32, b: f32) -> f32 {
    if a > b {
        a
    } else {
        b
    }
}
fn minps(a: f32, b: f32) -> f32 {
    if a < b {
        a
    } else {
        b
    }
}
fn mask(m: bool) -> f32 {
    f32::from_bits(if m { u32::MAX } else { 0 })
}

/// An instruction of two operands: its name, the emulation, its definition on one lane.
type Case = (
    &'static str,
    fn(__m256, __m256) -> __m256,
    fn(f32, f32) -> f32,
);

/// The two-operand instructions with their definitions (SSE's for `maxps`, `minps`).
fn binary_cases() -> [Case; 16] {
    // SAFETY (each closure): register-only operations.
    [
        ("add", |a, b| unsafe { _mm256_add_ps(a, b) }, |a, b| a + b),
        ("sub", |a, b| unsafe { _mm256_sub_ps(a, b) }, |a, b| a - b),
        ("mul", |a, b| unsafe { _mm256_mul_ps(a, b) }, |a, b| a * b),
        ("div", |a, b| unsafe { _mm256_div_ps(a, b) }, |a, b| a / b),
        ("max", |a, b| unsafe { _mm256_max_ps(a, b) }, maxps),
        ("min", |a, b| unsafe { _mm256_min_ps(a, b) }, minps),
        (
            "and",
            |a, b| unsafe { _mm256_and_ps(a, b) },
            |a, b| f32::from_bits(a.to_bits() & b.to_bits()),
        ),
        (
            "or",
            |a, b| unsafe { _mm256_or_ps(a, b) },
            |a, b| f32::from_bits(a.to_bits() | b.to_bits()),
        ),
        (
            "xor",
            |a, b| unsafe { _mm256_xor_ps(a, b) },
            |a, b| f32::from_bits(a.to_bits() ^ b.to_bits()),
        ),
        (
            "andnot",
            |a, b| unsafe { _mm256_andnot_ps(a, b) },
            |a, b| f32::from_bits(!a.to_bits() & b.to_bits()),
        ),
        (
            "eq",
            |a, b| unsafe { _mm256_cmp_ps::<_CMP_EQ_OQ>(a, b) },
            |a, b| mask(a == b),
        ),
        (
            "lt",
            |a, b| unsafe { _mm256_cmp_ps::<_CMP_LT_OQ>(a, b) },
            |a, b| mask(a < b),
        ),
        (
            "nlt",
            |a, b| unsafe { _mm256_cmp_ps::<_CMP_NLT_UQ>(a, b) },
            |a, b| mask(a.partial_cmp(&b) != Some(std::cmp::Ordering::Less)),
        ),
        (
            "gt",
            |a, b| unsafe { _mm256_cmp_ps::<_CMP_GT_OQ>(a, b) },
            |a, b| mask(a > b),
        ),
        (
            "le",
            |a, b| unsafe { _mm256_cmp_ps::<_CMP_LE_OQ>(a, b) },
            |a, b| mask(a <= b),
        ),
        (
            "ge",
            |a, b| unsafe { _mm256_cmp_ps::<_CMP_GE_OQ>(a, b) },
            |a, b| mask(a >= b),
        ),
    ]
}

/// Each two-operand instruction against its definition applied lane by lane, bit for bit,
/// on values with NaNs, infinities and signed zeros.
#[test]
fn binary_instructions_match_their_definitions_lane_by_lane() {
    let (mut nans, mut zeros) = (0, 0);
    for k in 0..20_000u32 {
        let (a, b) = (lanes(2 * k), lanes(2 * k + 1));
        nans += a.iter().filter(|x| x.is_nan()).count();
        zeros += a.iter().filter(|x| **x == 0.0).count();
        for (name, vector, scalar) in binary_cases() {
            let got = get(vector(put(a), put(b))).map(f32::to_bits);
            let want: [u32; 8] = std::array::from_fn(|i| scalar(a[i], b[i]).to_bits());
            // NaN payloads of arithmetic are not compared (both are NaN).
            for i in 0..8 {
                let both_nan = f32::from_bits(got[i]).is_nan()
                    && f32::from_bits(want[i]).is_nan()
                    && matches!(name, "add" | "sub" | "mul" | "div");
                assert!(
                    both_nan || got[i] == want[i],
                    "{name} lane {i}: {} {} -> {:#x}, want {:#x}",
                    a[i],
                    b[i],
                    got[i],
                    want[i]
                );
            }
        }
    }
    assert!(nans > 1_000 && zeros > 1_000, "{nans} NaNs, {zeros} zeros");
}

/// `blendv` and `movemask` read each lane's sign bit alone (NaNs and negative zeros too).
#[test]
fn blendv_and_movemask_read_sign_bits() {
    let mut negative = 0;
    for k in 0..20_000u32 {
        let (a, b, m) = (lanes(3 * k), lanes(3 * k + 1), lanes(3 * k + 2));
        // SAFETY: register-only operations.
        let (sel, bits) = unsafe {
            (
                _mm256_blendv_ps(put(a), put(b), put(m)),
                _mm256_movemask_ps(put(m)),
            )
        };
        for i in 0..8 {
            let sign = m[i].is_sign_negative();
            negative += usize::from(sign);
            let want = if sign { b[i] } else { a[i] };
            assert_eq!(get(sel)[i].to_bits(), want.to_bits(), "blendv lane {i}");
            assert_eq!((bits >> i) & 1 == 1, sign, "movemask lane {i}: {}", m[i]);
        }
    }
    assert!(negative > 10_000, "{negative} negative lanes");
}

/// The shuffles, the integer comparison and the byte mask, against their definitions.
#[test]
fn shuffles_and_integer_operations_match_their_definitions() {
    for k in 0..2_000u32 {
        let (a, b) = (lanes(2 * k), lanes(2 * k + 1));
        let bits = |v: __m256| get(v).map(f32::to_bits);
        let (x, y) = (a.map(f32::to_bits), b.map(f32::to_bits));
        // SAFETY: register-only operations.
        let (lo, hi, s44, see) = unsafe {
            (
                _mm256_unpacklo_ps(put(a), put(b)),
                _mm256_unpackhi_ps(put(a), put(b)),
                _mm256_shuffle_ps::<0x44>(put(a), put(b)),
                _mm256_shuffle_ps::<0xee>(put(a), put(b)),
            )
        };
        for h in [0, 4] {
            let want_lo = [x[h], y[h], x[h + 1], y[h + 1]];
            let want_hi = [x[h + 2], y[h + 2], x[h + 3], y[h + 3]];
            assert_eq!(bits(lo)[h..h + 4], want_lo);
            assert_eq!(bits(hi)[h..h + 4], want_hi);
            assert_eq!(bits(s44)[h..h + 4], [x[h], x[h + 1], y[h], y[h + 1]]);
            assert_eq!(
                bits(see)[h..h + 4],
                [x[h + 2], x[h + 3], y[h + 2], y[h + 3]]
            );
        }
        // Integers: lanes equal half of the time.
        let c = mix(k) as i32;
        let ints: [f32; 8] = std::array::from_fn(|i| {
            f32::from_bits(if mix(k + i as u32) % 2 == 0 {
                c as u32
            } else {
                i as u32
            })
        });
        // SAFETY: register-only operations.
        let eq = unsafe {
            _mm256_castsi256_ps(_mm256_cmpeq_epi32(
                _mm256_castps_si256(put(ints)),
                _mm256_set1_epi32(c),
            ))
        };
        for (got, int) in get(eq).into_iter().zip(ints) {
            assert_eq!(got.to_bits(), mask(int.to_bits() == c as u32).to_bits());
        }
        let word = (u64::from(mix(k)) << 32) | (u64::from(mix(k + 1)) & 0xff00_ff00_00ff_ff00);
        // SAFETY: register-only operations.
        let zero_bytes = unsafe {
            _mm_movemask_epi8(_mm_cmpeq_epi8(
                _mm_cvtsi64_si128(word as i64),
                _mm_setzero_si128(),
            ))
        };
        let want = (0..16).fold(0, |m, i| {
            let byte = if i < 8 { (word >> (8 * i)) & 0xff } else { 0 };
            m | (i32::from(byte == 0) << i)
        });
        assert_eq!(zero_bytes, want, "{word:#x}");
    }
}
