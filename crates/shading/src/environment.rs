//! The environment: a constant colour, or an equirectangular HDR image importance-sampled by
//! luminance and combined with BSDF sampling by multiple importance sampling.
//!
//! Mapping (Blender's equirectangular convention, turned into glTF's +Y up): the image centre
//! looks along +X, u grows towards +Z (`u = 0.5 + atan2(z, x) / 2π`), the top row is straight up
//! (`row = acos(y) / π`). `rotation` turns the environment counter-clockwise about +Y, seen from
//! above. For lighting, radiance is piecewise constant per texel (nearest lookup), exactly the
//! density the sampler draws from, so a texel is never sampled with the wrong weight; camera
//! rays that see the environment directly get a bilinear lookup.

use crate::color::luminance;
use crate::warp::AliasTable;
use glam::{Vec2, Vec3};
use std::f32::consts::{PI, TAU};
use std::sync::Arc;

/// How directions towards an environment image are drawn for next-event estimation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum EnvSampling {
    /// In proportion to texel luminance × solid angle (the default).
    #[default]
    Importance,
    /// Uniformly over the sphere (for comparisons; much noisier on bright small sources).
    Uniform,
}

/// An equirectangular environment image with its placement.
#[derive(Debug, Clone, PartialEq)]
pub struct EnvImage {
    /// Width in texels (≥ 1).
    pub width: u32,
    /// Height in texels (≥ 1).
    pub height: u32,
    /// Linear Rec.709 radiance, rows top (up) to bottom, `width * height` long.
    pub texels: Vec<Vec3>,
    /// Rotation about +Y in radians.
    pub rotation: f32,
    /// Multiplier on every texel.
    pub strength: f32,
    /// Next-event sampling strategy.
    pub sampling: EnvSampling,
}

/// What rays that leave the scene see.
#[derive(Debug, Clone, PartialEq)]
pub enum Environment {
    /// Uniform radiance (linear RGB); black by default (SPEC §4).
    Constant(Vec3),
    /// An equirectangular image.
    Image(Arc<EnvImage>),
}

impl Default for Environment {
    fn default() -> Self {
        Self::Constant(Vec3::ZERO)
    }
}

impl Environment {
    /// Why the environment cannot be rendered, if it cannot.
    pub fn problem(&self) -> Option<String> {
        match self {
            Self::Constant(c) => (!c.is_finite() || c.min_element() < 0.0)
                .then(|| format!("colour {c} must be finite and ≥ 0")),
            Self::Image(im) => {
                if im.width == 0 || im.height == 0 {
                    Some("the image has no texels".into())
                } else if im.texels.len() != im.width as usize * im.height as usize {
                    Some(format!(
                        "{} texels for a {}×{} image",
                        im.texels.len(),
                        im.width,
                        im.height
                    ))
                } else if !im.strength.is_finite() || im.strength < 0.0 {
                    Some(format!("strength {} must be finite and ≥ 0", im.strength))
                } else if !im.rotation.is_finite() {
                    Some(format!("rotation {} must be finite", im.rotation))
                } else {
                    None
                }
            }
        }
    }
}

/// A direction drawn towards the environment.
#[derive(Debug, Clone, Copy)]
pub struct EnvSample {
    /// Unit world direction.
    pub wi: Vec3,
    /// Radiance arriving from it.
    pub radiance: Vec3,
    /// Solid-angle density.
    pub pdf: f32,
}

/// The environment prepared for rendering.
#[derive(Debug)]
pub enum EnvLight {
    /// Constant radiance: found by BSDF sampling only.
    Constant(Vec3),
    /// An image with its sampling tables.
    Image(ImageLight),
}

#[derive(Debug)]
/// An equirectangular image as a light: the image, its texel distribution and rotation.
pub struct ImageLight {
    image: Arc<EnvImage>,
    /// Texel distribution (`None` for uniform sampling or an all-black image).
    table: Option<AliasTable>,
    /// sin/cos of the rotation.
    rot: Vec2,
}

impl EnvLight {
    /// Prepares `env`, which must have passed [`Environment::problem`].
    pub fn new(env: &Environment) -> Self {
        match env {
            Environment::Constant(c) => Self::Constant(*c),
            Environment::Image(im) => {
                let (w, h) = (im.width as usize, im.height as usize);
                let table = (im.sampling == EnvSampling::Importance)
                    .then(|| {
                        // Texel power: luminance × solid angle.
                        let weights: Vec<f64> = (0..w * h)
                            .map(|i| {
                                let omega = texel_solid_angle(im.width, im.height, i / w);
                                let l = luminance(im.texels[i]);
                                if l.is_finite() && l > 0.0 {
                                    (l * omega) as f64
                                } else {
                                    0.0
                                }
                            })
                            .collect();
                        let total: f64 = weights.iter().sum();
                        (total > 0.0 && total.is_finite()).then(|| AliasTable::new(&weights))
                    })
                    .flatten();
                let (s, c) = im.rotation.sin_cos();
                Self::Image(ImageLight {
                    image: im.clone(),
                    table,
                    rot: Vec2::new(s, c),
                })
            }
        }
    }

    /// True when next-event estimation samples the environment (then BSDF-sampled rays that
    /// escape are MIS-weighted against [`EnvLight::pdf`]).
    pub fn is_sampled(&self) -> bool {
        matches!(self, Self::Image(_))
    }

    /// Radiance arriving along `-dir` from the environment (`dir` unit, pointing away from
    /// the scene).
    pub fn radiance(&self, dir: Vec3) -> Vec3 {
        match self {
            Self::Constant(c) => *c,
            Self::Image(im) => {
                let (x, y) = im.texel_of(dir);
                im.texel(x, y)
            }
        }
    }

    /// Radiance seen directly by a camera ray: bilinearly filtered (as Blender's environment
    /// texture), so a low-resolution map does not show its texels behind the scene. Camera
    /// rays are not weighted by MIS, so filtering them differently from what light sampling
    /// integrates costs nothing in correctness.
    pub fn radiance_seen(&self, dir: Vec3) -> Vec3 {
        match self {
            Self::Constant(c) => *c,
            Self::Image(im) => im.bilinear(dir),
        }
    }

    /// Solid-angle density with which [`EnvLight::sample`] draws `dir`.
    pub fn pdf(&self, dir: Vec3) -> f32 {
        match self {
            Self::Constant(_) => 0.0,
            Self::Image(im) => match &im.table {
                None => 1.0 / (4.0 * PI),
                Some(t) => {
                    let (x, y) = im.texel_of(dir);
                    let i = y * im.image.width as usize + x;
                    im.texel_pdf(t.pmf(i), y)
                }
            },
        }
    }

    /// Draws a direction towards the environment from two uniform numbers.
    pub fn sample(&self, u: [f32; 2]) -> Option<EnvSample> {
        let Self::Image(im) = self else {
            return None;
        };
        let (w, h) = (im.image.width as usize, im.image.height as usize);
        match &im.table {
            None => {
                // Uniform sphere.
                let z = 1.0 - 2.0 * u[0];
                let r = (1.0 - z * z).max(0.0).sqrt();
                let phi = TAU * u[1];
                let wi = Vec3::new(r * phi.cos(), z, r * phi.sin());
                Some(EnvSample {
                    wi,
                    radiance: self.radiance(wi),
                    pdf: 1.0 / (4.0 * PI),
                })
            }
            Some(t) => {
                // u[0] picks the texel; what the pick leaves of it and u[1] place the point.
                let (i, fx) = t.sample_remap(u[0]);
                let (x, y) = (i % w, i / w);
                // Kept off the texel's edges, where rounding in the inverse mapping could name
                // the neighbour and pair this texel's density with another's radiance.
                let su = (x as f32 + fx.clamp(1e-3, 1.0 - 1e-3)) / w as f32;
                let phi = TAU * (su - 0.5);
                // Uniform in cos θ between the row's edges: uniform in solid angle.
                let c0 = (y as f32 / h as f32 * PI).cos();
                let c1 = ((y + 1) as f32 / h as f32 * PI).cos();
                let ct = c0 + (c1 - c0) * u[1].clamp(1e-3, 1.0 - 1e-3);
                let st = (1.0 - ct * ct).max(0.0).sqrt();
                let local = Vec3::new(st * phi.cos(), ct, st * phi.sin());
                let wi = im.to_world(local);
                let pdf = im.texel_pdf(t.pmf(i), y);
                (pdf > 0.0 && pdf.is_finite()).then(|| EnvSample {
                    wi,
                    radiance: im.texel(x, y),
                    pdf,
                })
            }
        }
    }
}

impl ImageLight {
    fn texel(&self, x: usize, y: usize) -> Vec3 {
        self.image.texels[y * self.image.width as usize + x] * self.image.strength
    }

    /// Environment-local direction (before rotation) from a world direction.
    fn to_local(&self, d: Vec3) -> Vec3 {
        // Rotating the environment by +θ about +Y means looking up the world direction
        // rotated by −θ.
        let (s, c) = (self.rot.x, self.rot.y);
        Vec3::new(c * d.x - s * d.z, d.y, s * d.x + c * d.z)
    }

    fn to_world(&self, l: Vec3) -> Vec3 {
        let (s, c) = (self.rot.x, self.rot.y);
        Vec3::new(c * l.x + s * l.z, l.y, -s * l.x + c * l.z)
    }

    /// Bilinear lookup: u wraps around, v clamps at the poles.
    fn bilinear(&self, dir: Vec3) -> Vec3 {
        let d = self.to_local(dir);
        let (w, h) = (self.image.width as i64, self.image.height as i64);
        let u = 0.5 + d.z.atan2(d.x) / TAU;
        let v = d.y.clamp(-1.0, 1.0).acos() / PI;
        if !(u.is_finite() && v.is_finite()) {
            return self.texel(0, 0);
        }
        let x = u * w as f32 - 0.5;
        let y = v * h as f32 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let at =
            |xi: i64, yi: i64| self.texel(xi.rem_euclid(w) as usize, yi.clamp(0, h - 1) as usize);
        let top = at(x0, y0).lerp(at(x0 + 1, y0), fx);
        let bottom = at(x0, y0 + 1).lerp(at(x0 + 1, y0 + 1), fx);
        top.lerp(bottom, fy)
    }

    /// The texel a world direction falls in.
    fn texel_of(&self, dir: Vec3) -> (usize, usize) {
        let d = self.to_local(dir);
        let (w, h) = (self.image.width as usize, self.image.height as usize);
        let u = 0.5 + d.z.atan2(d.x) / TAU;
        let v = d.y.clamp(-1.0, 1.0).acos() / PI;
        let x = ((u * w as f32) as isize).clamp(0, w as isize - 1) as usize;
        let y = ((v * h as f32) as isize).clamp(0, h as isize - 1) as usize;
        if u.is_nan() || v.is_nan() {
            return (0, 0);
        }
        (x, y)
    }

    /// Solid-angle density of a direction inside texel row `y` picked with probability `pmf`.
    /// Directions are drawn uniformly in solid angle within the texel (uniform in φ and in
    /// cos θ), so the density is the pick probability over the texel's solid angle, exactly.
    fn texel_pdf(&self, pmf: f32, y: usize) -> f32 {
        let omega = texel_solid_angle(self.image.width, self.image.height, y);
        if omega > 0.0 {
            pmf / omega
        } else {
            0.0
        }
    }
}

/// Solid angle of a texel in row `y` of a `w × h` equirectangular image:
/// (2π / w) · (cos θ_top − cos θ_bottom).
fn texel_solid_angle(w: u32, h: u32, y: usize) -> f32 {
    let t0 = y as f32 / h as f32 * PI;
    let t1 = (y + 1) as f32 / h as f32 * PI;
    TAU / w as f32 * (t0.cos() - t1.cos())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(w: u32, h: u32, f: impl Fn(u32, u32) -> Vec3, sampling: EnvSampling) -> EnvLight {
        EnvLight::new(&Environment::Image(Arc::new(EnvImage {
            width: w,
            height: h,
            texels: (0..w * h).map(|i| f(i % w, i / w)).collect(),
            rotation: 0.7,
            strength: 2.0,
            sampling,
        })))
    }

    #[test]
    fn mapping_matches_blender() {
        let mut im = ImageLight {
            image: Arc::new(EnvImage {
                width: 4,
                height: 2,
                texels: vec![Vec3::ONE; 8],
                rotation: 0.0,
                strength: 1.0,
                sampling: EnvSampling::Uniform,
            }),
            table: None,
            rot: Vec2::new(0.0, 1.0),
        };
        // The image centre (column 2) looks along +X; row 0 is the upper hemisphere.
        assert_eq!(im.texel_of(Vec3::new(1.0, 0.1, 0.01).normalize()), (2, 0));
        assert_eq!(im.texel_of(Vec3::new(1.0, -0.1, 0.01).normalize()), (2, 1));
        // u grows towards +Z; −X is the left edge.
        assert_eq!(im.texel_of(Vec3::new(-0.3, 0.1, 1.0).normalize()), (3, 0));
        assert_eq!(im.texel_of(Vec3::new(-1.0, 0.1, -0.01).normalize()), (0, 0));
        // Rotated by 90° about +Y (right hand): the centre moves from +X to −Z.
        im.rot = Vec2::new(1.0, 0.0);
        assert_eq!(im.texel_of(Vec3::new(0.01, 0.1, -1.0).normalize()), (2, 0));
        let d = Vec3::new(0.3, -0.5, 0.8).normalize();
        assert!((im.to_world(im.to_local(d)) - d).length() < 1e-6);
    }

    #[test]
    fn camera_rays_see_a_bilinear_map() {
        let e = image(4, 2, |x, _| Vec3::splat(x as f32), EnvSampling::Importance);
        let EnvLight::Image(im) = &e else {
            unreachable!()
        };
        // Texel values are 2 × column (strength 2). At column 1's centre: 2; halfway between
        // columns 1 and 2: their mean, 3.
        let dir = |u: f32, v: f32| {
            let (phi, theta) = (TAU * (u - 0.5), v * PI);
            im.to_world(Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            ))
        };
        let centre = e.radiance_seen(dir(1.5 / 4.0, 0.25));
        assert!(
            (centre - Vec3::splat(2.0)).abs().max_element() < 1e-4,
            "{centre}"
        );
        let between = e.radiance_seen(dir(0.5, 0.25));
        assert!(
            (between - Vec3::splat(3.0)).abs().max_element() < 1e-4,
            "{between}"
        );
        // u wraps: between the last column (3) and the first (0).
        let wrap = e.radiance_seen(dir(0.999, 0.25));
        // Clamping would give the last column's 6 here.
        assert!(wrap.x > 2.0 && wrap.x < 4.0, "{wrap}");
    }

    /// pdf() agrees with what sample() draws, and the density integrates to 1 over the sphere.
    #[test]
    fn importance_sampling_is_consistent() {
        let e = image(
            16,
            8,
            |x, y| {
                if (x, y) == (3, 2) {
                    Vec3::splat(500.0)
                } else {
                    Vec3::new(0.1 * x as f32, 0.2, 0.05 * y as f32)
                }
            },
            EnvSampling::Importance,
        );
        let n = 256;
        let mut hits_bright = 0;
        let mut est = 0.0f64;
        // u[0] stratified finely (it picks the texel), u[1] a golden-ratio sequence.
        for k in 0..n * n {
            {
                let u = [
                    (k as f32 + 0.5) / (n * n) as f32,
                    (k as f32 * 0.618_034).fract(),
                ];
                let s = e.sample(u).unwrap();
                assert!((s.wi.length() - 1.0).abs() < 1e-4);
                let p = e.pdf(s.wi);
                assert!((p - s.pdf).abs() <= 1e-3 * s.pdf, "{p} vs {}", s.pdf);
                assert_eq!(e.radiance(s.wi), s.radiance);
                if s.radiance.x > 100.0 {
                    hits_bright += 1;
                }
                // E[1/pdf] = area of the support.
                est += 1.0 / s.pdf as f64;
            }
        }
        let frac = hits_bright as f64 / (n * n) as f64;
        assert!(frac > 0.9 && frac < 0.99, "bright texel drawn {frac}");
        let area = est / (n * n) as f64;
        assert!(
            (area - 4.0 * PI as f64).abs() < 0.05 * 4.0 * PI as f64,
            "{area}"
        );
        // Uniform quadrature of the pdf over the sphere integrates to 1.
        let m = 400;
        let mut sum = 0.0f64;
        for i in 0..m {
            for j in 0..m {
                let z = 1.0 - 2.0 * (i as f32 + 0.5) / m as f32;
                let r = (1.0 - z * z).sqrt();
                let phi = TAU * (j as f32 + 0.5) / m as f32;
                sum += e.pdf(Vec3::new(r * phi.cos(), z, r * phi.sin())) as f64;
            }
        }
        let integral = sum * 4.0 * PI as f64 / (m * m) as f64;
        assert!((integral - 1.0).abs() < 0.02, "{integral}");
    }

    #[test]
    fn bad_environments_are_reported() {
        assert!(Environment::Constant(Vec3::new(-1.0, 0.0, 0.0))
            .problem()
            .is_some());
        let bad = EnvImage {
            width: 2,
            height: 2,
            texels: vec![Vec3::ONE; 3],
            rotation: 0.0,
            strength: 1.0,
            sampling: EnvSampling::Importance,
        };
        assert!(Environment::Image(Arc::new(bad.clone()))
            .problem()
            .is_some());
        let nan = EnvImage {
            texels: vec![Vec3::ONE; 4],
            strength: f32::NAN,
            ..bad
        };
        assert!(Environment::Image(Arc::new(nan)).problem().is_some());
    }
}
