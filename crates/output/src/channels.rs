//! The EXR channels of a render and each pixel's values in them: the beauty unprefixed, then
//! each pass as `<Pass>.<channel>`, resolved from the film's sums.

use aperture_imageio::{ChannelSpec, SampleType};
use aperture_render::aov::slot;
use aperture_render::cryptomatte::RANKS;
use aperture_render::film::Film;
use aperture_render::passes::{Pass, PassKind, PassSet};
use glam::{Mat3, Vec3};

/// Largest finite half float: colour values beyond it are clamped when written as half.
pub const HALF_MAX: f32 = 65504.0;

/// The passes a file gets: those asked for, plus the sample count when the render needs it
/// said (adaptive, a region, a sample range) or when nothing else would make the file a
/// multilayer one (SPEC §6: at least one dotted pass, so Blender opens it as multilayer).
pub fn file_passes(asked: PassSet, needs_sample_count: bool) -> PassSet {
    if needs_sample_count || asked.is_empty() {
        asked.with(Pass::SampleCount)
    } else {
        asked
    }
}

/// Channels of a file with `passes`, in the order [`PixelResolver::pixel`] writes values.
pub fn channels(passes: PassSet, half: bool) -> Vec<ChannelSpec> {
    let colour = if half {
        SampleType::F16
    } else {
        SampleType::F32
    };
    let mut out: Vec<ChannelSpec> = ["R", "G", "B", "A"]
        .map(|c| ChannelSpec {
            name: c.into(),
            sample_type: colour,
        })
        .into();
    for pass in passes.iter() {
        let sample_type = if pass.kind() == PassKind::Colour {
            colour
        } else {
            SampleType::F32
        };
        let layers: Vec<String> = if pass.kind() == PassKind::Cryptomatte {
            (0..RANKS / 2)
                .map(|i| format!("{}{i:02}", pass.name()))
                .collect()
        } else {
            vec![pass.name().to_owned()]
        };
        for layer in layers {
            for c in pass.channels() {
                out.push(ChannelSpec {
                    name: format!("{layer}.{c}"),
                    sample_type,
                });
            }
        }
    }
    out
}

/// Turns a film's sums into the values of [`channels`], pixel by pixel.
#[derive(Clone, Copy)]
pub struct PixelResolver<'a> {
    film: &'a Film,
    passes: PassSet,
    half: bool,
    /// Camera space (x right, y up, z forward: Cycles') from world, for denoising normals.
    camera_from_world: Mat3,
    /// Added to positions: where the file's origin went (see `Scene::world_origin`).
    world_origin: Vec3,
    /// Colour values clamped to the half range so far.
    pub clamped: u64,
}

impl<'a> PixelResolver<'a> {
    /// A resolver for `film`, writing `passes` (which the film must hold; the sample count
    /// comes from its counters).
    pub fn new(
        film: &'a Film,
        passes: PassSet,
        half: bool,
        world_from_camera: Mat3,
        world_origin: Vec3,
    ) -> Self {
        // Our camera looks down −Z; Cycles' camera space looks down +Z.
        let cycles = Mat3::from_diagonal(Vec3::new(1.0, 1.0, -1.0));
        Self {
            film,
            passes,
            half,
            camera_from_world: cycles * world_from_camera.transpose(),
            world_origin,
            clamped: 0,
        }
    }

    fn colour(&mut self, out: &mut Vec<f32>, v: Vec3) {
        for c in v.to_array() {
            out.push(if self.half && c.abs() > HALF_MAX {
                self.clamped += 1;
                c.clamp(-HALF_MAX, HALF_MAX)
            } else {
                c
            });
        }
    }

    /// Every pixel's values, rows top to bottom (`channels` per pixel), resolved in parallel
    /// a row at a time; and how many colour values were clamped to the half range.
    pub fn rows(&self, channels: usize) -> (Vec<f32>, u64) {
        use rayon::prelude::*;
        let w = self.film.window();
        let per_row = w.width as usize * channels;
        let mut values = vec![0.0f32; w.pixels() * channels];
        let clamped = values
            .par_chunks_mut(per_row.max(1))
            .enumerate()
            .map(|(y, row)| {
                let mut me = PixelResolver {
                    clamped: 0,
                    ..*self
                };
                let mut out = Vec::with_capacity(per_row);
                for x in 0..w.width as usize {
                    me.pixel(y * w.width as usize + x, &mut out);
                }
                row.copy_from_slice(&out);
                me.clamped
            })
            .sum();
        (values, clamped)
    }

    /// Appends the values of pixel `i` of the film (row-major in its window).
    pub fn pixel(&mut self, i: usize, out: &mut Vec<f32>) {
        let film = self.film;
        let beauty = film.accum.sums[i].resolve();
        self.colour(out, Vec3::new(beauty[0], beauty[1], beauty[2]));
        out.push(beauty[3]);
        let lay = film.accum.layout;
        let light = |s: usize| film.mean3(i, lay.light.map(|o| o + 3 * s));
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
                Pass::Normal => {
                    out.extend(film.mean3(i, lay.normal).unwrap_or_default().to_array())
                }
                Pass::DenoisingAlbedo => {
                    let a = film.mean3(i, lay.albedo).unwrap_or_default();
                    self.colour(out, a);
                }
                Pass::DenoisingNormal => {
                    let n = film.mean3(i, lay.denoising_normal).unwrap_or_default();
                    out.extend((self.camera_from_world * n).to_array());
                }
                Pass::DiffuseDirect
                | Pass::DiffuseIndirect
                | Pass::GlossyDirect
                | Pass::GlossyIndirect
                | Pass::TransmissionDirect
                | Pass::TransmissionIndirect => {
                    let (s, colour) = light_slots(pass);
                    let v = divide(
                        light(s).unwrap_or_default(),
                        light(colour).unwrap_or_default(),
                    );
                    self.colour(out, v);
                }
                Pass::DiffuseColor | Pass::GlossyColor | Pass::TransmissionColor => {
                    let v = light(light_slots(pass).0).unwrap_or_default();
                    self.colour(out, v);
                }
                Pass::Emission => self.colour(out, light(slot::EMISSION).unwrap_or_default()),
                Pass::Environment => self.colour(out, light(slot::ENVIRONMENT).unwrap_or_default()),
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
    fn channel_names_follow_blender() {
        let names: Vec<String> = channels(PassSet::compositing(), false)
            .into_iter()
            .map(|c| c.name)
            .collect();
        let expected = [
            "R",
            "G",
            "B",
            "A",
            "Depth.Z",
            "Normal.X",
            "Normal.Y",
            "Normal.Z",
            "Denoising Albedo.R",
            "Denoising Albedo.G",
            "Denoising Albedo.B",
            "Denoising Normal.X",
            "Denoising Normal.Y",
            "Denoising Normal.Z",
        ];
        assert_eq!(names[..expected.len()], expected);
        assert!(names.contains(&"CryptoObject02.A".to_string()));
        assert!(names.contains(&"CryptoMaterial00.R".to_string()));
        assert_eq!(names.len(), 14 + 2 * 3 * 4);
        // Half applies to colour only.
        let half = channels(PassSet::all(), true);
        let kind = |n: &str| half.iter().find(|c| c.name == n).unwrap().sample_type;
        assert_eq!(kind("R"), SampleType::F16);
        assert_eq!(kind("Glossy Direct.G"), SampleType::F16);
        assert_eq!(kind("Denoising Albedo.B"), SampleType::F16);
        assert_eq!(kind("Depth.Z"), SampleType::F32);
        assert_eq!(kind("Normal.X"), SampleType::F32);
        assert_eq!(kind("CryptoObject00.R"), SampleType::F32);
        // The sample count joins when asked or when the file would have no dotted pass.
        assert!(file_passes(PassSet::NONE, false).contains(Pass::SampleCount));
        assert!(!file_passes(PassSet::compositing(), false).contains(Pass::SampleCount));
        assert!(file_passes(PassSet::compositing(), true).contains(Pass::SampleCount));
    }

    #[test]
    fn division_keeps_the_product() {
        let (l, c) = (Vec3::new(0.3, 0.2, 0.1), Vec3::new(0.5, 0.0, 0.25));
        let d = divide(l, c);
        assert_eq!(d, Vec3::new(0.6, 0.0, 0.4));
        assert!((d * c - Vec3::new(0.3, 0.0, 0.1)).length() < 1e-7);
    }
}
