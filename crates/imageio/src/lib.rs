//! Writing and reading images: EXR (scene-referred float, with passes and metadata) and PNG
//! (display-referred, after exposure and a view transform), plus image-error metrics.
//!
//! ```
//! use aperture_imageio::{read_exr, write_image, Image, Layer, MetaValue, PngOptions};
//! let mut image = Image::new(2, 2);
//! image.rgba[0] = [1.0, 0.5, 0.25, 1.0];
//! image.layers.push(Layer::new("depth", &["Z"], vec![1.5; 4]));
//! image.metadata.push(("aperture:radius".into(), MetaValue::Float(0.05)));
//!
//! let dir = std::env::temp_dir();
//! let exr = dir.join(format!("aperture-doc-{}.exr", std::process::id()));
//! write_image(&exr, &image, &PngOptions::default())?;
//! assert_eq!(read_exr(&exr)?, image);
//!
//! let png = exr.with_extension("png");
//! write_image(&png, &image, &PngOptions { exposure: 1.0, ..Default::default() })?;
//! # std::fs::remove_file(exr).unwrap();
//! # std::fs::remove_file(png).unwrap();
//! # Ok::<(), aperture_imageio::Error>(())
//! ```
//!
//! Every writer is atomic: the file appears whole, under its final name, or not at all.

mod atomic;
mod env;
mod error;
mod exr;
mod format;
pub mod metrics;
mod model;
mod options;
mod png;
pub mod view;

pub use crate::env::{decode_env_image, read_env_image, EnvFormat};
pub use crate::error::{Error, NameKind};
pub use crate::exr::{
    decode_exr, decode_exr_within, encode_exr, read_exr, read_exr_header, write_exr,
    write_exr_streamed, ChannelSpec, ExrHeader, ExrLayout, LateValues, RowWriter,
};
pub use crate::format::{write_image, Format};
pub use crate::model::{Image, Layer, MetaValue, Placement, SampleType};
pub use crate::options::{PngOptions, ViewTransform};
pub use crate::png::{encode_png, write_png};

#[cfg(test)]
mod tests;
