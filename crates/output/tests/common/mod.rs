//! What the output tests share: a hand-built scene rendered and written as EXR through the one
//! entry point, `aperture_output::write::write_image`.

use aperture_denoise::Denoiser;
use aperture_output::write::{write_image, ImageFormat, ImageOutput};
use aperture_output::{ExrOptions, OutputError, RenderSummary};
use aperture_render::{Frame, RenderOptions};
use aperture_scene::Scene;
use std::path::Path;

/// `scene` (its BVH built with the default preset) rendered with `opts` and written to `path`
/// as EXR, denoised by `denoiser` when given.
#[allow(dead_code)]
pub fn write_exr(
    scene: &Scene,
    opts: &RenderOptions,
    path: &Path,
    exr: &ExrOptions,
    denoiser: Option<&Denoiser>,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<RenderSummary, OutputError> {
    let frame = Frame::still(scene.clone(), Default::default());
    let out = ImageOutput {
        path,
        format: ImageFormat::Exr(*exr),
        denoiser,
    };
    write_image(&frame, opts, &out, progress)
}
