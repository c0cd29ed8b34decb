//! The bokeh image (`aperture_image`): the aperture's transmission as an image over the square
//! circumscribing the aperture's circle, importance-sampled from its luminance and limited by
//! the stop (the round aperture, or the blades' polygon), turned by `aperture_rotation` (the
//! camera squeezes it by `aperture_ratio` as it squeezes the plain aperture).
//!
//! The sampling tables live as long as the process, one per image, rotation and blade count
//! (interned by content): the camera stays `Copy` and holds a reference to them.

use aperture_scene::Dof;
use aperture_shading::warp_image::ImageDistribution;
use aperture_shading::warp_lens::first_inside;
use glam::Vec2;
use std::collections::HashMap;
use std::f32::consts::{PI, TAU};
use std::sync::Mutex;

/// A bokeh image ready to sample.
#[derive(Debug)]
pub struct Bokeh {
    /// The image's texels masked by the stop's circle, over `[0, 1]²` (y down).
    dist: ImageDistribution,
    /// `(sin, cos)` of `aperture_rotation`.
    rot: Vec2,
    /// Unit normals of the blades' edges in the lens plane (empty: the round stop).
    edges: Vec<Vec2>,
    /// The edges' distance from the centre: `cos(π / blades)`.
    apothem: f32,
}

/// A camera's reference to its [`Bokeh`]: equal when it is the same table.
#[derive(Clone, Copy)]
pub struct BokehRef(&'static Bokeh);

impl PartialEq for BokehRef {
    fn eq(&self, other: &Self) -> bool {
        std::ptr::eq(self.0, other.0)
    }
}

impl std::fmt::Debug for BokehRef {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (w, h) = self.0.dist.size();
        write!(f, "Bokeh({w}x{h}, {} blades)", self.0.edges.len())
    }
}

impl std::ops::Deref for BokehRef {
    type Target = Bokeh;
    fn deref(&self) -> &Bokeh {
        self.0
    }
}

/// Tables made so far, by image hash, rotation bits and blade count.
type Interned = HashMap<(u64, u32, u32), Option<&'static Bokeh>>;

impl Bokeh {
    /// The bokeh image of `dof`; `None` (the plain aperture's sampler, bit for bit) without an
    /// image, for a constant one, for a pinhole, or when no light passes inside the stop.
    pub fn of(dof: &Dof) -> Option<BokehRef> {
        let image = dof.lens_options.aperture_image.as_deref()?;
        if image.is_constant() || dof.effective_radius() <= 0.0 {
            return None;
        }
        let blades = if dof.blades >= 3 { dof.blades } else { 0 };
        static TABLES: Mutex<Option<Interned>> = Mutex::new(None);
        let key = (image.hash, dof.rotation.to_bits(), blades);
        let mut tables = TABLES.lock().unwrap_or_else(|e| e.into_inner());
        let made = tables
            .get_or_insert_with(HashMap::new)
            .entry(key)
            .or_insert_with(|| {
                let b = Self::new(image, dof.rotation, blades)?;
                Some(&*Box::leak(Box::new(b)))
            });
        made.map(BokehRef)
    }

    fn new(image: &aperture_scene::ApertureImage, rotation: f32, blades: u32) -> Option<Self> {
        let (w, h) = (image.width as usize, image.height as usize);
        // Texels wholly outside the stop's circle never pass: left out of the tables.
        let weights: Vec<f32> = (image.luminance.iter().enumerate())
            .map(|(i, &l)| {
                let (x, y) = ((i % w) as f32, (i / w) as f32);
                let lo = Vec2::new(2.0 * x / w as f32 - 1.0, 2.0 * y / h as f32 - 1.0);
                let hi = Vec2::new(
                    2.0 * (x + 1.0) / w as f32 - 1.0,
                    2.0 * (y + 1.0) / h as f32 - 1.0,
                );
                let nearest = Vec2::ZERO.clamp(lo, hi);
                if nearest.length_squared() <= 1.0 {
                    l
                } else {
                    0.0
                }
            })
            .collect();
        let edges = (0..blades)
            .map(|k| {
                let a = rotation + TAU * k as f32 / blades as f32;
                Vec2::new(a.cos(), a.sin())
            })
            .collect();
        let (s, c) = rotation.sin_cos();
        Some(Self {
            dist: ImageDistribution::new(w, h, &weights)?,
            rot: Vec2::new(s, c),
            edges,
            apothem: if blades >= 3 {
                (PI / blades as f32).cos()
            } else {
                1.0
            },
        })
    }

    /// The image's point for `v ∈ [0, 1)²`, turned, in aperture radii (x right, y up).
    #[inline]
    fn point(&self, v: Vec2) -> Vec2 {
        let q = self.dist.sample(v);
        let p = Vec2::new(2.0 * q.x - 1.0, 1.0 - 2.0 * q.y);
        let (s, c) = (self.rot.x, self.rot.y);
        Vec2::new(c * p.x - s * p.y, s * p.x + c * p.y)
    }

    /// Whether `p` (aperture radii) passes the stop: the unit circle, or the blades' polygon
    /// inscribed in it.
    #[inline]
    fn in_stop(&self, p: Vec2) -> bool {
        const SLACK: f32 = 1.0 + 1e-6;
        if self.edges.is_empty() {
            p.length_squared() <= SLACK
        } else {
            self.edges.iter().all(|n| n.dot(p) <= self.apothem * SLACK)
        }
    }

    /// A lens point for `u ∈ [0, 1)²` in aperture radii (before the squeeze), distributed as
    /// the image's transmission over the stop, clipped by the lens barrel when `barrel` (its
    /// centre; the barrel has the aperture's radius) is given. Rejection with retries hashed
    /// from `u`, so the point is a pure function of `u`; when 64 draws miss (a barrel that
    /// barely meets the image's light) the middle of the stop and the barrel.
    #[inline]
    pub fn sample(&self, u: Vec2, barrel: Option<Vec2>) -> Vec2 {
        let inside = |p: Vec2| {
            self.in_stop(p) && barrel.is_none_or(|c| (p - c).length_squared() <= 1.0 + 2e-6)
        };
        match first_inside(u, |v| self.point(v), inside) {
            (p, true) => p,
            (_, false) => barrel.map_or(Vec2::ZERO, |c| 0.5 * c),
        }
    }
}
