//! The film: per-pixel sums in f64, resolved to RGBA f32 (A = coverage).
//!
//! Samples are weighted 1 and land in their own pixel (filter importance sampling), so the film
//! only sums. A sample whose radiance is NaN or infinite is dropped and counted, never summed.

use glam::Vec3;

/// Sums of one pixel.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PixelSum {
    /// Sum of radiance.
    pub rgb: [f64; 3],
    /// Number of samples whose primary ray hit geometry.
    pub hits: f64,
    /// Number of samples summed (dropped ones excluded).
    pub count: f64,
}

impl PixelSum {
    /// Adds one finite sample. Returns false (and adds nothing) when `l` is not finite.
    pub fn add(&mut self, l: Vec3, hit: bool) -> bool {
        if !l.is_finite() {
            return false;
        }
        self.rgb[0] += l.x as f64;
        self.rgb[1] += l.y as f64;
        self.rgb[2] += l.z as f64;
        self.hits += f64::from(u8::from(hit));
        self.count += 1.0;
        true
    }

    /// The pixel's mean radiance and coverage.
    pub fn resolve(&self) -> [f32; 4] {
        if self.count == 0.0 {
            return [0.0; 4];
        }
        let inv = 1.0 / self.count;
        [
            (self.rgb[0] * inv) as f32,
            (self.rgb[1] * inv) as f32,
            (self.rgb[2] * inv) as f32,
            (self.hits * inv) as f32,
        ]
    }
}

/// A rendered image before output: sums per pixel plus counters.
#[derive(Debug, Clone, PartialEq)]
pub struct Film {
    width: u32,
    height: u32,
    pixels: Vec<PixelSum>,
    /// Samples each pixel took, dropped ones included (all `spp` unless sampling was adaptive).
    taken: Vec<u32>,
    dropped: u64,
}

impl Film {
    /// An empty film.
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            pixels: vec![PixelSum::default(); width as usize * height as usize],
            taken: vec![0; width as usize * height as usize],
            dropped: 0,
        }
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Samples dropped because their radiance was NaN or infinite.
    pub fn dropped_samples(&self) -> u64 {
        self.dropped
    }

    /// The sums of pixel `(x, y)` (row 0 at the top).
    pub fn pixel_sum(&self, x: u32, y: u32) -> &PixelSum {
        &self.pixels[y as usize * self.width as usize + x as usize]
    }

    /// Samples pixel `(x, y)` took, dropped ones included: the render's `spp`, or fewer where
    /// adaptive sampling stopped it early.
    pub fn samples_taken(&self, x: u32, y: u32) -> u32 {
        self.taken[y as usize * self.width as usize + x as usize]
    }

    /// Samples taken per pixel, rows top to bottom (the `samples` pass).
    pub fn samples_per_pixel(&self) -> &[u32] {
        &self.taken
    }

    /// Samples taken over the whole image, dropped ones included.
    pub fn total_samples(&self) -> u64 {
        self.taken.iter().map(|&n| u64::from(n)).sum()
    }

    /// Mean RGBA of pixel `(x, y)`; A is the fraction of primary rays that hit geometry.
    pub fn pixel(&self, x: u32, y: u32) -> [f32; 4] {
        self.pixel_sum(x, y).resolve()
    }

    /// Every pixel resolved, rows top to bottom.
    pub fn to_rgba(&self) -> Vec<[f32; 4]> {
        self.pixels.iter().map(PixelSum::resolve).collect()
    }

    /// Copies a finished tile in. Tiles own disjoint pixels, so the order of calls does not
    /// change the result; the renderer still merges in a fixed order.
    pub(crate) fn merge_tile(
        &mut self,
        x0: u32,
        y0: u32,
        w: u32,
        sums: &[PixelSum],
        taken: u32,
        dropped: u64,
    ) {
        for (row, chunk) in sums.chunks(w as usize).enumerate() {
            let start = (y0 as usize + row) * self.width as usize + x0 as usize;
            self.pixels[start..start + chunk.len()].copy_from_slice(chunk);
            self.taken[start..start + chunk.len()].fill(taken);
        }
        self.dropped += dropped;
    }

    /// Mutable sums and sample counts of every pixel, for the adaptive renderer's rounds.
    pub(crate) fn state_mut(&mut self) -> (&mut [PixelSum], &mut [u32], &mut u64) {
        (&mut self.pixels, &mut self.taken, &mut self.dropped)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn non_finite_samples_are_dropped() {
        let mut p = PixelSum::default();
        assert!(p.add(Vec3::new(1.0, 2.0, 3.0), true));
        assert!(!p.add(Vec3::new(f32::NAN, 0.0, 0.0), true));
        assert!(!p.add(Vec3::new(0.0, f32::INFINITY, 0.0), false));
        assert!(p.add(Vec3::new(3.0, 2.0, 1.0), false));
        assert_eq!(p.resolve(), [2.0, 2.0, 2.0, 0.5]);
    }

    #[test]
    fn tiles_land_where_they_belong() {
        let mut f = Film::new(4, 3);
        let mut s = PixelSum::default();
        s.add(Vec3::ONE, true);
        f.merge_tile(
            2,
            1,
            2,
            &[s, PixelSum::default(), PixelSum::default(), s],
            7,
            5,
        );
        assert_eq!(f.pixel(2, 1), [1.0; 4]);
        assert_eq!(f.pixel(3, 2), [1.0; 4]);
        assert_eq!(f.pixel(3, 1), [0.0; 4]);
        assert_eq!(f.pixel(0, 0), [0.0; 4]);
        assert_eq!(f.dropped_samples(), 5);
        assert_eq!(f.samples_taken(3, 2), 7);
        assert_eq!(f.samples_taken(0, 0), 0);
        assert_eq!(f.total_samples(), 4 * 7);
    }
}
