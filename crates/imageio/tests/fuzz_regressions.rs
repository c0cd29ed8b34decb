//! Inputs the fuzzers found (fuzz/, tools/fuzz.sh), each a small file in `tests/data/fuzz/`:
//! every one is an error from the reader, never a panic, a hang or an allocation past the
//! limits.

use std::path::{Path, PathBuf};

fn data(name: &str) -> (PathBuf, Vec<u8>) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/fuzz")
        .join(name);
    let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    (path, bytes)
}

/// Fuzz target `exr`, 87,817 executions in: a B44-compressed block whose damaged data makes the
/// `exr` crate's decoder overflow (`attempt to subtract with overflow`, b44/mod.rs). With
/// overflow checks (debug builds) the decoder panics, and the panic is caught and reported as
/// a damaged file; without them (release) the subtraction wraps and the block decodes to some
/// pixels. Either way the reader returns, and what it returns is whole; the catching itself is
/// tested in every profile by `exr::tests::damaged::a_panic_inside_decoding_is_a_damaged_file_error`.
/// (The fuzzer reported a timeout: symbolising the panic's backtrace under AddressSanitizer
/// took over 2 s.)
#[test]
fn exr_whose_decoder_overflows_is_read_or_refused_in_every_profile() {
    let (path, bytes) = data("exr-decoder-panic.exr");
    let whole = |image: &aperture_imageio::Image| {
        assert!(image.width > 0 && image.height > 0);
        assert_eq!(image.rgba.len(), image.pixel_count());
    };
    match aperture_imageio::decode_exr(&bytes, &path) {
        Ok(image) => whole(&image),
        Err(e) => {
            let msg = e.to_string();
            assert!(msg.contains("exr-decoder-panic.exr"), "{msg}");
            eprintln!("{msg}");
        }
    }
    match aperture_imageio::decode_env_image(&bytes, &path, 1 << 30) {
        Ok(image) => whole(&image),
        Err(e) => assert!(e.to_string().contains("EXR"), "{e}"),
    }
}

/// Fuzz target `exr`, 527,981 executions in: an offset table entry near `usize::MAX`
/// overflowed the DWA guard's own arithmetic (`guard.rs`, before the decoder ran). Now every
/// position read from the file is added with a check; the file is an ordinary error.
#[test]
fn exr_with_an_offset_near_usize_max_is_an_error_not_an_overflow() {
    let (path, bytes) = data("exr-offset-overflow.exr");
    match aperture_imageio::decode_exr(&bytes, &path) {
        Ok(_) => {}
        Err(e) => assert!(!e.to_string().contains("panicked"), "{e}"),
    }
}

/// Fuzz target `exr`, 530,981 executions in (a timeout): a 419-byte file whose block claims
/// far more bytes than the file holds; the `exr` decoder allocated and cleared that much before
/// reading it (seconds). Now every block's claimed size is checked against the file first.
#[test]
fn exr_block_claiming_more_than_the_file_is_refused_before_decoding() {
    let (path, bytes) = data("exr-block-claims-2gb.exr");
    let e = aperture_imageio::decode_exr(&bytes, &path).expect_err("damaged");
    assert!(e.to_string().contains("claims"), "{e}");
}

/// Fuzz target `env`, 886,879 executions in: an EXR environment map whose data window is so
/// large that its size in bytes overflowed the limit check's multiplication (`env.rs`; in
/// release builds it wrapped and could pass the check). Now counted in u128: refused as too
/// large, with the true size.
#[test]
fn environment_map_whose_size_overflows_u64_is_refused_as_too_large() {
    let (path, bytes) = data("env-size-overflow.exr");
    let e = aperture_imageio::decode_env_image(&bytes, &path, 1 << 30).expect_err("too large");
    assert!(!e.to_string().contains("panicked"), "{e}");
    if let aperture_imageio::Error::TooLarge {
        width,
        height,
        needed,
        ..
    } = &e
    {
        assert_eq!(
            *needed,
            u128::from(*width) * u128::from(*height) * 28,
            "{e}"
        );
    }
}

/// Fuzz target `exr` with one allocation limited to 96 MiB (an out-of-memory finding): a
/// 387-byte file whose header claims 258 MB of samples, within the reader's default allowance
/// (1 GiB, or 4096 times the file). A caller with a smaller budget (environment maps, the fuzz
/// targets) gets an error before the decoder allocates.
#[test]
fn exr_claiming_more_samples_than_the_budget_is_refused_before_allocating() {
    let (path, bytes) = data("exr-claims-258mb.exr");
    let e = aperture_imageio::decode_exr_within(&bytes, &path, 64 << 20).expect_err("too big");
    assert!(e.to_string().contains("bytes of samples"), "{e}");
}

/// Fuzz target `exr`, 38,488 executions in (a timeout): a 518-byte file whose header implies
/// billions of blocks; the size guards walked an offset table of that many entries. The walk
/// now stops where the file's bytes do.
#[test]
fn exr_claiming_billions_of_blocks_is_checked_in_time_linear_in_the_file() {
    let (path, bytes) = data("exr-billions-of-chunks.exr");
    // Under the test profile a walk of billions of entries would take minutes.
    let r = aperture_imageio::decode_exr_within(&bytes, &path, 64 << 20);
    eprintln!("{r:?}");
    assert!(r.is_err(), "a damaged file");
}
