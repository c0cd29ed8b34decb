//! How scene-referred values become a PNG: exposure and the view transform.

/// The display transform applied before quantising to PNG (`--view`; the first paragraph of
/// each value's comment is its help there).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum ViewTransform {
    /// Clip to [0, 1], then the sRGB transfer function.
    #[default]
    Standard,
    /// Blender's AgX base view (SPEC §6).
    ///
    /// No look, approximated; see [`crate::view::agx`].
    #[cfg_attr(feature = "clap", value(name = "agx"))]
    AgX,
}

/// How to turn scene-referred values into a PNG.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PngOptions {
    /// Exposure in stops: values are multiplied by `2^exposure` first.
    pub exposure: f32,
    /// View transform.
    pub view: ViewTransform,
    /// Write 16 bits per channel instead of 8.
    pub sixteen_bit: bool,
}

impl Default for PngOptions {
    fn default() -> Self {
        Self {
            exposure: 0.0,
            view: ViewTransform::Standard,
            sixteen_bit: false,
        }
    }
}
