//! libFuzzer target `env`: see `aperture_fuzz_harness::env`.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| aperture_fuzz_harness::env(data));
