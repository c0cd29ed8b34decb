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
