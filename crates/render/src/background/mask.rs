//! A set of pixels of an image: the union of rectangles, one bit a pixel.

use super::window::PixelRect;

/// Pixels of a `width × height` image, one bit each, row by row.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct PixelMask {
    width: u32,
    height: u32,
    bits: Vec<u64>,
    count: u64,
}

impl PixelMask {
    /// The pixels of `width × height` inside any of `rects`.
    pub fn from_rects(width: u32, height: u32, rects: &[PixelRect]) -> Self {
        let (w, h) = (width as usize, height as usize);
        let mut bits = vec![0u64; (w * h).div_ceil(64)];
        for r in rects {
            let (x0, x1) = (r.x0.max(0), r.x1.min(w as i64 - 1));
            let (y0, y1) = (r.y0.max(0), r.y1.min(h as i64 - 1));
            if x0 > x1 || y0 > y1 {
                continue;
            }
            // Each row's run of bits, a word at a time.
            for y in y0 as usize..=y1 as usize {
                let (a, b) = (y * w + x0 as usize, y * w + x1 as usize + 1);
                let mut k = a;
                while k < b {
                    let (word, bit) = (k / 64, k % 64);
                    let n = (64 - bit).min(b - k);
                    let run = if n == 64 {
                        u64::MAX
                    } else {
                        ((1u64 << n) - 1) << bit
                    };
                    bits[word] |= run;
                    k += n;
                }
            }
        }
        let count = bits.iter().map(|b| u64::from(b.count_ones())).sum();
        Self {
            width,
            height,
            bits,
            count,
        }
    }

    /// Whether pixel `(x, y)` is in the set (`false` outside the image).
    #[inline(always)]
    pub fn contains(&self, x: u32, y: u32) -> bool {
        if x >= self.width || y >= self.height {
            return false;
        }
        let k = y as usize * self.width as usize + x as usize;
        self.bits
            .get(k / 64)
            .is_some_and(|b| b >> (k % 64) & 1 != 0)
    }

    /// Whether every pixel of the image is in the set.
    pub fn is_all(&self) -> bool {
        self.count == u64::from(self.width) * u64::from(self.height)
    }

    /// How many pixels are in the set.
    #[cfg(test)]
    pub fn count(&self) -> u64 {
        self.count
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_mask_is_the_union_of_the_rectangles() {
        let (w, h) = (37u32, 23u32);
        let mut seed = 1u32;
        let mut next = |n: i64| {
            seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            i64::from(seed >> 8) % n - 3
        };
        for case in 0..200 {
            let rects: Vec<PixelRect> = (0..case % 6)
                .map(|_| PixelRect {
                    x0: next(44),
                    x1: next(44),
                    y0: next(30),
                    y1: next(30),
                })
                .collect();
            let mask = PixelMask::from_rects(w, h, &rects);
            let mut count = 0;
            for y in 0..h + 2 {
                for x in 0..w + 2 {
                    let want = x < w && y < h && rects.iter().any(|r| r.contains(x, y));
                    assert_eq!(mask.contains(x, y), want, "case {case}: ({x}, {y})");
                    count += u64::from(want);
                }
            }
            assert_eq!(mask.count(), count);
            assert_eq!(mask.is_all(), count == u64::from(w * h));
        }
        assert!(PixelMask::from_rects(w, h, &[PixelRect::all(w, h)]).is_all());
        assert_eq!(PixelMask::from_rects(w, h, &[]).count(), 0);
    }
}
