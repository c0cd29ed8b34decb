//! The primary samples of a render: for sample `i` of pixel `(x, y)`, its sample stream and
//! camera ray, with what a render's samples and a pixel's consecutive samples share worked out
//! once (the camera's constants, a row's and a pixel's seed and scramble hashes, the
//! bit-reversed index), and a thin-lens camera's rays made four at a time ([`LensLanes`]).
//! The values are exactly those of drawing each sample alone: a pure function of (pixel,
//! index, dimension, seed).

use crate::background::PixelMask;
use crate::camera::{Camera, CameraRay, CameraSample};
use crate::camera_lanes::{LensLanes, LANES};
use crate::filter::Filter;
use crate::integrator::wavefront::CameraStart;
use crate::motion::FrameMotion;
use crate::sampler::pixel_run::PixelRun;
use crate::sampler::{pixel_seed_in_row, row_seed, SampleStream, SamplerKind};
use glam::{Vec2, Vec3};

/// Makes the primary samples of a render, pixel by pixel; cheapest when a pixel's samples come
/// one after another in index order, as tiles and adaptive rounds give them.
pub(crate) struct PrimarySamples<'a> {
    /// The camera of the one-at-a-time path (orthographic, polygonal apertures), copied in.
    camera: Camera,
    filter: &'a Filter,
    seed: u32,
    sample_offset: u32,
    /// `sample_offset.reverse_bits()`.
    offset_rev: u32,
    /// The pixel of `run`, if any yet.
    pixel: Option<(u32, u32)>,
    /// The row of the last pixel, if any yet, and its [`row_seed`].
    row: (Option<u32>, u32),
    /// Its centre in raster coordinates.
    centre: Vec2,
    run: PixelRun,
    /// The camera's rays made [`LANES`] at a time, when it is a kind the lanes cover.
    lanes: Option<LensLanes>,
    /// The pixels whose rays may meet the scene (all when `None`); the others' samples are
    /// [`Start::Background`].
    scene: Option<&'a PixelMask>,
    /// The frame's motion, when something in it moves (motion blur on): each sample draws its
    /// time, and a moving camera makes its rays one at a time at that time.
    motion: Option<&'a FrameMotion>,
    /// The weight of each traced sample of the last [`PrimarySamples::fill`]s, in the order of
    /// their `starts`, for a camera whose rays carry one (a lens prescription); empty for the
    /// others (weight 1).
    weights: Vec<f32>,
}

/// What a sample's camera gave: a traced ray, no ray, or a ray that provably leaves the scene
/// at once (its pixel lies outside [`PrimarySamples::with_scene`]'s pixels; not traced), or a
/// ray a lens prescription blocks (a black sample, counted).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Start {
    Traced,
    NoRay,
    Background,
    Black,
}

impl<'a> PrimarySamples<'a> {
    /// The samples of sequence `kind` under `seed`, index `sample_offset + i` for sample `i`,
    /// through `camera` and `filter`.
    pub fn new(
        camera: &Camera,
        filter: &'a Filter,
        kind: SamplerKind,
        seed: u32,
        sample_offset: u32,
    ) -> Self {
        Self {
            camera: *camera,
            lanes: LensLanes::new(camera),
            filter,
            seed,
            sample_offset,
            offset_rev: sample_offset.reverse_bits(),
            pixel: None,
            row: (None, 0),
            centre: Vec2::ZERO,
            run: PixelRun::new(kind, 0, 0),
            scene: None,
            motion: None,
            weights: Vec::new(),
        }
    }

    /// Samples at their time in the shutter of `motion` (when something moves in it).
    pub fn with_motion(self, motion: Option<&'a FrameMotion>) -> Self {
        let motion = motion.filter(|m| m.moves());
        Self {
            // The lanes make a still camera's rays.
            lanes: self
                .lanes
                .filter(|_| motion.is_none_or(|m| m.camera.is_none())),
            motion,
            ..self
        }
    }

    /// Samples of pixels outside `scene` become [`Start::Background`], without their numbers or
    /// rays (the caller knows those rays meet nothing: [`crate::background::scene_pixels`]).
    pub fn with_scene(self, scene: &'a PixelMask) -> Self {
        Self {
            scene: Some(scene),
            ..self
        }
    }

    /// The next item of `items` whose pixel may see the scene; the ones before it go to `run`
    /// as [`Start::Background`].
    #[inline(always)]
    fn next_in_scene<K>(
        &self,
        items: &mut impl Iterator<Item = (K, u32, u32, u32)>,
        run: &mut Vec<(K, Start)>,
    ) -> Option<(K, u32, u32, u32)> {
        loop {
            let item = items.next()?;
            if self.scene.is_none_or(|m| m.contains(item.1, item.2)) {
                return Some(item);
            }
            run.push((item.0, Start::Background));
        }
    }

    /// Takes items `(key, x, y, i)` from `items` until `n` of them are traced or none is left:
    /// appends each one's key and [`Start`] to `run`, and the ray (origin, unit direction) and
    /// stream of each traced one to `starts`.
    pub fn fill<K: Copy>(
        &mut self,
        items: &mut impl Iterator<Item = (K, u32, u32, u32)>,
        n: usize,
        run: &mut Vec<(K, Start)>,
        starts: &mut Vec<CameraStart>,
    ) {
        if self.camera.realistic.is_some() {
            return self.fill_weighted(items, n, run, starts);
        }
        let Some(lanes) = self.lanes else {
            for _ in 0..n {
                let Some((key, x, y, i)) = self.next_in_scene(items, run) else {
                    return;
                };
                let (stream, ray, time, channel) = self.sample_timed(x, y, i);
                let start = match &ray {
                    Some(r) => {
                        starts.push(CameraStart {
                            origin: r.origin,
                            dir: r.dir,
                            stream,
                            time,
                            channel,
                        });
                        Start::Traced
                    }
                    None => Start::NoRay,
                };
                run.push((key, start));
            }
            return;
        };
        // The usual camera: the rays of `LANES` samples at a time. Each lane's entry of `run`
        // is written when it is taken (background samples may follow it) and settled once its
        // ray is made.
        let mut left = n;
        loop {
            let (mut film, mut lens) = ([[0.0; LANES]; 2], [[0.0; LANES]; 2]);
            let mut taken: [Option<(usize, SampleStream)>; LANES] = [None; LANES];
            for (l, slot) in taken[..left.min(LANES)].iter_mut().enumerate() {
                let Some((key, x, y, i)) = self.next_in_scene(items, run) else {
                    break;
                };
                let (stream, p_film, p_lens) = self.numbers(x, y, i);
                (film[0][l], film[1][l]) = (p_film.x, p_film.y);
                (lens[0][l], lens[1][l]) = (p_lens.x, p_lens.y);
                *slot = Some((run.len(), stream));
                run.push((key, Start::Traced));
            }
            left = left.saturating_sub(LANES);
            let rays = lanes.rays(film, lens);
            let (o, d) = (&rays.origin, &rays.dir);
            for (l, slot) in taken.iter().enumerate() {
                // An empty lane: the items or the `n` ran out.
                let &Some((at, stream)) = slot else {
                    return;
                };
                if rays.made[l] {
                    let origin = Vec3::new(o[0][l], o[1][l], o[2][l]);
                    let time = self.time_of(&stream, film[1][l]);
                    // The lanes never take a lens with chromatic aberration: no channel.
                    starts.push(CameraStart {
                        origin,
                        dir: Vec3::new(d[0][l], d[1][l], d[2][l]),
                        stream,
                        time,
                        channel: None,
                    });
                } else {
                    run[at].1 = Start::NoRay;
                }
            }
            if left == 0 {
                return;
            }
        }
    }

    /// [`PrimarySamples::fill`] for a camera whose rays carry a weight (a lens prescription):
    /// one at a time, each traced sample's weight into [`PrimarySamples::weights`], a blocked
    /// ray a [`Start::Black`] sample.
    fn fill_weighted<K: Copy>(
        &mut self,
        items: &mut impl Iterator<Item = (K, u32, u32, u32)>,
        n: usize,
        run: &mut Vec<(K, Start)>,
        starts: &mut Vec<CameraStart>,
    ) {
        self.weights.truncate(starts.len());
        for _ in 0..n {
            let Some((key, x, y, i)) = self.next_in_scene(items, run) else {
                return;
            };
            let (stream, sample) = self.camera_sample(x, y, i);
            let time = sample.time;
            let ray = match self.motion.and_then(|m| m.camera.as_ref()) {
                Some(path) => path.camera_at(time).generate_ray_weighted(&sample),
                None => self.camera.generate_ray_weighted(&sample),
            };
            let start = match ray {
                Some((r, w)) => {
                    // A prescription traces its own glass: no channel.
                    starts.push(CameraStart {
                        origin: r.origin,
                        dir: r.dir,
                        stream,
                        time,
                        channel: None,
                    });
                    self.weights.push(w);
                    Start::Traced
                }
                None => Start::Black,
            };
            run.push((key, start));
        }
    }

    /// The weights of the traced samples of the last fills (see the field); empty: all 1.
    pub fn weights(&self) -> &[f32] {
        &self.weights
    }

    /// Sample `i` of pixel `(x, y)`: its stream and its camera ray (`None` when the camera
    /// makes none).
    #[inline(always)]
    #[cfg(test)]
    pub fn sample(&mut self, x: u32, y: u32, i: u32) -> (SampleStream, Option<CameraRay>) {
        let (stream, ray, _, _) = self.sample_timed(x, y, i);
        (stream, ray)
    }

    /// [`PrimarySamples::sample`] with the sample's normalised time in the shutter (0 without
    /// motion blur) and, under chromatic aberration, the colour channel its ray was made for.
    #[inline(always)]
    fn sample_timed(
        &mut self,
        x: u32,
        y: u32,
        i: u32,
    ) -> (SampleStream, Option<CameraRay>, f32, Option<u8>) {
        let (stream, sample) = self.camera_sample(x, y, i);
        // Chromatic aberration: the channel this path carries (the integrator weighs it),
        // drawn once here; green's ray is the plain one.
        let channel = self
            .camera
            .lens
            .chromatic
            .map(|_| crate::lens::channel_of(stream.wavelength(0)).0);
        let ray = match self.motion.and_then(|m| m.camera.as_ref()) {
            Some(path) => path.generate_ray_channel(&sample, channel.unwrap_or(1)),
            None => self
                .camera
                .generate_ray_channel(&sample, channel.unwrap_or(1)),
        };
        (stream, ray, sample.time, channel.map(|c| c as u8))
    }

    /// The numbers of sample `i` of pixel `(x, y)`: its stream, and its film point, lens point
    /// and normalised shutter time for the camera.
    #[inline(always)]
    fn camera_sample(&mut self, x: u32, y: u32, i: u32) -> (SampleStream, CameraSample) {
        let (stream, p_film, p_lens) = self.numbers(x, y, i);
        let time = self.time_of(&stream, p_film.y);
        let sample = CameraSample {
            p_film,
            p_lens,
            time,
        };
        (stream, sample)
    }

    /// The normalised shutter time of a sample at film row `row` (0 without motion blur: the
    /// time dimension is not even drawn).
    #[inline(always)]
    fn time_of(&self, stream: &SampleStream, row: f32) -> f32 {
        match self.motion {
            None => 0.0,
            Some(m) => m
                .shutter
                .normalised_time(stream.time(), row, self.camera.height),
        }
    }

    /// Sample `i` of pixel `(x, y)`: its stream and the numbers it gives the camera.
    #[inline(always)]
    fn numbers(&mut self, x: u32, y: u32, i: u32) -> (SampleStream, Vec2, Vec2) {
        let index = self.sample_offset.wrapping_add(i);
        if self.pixel == Some((x, y)) {
            self.run.seek(index);
        } else {
            self.pixel = Some((x, y));
            self.centre = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            if self.row.0 != Some(y) {
                self.row = (Some(y), row_seed(y, self.seed));
            }
            let seed = pixel_seed_in_row(x, self.row.1);
            // A pixel's first sample is almost always its first index: reversed once.
            let rev = if index == self.sample_offset {
                self.offset_rev
            } else {
                index.reverse_bits()
            };
            self.run.restart(seed, index, rev);
        }
        // The camera's 4-D point: pixel pair, lens pair (which a pinhole camera ignores).
        let (stream, c) = self.run.next();
        let p_lens = Vec2::new(c[2], c[3]);
        let offset = self.filter.sample([c[0], c[1]]);
        let p_film = Vec2::new(self.centre.x + offset.x, self.centre.y + offset.y);
        (stream, p_film, p_lens)
    }
}

/// Sample `(x, y, index)` under `seed` as drawn alone, the way every sample was drawn before
/// [`PrimarySamples`]: a fresh stream, its camera pair (a pinhole: its pixel pair), the
/// filter, the camera. The reference of this module's tests and of the renderer's.
#[cfg(test)]
pub(crate) fn drawn_alone(
    camera: &Camera,
    filter: &Filter,
    kind: SamplerKind,
    (x, y, index, seed): (u32, u32, u32, u32),
) -> (SampleStream, Option<CameraRay>) {
    let stream = SampleStream::new(kind, x, y, index, seed);
    let (u_film, p_lens) = if camera.aperture == crate::camera::Aperture::Pinhole {
        (stream.pixel(), Vec2::ZERO)
    } else {
        let c = stream.camera();
        ([c[0], c[1]], Vec2::new(c[2], c[3]))
    };
    let offset = filter.sample(u_film);
    let sample = CameraSample {
        p_film: Vec2::new(x as f32 + 0.5 + offset.x, y as f32 + 0.5 + offset.y),
        p_lens,
        time: 0.0,
    };
    (stream, camera.generate_ray(&sample))
}

#[cfg(test)]
mod tests;
