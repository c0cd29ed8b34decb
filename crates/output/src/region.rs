//! The part of the image a file holds: the whole image or a window of it (a tile, a region).

use aperture_imageio::Placement;
use aperture_render::film::Window;
use aperture_render::RenderOptions;

/// True when a file of `window` rendered with `opts` must say how many samples each pixel
/// took (SPEC §6): adaptive, a region of the image, or a batch of samples past the first.
pub(crate) fn needs_sample_count(opts: &RenderOptions, window: Window) -> bool {
    opts.adaptive.is_some() || !is_whole(window, opts) || opts.sample_offset > 0
}

/// True when `window` is the whole image of `opts`.
pub(crate) fn is_whole(window: Window, opts: &RenderOptions) -> bool {
    (window.x0, window.y0, window.width, window.height) == (0, 0, opts.width, opts.height)
}

/// Where `window` sits in the whole image of `opts`, `None` when it is the whole image.
pub(crate) fn placement(window: Window, opts: &RenderOptions) -> Option<Placement> {
    (!is_whole(window, opts)).then_some(Placement {
        x: window.x0,
        y: window.y0,
        full_width: opts.width,
        full_height: opts.height,
    })
}
