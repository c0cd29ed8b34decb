//! A film already in memory as the plain image of the EXR [`crate::write::write_image`]
//! writes: the same channels and header.

use crate::error::OutputError;
use crate::summary::RenderSummary;
use crate::{channels, header, region};
use aperture_imageio::{Image, Layer};
use aperture_render::film::Film;
use aperture_render::resolve::Resolver;
use aperture_render::{scene_camera, RenderOptions};
use aperture_scene::Scene;
use glam::Mat3;

/// A rendered film as a plain image with the channels and header of
/// [`write::write_image`]'s EXR
/// (`render_secs` into the header's render time): the same file, for a film already in
/// memory.
pub fn film_to_image(
    film: &Film,
    scene: &Scene,
    opts: &RenderOptions,
    half: bool,
    render_secs: f64,
) -> Result<Image, OutputError> {
    let camera = scene_camera(scene, opts)?;
    let window = film.window();
    let passes = channels::file_passes(film.passes(), region::needs_sample_count(opts, window));
    let specs = channels::channels(passes, half);
    let world_from_camera = Mat3::from(camera.world_from_camera.matrix3);
    let resolver = Resolver::new(
        film,
        passes,
        world_from_camera,
        scene.world_origin.as_vec3(),
    );
    let mut values = resolver.rows();
    let half_clamped = channels::clamp_half(&mut values, &specs);
    let n = window.pixels();
    let mut image = Image::new(film.width(), film.height());
    image.beauty_type = specs[0].sample_type;
    image.placement = region::placement(window, opts);
    let stride = specs.len();
    for (p, px) in image.rgba.iter_mut().enumerate() {
        px.copy_from_slice(&values[p * stride..p * stride + 4]);
    }
    // Channels `Layer.c` of one layer are adjacent: group them.
    let mut c = 4;
    while c < stride {
        let (layer, _) = specs[c].name.rsplit_once('.').expect("dotted pass channel");
        let count = specs[c..]
            .iter()
            .take_while(|s| s.name.rsplit_once('.').map(|x| x.0) == Some(layer))
            .count();
        let names: Vec<&str> = specs[c..c + count]
            .iter()
            .map(|s| s.name.rsplit_once('.').expect("dotted").1)
            .collect();
        let data = (0..n)
            .flat_map(|p| {
                values[p * stride + c..p * stride + c + count]
                    .iter()
                    .copied()
            })
            .collect();
        let mut l = Layer::new(layer, &names, data);
        l.sample_type = specs[c].sample_type;
        image.layers.push(l);
        c += count;
    }
    image.metadata = header::metadata(scene, &camera, opts, passes);
    let whole = region::is_whole(window, opts);
    image
        .metadata
        .extend(header::split_metadata(scene, opts, (window, whole), None));
    let summary = RenderSummary {
        samples: film.total_samples(),
        dropped: film.dropped_samples(),
        render_secs,
        half_clamped,
        ..RenderSummary::of(film.window())
    };
    for (key, value) in header::late_values(&summary, opts, None) {
        if let Some(slot) = image.metadata.iter_mut().find(|(k, _)| *k == key) {
            slot.1 = value;
        }
    }
    Ok(image)
}
