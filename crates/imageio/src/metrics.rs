//! Image-error metrics over the RGB of the beauty pass (alpha and layers are ignored).
//!
//! Sums run in f64 in pixel order, so results are deterministic. A NaN in either image makes
//! the result NaN, which no threshold passes: tests comparing images fail loudly.

use crate::error::Error;
use crate::model::Image;

/// The ε in [`relative_mse`]'s denominator, as in common practice (e.g. Rousselle et al.):
/// keeps near-black reference pixels from dominating.
pub const RELATIVE_MSE_EPSILON: f64 = 1e-2;

/// Rec.709 / sRGB luminance weights (Y of linear Rec.709 RGB).
pub const LUMINANCE_WEIGHTS: [f64; 3] = [0.2126, 0.7152, 0.0722];

/// Luminance Y of a linear Rec.709 colour.
pub fn luminance(rgb: [f32; 3]) -> f32 {
    luminance_f64(rgb) as f32
}

fn luminance_f64(rgb: [f32; 3]) -> f64 {
    LUMINANCE_WEIGHTS
        .iter()
        .zip(rgb)
        .map(|(w, c)| w * f64::from(c))
        .sum()
}

/// Luminance of every pixel of the beauty, row by row.
pub fn luminance_image(image: &Image) -> Vec<f32> {
    image
        .rgba
        .iter()
        .map(|px| luminance([px[0], px[1], px[2]]))
        .collect()
}

fn checked(image: &Image) -> Result<(), Error> {
    image.validate_beauty()
}

/// Both images are valid and of one size.
fn comparable(a: &Image, b: &Image) -> Result<(), Error> {
    checked(a)?;
    checked(b)?;
    if (a.width, a.height) != (b.width, b.height) {
        return Err(Error::SizeMismatch {
            left: (a.width, a.height),
            right: (b.width, b.height),
        });
    }
    Ok(())
}

/// Mean of `f(a, b)` over all pixels and the three colour channels.
fn mean_over(a: &Image, b: &Image, f: impl Fn(f64, f64) -> f64) -> Result<f64, Error> {
    comparable(a, b)?;
    let mut sum = 0.0;
    for (pa, pb) in a.rgba.iter().zip(&b.rgba) {
        for c in 0..3 {
            sum += f(f64::from(pa[c]), f64::from(pb[c]));
        }
    }
    Ok(sum / (3 * a.pixel_count()) as f64)
}

/// Root mean squared error: `sqrt(mean((a − b)²))` over pixels and RGB.
pub fn rmse(a: &Image, b: &Image) -> Result<f64, Error> {
    mse(a, b).map(f64::sqrt)
}

/// Mean squared error: `mean((a − b)²)` over pixels and RGB.
pub fn mse(a: &Image, b: &Image) -> Result<f64, Error> {
    mean_over(a, b, |x, y| (x - y) * (x - y))
}

/// Relative mean squared error against the reference `b`:
/// `mean((a − b)² / (b² + ε))` over pixels and RGB, ε = [`RELATIVE_MSE_EPSILON`].
pub fn relative_mse(a: &Image, reference: &Image) -> Result<f64, Error> {
    mean_over(a, reference, |x, y| {
        (x - y) * (x - y) / (y * y + RELATIVE_MSE_EPSILON)
    })
}

/// Mean absolute error: `mean(|a − b|)` over pixels and RGB.
pub fn mae(a: &Image, b: &Image) -> Result<f64, Error> {
    mean_over(a, b, |x, y| (x - y).abs())
}

/// LDR FLIP of `a` against the reference: the mean of NVIDIA's FLIP error map (0 = no visible
/// difference, 1 = the largest), computed on the 8-bit sRGB images of the `Standard` view
/// (clip to [0, 1], sRGB OETF), i.e. on what the PNG output shows, at FLIP's default 67 pixels
/// per degree (a 0.7 m viewing distance from a 24" 4K screen).
///
/// LDR because the bindings expose only LDR-FLIP; highlights above 1 count as clipped, so this
/// complements the HDR metrics above rather than replacing them.
pub fn flip(a: &Image, reference: &Image) -> Result<f64, Error> {
    comparable(a, reference)?;
    let has_nan = |im: &Image| im.rgba.iter().any(|p| p[..3].iter().any(|c| c.is_nan()));
    if has_nan(a) || has_nan(reference) {
        // The view maps NaN to black; keep the other metrics' rule that NaN fails loudly.
        return Ok(f64::NAN);
    }
    let ldr = |im: &Image| -> nv_flip::FlipImageRgb8 {
        let bytes: Vec<u8> = im
            .rgba
            .iter()
            .flat_map(|p| crate::view::standard([p[0], p[1], p[2]]))
            .map(|c| (c * 255.0 + 0.5) as u8)
            .collect();
        nv_flip::FlipImageRgb8::with_data(im.width, im.height, &bytes)
    };
    let map = nv_flip::flip(ldr(reference), ldr(a), nv_flip::DEFAULT_PIXELS_PER_DEGREE);
    Ok(f64::from(nv_flip::FlipPool::from_image(&map).mean()))
}

/// Mean of each colour channel over all pixels.
pub fn mean_rgb(image: &Image) -> Result<[f64; 3], Error> {
    checked(image)?;
    let mut sum = [0.0f64; 3];
    for px in &image.rgba {
        for (s, &c) in sum.iter_mut().zip(px) {
            *s += f64::from(c);
        }
    }
    let n = image.pixel_count() as f64;
    Ok(sum.map(|s| s / n))
}

/// Mean luminance over all pixels.
pub fn mean_luminance(image: &Image) -> Result<f64, Error> {
    let [r, g, b] = mean_rgb(image)?;
    // Luminance is linear, so the luminance of the mean is the mean of the luminances.
    Ok(LUMINANCE_WEIGHTS[0] * r + LUMINANCE_WEIGHTS[1] * g + LUMINANCE_WEIGHTS[2] * b)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(pixels: &[[f32; 3]], width: u32) -> Image {
        let mut im = Image::new(width, pixels.len() as u32 / width);
        im.rgba = pixels.iter().map(|&[r, g, b]| [r, g, b, 1.0]).collect();
        im
    }

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-12 * b.abs().max(1.0)
    }

    #[test]
    fn hand_computed_values() {
        // Differences per channel: (1, 0, 0) and (0, 2, -1); alpha differs and is ignored.
        let a = image(&[[1.0, 0.0, 0.5], [0.0, 3.0, 0.0]], 2);
        let mut b = image(&[[0.0, 0.0, 0.5], [0.0, 1.0, 1.0]], 2);
        b.rgba[0][3] = 0.0;
        // Squares: 1, 0, 0, 0, 4, 1 -> sum 6 over 6 values.
        assert!(close(mse(&a, &b).unwrap(), 1.0));
        assert!(close(rmse(&a, &b).unwrap(), 1.0));
        // Absolute: 1 + 2 + 1 = 4 over 6.
        assert!(close(mae(&a, &b).unwrap(), 4.0 / 6.0));
        // Relative, reference b: 1/(0+0.01) + 4/(1+0.01) + 1/(1+0.01), over 6.
        let expected = (100.0 + 4.0 / 1.01 + 1.0 / 1.01) / 6.0;
        assert!(close(relative_mse(&a, &b).unwrap(), expected));
        // Not symmetric: with a as the reference the denominators change.
        let swapped = (1.0 / 1.01 + 4.0 / 9.01 + 1.0 / 0.01) / 6.0;
        assert!(close(relative_mse(&b, &a).unwrap(), swapped));
    }

    #[test]
    fn rmse_of_uniform_offset() {
        let a = image(&[[0.25; 3]; 4], 2);
        let b = image(&[[0.75; 3]; 4], 2);
        assert!(close(rmse(&a, &b).unwrap(), 0.5));
        assert_eq!(rmse(&a, &a).unwrap(), 0.0);
    }

    #[test]
    fn means_and_luminance() {
        let im = image(&[[1.0, 2.0, 3.0], [3.0, 0.0, -1.0]], 1);
        assert_eq!(mean_rgb(&im).unwrap(), [2.0, 1.0, 1.0]);
        assert!(close(
            mean_luminance(&im).unwrap(),
            0.2126 * 2.0 + 0.7152 + 0.0722
        ));
        assert!((luminance([1.0, 1.0, 1.0]) - 1.0).abs() < 1e-6);
        assert!((luminance([0.0, 1.0, 0.0]) - 0.7152).abs() < 1e-7);
        let lum = luminance_image(&im);
        assert!((lum[0] - (0.2126 + 1.4304 + 0.2166)).abs() < 1e-6);
    }

    #[test]
    fn size_mismatch_and_bad_buffers_are_errors() {
        let a = image(&[[0.0; 3]; 4], 2);
        let b = image(&[[0.0; 3]; 4], 4);
        assert!(matches!(
            rmse(&a, &b),
            Err(Error::SizeMismatch {
                left: (2, 2),
                right: (4, 1)
            })
        ));
        assert!(relative_mse(&a, &b).is_err());
        assert!(mae(&b, &a).is_err());
        let mut short = a.clone();
        short.rgba.pop();
        assert!(matches!(rmse(&short, &a), Err(Error::BufferSize { .. })));
        assert!(mean_rgb(&short).is_err());
        assert!(matches!(
            mean_rgb(&Image::new(0, 0)),
            Err(Error::EmptyImage { .. })
        ));
    }

    #[test]
    fn nan_propagates() {
        let a = image(&[[f32::NAN, 0.0, 0.0]], 1);
        let b = image(&[[0.0; 3]], 1);
        assert!(rmse(&a, &b).unwrap().is_nan());
        assert!(flip(&a, &b).unwrap().is_nan());
        assert!(flip(&b, &a).unwrap().is_nan());
    }

    /// A grey ramp, and copies of it with growing per-pixel noise.
    fn ramp(noise: f32) -> Image {
        let (w, h) = (32u32, 24u32);
        let mut state = 12345u32;
        let pixels: Vec<[f32; 3]> = (0..w * h)
            .map(|i| {
                // xorshift: deterministic noise in [-1, 1).
                state ^= state << 13;
                state ^= state >> 17;
                state ^= state << 5;
                let n = (state as f32 / u32::MAX as f32) * 2.0 - 1.0;
                let v = 0.1 + 0.6 * (i % w) as f32 / w as f32;
                [v + noise * n, v, v - noise * n]
            })
            .collect();
        image(&pixels, w)
    }

    #[test]
    fn flip_is_zero_for_equal_images_and_grows_with_noise() {
        let reference = ramp(0.0);
        assert_eq!(flip(&reference, &reference).unwrap(), 0.0);
        let small = flip(&ramp(0.02), &reference).unwrap();
        let large = flip(&ramp(0.2), &reference).unwrap();
        assert!(
            small > 0.0 && small < large && large < 1.0,
            "{small} {large}"
        );
        // Black against white is the largest difference FLIP knows.
        let black = image(&[[0.0; 3]; 64], 8);
        let white = image(&[[1.0; 3]; 64], 8);
        assert!(flip(&black, &white).unwrap() > 0.5);
        assert!(matches!(
            flip(&black, &reference),
            Err(Error::SizeMismatch { .. })
        ));
    }
}
