//! Inputs the fuzzers found (fuzz/, tools/fuzz.sh), each a small file in `tests/data/fuzz/`:
//! every one is an error from the loader, never a panic.

use std::path::Path;

fn data(name: &str) -> Vec<u8> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/fuzz")
        .join(name);
    std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Fuzz target `texture`, 645,393 executions in: a damaged JPEG on which zune-jpeg (the image
/// crate's JPEG decoder) overflows a multiplication (bitstream.rs, in builds with overflow
/// checks). Texture decoding now turns a decoder's panic into an error naming the image.
#[test]
fn a_jpeg_that_panics_its_decoder_is_an_error_naming_the_image() {
    let bytes = data("texture-jpeg-overflow.jpg");
    match aperture_scene::decode_texture(&bytes, 3, 1 << 30) {
        Ok(_) => {}
        Err(e) => {
            eprintln!("{e}");
            assert!(e.to_string().contains("images[3]"), "{e}");
        }
    }
}

/// Fuzz target `texture`, 316,119 executions in (a timeout): a 1049-byte JPEG whose header
/// claims an image hundreds of megabytes large, which the lenient decoder pads out with grey.
/// A JPEG or PNG cannot hold more than about 1100 decoded bytes per byte of file: refused from
/// its header, before decoding.
#[test]
fn a_jpeg_claiming_more_than_its_bytes_can_hold_is_refused_from_its_header() {
    let bytes = data("texture-jpeg-bomb.jpg");
    let e = aperture_scene::decode_texture(&bytes, 0, u64::MAX).expect_err("a bomb");
    assert!(e.to_string().contains("decompression bomb"), "{e}");
}

/// A KTX2 header (the identifier, then the fields `basis.rs` reads: pixel width at byte 20,
/// height at 24, level count at 40, and each level's uncompressed length at 80 + 24 × level
/// + 16), with nothing after its level index.
fn ktx2_header(width: u32, height: u32, uncompressed: &[u64]) -> Vec<u8> {
    let mut bytes = vec![0u8; 80 + 24 * uncompressed.len()];
    bytes[..12].copy_from_slice(&[
        0xAB, 0x4B, 0x54, 0x58, 0x20, 0x32, 0x30, 0xBB, 0x0D, 0x0A, 0x1A, 0x0A,
    ]);
    bytes[20..24].copy_from_slice(&width.to_le_bytes());
    bytes[24..28].copy_from_slice(&height.to_le_bytes());
    bytes[40..44].copy_from_slice(&(uncompressed.len() as u32).to_le_bytes());
    for (level, claimed) in uncompressed.iter().enumerate() {
        let at = 80 + 24 * level + 16;
        bytes[at..at + 8].copy_from_slice(&claimed.to_le_bytes());
    }
    bytes
}

/// Fuzz target `texture`, 5,379 executions in (`../shared/fuzz-findings/`
/// `texture-ktx2-level-overflow.bin`): a KTX2 header claiming 4294967295×4294967295. The most
/// a level of that size holds, 16 bytes per 4×4 block, is 2^64 bytes: one more than a u64
/// counts, so the check overflowed (a panic with overflow checks; in release it wrapped to 0
/// and refused the file as "holds at most 0"). Counted in u128 now: the true bound, in every
/// profile.
#[test]
fn a_ktx2_level_larger_than_a_u64_counts_is_refused_with_its_true_bound() {
    let side = u32::MAX;
    let bytes = ktx2_header(side, side, &[0, u64::MAX]);
    let e = aperture_scene::decode_texture(&bytes, 4, u64::MAX).expect_err("refused");
    let msg = e.to_string();
    // Level 1 is 2147483647 square: 2^29 × 2^29 blocks of 16 bytes.
    assert!(
        msg.contains("images[4]")
            && msg.contains("level 1 claims 18446744073709551615")
            && msg.contains("2147483647x2147483647")
            && msg.contains("holds at most 4611686018427387904"),
        "{msg}"
    );
}

/// The same size with a level 0 that claims u64::MAX bytes: within the true bound (2^64), so
/// the header check lets it through to the transcoder, which refuses the truncated file. The
/// old wrapped bound refused it as "holds at most 0".
#[test]
fn a_ktx2_level_0_within_2_pow_64_bytes_is_not_refused_by_a_wrapped_bound() {
    let bytes = ktx2_header(u32::MAX, u32::MAX, &[u64::MAX]);
    let e = aperture_scene::decode_texture(&bytes, 0, u64::MAX).expect_err("truncated");
    let msg = e.to_string();
    assert!(msg.contains("images[0]"), "{msg}");
    assert!(!msg.contains("at most 0"), "{msg}");
}

/// Fuzz target `load`, 16,992 executions into CI's smoke run (2026-12-07): a buffer URI whose
/// fifth byte falls inside a character (`"dataơpplication/…"`, `ơ` at bytes 4..6). The check
/// for a `data:` URI sliced its first five bytes and panicked; such a URI is a file name now,
/// refused as the missing file it names, with the buffer's place.
#[test]
fn a_uri_whose_fifth_byte_splits_a_character_is_an_error_not_a_panic() {
    for uri in [
        "dataơpplication/octet-stream;base64,AAAA",
        "é",
        "daté",
        "dataé:",
    ] {
        let gltf = format!(
            r#"{{"asset":{{"version":"2.0"}},"buffers":[{{"byteLength":3,"uri":"{uri}"}}]}}"#
        );
        let options = aperture_scene::LoadOptions::default();
        let folder = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/fuzz");
        match aperture_scene::Animated::load_bytes(gltf.as_bytes(), &folder, &options) {
            Ok(_) => panic!("{uri}: loaded a buffer from a file that does not exist"),
            Err(e) => {
                assert!(
                    !matches!(e, aperture_scene::Error::Panicked { .. }),
                    "{uri}: {e}"
                );
                assert!(e.to_string().contains("buffers[0]"), "{uri}: {e}");
            }
        }
    }
}
