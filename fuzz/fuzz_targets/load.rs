//! libFuzzer target `load`: see `aperture_fuzz_harness::load`.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| aperture_fuzz_harness::load(data));
