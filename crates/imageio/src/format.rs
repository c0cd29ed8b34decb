//! Writing an image in the format its path names.

use std::path::Path;

use crate::error::Error;
use crate::exr::write_exr;
use crate::model::Image;
use crate::options::PngOptions;
use crate::png::write_png;

/// The formats [`write_image`] chooses between.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Format {
    /// OpenEXR, scene-referred float.
    Exr,
    /// PNG, display-referred.
    Png,
}

impl Format {
    /// The format named by the path's extension (case-insensitive `.exr` or `.png`).
    pub fn from_path(path: &Path) -> Result<Self, Error> {
        let ext = path
            .extension()
            .and_then(|ext| ext.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("exr") => Ok(Format::Exr),
            Some("png") => Ok(Format::Png),
            _ => Err(Error::UnknownFormat {
                path: path.to_path_buf(),
            }),
        }
    }
}

/// Writes `image` to `path`, choosing EXR or PNG by the extension. The file is written whole or
/// not at all (a temporary file beside it, then a rename).
///
/// `png` is used only for PNG; EXR stores scene-referred values unchanged.
pub fn write_image(path: &Path, image: &Image, png: &PngOptions) -> Result<(), Error> {
    match Format::from_path(path)? {
        Format::Exr => write_exr(path, image),
        Format::Png => write_png(path, image, png),
    }
}
