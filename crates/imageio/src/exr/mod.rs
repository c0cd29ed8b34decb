//! OpenEXR output and input.
//!
//! Written files are one scan-line part, ZIP-compressed (lossless; 16 rows per block): beauty
//! in the unnamed layer's `R`,`G`,`B`,`A` so every viewer shows it, each [`crate::Layer`] as
//! `name.channel` channels beside it, metadata as header attributes. One part, rather than a
//! part per pass, is what compositors (Nuke, Blender) read most readily. Samples are float32,
//! or half where a layout asks for it.
//!
//! ZIP rather than PIZ: both are lossless; on a noisy 512x512 float render with five channels
//! ZIP16 gave 3.1 MB, wrote in 0.56 s and read in 0.06 s (one thread), PIZ 3.6 MB, 0.94 s and
//! 0.20 s. ZIP is also what Blender writes by default. Blocks are compressed in parallel.

mod attrs;
mod guard;
mod read;
mod write;

pub use read::{decode_exr, decode_exr_within, read_exr, read_exr_header, ExrHeader};
pub use write::{
    encode_exr, write_exr, write_exr_streamed, ChannelSpec, ExrLayout, LateValues, RowWriter,
};

#[cfg(test)]
mod tests;
