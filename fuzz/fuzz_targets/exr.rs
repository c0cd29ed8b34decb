//! libFuzzer target `exr`: see `aperture_fuzz_harness::exr`. Panics inside the `exr` crate,
//! which the reader catches and reports as a damaged file, are not findings
//! (`aperture_fuzz_harness::tolerate_exr_crate_panics`).
#![no_main]

libfuzzer_sys::fuzz_target!(
    init: aperture_fuzz_harness::tolerate_exr_crate_panics(),
    |data: &[u8]| aperture_fuzz_harness::exr(data)
);
