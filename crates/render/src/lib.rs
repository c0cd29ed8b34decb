//! Camera, sampler, path tracer and film: turns a scene and its acceleration structure into
//! films, for the whole image, a window of it, or band by band into a sink.
//!
//! ```
//! use aperture_render::{Frame, RenderOptions};
//! use aperture_shading::test_scenes;
//! // A white diffuse quad under a point light, seen by a thin-lens camera.
//! let frame = Frame::still(test_scenes::lit_plane(1.0), Default::default());
//! let opts = RenderOptions { width: 8, height: 8, spp: 4, ..Default::default() };
//! let film = frame.render(&opts, &|_, _| {})?;
//! assert_eq!(film.dropped_samples(), 0);
//! assert!(film.pixel(4, 4)[0] > 0.0);
//! # Ok::<(), aperture_render::RenderError>(())
//! ```
//!
//! The pieces follow pbrt-v4's split: a [`Camera`] turns numbers ([`CameraSample`]) into rays,
//! a [`SamplerKind`] produces those numbers as pure functions of (pixel, index, dimension,
//! seed), the path tracer turns rays into radiance (with what `aperture_shading` says of each
//! surface and light) and the [`Film`] sums it. A [`Session`] holds a loaded file, poses it into
//! [`Frame`]s (built once, rendered from any number of times: whole, by window, as [`Bands`]
//! or [`Progressive`]ly) and takes edits in place. Writing a film out is `aperture_output`'s
//! job: it takes the films this crate yields; nothing here knows of files.

pub mod adaptive;
pub mod aov;
mod background;
pub mod bands;
pub mod camera;
mod camera_lanes;
mod camera_prescription;
mod cancel;
pub mod cryptomatte;
pub mod film;
mod filter;
mod frame;
mod frame_accel;
mod frame_lights;
mod image_size;
pub mod info;
mod integrator;
pub mod lens;
pub mod motion;
mod options;
pub mod passes;
mod primary;
mod progressive;
pub mod realistic;
mod render;
pub mod resolve;
pub mod sampler;
pub mod sequence;
mod session;
mod spares;

pub use adaptive::AdaptiveOptions;
pub use bands::{Band, BandTotals, Bands};
pub use camera::{Aperture, Camera, CameraModel, CameraRay, CameraSample};
pub use cancel::Cancel;
pub use film::{Film, PixelSum, Window};
pub use filter::{Filter, FilterKind};
pub use frame::{Frame, FrameTimes};
pub use frame_accel::{
    accel_input_counts, auto_bvh_quality, build_accel, build_motion_accel, BvhQualityChoice,
    SceneHints,
};
pub use frame_lights::FrameLights;
pub use image_size::{default_height, image_size};
pub use integrator::Clamp;
pub use options::{RenderError, RenderOptions, DEFAULT_MAX_BOUNCES};
pub use passes::{Pass, PassSet};
pub use progressive::Progressive;
pub use render::{material_name, render, render_window, scene_camera, DEPTH_BACKGROUND, TILE};
pub use sampler::{SampleStream, SamplerKind, MAX_SPP};
pub use session::{FrameSpec, Session, SessionError};
