//! libFuzzer target `exr`: see `aperture_fuzz_harness::exr`.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| aperture_fuzz_harness::exr(data));
