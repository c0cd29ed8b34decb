//! libFuzzer target `texture`: see `aperture_fuzz_harness::texture`.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| aperture_fuzz_harness::texture(data));
