//! What a path tracer evaluates where a ray lands: the surface and its material (BSDFs with
//! their energy tables, textures, thin-film, coats, sheen), media inside transmissive meshes,
//! the scene's lights and the choice of one at a vertex, and the environment.
//!
//! ```
//! use aperture_shading::{test_scenes, Geometry, MaterialOverride, TransmissionModel};
//! use aperture_shading::lights::EmissiveLights;
//! // An emissive ball above a plane: its triangles become lights.
//! let mut scene = test_scenes::lit_plane(1.0);
//! scene.materials.push(test_scenes::emitter(glam::Vec3::ONE));
//! scene.meshes.push(test_scenes::icosphere(1, 1).into());
//! scene.instances.push(aperture_scene::Instance {
//!     mesh: 1,
//!     world_from_object: glam::Affine3A::IDENTITY,
//!     node: 1,
//!     materials: 0,
//! });
//! let geom = Geometry::with_transmission(&scene, MaterialOverride::None, TransmissionModel::Gltf);
//! assert!(EmissiveLights::build(&geom).is_some());
//! ```
//!
//! The renderer (`aperture_render`) asks these for values; nothing here traces a ray, so every
//! piece can be tested on its own numbers. All sampling warps live in [`warp`], as pbrt's
//! `util/sampling.h`.

pub mod bsdf;
pub mod color;
pub mod convention;
mod env_choice;
pub mod environment;
pub mod hit_prefetch;
pub mod light_bounds;
pub mod light_choice;
pub mod light_tree;
pub mod lights;
pub mod media;
pub mod punctual;
mod shade_extended;
pub mod sides;
pub mod spectrum;
pub mod surface;
pub mod test_scenes;
pub mod texture;
pub mod transmission;
pub mod warp;
pub mod warp_image;
pub mod warp_lens;

pub use bsdf::{
    Albedos, Bsdf, BsdfSample, CoatLayer, Compensation, DeltaSample, Dielectric, Frame, Interface,
    Lobe, LobeSplit, MetalRough, Principled, SheenLayer, ThinFilm,
};
pub use color::srgb_to_linear;
pub use convention::{Convention, ConventionModel};
pub use env_choice::{choose_environment, EnvLight};
pub use environment::{EnvImage, EnvSampling, Environment};
pub use sides::{single_sided_materials, SidesModel};
pub use surface::{Geometry, MaterialOverride};
pub use texture::transform_uv;
pub use transmission::{transmissive_meshes, TransmissionModel};
