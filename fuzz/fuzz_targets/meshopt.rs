//! libFuzzer target `meshopt`: see `aperture_fuzz_harness::meshopt`.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| aperture_fuzz_harness::meshopt(data));
