//! Camera, sampler, integrator and film: turns a scene and its acceleration structure into an
//! image.
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
//! seed), the path tracer turns rays into radiance and the [`Film`] sums it.

pub mod adaptive;
mod aov;
mod background;
mod bsdf;
pub mod camera;
mod camera_lanes;
mod cancel;
mod color;
pub mod cryptomatte;
mod environment;
mod film;
mod filter;
mod footprint;
mod hit_prefetch;
mod integrator;
mod light_choice;
mod lights;
mod media;
pub mod output;
pub mod passes;
mod primary;
pub mod raybench;
mod render;
pub mod sampler;
pub mod sequence;
mod shade_extended;
mod spares;
mod spectrum;
mod surface;
pub mod test_scenes;
mod texture;
mod transmission;
mod warp;

pub use adaptive::AdaptiveOptions;
pub use bsdf::{
    Albedos, Bsdf, BsdfSample, CoatLayer, Compensation, DeltaSample, Dielectric, Frame, Interface,
    Lobe, LobeSplit, MetalRough, Principled, SheenLayer, ThinFilm,
};
pub use camera::{default_height, Aperture, Camera, CameraModel, CameraRay, CameraSample};
pub use cancel::Cancel;
pub use color::srgb_to_linear;
pub use environment::{EnvImage, EnvSampling, Environment};
pub use film::{Film, PixelSum, Window};
pub use filter::{Filter, FilterKind};
pub use footprint::{check_output, footprint, Footprint, FootprintError, OutputKind};
pub use integrator::Clamp;
pub use passes::{Pass, PassSet};
pub use render::{
    auto_bvh_quality, build_accel, material_name, render, render_window, render_with_camera,
    scene_camera, RenderError, RenderOptions, DEFAULT_MAX_BOUNCES, DEPTH_BACKGROUND, TILE,
};
pub use sampler::{SampleStream, SamplerKind, MAX_SPP};
pub use surface::MaterialOverride;
pub use texture::transform_uv;
pub use transmission::{
    transmissive_meshes, ParseTransmissionError, TransmissionMode, TransmissionModel,
};
