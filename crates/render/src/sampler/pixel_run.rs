//! A pixel's consecutive samples, with what they share worked out once.

use super::{
    nibble_tables, random_4d, set_scramble, shuffle_scramble, sobol_scrambled, sobol_shuffle_rev,
    Int4, NibbleTable, SampleStream, SamplerKind,
};

/// `(index + 1).reverse_bits()` from `index` and `index_rev = index.reverse_bits()`: adding 1
/// flips the trailing ones of `index` and the zero above them, a run of low bits whose
/// reversal is the same run of high bits (5 instructions instead of the ~19 of a reversal on
/// x86, which has no instruction for it).
#[inline]
fn next_reversed(index: u32, index_rev: u32) -> u32 {
    let flipped = index ^ index.wrapping_add(1);
    // `flipped` is never 0, so the shift is below 32.
    index_rev ^ u32::MAX.wrapping_shl(flipped.leading_zeros())
}

/// The consecutive samples of one pixel, from a first index on, with what they all share
/// worked out once: the hashes of the index shuffle and of the camera set's scramble, the
/// camera set's table. Each step gives what [`SampleStream::for_pixel`] and
/// [`SampleStream::camera`] give for the next index, bit for bit (`pixel_run_matches_the_streams`
/// checks it), at about half the instructions.
#[derive(Clone, Copy)]
pub(crate) struct PixelRun {
    kind: SamplerKind,
    pixel_seed: u32,
    /// [`shuffle_scramble`] of the pixel seed.
    shuffle: u32,
    /// [`set_scramble`] of the camera set under the pixel seed.
    camera_scramble: Int4,
    camera_table: &'static NibbleTable,
    /// The next sample's index and its bit reversal.
    index: u32,
    index_rev: u32,
}

impl PixelRun {
    /// The samples `first, first + 1, …` of the pixel whose seed is `pixel_seed`.
    #[inline]
    pub fn new(kind: SamplerKind, pixel_seed: u32, first: u32) -> Self {
        Self {
            kind,
            pixel_seed,
            shuffle: shuffle_scramble(pixel_seed),
            camera_scramble: set_scramble(0, pixel_seed),
            camera_table: &nibble_tables()[0],
            index: first,
            index_rev: first.reverse_bits(),
        }
    }

    /// The index [`PixelRun::next`] gives next.
    #[cfg(test)]
    pub fn index(&self) -> u32 {
        self.index
    }

    /// Continues the run at `index` (not reversing it again when it is the next one).
    #[inline]
    pub fn seek(&mut self, index: u32) {
        if index != self.index {
            self.index = index;
            self.index_rev = index.reverse_bits();
        }
    }

    /// The stream of the next sample, without moving on.
    #[inline]
    pub fn stream(&self) -> SampleStream {
        SampleStream {
            kind: self.kind,
            pixel_seed: self.pixel_seed,
            index: self.index,
            shuffled_rev: sobol_shuffle_rev(self.index_rev, self.shuffle),
        }
    }

    /// The next sample's stream and its camera point (what [`SampleStream::camera`] gives).
    #[inline]
    pub fn next(&mut self) -> (SampleStream, [f32; 4]) {
        let (index, index_rev) = (self.index, self.index_rev);
        self.index = index.wrapping_add(1);
        self.index_rev = next_reversed(index, index_rev);
        let stream = SampleStream {
            kind: self.kind,
            pixel_seed: self.pixel_seed,
            index,
            shuffled_rev: sobol_shuffle_rev(index_rev, self.shuffle),
        };
        let shuffled_rev = stream.shuffled_rev;
        let camera = match self.kind {
            SamplerKind::Sobol => {
                sobol_scrambled(self.camera_table, shuffled_rev, self.camera_scramble)
            }
            SamplerKind::Random => random_4d(self.pixel_seed, index, 0),
        };
        (stream, camera)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampler::{hash_u32, pixel_seed, MAX_SPP};

    #[test]
    fn stepped_reversal_is_the_reversal() {
        let mut starts = vec![0, 1, 0xfffe, 0xffff, 0x7fff_fffe, u32::MAX - 2];
        let mut x = 17u32;
        starts.extend((0..200).map(|_| {
            x = hash_u32(x);
            x
        }));
        for start in starts {
            let (mut i, mut rev) = (start, start.reverse_bits());
            for _ in 0..40 {
                rev = next_reversed(i, rev);
                i = i.wrapping_add(1);
                assert_eq!(rev, i.reverse_bits(), "{i:#x}");
            }
        }
    }

    #[test]
    fn pixel_run_matches_the_streams() {
        for kind in [SamplerKind::Sobol, SamplerKind::Random] {
            for (x, y, seed) in [(0, 0, 0), (3, 7, 11), (319, 239, 1234)] {
                let ps = pixel_seed(x, y, seed);
                for first in [0, 5, 1000, MAX_SPP - 40] {
                    let mut run = PixelRun::new(kind, ps, first);
                    for index in first..first + 40 {
                        // A seek to the next index changes nothing; others restart.
                        if index % 7 == 3 {
                            run.seek(index + 5);
                            run.seek(index);
                        }
                        run.seek(index);
                        assert_eq!(run.index(), index);
                        let (stream, camera) = run.next();
                        let want = SampleStream::for_pixel(kind, ps, index);
                        assert_eq!(stream.shuffled_rev, want.shuffled_rev);
                        assert_eq!((stream.index, stream.pixel_seed), (index, ps));
                        assert_eq!(stream.bounce(2).bsdf, want.bounce(2).bsdf);
                        assert_eq!(camera.map(f32::to_bits), want.camera().map(f32::to_bits));
                        let pixel = want.pixel().map(f32::to_bits);
                        assert_eq!([camera[0], camera[1]].map(f32::to_bits), pixel);
                    }
                }
            }
        }
    }
}
