//! AVX's eight-float intrinsics as the packet kernels (`packet`, `triangle::lanes`) use them:
//! std's on x86-64; on aarch64 the same operations written with NEON ([`neon`]), AVX's results
//! bit for bit, so that one copy of each kernel serves both.

#[cfg(target_arch = "x86_64")]
pub(crate) use std::arch::x86_64::*;

#[cfg(target_arch = "aarch64")]
mod neon;
#[cfg(all(test, target_arch = "aarch64"))]
mod neon_tests;
#[cfg(target_arch = "aarch64")]
pub(crate) use neon::*;
