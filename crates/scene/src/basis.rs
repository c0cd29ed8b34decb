//! `KHR_texture_basisu`: KTX2 textures supercompressed with Basis Universal (ETC1S or UASTC),
//! transcoded to RGBA8 texels.
//!
//! The texels are what the reference transcoder gives for its uncompressed RGBA target: the
//! image as the encoder kept it (lossy against the original), top row first as glTF requires
//! of KTX2 images. The file's size is read from its header before anything is transcoded, so
//! the texture budget sees it like any other image's.

use crate::error::Error;

/// The 12 bytes every KTX2 file starts with.
const KTX2_IDENTIFIER: [u8; 12] = [
    0xAB, 0x4B, 0x54, 0x58, 0x20, 0x32, 0x30, 0xBB, 0x0D, 0x0A, 0x1A, 0x0A,
];

/// True when `bytes` are a KTX2 file (by content, as the other images are recognised).
pub(crate) fn is_ktx2(bytes: &[u8]) -> bool {
    bytes.starts_with(&KTX2_IDENTIFIER)
}

fn invalid(image: usize, reason: String) -> Error {
    Error::Invalid {
        at: format!("images[{image}]"),
        reason,
    }
}

fn transcoder(bytes: &[u8], image: usize) -> Result<basisu::Transcoder<'_>, Error> {
    basisu::Transcoder::new(bytes)
        .map_err(|e| invalid(image, format!("not a Basis Universal KTX2 texture ({e:?})")))
}

/// `f`, with a panic of the third-party transcoder on damaged data turned into an error naming
/// the image (the caller may run outside the texture decoders' own guard).
fn guarded<T>(image: usize, f: impl FnOnce() -> Result<T, Error>) -> Result<T, Error> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)).unwrap_or_else(|_| {
        Err(invalid(
            image,
            "the KTX2 transcoder panicked on damaged data".into(),
        ))
    })
}

/// The size of the KTX2 file's first (largest) level, after checking what its levels claim
/// ([`check_level_index`]): the header stage, before any texture is transcoded.
pub(crate) fn dimensions(bytes: &[u8], image: usize) -> Result<(u32, u32), Error> {
    check_level_index(bytes, image)?;
    guarded(image, || level_size(&transcoder(bytes, image)?, image))
}

fn level_size(t: &basisu::Transcoder<'_>, image: usize) -> Result<(u32, u32), Error> {
    let level = t
        .image_level_info(0)
        .map_err(|e| invalid(image, format!("KTX2 level 0: {e:?}")))?;
    Ok((level.width, level.height))
}

/// Refuses a level index whose levels claim more uncompressed bytes than a Basis level of their
/// size can hold: 16 bytes per 4×4 block (UASTC; ETC1S takes less). The transcoder allocates
/// what a zstd-supercompressed level claims before inflating it, so a damaged length would be
/// an allocation of terabytes (fuzz target `texture`).
fn check_level_index(bytes: &[u8], image: usize) -> Result<(), Error> {
    let u32_at = |o: usize| {
        bytes
            .get(o..o + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    let u64_at = |o: usize| {
        bytes
            .get(o..o + 8)
            .map(|b| u64::from_le_bytes(b.try_into().unwrap_or_default()))
    };
    let truncated = || invalid(image, "KTX2 header truncated".into());
    let (width, height) = (
        u32_at(20).ok_or_else(truncated)?,
        u32_at(24).ok_or_else(truncated)?,
    );
    let levels = u32_at(40).ok_or_else(truncated)?.max(1);
    for level in 0..levels.min(32) {
        let entry = 80 + 24 * level as usize;
        let claimed = u64_at(entry + 16).ok_or_else(truncated)?;
        // u128: a 2^32-1 square level holds 2^64 bytes, one more than a u64 counts.
        let blocks = |side: u32| u128::from((side >> level).max(1).div_ceil(4));
        let most = 16 * blocks(width) * blocks(height.max(1));
        if u128::from(claimed) > most {
            return Err(invalid(
                image,
                format!(
                    "KTX2 level {level} claims {claimed} uncompressed bytes; a {}x{} Basis level \
                     holds at most {most}",
                    (width >> level).max(1),
                    (height >> level).max(1)
                ),
            ));
        }
    }
    Ok(())
}

/// Transcodes level 0 to RGBA8 texels, rows top to bottom, for a file [`dimensions`] accepted.
/// HDR Basis formats are not glTF textures (the extension allows ETC1S and UASTC LDR) and are
/// refused.
pub(crate) fn decode(bytes: &[u8], image: usize) -> Result<(u32, u32, Vec<[u8; 4]>), Error> {
    guarded(image, || transcode(bytes, image))
}

fn transcode(bytes: &[u8], image: usize) -> Result<(u32, u32, Vec<[u8; 4]>), Error> {
    let t = transcoder(bytes, image)?;
    if t.is_video() || t.layer_count() > 1 || t.face_count() > 1 {
        return Err(invalid(
            image,
            "a KTX2 array, cube map or video is not a glTF texture".into(),
        ));
    }
    let (width, height) = level_size(&t, image)?;
    let rgba = t
        .transcode(0, basisu::TargetFormat::Rgba32, basisu::DecodeFlags::NONE)
        .map_err(|e| {
            invalid(
                image,
                format!("KTX2 ({:?}) to RGBA: {e:?}", t.source_format()),
            )
        })?;
    let texels = u128::from(width) * u128::from(height);
    if rgba.len() as u128 != 4 * texels {
        return Err(invalid(
            image,
            format!(
                "transcoded {} bytes for a {width}x{height} image",
                rgba.len()
            ),
        ));
    }
    let texels = rgba
        .chunks_exact(4)
        .map(|c| [c[0], c[1], c[2], c[3]])
        .collect();
    Ok((width, height, texels))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn other_bytes_are_not_ktx2_and_damaged_ktx2_is_an_error_naming_the_image() {
        assert!(!is_ktx2(b"\x89PNG\r\n\x1a\n"));
        let mut bytes = KTX2_IDENTIFIER.to_vec();
        bytes.extend_from_slice(&[0u8; 40]);
        assert!(is_ktx2(&bytes));
        let e = decode(&bytes, 7).unwrap_err().to_string();
        assert!(e.contains("images[7]"), "{e}");
        let e = dimensions(&KTX2_IDENTIFIER, 3).unwrap_err().to_string();
        assert!(e.contains("images[3]"), "{e}");
    }
}
