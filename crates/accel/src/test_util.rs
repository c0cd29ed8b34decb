//! Helpers shared by the crate's unit tests.

/// A 32-bit integer hash with good avalanche ("lowbias32", Chris Wellons): test inputs as a pure
/// function of a counter.
pub(crate) fn mix(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb_352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846c_a68b);
    x ^ (x >> 16)
}

/// A test coordinate for counter `k`: uniform in `[-scale, scale)`, and one time in sixteen
/// each exactly zero, negative zero, tiny (times 1e-30), infinite or NaN. Used by the packet
/// tests only.
#[cfg(any(target_arch = "x86_64", target_arch = "aarch64"))]
pub(crate) fn awkward(k: u32, scale: f32) -> f32 {
    let u = scale * (2.0 * ((mix(k) >> 8) as f32 / (1u32 << 24) as f32) - 1.0);
    match mix(k ^ 0x3c) % 16 {
        0 => 0.0,
        1 => -0.0,
        2 => u * 1e-30,
        3 => f32::INFINITY,
        4 => f32::NAN,
        _ => u,
    }
}

/// Whether the eight-lane kernels can run here: AVX2 and FMA on x86-64; always on aarch64,
/// where NEON is baseline (`crate::avx`).
#[cfg(any(target_arch = "x86_64", target_arch = "aarch64"))]
pub(crate) fn lanes8() -> bool {
    #[cfg(target_arch = "x86_64")]
    let yes = is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma");
    #[cfg(target_arch = "aarch64")]
    let yes = true;
    yes
}
