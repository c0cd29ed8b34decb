//! Intel Open Image Denoise 2.x for aperture, loaded at run time (`dlopen`): no build or link
//! dependency, so a machine without OIDN builds and renders as before, and only denoising
//! needs the library. [`Denoiser::load`] finds it in the order [`locate`] documents.
//!
//! The filtering is by default OIDN's "accurate" path, as Blender Cycles does it: the albedo and
//! normal are each denoised first by their own `RT` filter, then the beauty's `RT` filter (HDR,
//! `quality` high) takes them with `cleanAux` set. [`Settings`] offers Cycles' two other
//! prefilters and OIDN's faster networks, which trade quality for time (one filter instead of
//! three, a smaller network).
//!
//! ```
//! use aperture_denoise::{DenoiseError, Denoiser};
//! // A path that is no library gives a typed error that says how to get one.
//! let err = Denoiser::load(Some(std::path::Path::new("/nonexistent/libOpenImageDenoise.so.2")))
//!     .err()
//!     .expect("not a library");
//! assert!(matches!(err, DenoiseError::Load { .. }));
//! assert!(err.to_string().contains("tools/oidn/install.sh"));
//! ```
//!
//! With the library (`tools/oidn/install.sh`):
//!
//! ```no_run
//! use aperture_denoise::{Denoiser, Images};
//! let denoiser = Denoiser::load(None)?;
//! let (w, h) = (4, 4);
//! let colour = vec![[0.5f32; 3]; w * h];
//! let albedo = vec![[0.8f32; 3]; w * h];
//! let normal = vec![[0.0f32, 0.0, 1.0]; w * h];
//! let clean = denoiser.denoise(&Images { width: w, height: h, colour: &colour, albedo: &albedo, normal: &normal })?;
//! assert_eq!(clean.len(), w * h);
//! # Ok::<(), aperture_denoise::DenoiseError>(())
//! ```

mod error;
mod ffi;
pub mod locate;
mod platform;
mod settings;

pub use error::{DenoiseError, HOW_TO_GET};
pub use locate::{Candidate, Origin};
pub use settings::{Prefilter, Quality, Settings};

use std::path::{Path, PathBuf};

/// The images of one denoising: packed RGB rows of `width * height` pixels each.
#[derive(Debug, Clone, Copy)]
pub struct Images<'a> {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// The noisy beauty, linear HDR (premultiplied by alpha is fine: alpha is not denoised).
    pub colour: &'a [[f32; 3]],
    /// The first rough surface's albedo (`Denoising Albedo`), in [0, 1].
    pub albedo: &'a [[f32; 3]],
    /// Its shading normal (`Denoising Normal`), in any fixed space, components in [−1, 1].
    pub normal: &'a [[f32; 3]],
}

/// A loaded OIDN library with its CPU device, ready to filter.
pub struct Denoiser {
    device: ffi::Device,
    path: PathBuf,
    origin: Origin,
    version: i32,
    settings: Settings,
}

impl std::fmt::Debug for Denoiser {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Denoiser")
            .field("path", &self.path)
            .field("origin", &self.origin)
            .field("version", &self.version_string())
            .field("settings", &self.settings)
            .finish()
    }
}

impl Denoiser {
    /// Finds and loads the library: `explicit` (`--oidn`), else `APERTURE_OIDN`, and only
    /// when neither is given, the implicit places of [`locate`] in order.
    pub fn load(explicit: Option<&Path>) -> Result<Self, DenoiseError> {
        let env = std::env::var(locate::ENV).ok();
        if let Some(c) = locate::explicit_choice(explicit, env.as_deref()) {
            return Self::open(&c).map_err(|reason| DenoiseError::Load {
                path: c.path,
                origin: c.origin,
                reason,
            });
        }
        let mut tried = Vec::new();
        for c in locate::implicit_candidates() {
            match Self::open(&c) {
                Ok(d) => return Ok(d),
                // The usual case, said briefly; anything else (a 1.x library) in full.
                Err(reason) if c.origin == Origin::System && reason.contains("cannot open") => {
                    tried.push(format!("not on the {}", c.origin));
                }
                Err(reason) => tried.push(format!("{}: {reason}", c.path.display())),
            }
        }
        if let Some(dir) = locate::cache_dir() {
            tried.push(format!("not in {}", dir.display()));
        }
        tried.push("no pyoidn or Blender found".into());
        Err(DenoiseError::NotFound {
            tried: tried.join("; "),
        })
    }

    /// Loads one candidate and checks it is OIDN 2.x.
    fn open(c: &Candidate) -> Result<Self, String> {
        let device = ffi::Device::open(&c.path)?;
        let version = device.version();
        if !(20000..30000).contains(&version) {
            return Err(format!("version {version} is not 2.x"));
        }
        Ok(Denoiser {
            device,
            path: c.path.clone(),
            origin: c.origin,
            version,
            settings: Settings::default(),
        })
    }

    /// The same library and device, filtering with `settings` from now on.
    pub fn with_settings(mut self, settings: Settings) -> Self {
        self.settings = settings;
        self
    }

    /// The settings every [`Denoiser::denoise`] uses.
    pub fn settings(&self) -> Settings {
        self.settings
    }

    /// The library loaded (a bare file name when the system's search found it).
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Where in the search order it was found.
    pub fn origin(&self) -> Origin {
        self.origin
    }

    /// OIDN's version, `major.minor.patch`.
    pub fn version_string(&self) -> String {
        let v = self.version;
        format!("{}.{}.{}", v / 10000, v / 100 % 100, v % 100)
    }

    /// Denoises `images.colour` with the albedo and normal as [`Settings::prefilter`] says, HDR,
    /// at [`Settings::quality`]. Returns the denoised RGB, same size.
    pub fn denoise(&self, images: &Images<'_>) -> Result<Vec<[f32; 3]>, DenoiseError> {
        let n = images.width * images.height;
        for (what, px) in [
            ("colour", images.colour),
            ("albedo", images.albedo),
            ("normal", images.normal),
        ] {
            if px.len() != n || n == 0 {
                return Err(DenoiseError::Size {
                    what,
                    len: px.len(),
                    width: images.width,
                    height: images.height,
                });
            }
        }
        let prefiltered;
        let (albedo, normal) = match self.settings.prefilter {
            Prefilter::Accurate => {
                prefiltered = (
                    self.prefilter("albedo", images, images.albedo)?,
                    self.prefilter("normal", images, images.normal)?,
                );
                (&prefiltered.0[..], &prefiltered.1[..])
            }
            Prefilter::Fast | Prefilter::None => (images.albedo, images.normal),
        };
        let mut out = vec![[0.0f32; 3]; n];
        let run = ffi::Run {
            kind: "RT",
            width: images.width,
            height: images.height,
            inputs: &[
                ("color", images.colour),
                ("albedo", albedo),
                ("normal", normal),
            ],
            bools: &[
                ("hdr", true),
                ("cleanAux", self.settings.prefilter.clean_aux()),
            ],
            ints: &[("quality", self.settings.quality.oidn())],
        };
        self.device
            .run(&run, &mut out)
            .map_err(|message| DenoiseError::Filter {
                stage: "beauty",
                message,
            })?;
        Ok(out)
    }

    /// One auxiliary image denoised by its own `RT` filter (OIDN's prefiltering).
    fn prefilter(
        &self,
        stage: &'static str,
        images: &Images<'_>,
        pixels: &[[f32; 3]],
    ) -> Result<Vec<[f32; 3]>, DenoiseError> {
        let mut out = vec![[0.0f32; 3]; pixels.len()];
        let inputs = [(stage, pixels)];
        let run = ffi::Run {
            kind: "RT",
            width: images.width,
            height: images.height,
            inputs: &inputs,
            bools: &[],
            ints: &[("quality", self.settings.quality.oidn())],
        };
        self.device
            .run(&run, &mut out)
            .map_err(|message| DenoiseError::Filter { stage, message })?;
        Ok(out)
    }
}
