//! PNG output: exposure, then a view transform, then quantisation.
//!
//! Alpha: PNG stores straight (unassociated) alpha, while [`Image`] RGB is premultiplied by
//! coverage, so RGB is divided by A before the view transform (where A > 0) and A is written
//! as coverage, linearly quantised. Fully opaque images are unaffected.
//!
//! Quantisation rounds to nearest; NaN becomes 0 and infinities are clipped before anything
//! else, so they never reach the file. The output depends only on the image and options.

use std::path::Path;

use image::codecs::png::{CompressionType, FilterType, PngEncoder};
use image::{ExtendedColorType, ImageEncoder};

use crate::atomic::write_atomically;
use crate::error::Error;
use crate::model::Image;
use crate::options::PngOptions;
use crate::view::{self, sanitize};

/// One pixel to display values in [0, 1]: RGB display-encoded, A linear coverage.
/// `scale` is `2^exposure`.
fn display_pixel(px: [f32; 4], scale: f64, options: &PngOptions) -> [f64; 4] {
    let alpha = sanitize(px[3]).clamp(0.0, 1.0);
    let mut rgb = [0f32; 3];
    for (out, &c) in rgb.iter_mut().zip(&px[..3]) {
        let mut v = sanitize(c) * scale;
        if alpha > 0.0 {
            v /= alpha;
        }
        // Back to f32 for the view; beyond f32's range the view clips anyway.
        *out = v.clamp(f64::from(f32::MIN), f64::from(f32::MAX)) as f32;
    }
    let [r, g, b] = view::apply(options.view, rgb).map(|c| sanitize(c).clamp(0.0, 1.0));
    [r, g, b, alpha]
}

/// Nearest quantisation of a value in [0, 1] to `0..=max`.
fn quantise(v: f64, max: f64) -> f64 {
    (v * max + 0.5).floor().clamp(0.0, max)
}

/// Encodes `image` as PNG into memory, as [`write_png`] describes. `path` only names the file
/// in errors.
pub fn encode_png(image: &Image, options: &PngOptions, path: &Path) -> Result<Vec<u8>, Error> {
    image.validate_beauty()?;
    if !options.exposure.is_finite() {
        return Err(Error::InvalidOption {
            option: "exposure",
            value: options.exposure.to_string(),
            reason: "must be finite",
        });
    }
    let scale = f64::from(options.exposure).exp2();

    let (raw, color) = if options.sixteen_bit {
        let mut raw = Vec::with_capacity(image.rgba.len() * 8);
        for &px in &image.rgba {
            for v in display_pixel(px, scale, options) {
                // The encoder wants native-endian samples and swaps them itself.
                raw.extend_from_slice(&(quantise(v, 65535.0) as u16).to_ne_bytes());
            }
        }
        (raw, ExtendedColorType::Rgba16)
    } else {
        let mut raw = Vec::with_capacity(image.rgba.len() * 4);
        for &px in &image.rgba {
            for v in display_pixel(px, scale, options) {
                raw.push(quantise(v, 255.0) as u8);
            }
        }
        (raw, ExtendedColorType::Rgba8)
    };

    let mut bytes = Vec::new();
    PngEncoder::new_with_quality(&mut bytes, CompressionType::Default, FilterType::Adaptive)
        .write_image(&raw, image.width, image.height, color)
        .map_err(|e| Error::Png {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
    Ok(bytes)
}

/// Writes `image` to `path` as PNG, atomically: RGBA, 8 bits (16 with
/// [`PngOptions::sixteen_bit`]), sRGB-encoded. Layers and metadata are not written.
///
/// Per pixel: NaN becomes 0 and infinities are clipped; RGB is multiplied by `2^exposure`;
/// PNG stores straight alpha while [`Image`] RGB is premultiplied, so RGB is divided by A
/// where A > 0; then the view transform; then rounding to nearest. A is written as coverage,
/// clipped to [0, 1] and quantised linearly. The bytes depend only on the image and options.
pub fn write_png(path: &Path, image: &Image, options: &PngOptions) -> Result<(), Error> {
    let bytes = encode_png(image, options, path)?;
    write_atomically(path, &bytes)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::atomic::tests::{entries, scratch_dir};
    use crate::options::ViewTransform;
    use crate::view::srgb_oetf;

    fn decode8(bytes: &[u8]) -> image::RgbaImage {
        image::load_from_memory(bytes).unwrap().to_rgba8()
    }

    fn decode16(bytes: &[u8]) -> image::ImageBuffer<image::Rgba<u16>, Vec<u16>> {
        let decoded = image::load_from_memory(bytes).unwrap();
        assert_eq!(decoded.color(), image::ColorType::Rgba16);
        decoded.to_rgba16()
    }

    fn gradient(w: u32, h: u32) -> Image {
        let mut image = Image::new(w, h);
        for (p, px) in image.rgba.iter_mut().enumerate() {
            let v = p as f32 / (w * h - 1) as f32;
            *px = [v, v * v, 1.0 - v, 1.0];
        }
        image
    }

    #[test]
    fn round_trip_within_quantisation() {
        let image = gradient(16, 4);
        for sixteen_bit in [false, true] {
            let options = PngOptions {
                sixteen_bit,
                ..Default::default()
            };
            let bytes = encode_png(&image, &options, "t".as_ref()).unwrap();
            let (max, values): (f32, Vec<f32>) = if sixteen_bit {
                let d = decode16(&bytes);
                (
                    65535.0,
                    d.pixels().flat_map(|p| p.0).map(f32::from).collect(),
                )
            } else {
                let d = decode8(&bytes);
                (255.0, d.pixels().flat_map(|p| p.0).map(f32::from).collect())
            };
            assert_eq!(values.len(), 16 * 4 * 4);
            for (i, px) in image.rgba.iter().enumerate() {
                for c in 0..4 {
                    let expected = if c == 3 { px[3] } else { srgb_oetf(px[c]) };
                    let got = values[i * 4 + c] / max;
                    // Nearest rounding: at most half a step away.
                    assert!(
                        (got - expected).abs() <= 0.5 / max + 1e-6,
                        "pixel {i} channel {c}: {got} vs {expected}"
                    );
                }
            }
        }
    }

    #[test]
    fn known_8bit_values() {
        let mut image = Image::new(4, 1);
        image.rgba = vec![
            [0.0, 1.0, 0.18, 1.0],
            [2.0, -1.0, f32::NAN, 1.0],
            [f32::INFINITY, f32::NEG_INFINITY, 0.5, 1.0],
            [0.0, 0.0, 0.0, 0.0],
        ];
        let png = decode8(&encode_png(&image, &Default::default(), "t".as_ref()).unwrap());
        assert_eq!(png.get_pixel(0, 0).0, [0, 255, 118, 255]);
        assert_eq!(png.get_pixel(1, 0).0, [255, 0, 0, 255]);
        assert_eq!(png.get_pixel(2, 0).0, [255, 0, 188, 255]);
        assert_eq!(png.get_pixel(3, 0).0, [0, 0, 0, 0]);
    }

    #[test]
    fn exposure_doubles_linear_values() {
        // 0.09 at +1 stop must look exactly like 0.18 at 0 stops.
        let mut dim = Image::new(1, 1);
        dim.rgba[0] = [0.09, 0.045, 0.2, 1.0];
        let mut bright = dim.clone();
        bright.rgba[0] = [0.18, 0.09, 0.4, 1.0];
        let plus_one = PngOptions {
            exposure: 1.0,
            ..Default::default()
        };
        let a = encode_png(&dim, &plus_one, "t".as_ref()).unwrap();
        let b = encode_png(&bright, &Default::default(), "t".as_ref()).unwrap();
        assert_eq!(decode8(&a).get_pixel(0, 0).0, decode8(&b).get_pixel(0, 0).0);
        assert_eq!(decode8(&a).get_pixel(0, 0).0[0], 118);
        // And -1 stop halves.
        let minus_one = PngOptions {
            exposure: -1.0,
            ..Default::default()
        };
        let c = encode_png(&bright, &minus_one, "t".as_ref()).unwrap();
        let d = encode_png(&dim, &Default::default(), "t".as_ref()).unwrap();
        assert_eq!(decode8(&c).get_pixel(0, 0).0, decode8(&d).get_pixel(0, 0).0);
    }

    #[test]
    fn straight_alpha_undoes_premultiplication() {
        // Half coverage of a 0.18 grey is stored premultiplied as 0.09.
        let mut image = Image::new(1, 1);
        image.rgba[0] = [0.09, 0.09, 0.09, 0.5];
        let png = decode8(&encode_png(&image, &Default::default(), "t".as_ref()).unwrap());
        assert_eq!(png.get_pixel(0, 0).0, [118, 118, 118, 128]);
    }

    #[test]
    fn sixteen_bit_known_values() {
        let mut image = Image::new(2, 1);
        image.rgba = vec![[0.0, 1.0, 0.18, 1.0], [1.0, 1.0, 1.0, 0.25]];
        let options = PngOptions {
            sixteen_bit: true,
            ..Default::default()
        };
        let png = decode16(&encode_png(&image, &options, "t".as_ref()).unwrap());
        let mid = (f64::from(srgb_oetf(0.18)) * 65535.0 + 0.5).floor() as u16;
        assert_eq!(png.get_pixel(0, 0).0, [0, 65535, mid, 65535]);
        // Premultiplied 1.0 at A = 0.25 is 4.0 straight, which clips to white.
        assert_eq!(png.get_pixel(1, 0).0, [65535, 65535, 65535, 16384]);
    }

    #[test]
    fn agx_view_differs_from_standard_and_is_deterministic() {
        let image = gradient(8, 2);
        let agx = PngOptions {
            view: ViewTransform::AgX,
            ..Default::default()
        };
        let a = encode_png(&image, &agx, "t".as_ref()).unwrap();
        assert_eq!(a, encode_png(&image, &agx, "t".as_ref()).unwrap());
        assert_ne!(
            a,
            encode_png(&image, &Default::default(), "t".as_ref()).unwrap()
        );
    }

    #[test]
    fn non_finite_exposure_is_refused() {
        for exposure in [f32::NAN, f32::INFINITY] {
            let options = PngOptions {
                exposure,
                ..Default::default()
            };
            let err = encode_png(&Image::new(1, 1), &options, "t".as_ref()).unwrap_err();
            assert!(matches!(
                err,
                Error::InvalidOption {
                    option: "exposure",
                    ..
                }
            ));
        }
    }

    #[test]
    fn huge_exposure_stays_finite() {
        let mut image = Image::new(1, 1);
        image.rgba[0] = [1e-30, 0.0, -1.0, 1.0];
        let options = PngOptions {
            exposure: 200.0,
            ..Default::default()
        };
        let png = decode8(&encode_png(&image, &options, "t".as_ref()).unwrap());
        assert_eq!(png.get_pixel(0, 0).0, [255, 0, 0, 255]);
    }

    #[test]
    fn write_png_is_atomic_and_rows_run_top_down() {
        let dir = scratch_dir("png-file");
        let path = dir.join("a.png");
        let mut image = Image::new(1, 2);
        image.rgba = vec![[1.0, 1.0, 1.0, 1.0], [0.0, 0.0, 0.0, 1.0]];
        write_png(&path, &image, &Default::default()).unwrap();
        assert_eq!(entries(&dir), vec!["a.png".to_string()]);
        let png = image::open(&path).unwrap().to_rgba8();
        assert_eq!(png.get_pixel(0, 0).0, [255; 4]);
        assert_eq!(png.get_pixel(0, 1).0, [0, 0, 0, 255]);

        let err = write_png(
            &dir.join("missing").join("b.png"),
            &image,
            &Default::default(),
        )
        .unwrap_err();
        assert!(matches!(err, Error::Io { .. }), "{err}");
        assert_eq!(entries(&dir), vec!["a.png".to_string()]);
    }

    #[test]
    fn bad_buffer_is_an_error() {
        let mut image = Image::new(2, 2);
        image.rgba.pop();
        assert!(matches!(
            encode_png(&image, &Default::default(), "t".as_ref()),
            Err(Error::BufferSize { .. })
        ));
    }
}
