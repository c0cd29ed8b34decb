//! libFuzzer target `draco`: see `aperture_fuzz_harness::draco`.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| aperture_fuzz_harness::draco(data));
