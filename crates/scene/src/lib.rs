//! glTF 2.0 files turned into a render-ready [`Scene`]: geometry stored once per mesh with a list of
//! instance transforms, materials, textures decoded to texels, punctual lights in SPEC §4 units and
//! cameras whose depth of field is resolved as SPEC §3 says.
//!
//! ```no_run
//! use aperture_scene::{load, LoadOptions};
//! let scene = load("assets/demo.glb".as_ref(), &LoadOptions::default())?;
//! println!("{} triangles drawn", scene.drawn_triangle_count());
//! # Ok::<(), aperture_scene::Error>(())
//! ```
//!
//! What the loader guarantees:
//! - `extensionsRequired` is checked before any buffer is read ([`SUPPORTED_EXTENSIONS`]); an
//!   extension that is only used is ignored (and reported in [`SceneStats::warnings`]).
//! - Without a time the stored pose is drawn: node transforms, morph weights (`node.weights`, else
//!   `mesh.weights`) and skins posed by their joints (SPEC §7). With [`LoadOptions::time`] the
//!   selected animations are evaluated at that time; [`Animated`] loads once and poses at any time.
//! - `KHR_draco_mesh_compression` and `KHR_meshopt_compression` (or `EXT_`) geometry is
//!   decoded, its sizes checked against the accessors before anything is allocated.
//! - Only the selected scene's meshes are loaded, each once, with one [`Instance`] per drawing node
//!   or `EXT_mesh_gpu_instancing` instance; only images used by drawn materials are decoded, in
//!   parallel.
//! - Bad input is an [`Error`] saying where, never a panic; every count is checked against the
//!   bytes that back it before anything is allocated.
//! - Normal-mapped triangles always have tangents: `TANGENT` where given, MikkTSpace tangents
//!   otherwise ([`generate_missing_tangents`]).
//! - External URIs resolve only inside the scene file's folder: no `..`, absolute paths or
//!   `http:`.
//! - Node transforms are composed in f64 and rounded to f32 once, relative to
//!   [`Scene::world_origin`] (the drawn geometry's centre when the scene lies far from the file's
//!   origin), so a scene placed at 1e6 renders as it does at the origin; scenes too large for
//!   their details or too small for float32 (below 1e-8 across) get a warning (docs/accuracy.md, "float32
//!   limits"), and a transform that overflows f32 is an error.
#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

mod accessor;
mod animated;
mod animation;
mod auto_camera;
mod basis;
mod buffers;
mod camera;
mod camera_select;
mod dof;
mod draco;
mod edit;
mod error;
mod geometry;
mod glb;
mod hash;
mod ibl;
mod load;
mod material;
mod material_ext;
mod mesh;
mod meshopt;
mod morph;
mod nodes;
mod origin;
mod pbr;
mod pointer;
mod prepass;
mod shared;
mod shutter_extras;
mod skin;
mod tangents;
mod texels;
mod topology;
mod types;
mod uri;

pub use animated::Animated;
pub use animation::{AnimationInfo, AnimationSelection};
pub use dof::{lens_from_yfov, DEFAULT_ASPECT};
pub use edit::{Edit, Touched};
pub use error::Error;
pub use geometry::Geometry;
pub use hash::content_hash;
pub use load::{load, load_bytes};
pub use pbr::*;
pub use prepass::SUPPORTED_EXTENSIONS;
pub use shutter_extras::{MotionExtras, RollingShutter, ShutterPosition};
pub use tangents::generate_missing_tangents;
pub use texels::{decode_texture, decodes as texture_decodes};
pub use types::*;
