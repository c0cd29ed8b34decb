//! The fuzz targets' entry points: each takes arbitrary bytes and must return, whatever they
//! are, without panicking, within the memory budget [`MEMORY_BUDGET`] and quickly.
//!
//! The same functions run under libFuzzer (`fuzz/fuzz_targets/*.rs`, nightly, `tools/fuzz.sh`)
//! and, on stable, in this crate's corpus replay test, which feeds every committed corpus file
//! (`fuzz/corpus/<target>/`) through them in CI.

#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

mod wrap;

use std::path::Path;

use aperture_budget::MemoryBudget;
use aperture_scene::{Animated, LoadOptions};

/// The memory budget every target loads with: an allocation past it must be refused with an
/// error (libFuzzer's `-malloc_limit_mb` in `tools/fuzz.sh` is set just above it, so exceeding
/// it is reported as an out-of-memory crash). Small, as image crates' own fuzzers keep theirs:
/// a legitimately large image within a larger budget takes seconds to decode under
/// AddressSanitizer and would be reported as a timeout (one input may take 2 s).
pub const MEMORY_BUDGET: u64 = 64 << 20;

/// The fuzz targets, by the name of their corpus folder and libFuzzer binary.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Target {
    /// [`load`].
    Load,
    /// [`exr`].
    Exr,
    /// [`env`].
    Env,
    /// [`texture`].
    Texture,
    /// [`draco`].
    Draco,
    /// [`meshopt`].
    Meshopt,
}

impl Target {
    /// Every target.
    pub const ALL: [Target; 6] = [
        Target::Load,
        Target::Exr,
        Target::Env,
        Target::Texture,
        Target::Draco,
        Target::Meshopt,
    ];

    /// The target's name (its corpus folder and fuzz binary).
    pub fn name(self) -> &'static str {
        match self {
            Target::Load => "load",
            Target::Exr => "exr",
            Target::Env => "env",
            Target::Texture => "texture",
            Target::Draco => "draco",
            Target::Meshopt => "meshopt",
        }
    }

    /// Runs the target's entry point on `data`.
    pub fn run(self, data: &[u8]) {
        match self {
            Target::Load => load(data),
            Target::Exr => exr(data),
            Target::Env => env(data),
            Target::Texture => texture(data),
            Target::Draco => draco(data),
            Target::Meshopt => meshopt(data),
        }
    }
}

/// A folder that does not exist: external URIs of fuzzed files resolve to nothing, so only
/// in-memory resources (the GLB BIN chunk, `data:` URIs) are read.
const NO_FOLDER: &str = "/nonexistent/aperture-fuzz";

fn options() -> LoadOptions {
    LoadOptions {
        memory: MemoryBudget::fixed(MEMORY_BUDGET),
        ..LoadOptions::default()
    }
}

/// `data` as a `.glb` or `.gltf` file: loaded, then posed as stored and at two times (so
/// animation samplers, skins, morph targets and pointers are evaluated).
pub fn load(data: &[u8]) {
    let doc = match Animated::load_bytes(data, Path::new(NO_FOLDER), &options()) {
        Ok(doc) => doc,
        // The loader's own guard caught a panic: still a finding.
        Err(e @ aperture_scene::Error::Panicked { .. }) => panic!("{e}"),
        Err(_) => return,
    };
    let _ = doc.scene_at(None);
    if doc.is_animated() {
        let _ = doc.scene_at(Some(0.37));
        let _ = doc.scene_at(Some(-1e3));
    }
}

/// Crates whose panics the readers catch and report as damaged data: the `exr` crate (its
/// B44 decoder overflows on some damaged blocks; `aperture_imageio::decode_exr`) and the image
/// crate's decoders (zune-jpeg overflows on some damaged JPEGs; `aperture_scene`'s texture
/// decoding).
const CAUGHT_IN: &[&str] = &[
    "/exr-1.",
    "/image-0.",
    "/zune-jpeg-",
    "/zune-core-",
    "/png-0.",
    "/image-webp-",
    "/basisu-0.",
    "/ruzstd-",
];

/// For targets whose readers catch third-party decoders' panics, under libFuzzer, whose panic
/// hook aborts on every panic: a panic raised inside one of those crates is left to the
/// reader's `catch_unwind` (if nothing catches it, libFuzzer's own wrapper still aborts: a
/// finding); any other panic aborts at once, as before. Call once, after libFuzzer's hook is
/// installed (the targets' `init`).
pub fn tolerate_caught_decoder_panics() {
    let aborting = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let caught = info.location().is_some_and(|l| {
            let file = l.file().replace('\\', "/");
            CAUGHT_IN.iter().any(|c| file.contains(c))
        });
        if !caught {
            aborting(info);
        }
    }));
}

/// `data` as an OpenEXR file (`merge` parts and EXR environment maps are read by it).
pub fn exr(data: &[u8]) {
    let _ = aperture_imageio::decode_exr_within(data, Path::new("fuzz.exr"), MEMORY_BUDGET);
}

/// `data` as an environment map (Radiance HDR or EXR, told apart by content).
pub fn env(data: &[u8]) {
    let _ = aperture_imageio::decode_env_image(data, Path::new("fuzz.hdr"), MEMORY_BUDGET);
}

/// `data` as a texture image (PNG, JPEG, WebP, KTX2), decoded as the loader decodes them.
pub fn texture(data: &[u8]) {
    let _ = aperture_scene::decode_texture(data, 0, MEMORY_BUDGET);
}

/// `data` as a `KHR_draco_mesh_compression` primitive: see [`wrap::draco`].
pub fn draco(data: &[u8]) {
    if let Some(glb) = wrap::draco(data) {
        load(&glb);
    }
}

/// `data` as an `EXT_meshopt_compression` buffer view: see [`wrap::meshopt`].
pub fn meshopt(data: &[u8]) {
    if let Some(glb) = wrap::meshopt(data) {
        load(&glb);
    }
}

pub use wrap::{
    draco as wrap_draco, draco_input, glb, meshopt as wrap_meshopt, meshopt_input, MeshoptMode,
};
