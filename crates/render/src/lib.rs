//! Camera, sampler, path tracer and film: turns a scene and its acceleration structure into
//! films, for the whole image, a window of it, or band by band into a sink.
//!
//! ```
//! use aperture_render::{build_accel, render, test_scenes, RenderOptions};
//! // A white diffuse quad under a point light, seen by a thin-lens camera.
//! let scene = test_scenes::lit_plane(1.0);
//! let accel = build_accel(&scene, Default::default());
//! let opts = RenderOptions { width: 8, height: 8, spp: 4, ..Default::default() };
//! let film = render(&scene, &accel, &opts, &|_, _| {})?;
//! assert_eq!(film.dropped_samples(), 0);
//! assert!(film.pixel(4, 4)[0] > 0.0);
//! # Ok::<(), aperture_render::RenderError>(())
//! ```
//!
//! The pieces follow pbrt-v4's split: a [`Camera`] turns numbers ([`CameraSample`]) into rays,
//! a [`SamplerKind`] produces those numbers as pure functions of (pixel, index, dimension,
//! seed), the path tracer turns rays into radiance (with what `aperture_shading` says of each
//! surface and light) and the [`Film`] sums it. Writing a film out is `aperture_output`'s job:
//! it hands [`render_bands`] a sink; nothing here knows of files.

pub mod adaptive;
pub mod aov;
mod background;
pub mod bands;
pub mod camera;
mod camera_lanes;
mod cancel;
pub mod cryptomatte;
pub mod film;
mod filter;
mod frame_accel;
mod integrator;
pub mod motion;
mod options;
pub mod passes;
mod primary;
mod render;
pub mod sampler;
pub mod sequence;
mod spares;

pub use adaptive::AdaptiveOptions;
pub use camera::{default_height, Aperture, Camera, CameraModel, CameraRay, CameraSample};
pub use cancel::Cancel;
pub use film::{Film, PixelSum, Window};
pub use filter::{Filter, FilterKind};
pub use frame_accel::{
    auto_bvh_quality, build_accel, build_frame_accel, build_motion_accel, BvhQualityChoice,
    SceneHints,
};
pub use integrator::Clamp;
pub use options::{RenderError, RenderOptions, DEFAULT_MAX_BOUNCES};
pub use passes::{Pass, PassSet};
pub use render::{
    material_name, render, render_bands, render_window, render_with_camera, scene_camera,
    BandTotals, DEPTH_BACKGROUND, TILE,
};
pub use sampler::{SampleStream, SamplerKind, MAX_SPP};

// What the options and the public API take from the shading crate, under their old names.
pub use aperture_shading::{single_sided_materials, Convention, ConventionModel, SidesModel};
pub use aperture_shading::{
    srgb_to_linear, test_scenes, transform_uv, transmissive_meshes, EnvImage, EnvSampling,
    Environment, MaterialOverride, TransmissionModel,
};
pub use aperture_shading::{
    Albedos, Bsdf, BsdfSample, CoatLayer, Compensation, DeltaSample, Dielectric, Frame, Interface,
    Lobe, LobeSplit, MetalRough, Principled, SheenLayer, ThinFilm,
};
