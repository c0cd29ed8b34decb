//! The film: per-pixel sums in f64 of a window of the image, for the beauty and for whatever
//! the requested passes need; resolved to means at output.
//!
//! Samples are weighted 1 and land in their own pixel (filter importance sampling), so the film
//! only sums, and every averaged pass goes through the same filter as the beauty. A sample
//! whose radiance is NaN or infinite is dropped and counted, never summed, in every pass.

use crate::aov::{self, SampleAov};
use crate::cryptomatte::CryptoPixel;
use crate::passes::{Pass, PassSet};
use glam::Vec3;

/// Sums of one pixel.
#[derive(Debug, Clone, Copy, Default, PartialEq, bytemuck::Zeroable)]
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
    #[inline]
    pub fn add(&mut self, l: Vec3, hit: bool) -> bool {
        // One vector test instead of three scalar ones (the same answer).
        if !glam::Vec3A::from(l).is_finite() {
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

/// A rectangle of pixels of the image: `x0 ≤ x < x0 + width`, `y0 ≤ y < y0 + height` (x right,
/// y down).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Window {
    /// First column.
    pub x0: u32,
    /// First row.
    pub y0: u32,
    /// Columns.
    pub width: u32,
    /// Rows.
    pub height: u32,
}

impl Window {
    /// The whole `width × height` image.
    pub fn whole(width: u32, height: u32) -> Self {
        Self {
            x0: 0,
            y0: 0,
            width,
            height,
        }
    }

    /// Pixels in the window.
    pub fn pixels(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// The window grown by `by` pixels on every side, kept inside a `w × h` image.
    pub fn grown(&self, by: u32, w: u32, h: u32) -> Self {
        let x0 = self.x0.saturating_sub(by);
        let y0 = self.y0.saturating_sub(by);
        let x1 = (self.x0 + self.width).saturating_add(by).min(w);
        let y1 = (self.y0 + self.height).saturating_add(by).min(h);
        Self {
            x0,
            y0,
            width: x1 - x0,
            height: y1 - y0,
        }
    }

    /// The window from `x0` to `x1` and `y0` to `y1`, half-open (pbrt's `--pixelbounds`,
    /// SPEC §8's `--region`); `None` unless `x0 < x1` and `y0 < y1`.
    pub fn from_corners(x0: u32, y0: u32, x1: u32, y1: u32) -> Option<Self> {
        (x0 < x1 && y0 < y1).then(|| Self {
            x0,
            y0,
            width: x1 - x0,
            height: y1 - y0,
        })
    }

    /// One past the last column and row: `(x1, y1)`.
    pub fn end(&self) -> (u32, u32) {
        (self.x0 + self.width, self.y0 + self.height)
    }

    /// Band `k` of `n` of a `w × h` image (`--tile K/N`, 0-based as Slurm array and Kubernetes
    /// indexed-job indices are): whole rows `⌊k·h/n⌋ .. ⌊(k+1)·h/n⌋`, so the bands tile the
    /// image and differ in height by at most one row. `None` unless `k < n ≤ h`.
    pub fn band(k: u32, n: u32, w: u32, h: u32) -> Option<Self> {
        if k >= n || n > h || w == 0 {
            return None;
        }
        let row = |k: u32| (u64::from(k) * u64::from(h) / u64::from(n)) as u32;
        Self::from_corners(0, row(k), w, row(k + 1))
    }

    /// True when the two windows share a pixel.
    pub fn overlaps(&self, other: &Window) -> bool {
        let (ax1, ay1) = self.end();
        let (bx1, by1) = other.end();
        self.x0 < bx1 && other.x0 < ax1 && self.y0 < by1 && other.y0 < ay1
    }

    /// True when the window lies inside a `w × h` image and holds a pixel.
    pub fn fits(&self, w: u32, h: u32) -> bool {
        self.width > 0
            && self.height > 0
            && u64::from(self.x0) + u64::from(self.width) <= u64::from(w)
            && u64::from(self.y0) + u64::from(self.height) <= u64::from(h)
    }
}

/// Which averaged quantities are summed per sample, and where in a pixel's `f64` sums.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct AovLayout {
    /// Offset of the normal sum, if summed.
    pub normal: Option<usize>,
    /// Offset of the denoising albedo.
    pub albedo: Option<usize>,
    /// Offset of the denoising normal (world space).
    pub denoising_normal: Option<usize>,
    /// Offset of the eleven light passes (three values each), if any is asked for.
    pub light: Option<usize>,
    /// Values per pixel.
    pub stride: usize,
    /// Cryptomatte of objects.
    pub crypto_object: bool,
    /// Cryptomatte of materials.
    pub crypto_material: bool,
}

impl AovLayout {
    /// The sums `passes` need.
    pub fn new(passes: PassSet) -> Self {
        let mut stride = 0;
        let mut take = |on: bool, n: usize| {
            on.then(|| {
                stride += n;
                stride - n
            })
        };
        let normal = take(passes.contains(Pass::Normal), 3);
        let albedo = take(passes.contains(Pass::DenoisingAlbedo), 3);
        let denoising_normal = take(passes.contains(Pass::DenoisingNormal), 3);
        let light = take(passes.has_light_passes(), 33);
        Self {
            normal,
            albedo,
            denoising_normal,
            light,
            stride,
            crypto_object: passes.contains(Pass::CryptoObject),
            crypto_material: passes.contains(Pass::CryptoMaterial),
        }
    }

    /// True when samples must record more than their radiance.
    pub fn records(&self) -> bool {
        self.stride > 0 || self.crypto_object || self.crypto_material
    }
}

/// Cryptomatte IDs (float bits) of each instance's node and of each material.
#[derive(Debug, Clone, Default)]
pub struct CryptoIds {
    /// By instance: the ID of its node's name (empty when the pass is off).
    pub object: Vec<u32>,
    /// By material: the ID of its name (empty when the pass is off).
    pub material: Vec<u32>,
}

/// Per-pixel accumulators of a set of pixels: the beauty and whatever the passes need.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Accum {
    /// Where each pass sits in a pixel's `aov` values.
    pub layout: AovLayout,
    /// Each pixel's beauty sum.
    pub sums: Vec<PixelSum>,
    /// Each pixel's pass sums, `layout.stride` values a pixel.
    pub aov: Vec<f64>,
    /// Each pixel's Cryptomatte object coverage.
    pub crypto_object: Vec<CryptoPixel>,
    /// Each pixel's Cryptomatte material coverage.
    pub crypto_material: Vec<CryptoPixel>,
}

impl Accum {
    /// Empty accumulators for `n` pixels: what [`Accum::reset`] makes, in zeroed allocations,
    /// so that a film's pages are first touched when its tiles land (by whichever thread
    /// merges them) rather than all at once before any tile starts: writing the 3 MB of a
    /// 320 × 240 film took 1 ms on one thread while the other waited.
    pub fn new(n: usize, layout: AovLayout) -> Self {
        let crypto = |on: bool| bytemuck::zeroed_vec(if on { n } else { 0 });
        Self {
            layout,
            sums: bytemuck::zeroed_vec(n),
            aov: vec![0.0; n * layout.stride],
            crypto_object: crypto(layout.crypto_object),
            crypto_material: crypto(layout.crypto_material),
        }
    }

    /// Makes these accumulators empty ones for `n` pixels of `layout` (what [`Accum::new`]
    /// makes), keeping their allocations.
    pub fn reset(&mut self, n: usize, layout: AovLayout) {
        self.layout = layout;
        self.sums.clear();
        self.sums.resize(n, PixelSum::default());
        self.aov.clear();
        self.aov.resize(n * layout.stride, 0.0);
        self.crypto_object.clear();
        self.crypto_object.resize(
            if layout.crypto_object { n } else { 0 },
            CryptoPixel::default(),
        );
        self.crypto_material.clear();
        self.crypto_material.resize(
            if layout.crypto_material { n } else { 0 },
            CryptoPixel::default(),
        );
    }

    /// Adds sample radiance `l` (coverage `hit`) and its pass record to pixel `k`. Returns
    /// false, adding nothing anywhere, when the radiance is not finite (a dropped sample).
    #[inline]
    pub fn add(&mut self, k: usize, l: Vec3, hit: bool, rec: &SampleAov, ids: &CryptoIds) -> bool {
        if !self.layout.records() {
            return self.add_radiance(k, l, hit);
        }
        if !self.sums[k].add(l, hit) {
            return false;
        }
        let lay = self.layout;
        if lay.stride > 0 {
            let sums = &mut self.aov[k * lay.stride..(k + 1) * lay.stride];
            let mut put = |at: Option<usize>, v: Vec3| {
                if let Some(o) = at {
                    sums[o] += f64::from(v.x);
                    sums[o + 1] += f64::from(v.y);
                    sums[o + 2] += f64::from(v.z);
                }
            };
            put(lay.normal, rec.normal);
            put(lay.albedo, rec.albedo);
            put(lay.denoising_normal, rec.denoising_normal);
            if let Some(o) = lay.light {
                for (i, v) in rec.light.iter().enumerate() {
                    put(Some(o + 3 * i), *v);
                }
            }
        }
        if lay.crypto_object && rec.instance != aov::NONE {
            if let Some(&id) = ids.object.get(rec.instance as usize) {
                self.crypto_object[k].add(id);
            }
        }
        if lay.crypto_material && rec.material != aov::NONE {
            if let Some(&id) = ids.material.get(rec.material as usize) {
                self.crypto_material[k].add(id);
            }
        }
        true
    }

    /// [`Accum::add`] for a layout that records nothing but radiance ([`AovLayout::records`]
    /// false; with one that does, the passes would miss the sample): inlined into the
    /// per-sample loop, without the layout's checks.
    #[inline]
    pub fn add_radiance(&mut self, k: usize, l: Vec3, hit: bool) -> bool {
        self.sums.get_mut(k).is_some_and(|s| s.add(l, hit))
    }

    /// Copies pixel `from` of `other` into pixel `to`.
    pub fn copy_pixel(&mut self, to: usize, other: &Accum, from: usize) {
        self.copy_pixels(to, other, from, 1);
    }

    /// Copies pixels `from..from + n` of `other` into pixels `to..to + n`.
    pub fn copy_pixels(&mut self, to: usize, other: &Accum, from: usize, n: usize) {
        self.sums[to..to + n].copy_from_slice(&other.sums[from..from + n]);
        let s = self.layout.stride;
        self.aov[to * s..(to + n) * s].copy_from_slice(&other.aov[from * s..(from + n) * s]);
        if self.layout.crypto_object {
            self.crypto_object[to..to + n].copy_from_slice(&other.crypto_object[from..from + n]);
        }
        if self.layout.crypto_material {
            self.crypto_material[to..to + n]
                .copy_from_slice(&other.crypto_material[from..from + n]);
        }
    }
}

/// A rendered window of an image before output: sums per pixel plus counters.
#[derive(Debug, Clone, PartialEq)]
pub struct Film {
    window: Window,
    image_width: u32,
    image_height: u32,
    passes: PassSet,
    /// The pixels' sums.
    pub accum: Accum,
    /// Samples each pixel took, dropped ones included (all `spp` unless sampling was adaptive).
    taken: Vec<u32>,
    dropped: u64,
    /// Depth along the view axis of the centre ray's hit (`Depth` pass), or empty.
    pub depth: Vec<f32>,
    /// World position of that hit (`Position` pass), or empty.
    pub position: Vec<Vec3>,
    /// Its screen motion towards the previous and next frames (`Vector` pass), or empty.
    pub vector: Vec<[f32; 4]>,
}

impl Film {
    /// An empty film of the whole `width × height` image, beauty only.
    pub fn new(width: u32, height: u32) -> Self {
        Self::for_window(Window::whole(width, height), width, height, PassSet::NONE)
    }

    /// An empty film of `window` of a `width × height` image, with room for `passes`.
    pub fn for_window(window: Window, width: u32, height: u32, passes: PassSet) -> Self {
        let n = window.pixels();
        Self {
            window,
            image_width: width,
            image_height: height,
            passes,
            accum: Accum::new(n, AovLayout::new(passes)),
            taken: vec![0; n],
            dropped: 0,
            depth: Vec::new(),
            position: Vec::new(),
            vector: Vec::new(),
        }
    }

    /// Width of the film (its window) in pixels.
    pub fn width(&self) -> u32 {
        self.window.width
    }

    /// Height of the film (its window) in pixels.
    pub fn height(&self) -> u32 {
        self.window.height
    }

    /// Which pixels of the image the film holds.
    pub fn window(&self) -> Window {
        self.window
    }

    /// Size of the whole image the window belongs to.
    pub fn image_size(&self) -> (u32, u32) {
        (self.image_width, self.image_height)
    }

    /// The passes the film was rendered with.
    pub fn passes(&self) -> PassSet {
        self.passes
    }

    /// Samples dropped because their radiance was NaN or infinite.
    pub fn dropped_samples(&self) -> u64 {
        self.dropped
    }

    fn index(&self, x: u32, y: u32) -> usize {
        y as usize * self.window.width as usize + x as usize
    }

    /// The sums of pixel `(x, y)` of the window (row 0 at the top).
    pub fn pixel_sum(&self, x: u32, y: u32) -> &PixelSum {
        &self.accum.sums[self.index(x, y)]
    }

    /// Samples pixel `(x, y)` took, dropped ones included: the render's `spp`, or fewer where
    /// adaptive sampling stopped it early.
    pub fn samples_taken(&self, x: u32, y: u32) -> u32 {
        self.taken[self.index(x, y)]
    }

    /// Samples taken per pixel, rows top to bottom (the `Debug Sample Count` pass).
    pub fn samples_per_pixel(&self) -> &[u32] {
        &self.taken
    }

    /// Samples taken over the whole window, dropped ones included.
    pub fn total_samples(&self) -> u64 {
        self.taken.iter().map(|&n| u64::from(n)).sum()
    }

    /// Mean RGBA of pixel `(x, y)`; A is the fraction of primary rays that hit geometry.
    pub fn pixel(&self, x: u32, y: u32) -> [f32; 4] {
        self.pixel_sum(x, y).resolve()
    }

    /// Every pixel resolved, rows top to bottom.
    pub fn to_rgba(&self) -> Vec<[f32; 4]> {
        self.accum.sums.iter().map(PixelSum::resolve).collect()
    }

    /// Copies a finished tile in (`x0`, `y0` relative to the window, `w` pixels wide), with
    /// the samples each of its pixels took. Tiles own disjoint pixels and `dropped` is a sum,
    /// so the order of calls does not change the result: the renderer merges each tile as it
    /// finishes.
    pub fn merge_tile(
        &mut self,
        x0: u32,
        y0: u32,
        w: u32,
        tile: &Accum,
        taken: &[u32],
        dropped: u64,
    ) {
        // Row by row as slices: pixel by pixel it was ~110 instructions a pixel, run on one
        // thread after the tiles (a fixed cost of every render).
        let w = w as usize;
        for (ty, from) in (0..tile.sums.len()).step_by(w.max(1)).enumerate() {
            let n = w.min(tile.sums.len() - from);
            let to = self.index(x0, y0 + ty as u32);
            self.accum.copy_pixels(to, tile, from, n);
            self.taken[to..to + n].copy_from_slice(&taken[from..from + n]);
        }
        self.dropped += dropped;
    }

    /// Sample counts of every pixel and the dropped count, for the adaptive renderer.
    pub fn counts_mut(&mut self) -> (&mut [u32], &mut u64) {
        (&mut self.taken, &mut self.dropped)
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
    fn new_accumulators_are_reset_ones() {
        // `new` allocates zeroed memory; `reset` writes each type's default: the two must be
        // the same empty sums, with and without passes (Cryptomatte included).
        for passes in [PassSet::default(), PassSet::all()] {
            let layout = AovLayout::new(passes);
            for n in [0, 1, 37] {
                let mut reset = Accum::default();
                reset.reset(n, layout);
                let new = Accum::new(n, layout);
                assert_eq!(new, reset, "{n} pixels");
                assert_eq!(new.sums.len(), n);
            }
        }
        assert!(AovLayout::new(PassSet::all()).crypto_object);
    }

    #[test]
    fn tiles_land_where_they_belong() {
        let mut f = Film::new(4, 3);
        let mut tile = Accum::new(4, AovLayout::default());
        tile.sums[0].add(Vec3::ONE, true);
        tile.sums[3].add(Vec3::ONE, true);
        f.merge_tile(2, 1, 2, &tile, &[7, 7, 6, 7], 5);
        assert_eq!(f.pixel(2, 1), [1.0; 4]);
        assert_eq!(f.pixel(3, 2), [1.0; 4]);
        assert_eq!(f.pixel(3, 1), [0.0; 4]);
        assert_eq!(f.pixel(0, 0), [0.0; 4]);
        assert_eq!(f.dropped_samples(), 5);
        assert_eq!(f.samples_taken(3, 2), 7);
        assert_eq!(f.samples_taken(2, 2), 6);
        assert_eq!(f.samples_taken(0, 0), 0);
        assert_eq!(f.total_samples(), 3 * 7 + 6);
    }

    #[test]
    fn pass_records_are_summed_and_dropped_with_the_beauty() {
        let passes = PassSet::parse("Normal,Emission,CryptoObject").unwrap();
        let layout = AovLayout::new(passes);
        assert_eq!(
            (layout.normal, layout.light, layout.stride),
            (Some(0), Some(3), 36)
        );
        let ids = CryptoIds {
            object: vec![11, 22],
            material: vec![],
        };
        let mut acc = Accum::new(1, layout);
        let mut rec = SampleAov {
            normal: Vec3::Z,
            instance: 1,
            ..SampleAov::default()
        };
        rec.light[aov::slot::EMISSION] = Vec3::splat(2.0);
        assert!(acc.add(0, Vec3::splat(2.0), true, &rec, &ids));
        assert!(!acc.add(0, Vec3::NAN, true, &rec, &ids));
        assert!(acc.add(0, Vec3::ZERO, false, &SampleAov::default(), &ids));
        assert_eq!(&acc.aov[..3], &[0.0, 0.0, 1.0]);
        assert_eq!(acc.aov[3 + 3 * aov::slot::EMISSION], 2.0);
        assert_eq!(acc.crypto_object[0].ranked(2.0)[0], (22, 0.5));
    }

    #[test]
    fn windows_grow_inside_the_image() {
        let w = Window {
            x0: 3,
            y0: 0,
            width: 4,
            height: 2,
        };
        assert_eq!(
            w.grown(5, 10, 4),
            Window {
                x0: 0,
                y0: 0,
                width: 10,
                height: 4
            }
        );
        assert!(w.fits(7, 2) && !w.fits(6, 2));
    }

    #[test]
    fn bands_tile_the_image() {
        for (n, h) in [(1, 1), (4, 10), (3, 7), (7, 7), (5, 1080)] {
            let bands: Vec<Window> = (0..n).map(|k| Window::band(k, n, 9, h).unwrap()).collect();
            assert_eq!(bands[0].y0, 0);
            assert_eq!(bands[n as usize - 1].end(), (9, h));
            for pair in bands.windows(2) {
                assert_eq!(pair[0].end().1, pair[1].y0, "{n} bands of {h}");
                assert!(pair[0].height.abs_diff(pair[1].height) <= 1);
                assert!(!pair[0].overlaps(&pair[1]));
            }
        }
        assert_eq!(Window::band(4, 4, 9, 10), None);
        assert_eq!(Window::band(0, 11, 9, 10), None, "more bands than rows");
        assert_eq!(Window::band(0, 0, 9, 10), None);
        assert_eq!(
            Window::from_corners(2, 3, 5, 4),
            Some(Window {
                x0: 2,
                y0: 3,
                width: 3,
                height: 1
            })
        );
        assert_eq!(Window::from_corners(2, 3, 2, 4), None);
        let a = Window::from_corners(0, 0, 4, 4).unwrap();
        assert!(a.overlaps(&Window::from_corners(3, 3, 5, 5).unwrap()));
        assert!(!a.overlaps(&Window::from_corners(4, 0, 5, 5).unwrap()));
    }
}
