//! A pixel's consecutive samples, with what they share worked out once.

use super::{
    random_4d, set_scramble, shuffle_scramble, sobol_scrambled, sobol_shuffle_rev, Int4,
    SampleStream, SamplerKind,
};

/// The camera set's Sobol point per byte of the top 16 index bits (most significant first) and
/// per value of that byte: 8 KiB, built once. Two lookups give a sample's point, where the
/// nibble tables of the other sets take four (`byte_table_matches_the_crate` checks it).
type ByteTable = [[Int4; 256]; 2];

/// The [`ByteTable`] of the camera's dimension set (0).
fn camera_bytes() -> &'static ByteTable {
    use sobol_burley::parts::sobol_int4_rev;
    static TABLE: std::sync::OnceLock<Box<ByteTable>> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| {
        Box::new(std::array::from_fn(|k| {
            std::array::from_fn(|v| sobol_int4_rev((v as u32) << (24 - 8 * k), 0))
        }))
    })
}

/// `sobol_burley::parts::sobol_int4_rev(index_rev, 0)` by two lookups in [`camera_bytes`].
#[inline]
fn camera_sobol(t: &ByteTable, index_rev: u32) -> Int4 {
    t[0][(index_rev >> 24) as u8 as usize] ^ t[1][(index_rev >> 16) as u8 as usize]
}

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
    camera_table: &'static ByteTable,
    /// The next sample's index and its bit reversal.
    index: u32,
    index_rev: u32,
}

impl PixelRun {
    /// The samples `first, first + 1, …` of the pixel whose seed is `pixel_seed`.
    #[inline]
    pub fn new(kind: SamplerKind, pixel_seed: u32, first: u32) -> Self {
        let mut run = Self {
            kind,
            pixel_seed,
            shuffle: 0,
            camera_scramble: [0; 4].into(),
            camera_table: camera_bytes(),
            index: first,
            index_rev: 0,
        };
        run.restart(pixel_seed, first, first.reverse_bits());
        run
    }

    /// Starts over at the samples `first, first + 1, …` of the pixel whose seed is
    /// `pixel_seed`, given `first_rev = first.reverse_bits()`: what [`PixelRun::new`] makes,
    /// for callers that go from pixel to pixel (the table is looked up once, and a common
    /// first index reversed once).
    #[inline]
    pub fn restart(&mut self, pixel_seed: u32, first: u32, first_rev: u32) {
        self.pixel_seed = pixel_seed;
        self.shuffle = shuffle_scramble(pixel_seed);
        self.camera_scramble = set_scramble(0, pixel_seed);
        self.index = first;
        self.index_rev = first_rev;
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
                let sobol = camera_sobol(self.camera_table, shuffled_rev);
                sobol_scrambled(sobol, self.camera_scramble)
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
    fn byte_table_matches_the_crate() {
        use sobol_burley::parts::sobol_int4_rev;
        let bits = |v: Int4| v.to_f32_norm().map(f32::to_bits);
        let mut x = 0x9e37_79b9u32;
        let mut revs = vec![
            0,
            u32::MAX,
            0xffff_0000,
            0x8000_0000,
            0x0001_0000,
            0x1234_5678,
        ];
        revs.extend((0..500).map(|_| {
            x = hash_u32(x);
            x
        }));
        for index_rev in revs {
            let want = bits(sobol_int4_rev(index_rev, 0));
            assert_eq!(
                bits(camera_sobol(camera_bytes(), index_rev)),
                want,
                "{index_rev:#x}"
            );
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
