//! Texture images decoded to texels within a memory budget.
//!
//! Every image's header is read first (its size and pixel format, a few bytes), the decoded
//! sizes of all textures are summed (an image used by several textures, with other samplers or
//! colour spaces, counts once per use) and compared with the budget; only then is anything
//! decoded, in parallel. Each decoder is also limited to what its own header claims, so a PNG
//! whose header lies cannot allocate past it (the image crate's `Limits`).

use std::io::Cursor;
use std::path::Path;

use image::ImageDecoder as _;
use rayon::prelude::*;

use crate::accessor::Buffers;
use crate::error::Error;
use crate::types::Texels;

/// What an image's header says: its size and the bytes a texel takes decoded by the image
/// crate and as stored in a [`Texels`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Header {
    width: u32,
    height: u32,
    /// Bytes per texel as the decoder produces it.
    native: u64,
    /// Bytes per texel as stored: 4 (RGBA8) or 16 (RGBA f32).
    stored: u64,
}

impl Header {
    fn texels(&self) -> u64 {
        u64::from(self.width) * u64::from(self.height)
    }

    /// The most bytes decoding takes at once: the decoder's buffer, its conversion to RGBA
    /// and the texel array built from that.
    fn peak(&self) -> u64 {
        self.texels() * (self.native + 2 * self.stored)
    }
}

fn image_error(image: usize) -> impl Fn(image::ImageError) -> Error {
    move |source| Error::Image { image, source }
}

fn decoder(bytes: &[u8], image: usize) -> Result<impl image::ImageDecoder + '_, Error> {
    image::ImageReader::new(Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| image_error(image)(image::ImageError::IoError(e)))?
        .into_decoder()
        .map_err(image_error(image))
}

/// Most decoded bytes a PNG or JPEG can hold per byte of file. Deflate (PNG) cannot
/// compress beyond 1032:1, and a baseline JPEG spends at least about two bits on every 8×8
/// block of every component (a DC code and an end of block), about 1:512 for RGB; a header
/// claiming more is a decompression bomb (or a truncated file the decoder would pad with
/// grey). WebP is not bounded so (a constant image codes to almost nothing).
const MAX_RATIO: u64 = 1100;

fn header(bytes: &[u8], image: usize) -> Result<Header, Error> {
    let h = if crate::basis::is_ktx2(bytes) {
        let (width, height) = crate::basis::dimensions(bytes, image)?;
        // The transcoder's RGBA8 output, then the texels built from it.
        Header {
            width,
            height,
            native: 4,
            stored: 4,
        }
    } else {
        decoder_header(bytes, image)?
    };
    if h.width == 0 || h.height == 0 {
        return Err(Error::Invalid {
            at: format!("images[{image}]"),
            reason: "image has no texels".into(),
        });
    }
    // Every size below is a product of the header's, up to `peak`: it must fit a u64.
    let peak = u128::from(h.texels()) * u128::from(h.native + 2 * h.stored);
    if u64::try_from(peak).is_err() {
        return Err(Error::Invalid {
            at: format!("images[{image}]"),
            reason: format!(
                "a {}x{} image needs {peak} bytes to decode, more than 64 bits count",
                h.width, h.height
            ),
        });
    }
    Ok(h)
}

/// [`header`] of a PNG, JPEG or WebP file, from its decoder, refusing decompression bombs.
fn decoder_header(bytes: &[u8], image: usize) -> Result<Header, Error> {
    let format = image::ImageReader::new(Cursor::new(bytes))
        .with_guessed_format()
        .ok()
        .and_then(|r| r.format());
    let d = decoder(bytes, image)?;
    let (width, height) = d.dimensions();
    let claimed =
        u128::from(width) * u128::from(height) * u128::from(d.color_type().bytes_per_pixel());
    let bounded = matches!(
        format,
        Some(image::ImageFormat::Png | image::ImageFormat::Jpeg)
    );
    if bounded && claimed > u128::from(MAX_RATIO) * bytes.len() as u128 + (1 << 20) {
        return Err(Error::Invalid {
            at: format!("images[{image}]"),
            reason: format!(
                "a {}-byte file cannot hold a {width}x{height} image ({claimed} bytes decoded): \
                 a decompression bomb or a truncated file",
                bytes.len()
            ),
        });
    }
    let ct = d.color_type();
    Ok(Header {
        width,
        height,
        native: u64::from(ct.bytes_per_pixel()),
        stored: if wide(ct) { 16 } else { 4 },
    })
}

/// 16-bit and float images are kept as f32; 8-bit ones as 8-bit.
fn wide(ct: image::ColorType) -> bool {
    use image::ColorType as C;
    matches!(
        ct,
        C::L16 | C::La16 | C::Rgb16 | C::Rgba16 | C::Rgb32F | C::Rgba32F
    )
}

/// Decodes one image's bytes to RGBA texels (8-bit stays 8-bit; 16-bit and float become f32),
/// refusing an image whose decoding would take more than `max_bytes`. `image` (its index in
/// the glTF file) only names it in errors. PNG, JPEG, WebP and KTX2 (Basis Universal) are read.
pub fn decode_texture(
    bytes: &[u8],
    image: usize,
    max_bytes: u64,
) -> Result<(u32, u32, Texels), Error> {
    let h = header(bytes, image)?;
    aperture_budget::MemoryBudget::fixed(max_bytes)
        .check(&format!("a {}x{} texture", h.width, h.height), h.peak())
        .map_err(|source| Error::OverBudget {
            at: format!("images[{image}]"),
            source,
        })?;
    decode_checked(bytes, image, h)
}

/// [`decode_unguarded`], with a decoder's panic on damaged data turned into an error: the
/// image crate's decoders are third-party code (zune-jpeg overflows on some damaged JPEGs in
/// builds with overflow checks), and one bad texture must not bring down the process.
fn decode_checked(bytes: &[u8], image: usize, h: Header) -> Result<(u32, u32, Texels), Error> {
    std::panic::catch_unwind(|| decode_unguarded(bytes, image, h)).unwrap_or_else(|panic| {
        let message = crate::error::panic_message(&*panic);
        Err(Error::Invalid {
            at: format!("images[{image}]"),
            reason: format!("the image decoder panicked on damaged data: {message}"),
        })
    })
}

/// Images whose texels [`decode_unguarded`] has begun to decode in this process ([`decodes`]).
static DECODES: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

/// How many images have had their texels decoded in this process so far (headers, which give
/// sizes, are not counted): what shows that a load skipping textures (`aperture info`), or a
/// texture no material reads, decoded nothing.
pub fn decodes() -> usize {
    DECODES.load(std::sync::atomic::Ordering::Relaxed)
}

fn decode_unguarded(bytes: &[u8], image: usize, h: Header) -> Result<(u32, u32, Texels), Error> {
    DECODES.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    if crate::basis::is_ktx2(bytes) {
        let (width, height, texels) = crate::basis::decode(bytes, image)?;
        return Ok((width, height, Texels::Rgba8(texels)));
    }
    let mut d = decoder(bytes, image)?;
    // The decoder may allocate what its header claims (and a little for its own state), not
    // more: a header that lies cannot grow it.
    let mut limits = image::Limits::default();
    limits.max_alloc = Some(h.texels() * h.native + (1 << 20));
    d.set_limits(limits).map_err(image_error(image))?;
    let img = image::DynamicImage::from_decoder(d).map_err(image_error(image))?;
    if (img.width(), img.height()) != (h.width, h.height) {
        return Err(Error::Invalid {
            at: format!("images[{image}]"),
            reason: format!(
                "decoded {}x{}, but its header says {}x{}",
                img.width(),
                img.height(),
                h.width,
                h.height
            ),
        });
    }
    let texels = if h.stored == 16 {
        Texels::Rgba32F(
            img.into_rgba32f()
                .into_raw()
                .chunks_exact(4)
                .map(|c| [c[0], c[1], c[2], c[3]])
                .collect(),
        )
    } else {
        Texels::Rgba8(
            img.into_rgba8()
                .into_raw()
                .chunks_exact(4)
                .map(|c| [c[0], c[1], c[2], c[3]])
                .collect(),
        )
    };
    Ok((h.width, h.height, texels))
}

/// The bytes of image `index`: its file, data URI or buffer view.
pub(crate) fn image_bytes<'a>(
    doc: &gltf::Document,
    buffers: &'a Buffers<'a>,
    base_dir: &Path,
    index: usize,
) -> Result<std::borrow::Cow<'a, [u8]>, Error> {
    let at = format!("images[{index}]");
    let image = doc.images().nth(index).ok_or_else(|| Error::Invalid {
        at: at.clone(),
        reason: "no such image".into(),
    })?;
    Ok(match image.source() {
        gltf::image::Source::Uri { uri, .. } => {
            std::borrow::Cow::Owned(crate::uri::load(base_dir, uri, &format!("{at}.uri"))?)
        }
        gltf::image::Source::View { view, .. } => {
            let buffer = buffers
                .data
                .get(view.buffer().index())
                .ok_or_else(|| Error::Invalid {
                    at: format!("bufferViews[{}]", view.index()),
                    reason: "buffer missing".into(),
                })?;
            let end = (view.offset() as u64).saturating_add(view.length() as u64);
            if end > buffer.len() as u64 {
                return Err(Error::OutOfBounds {
                    at: format!("{at}.bufferView (bufferViews[{}])", view.index()),
                    needed: end,
                    available: buffer.len() as u64,
                });
            }
            std::borrow::Cow::Borrowed(&buffer[view.offset()..view.offset() + view.length()])
        }
    })
}

/// Decodes `images` (glTF image indices, each used by `uses[k]` textures), once each, in
/// parallel, after checking that all their texels together fit `budget`.
pub(crate) fn decode_images(
    doc: &gltf::Document,
    buffers: &Buffers,
    base_dir: &Path,
    images: &[usize],
    uses: &[usize],
    budget: &aperture_budget::MemoryBudget,
) -> Result<Vec<(u32, u32, Texels)>, Error> {
    // Each file is read once; compressed bytes are small next to texels.
    let bytes: Vec<std::borrow::Cow<'_, [u8]>> = images
        .par_iter()
        .map(|&i| image_bytes(doc, buffers, base_dir, i))
        .collect::<Result<_, _>>()?;
    let headers: Vec<Header> = images
        .par_iter()
        .zip(&bytes)
        .map(|(&i, b)| header(b, i))
        .collect::<Result<_, _>>()?;
    // Kept: every use's texels. Transient: every decoder's buffers at once (the worst case of
    // parallel decoding).
    // u128: each image's sizes fit a u64 ([`header`]), their sum over many uses may not.
    let kept: u128 = headers
        .iter()
        .zip(uses)
        .map(|(h, &n)| u128::from(h.texels() * h.stored) * n as u128)
        .sum();
    let transient: u128 = headers
        .iter()
        .map(|h| u128::from(h.texels() * h.native))
        .sum();
    let largest = headers
        .iter()
        .zip(images)
        .max_by_key(|(h, _)| h.texels() * h.stored)
        .map(|(h, i)| format!(" (the largest, images[{i}], is {}x{})", h.width, h.height))
        .unwrap_or_default();
    budget
        .check(
            &format!(
                "decoding {} texture image(s) used {} time(s){largest}",
                images.len(),
                uses.iter().sum::<usize>()
            ),
            u64::try_from(kept + transient).unwrap_or(u64::MAX),
        )
        .map_err(|source| Error::OverBudget {
            at: "textures".into(),
            source,
        })?;
    images
        .par_iter()
        .zip(&headers)
        .zip(&bytes)
        .map(|((&i, &h), b)| decode_checked(b, i, h))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn png(w: u32, h: u32) -> Vec<u8> {
        let mut out = Vec::new();
        image::DynamicImage::ImageRgba8(image::RgbaImage::new(w, h))
            .write_to(&mut Cursor::new(&mut out), image::ImageFormat::Png)
            .unwrap();
        out
    }

    #[test]
    fn textures_decode_within_their_budget() {
        let (w, h, t) = decode_texture(&png(3, 2), 0, 1 << 20).unwrap();
        assert_eq!((w, h), (3, 2));
        assert_eq!(t, Texels::Rgba8(vec![[0; 4]; 6]));
        let e = decode_texture(&png(64, 64), 7, 1000).unwrap_err();
        assert!(matches!(e, Error::OverBudget { .. }), "{e}");
        assert!(e.to_string().contains("images[7]"), "{e}");
        assert!(e.to_string().contains("64x64"), "{e}");
    }

    #[test]
    fn a_header_claiming_a_huge_image_is_refused_before_decoding() {
        // A PNG whose IHDR claims 60000 x 60000 (14.4 GB as RGBA8), with the right CRC.
        let mut p = png(1, 1);
        p[16..20].copy_from_slice(&60000u32.to_be_bytes());
        p[20..24].copy_from_slice(&60000u32.to_be_bytes());
        let crc = crc32(&p[12..29]);
        p[29..33].copy_from_slice(&crc.to_be_bytes());
        // 14.4 GB from 69 bytes: more than deflate can expand them.
        let e = decode_texture(&p, 0, u64::MAX).unwrap_err();
        assert!(e.to_string().contains("decompression bomb"), "{e}");
        // A PNG whose size fits its bytes but not the budget: refused by the budget.
        let big = png(600, 600);
        let e = decode_texture(&big, 0, 1 << 20).unwrap_err();
        assert!(matches!(e, Error::OverBudget { .. }), "{e}");
    }

    fn crc32(bytes: &[u8]) -> u32 {
        let mut c = 0xFFFF_FFFFu32;
        for &b in bytes {
            c ^= u32::from(b);
            for _ in 0..8 {
                c = if c & 1 != 0 {
                    0xEDB8_8320 ^ (c >> 1)
                } else {
                    c >> 1
                };
            }
        }
        !c
    }
}
