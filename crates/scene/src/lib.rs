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
#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

mod accessor;
mod dof;
mod error;
mod glb;
mod load;
mod material;
mod mesh;
mod prepass;
mod types;
mod uri;

pub use dof::{lens_from_yfov, DEFAULT_ASPECT};
pub use error::Error;
pub use load::{load, load_bytes};
pub use prepass::SUPPORTED_EXTENSIONS;
pub use types::*;
