//! Render progress on stderr, and the film turned into an image for `aperture_imageio`.

use aperture_imageio::{Image, MetaValue};
use aperture_render::{Film, RenderOptions};
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal as _;

/// A progress bar with ETA, shown only when stderr is a terminal and not `--quiet`.
pub struct Progress {
    bar: Option<ProgressBar>,
}

impl Progress {
    /// A bar, or nothing when it would only clutter a log.
    pub fn new(quiet: bool) -> Self {
        let bar = (!quiet && std::io::stderr().is_terminal()).then(|| {
            let bar = ProgressBar::new(0);
            if let Ok(style) = ProgressStyle::with_template(
                "{spinner} [{elapsed_precise}] {wide_bar} {pos}/{len} tiles, ETA {eta}",
            ) {
                bar.set_style(style);
            }
            bar
        });
        Self { bar }
    }

    /// `done` of `total` tiles finished (called from worker threads).
    pub fn update(&self, done: usize, total: usize) {
        if let Some(bar) = &self.bar {
            bar.set_length(total as u64);
            // Tiles finish out of order; the counter only grows.
            if done as u64 > bar.position() {
                bar.set_position(done as u64);
            }
        }
    }

    /// Removes the bar.
    pub fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}

/// The film as a plain image with the header metadata of SPEC §6, under `aperture:` keys so
/// they cannot collide with the standard EXR attributes.
pub fn film_to_image(
    film: &Film,
    cam: &aperture_scene::Camera,
    opts: &RenderOptions,
    render_secs: f64,
) -> Image {
    let mut image = Image::new(film.width(), film.height());
    image.rgba = film.to_rgba();
    let dof = &cam.dof;
    let meta = [
        ("aperture:camera", MetaValue::Text(cam.name.clone())),
        (
            "aperture:apertureRadius",
            MetaValue::Float(dof.effective_radius()),
        ),
        (
            "aperture:focusDistance",
            MetaValue::Float(dof.focus_distance),
        ),
        ("aperture:apertureBlades", MetaValue::Int(dof.blades as i32)),
        ("aperture:spp", MetaValue::Int(opts.spp as i32)),
        ("aperture:seed", MetaValue::Int(opts.seed as i32)),
        ("aperture:renderTime", MetaValue::Float(render_secs as f32)),
        (
            "aperture:maxBounces",
            MetaValue::Int(opts.max_bounces as i32),
        ),
        (
            "aperture:sampler",
            MetaValue::Text(format!("{:?}", opts.sampler)),
        ),
        (
            "aperture:filter",
            MetaValue::Text(format!("{:?}", opts.filter)),
        ),
        (
            "aperture:droppedSamples",
            MetaValue::Int(film.dropped_samples().min(i32::MAX as u64) as i32),
        ),
        (
            "aperture:software",
            MetaValue::Text(format!("aperture {}", env!("CARGO_PKG_VERSION"))),
        ),
    ];
    image.metadata = meta.into_iter().map(|(k, v)| (k.to_string(), v)).collect();
    image
}

#[cfg(test)]
mod tests {
    use super::*;
    use aperture_render::{build_accel, render, test_scenes};

    #[test]
    fn exr_round_trip_keeps_pixels_and_metadata() {
        let mut scene = test_scenes::lit_plane(4.0);
        scene.cameras[0].dof.enabled = true;
        scene.cameras[0].dof.aperture_radius = 0.05;
        scene.cameras[0].dof.focus_distance = 7.5;
        let accel = build_accel(&scene, Default::default());
        let opts = RenderOptions {
            width: 20,
            height: 12,
            spp: 2,
            seed: 42,
            ..RenderOptions::default()
        };
        let film = render(&scene, &accel, &opts, &|_, _| {}).unwrap();
        let image = film_to_image(&film, &scene.cameras[0], &opts, 1.25);
        let path = std::env::temp_dir().join(format!("aperture-cli-{}.exr", std::process::id()));
        aperture_imageio::write_image(&path, &image, &Default::default()).unwrap();
        let back = aperture_imageio::read_exr(&path).unwrap();
        std::fs::remove_file(&path).unwrap();
        assert_eq!(back.width, 20);
        assert_eq!(back.rgba, film.to_rgba());
        assert!(back.rgba.iter().any(|p| p[0] > 0.0));
        let meta = |k: &str| back.meta(k).cloned();
        assert_eq!(
            meta("aperture:camera"),
            Some(MetaValue::Text("test camera".into()))
        );
        assert_eq!(
            meta("aperture:apertureRadius"),
            Some(MetaValue::Float(0.05))
        );
        assert_eq!(meta("aperture:focusDistance"), Some(MetaValue::Float(7.5)));
        assert_eq!(meta("aperture:spp"), Some(MetaValue::Int(2)));
        assert_eq!(meta("aperture:seed"), Some(MetaValue::Int(42)));
        assert_eq!(meta("aperture:renderTime"), Some(MetaValue::Float(1.25)));
    }
}
