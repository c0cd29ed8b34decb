//! Equirectangular environment images: Radiance HDR (RGBE) or OpenEXR, read into a plain
//! [`Image`] within a memory limit.
//!
//! Environment maps come from anywhere (an artist's download folder, a farm's shared disk), so
//! the reader is as careful as the scene loader: the size the file claims is checked against
//! the limit before any texel is allocated, and damaged files are errors, never panics.

use std::io::Cursor;
use std::path::Path;

use image::ImageDecoder as _;

use crate::error::Error;
use crate::model::Image;

/// The environment image formats, told apart by their first bytes (not the file name).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EnvFormat {
    /// Radiance RGBE (`#?RADIANCE` or `#?RGBE`).
    Hdr,
    /// OpenEXR.
    Exr,
}

impl EnvFormat {
    /// The format of `bytes`, from their magic number.
    pub fn sniff(bytes: &[u8]) -> Option<Self> {
        if bytes.starts_with(&[0x76, 0x2f, 0x31, 0x01]) {
            Some(EnvFormat::Exr)
        } else if bytes.starts_with(b"#?") {
            Some(EnvFormat::Hdr)
        } else {
            None
        }
    }
}

/// Bytes a decoded texel takes while reading: the decoder's RGB f32 plus the [`Image`]'s RGBA
/// f32.
const BYTES_PER_TEXEL: u64 = 12 + 16;

/// Reads the environment image at `path` (HDR or EXR, by content), refusing one whose decoded
/// texels would take more than `max_bytes`.
pub fn read_env_image(path: &Path, max_bytes: u64) -> Result<Image, Error> {
    let bytes = std::fs::read(path).map_err(|e| Error::Io {
        path: path.to_path_buf(),
        message: format!("reading: {e}"),
    })?;
    decode_env_image(&bytes, path, max_bytes)
}

/// Decodes environment image bytes; see [`read_env_image`]. `path` only names the file in
/// errors. The image's RGB is linear radiance; A is 1.
pub fn decode_env_image(bytes: &[u8], path: &Path, max_bytes: u64) -> Result<Image, Error> {
    let image = match EnvFormat::sniff(bytes) {
        Some(EnvFormat::Exr) => {
            let head = exr_size(bytes);
            if let Some((w, h)) = head {
                check_size(path, w, h, max_bytes)?;
            }
            let mut image = crate::exr::decode_exr_within(bytes, path, max_bytes)?;
            image.layers.clear();
            image.metadata.clear();
            image
        }
        Some(EnvFormat::Hdr) => decode_hdr(bytes, path, max_bytes)?,
        None => {
            return Err(Error::Decode {
                path: path.to_path_buf(),
                message: "neither a Radiance HDR (#?RADIANCE) nor an OpenEXR file".into(),
            })
        }
    };
    if image.width == 0 || image.height == 0 {
        return Err(Error::EmptyImage {
            width: image.width,
            height: image.height,
        });
    }
    Ok(image)
}

fn check_size(path: &Path, width: u32, height: u32, max_bytes: u64) -> Result<(), Error> {
    // u128: u32 × u32 × 28 overflows u64 for the largest sizes a header can claim.
    let needed = u128::from(width) * u128::from(height) * u128::from(BYTES_PER_TEXEL);
    if needed > u128::from(max_bytes) {
        return Err(Error::TooLarge {
            path: path.to_path_buf(),
            width,
            height,
            needed,
            limit: max_bytes,
        });
    }
    Ok(())
}

/// The data window size of an EXR's first part, when its header can be read.
fn exr_size(bytes: &[u8]) -> Option<(u32, u32)> {
    let meta = ::exr::meta::MetaData::read_from_buffered(Cursor::new(bytes), false).ok()?;
    let size = meta.headers.first()?.layer_size;
    Some((
        u32::try_from(size.width()).ok()?,
        u32::try_from(size.height()).ok()?,
    ))
}

fn decode_hdr(bytes: &[u8], path: &Path, max_bytes: u64) -> Result<Image, Error> {
    let fail = |e: image::ImageError| Error::Decode {
        path: path.to_path_buf(),
        message: format!("Radiance HDR: {e}"),
    };
    let mut decoder = image::codecs::hdr::HdrDecoder::new(Cursor::new(bytes)).map_err(fail)?;
    let (w, h) = decoder.dimensions();
    check_size(path, w, h, max_bytes)?;
    let mut limits = image::Limits::default();
    limits.max_alloc = Some(max_bytes);
    decoder.set_limits(limits).map_err(fail)?;
    let dynamic = image::DynamicImage::from_decoder(decoder).map_err(fail)?;
    let rgb = dynamic.into_rgb32f();
    let mut image = Image::new(w, h);
    image.rgba = rgb
        .into_raw()
        .chunks_exact(3)
        .map(|c| [c[0], c[1], c[2], 1.0])
        .collect();
    if image.rgba.len() != image.pixel_count() {
        return Err(Error::BufferSize {
            what: "Radiance HDR texels".into(),
            expected: image.pixel_count(),
            found: image.rgba.len(),
        });
    }
    Ok(image)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hdr_bytes(w: u32, h: u32, rgb: [f32; 3]) -> Vec<u8> {
        let mut out = Vec::new();
        let img = image::Rgb32FImage::from_pixel(w, h, image::Rgb(rgb));
        image::DynamicImage::ImageRgb32F(img)
            .write_to(&mut Cursor::new(&mut out), image::ImageFormat::Hdr)
            .unwrap();
        out
    }

    #[test]
    fn hdr_and_exr_read_by_content() {
        let hdr = hdr_bytes(8, 4, [0.5, 1.0, 2.0]);
        let im = decode_env_image(&hdr, Path::new("sky.exr"), 1 << 20).unwrap();
        assert_eq!((im.width, im.height), (8, 4));
        assert!((im.rgba[5][2] - 2.0).abs() < 0.02, "{:?}", im.rgba[5]);
        let mut e = Image::new(4, 2);
        e.rgba = vec![[0.25, 0.5, 4.0, 1.0]; 8];
        let exr = crate::exr::encode_exr(&e, Path::new("e.exr")).unwrap();
        let im = decode_env_image(&exr, Path::new("sky.hdr"), 1 << 20).unwrap();
        assert_eq!(im.rgba, e.rgba);
    }

    #[test]
    fn claimed_sizes_beyond_the_limit_are_refused_before_decoding() {
        // A header claiming 30000 x 30000 texels followed by nothing: 25 GB decoded.
        let bomb = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 30000 +X 30000\n".to_vec();
        let e = decode_env_image(&bomb, Path::new("bomb.hdr"), 1 << 30).unwrap_err();
        assert!(matches!(e, Error::TooLarge { width: 30000, .. }), "{e}");
        assert!(e.to_string().contains("bomb.hdr"), "{e}");
        let hdr = hdr_bytes(64, 32, [1.0; 3]);
        assert!(matches!(
            decode_env_image(&hdr, Path::new("s.hdr"), 1000),
            Err(Error::TooLarge { .. })
        ));
    }

    #[test]
    fn damaged_files_are_errors() {
        let hdr = hdr_bytes(16, 8, [1.0; 3]);
        for cut in [0, 3, 20, hdr.len() / 2, hdr.len() - 1] {
            let r = decode_env_image(&hdr[..cut], Path::new("cut.hdr"), 1 << 20);
            assert!(r.is_err(), "cut at {cut}");
        }
        assert!(matches!(
            decode_env_image(b"P6 1 1 255 abc", Path::new("x.hdr"), 1 << 20),
            Err(Error::Decode { .. })
        ));
    }
}
