//! libFuzzer target `exr`: see `aperture_fuzz_harness::exr`. Panics inside third-party
//! decoders, which the readers catch and report as damaged data, are not findings
//! (`aperture_fuzz_harness::tolerate_caught_decoder_panics`).
#![no_main]

libfuzzer_sys::fuzz_target!(
    init: aperture_fuzz_harness::tolerate_caught_decoder_panics(),
    |data: &[u8]| aperture_fuzz_harness::exr(data)
);
