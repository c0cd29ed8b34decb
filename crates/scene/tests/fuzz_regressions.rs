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
