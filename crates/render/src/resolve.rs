//! A film's sums turned into each pass's values, pixel by pixel: the beauty RGBA, then each
//! pass of the set in its order with [`Pass::channels`] values (Cryptomatte: [`RANKS`]
//! (ID, coverage) pairs). What the values are is the renderer's; what a file calls them and
//! stores them as (names, half floats) is the writer's.

use crate::aov::slot;
use crate::cryptomatte::RANKS;
use crate::film::Film;
use crate::passes::{Pass, PassSet};
use glam::{Mat3, Vec3};

/// Resolves a film's pixels into the values of its passes.
#[derive(Clone, Copy)]
pub struct Resolver<'a> {
    film: &'a Film,
    passes: PassSet,
    /// Camera space (x right, y up, z forward: Cycles') from world, for denoising normals.
    camera_from_world: Mat3,
    /// Added to positions: where the file's origin went (see `Scene::world_origin`).
    world_origin: Vec3,
}

impl<'a> Resolver<'a> {
    /// A resolver for `film`, giving `passes` (which the film must hold; the sample count
    /// comes from its counters); `world_from_camera` is the camera's rotation.
    pub fn new(
        film: &'a Film,
        passes: PassSet,
        world_from_camera: Mat3,
        world_origin: Vec3,
    ) -> Self {
        // Our camera looks down −Z; Cycles' camera space looks down +Z.
        let cycles = Mat3::from_diagonal(Vec3::new(1.0, 1.0, -1.0));
        Self {
            film,
            passes,
            camera_from_world: cycles * world_from_camera.transpose(),
            world_origin,
        }
    }

    /// The values a pixel takes: 4 for the beauty plus each pass's.
    pub fn values_per_pixel(&self) -> usize {
        4 + self
            .passes
            .iter()
            .map(|p| match p {
                Pass::CryptoObject | Pass::CryptoMaterial => 2 * RANKS,
                p => p.channels().len(),
            })
            .sum::<usize>()
    }

    /// Every pixel's values, rows top to bottom, resolved in parallel a row at a time.
    pub fn rows(&self) -> Vec<f32> {
        use rayon::prelude::*;
        let w = self.film.window();
        let per_row = w.width as usize * self.values_per_pixel();
        let mut values = vec![0.0f32; w.pixels() * self.values_per_pixel()];
        values
            .par_chunks_mut(per_row.max(1))
            .enumerate()
            .for_each(|(y, row)| {
                let mut out = Vec::with_capacity(per_row);
                for x in 0..w.width as usize {
                    self.pixel(y * w.width as usize + x, &mut out);
                }
                row.copy_from_slice(&out);
            });
        values
    }

    /// Appends the values of pixel `i` of the film (row-major in its window).
    pub fn pixel(&self, i: usize, out: &mut Vec<f32>) {
        let film = self.film;
        out.extend(film.accum.sums[i].resolve());
        let lay = film.accum.layout;
        let light = |s: usize| mean3(film, i, lay.light.map(|o| o + 3 * s));
        for pass in self.passes.iter() {
            match pass {
                Pass::Depth => out.push(film.depth.get(i).copied().unwrap_or(0.0)),
                Pass::Vector => out.extend(film.vector.get(i).copied().unwrap_or_default()),
                Pass::Position => {
                    let p = film.position.get(i).copied().unwrap_or(Vec3::ZERO);
                    let p = if p == Vec3::ZERO {
                        p
                    } else {
                        p + self.world_origin
                    };
                    out.extend(p.to_array());
                }
                Pass::Normal => out.extend(mean3(film, i, lay.normal).to_array()),
                Pass::DenoisingAlbedo => out.extend(mean3(film, i, lay.albedo).to_array()),
                Pass::DenoisingNormal => {
                    let n = mean3(film, i, lay.denoising_normal);
                    out.extend((self.camera_from_world * n).to_array());
                }
                Pass::DiffuseDirect
                | Pass::DiffuseIndirect
                | Pass::GlossyDirect
                | Pass::GlossyIndirect
                | Pass::TransmissionDirect
                | Pass::TransmissionIndirect => {
                    let (s, colour) = light_slots(pass);
                    out.extend(divide(light(s), light(colour)).to_array());
                }
                Pass::DiffuseColor | Pass::GlossyColor | Pass::TransmissionColor => {
                    out.extend(light(light_slots(pass).0).to_array())
                }
                Pass::Emission => out.extend(light(slot::EMISSION).to_array()),
                Pass::Environment => out.extend(light(slot::ENVIRONMENT).to_array()),
                Pass::CryptoObject | Pass::CryptoMaterial => {
                    let px = if pass == Pass::CryptoObject {
                        film.accum.crypto_object.get(i)
                    } else {
                        film.accum.crypto_material.get(i)
                    };
                    let ranks =
                        px.map_or([(0, 0.0); RANKS], |p| p.ranked(film.accum.sums[i].count));
                    for (id, coverage) in ranks {
                        out.push(f32::from_bits(id));
                        out.push(coverage);
                    }
                }
                Pass::SampleCount => out.push(film.samples_per_pixel()[i] as f32),
            }
        }
    }
}

/// The mean of an averaged pass (Normal, Denoising Albedo or Normal, a light pass before its
/// division by the Color pass) at pixel index `i`; zero when not rendered or not sampled.
fn mean3(film: &Film, i: usize, at: Option<usize>) -> Vec3 {
    let Some(o) = at else {
        return Vec3::ZERO;
    };
    let s = &film.accum.aov[i * film.accum.layout.stride + o..][..3];
    let n = film.accum.sums[i].count;
    if n > 0.0 {
        Vec3::new((s[0] / n) as f32, (s[1] / n) as f32, (s[2] / n) as f32)
    } else {
        Vec3::ZERO
    }
}

/// The light slot of a light pass and the slot of the Color pass it is divided by.
fn light_slots(pass: Pass) -> (usize, usize) {
    match pass {
        Pass::DiffuseDirect => (slot::DIFFUSE_DIRECT, slot::DIFFUSE_COLOR),
        Pass::DiffuseIndirect => (slot::DIFFUSE_INDIRECT, slot::DIFFUSE_COLOR),
        Pass::DiffuseColor => (slot::DIFFUSE_COLOR, slot::DIFFUSE_COLOR),
        Pass::GlossyDirect => (slot::GLOSSY_DIRECT, slot::GLOSSY_COLOR),
        Pass::GlossyIndirect => (slot::GLOSSY_INDIRECT, slot::GLOSSY_COLOR),
        Pass::GlossyColor => (slot::GLOSSY_COLOR, slot::GLOSSY_COLOR),
        Pass::TransmissionDirect => (slot::TRANSMISSION_DIRECT, slot::TRANSMISSION_COLOR),
        Pass::TransmissionIndirect => (slot::TRANSMISSION_INDIRECT, slot::TRANSMISSION_COLOR),
        _ => (slot::TRANSMISSION_COLOR, slot::TRANSMISSION_COLOR),
    }
}

/// Light over colour per channel, as Cycles divides its Direct and Indirect passes (0 where
/// the colour is 0: a lobe with no albedo in a channel scatters no light in it either).
fn divide(light: Vec3, colour: Vec3) -> Vec3 {
    let d = |l: f32, c: f32| if c != 0.0 { l / c } else { 0.0 };
    Vec3::new(
        d(light.x, colour.x),
        d(light.y, colour.y),
        d(light.z, colour.z),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn division_keeps_the_product() {
        let (l, c) = (Vec3::new(0.3, 0.2, 0.1), Vec3::new(0.5, 0.0, 0.25));
        let d = divide(l, c);
        assert_eq!(d, Vec3::new(0.6, 0.0, 0.4));
        assert!((d * c - Vec3::new(0.3, 0.0, 0.1)).length() < 1e-7);
    }

    #[test]
    fn a_pixel_has_the_values_its_passes_say() {
        let passes = PassSet::all();
        let film = Film::for_window(crate::film::Window::whole(3, 2), 3, 2, passes);
        let r = Resolver::new(&film, passes, Mat3::IDENTITY, Vec3::ZERO);
        let rows = r.rows();
        assert_eq!(rows.len(), 6 * r.values_per_pixel());
        let mut one = Vec::new();
        r.pixel(0, &mut one);
        assert_eq!(one.len(), r.values_per_pixel());
        // An empty film: no sample, every value zero.
        assert!(rows.iter().all(|&v| v == 0.0), "{rows:?}");
    }
}
