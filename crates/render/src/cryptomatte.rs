//! Cryptomatte (Friedman & Jones 2015, the Psyop specification as Blender and Nuke read it):
//! names hashed with MurmurHash3 into float IDs, per-pixel coverage of each ID accumulated
//! sample by sample, the strongest [`RANKS`] kept as (ID, coverage) pairs, two pairs to an
//! RGBA layer, and a manifest of names in the header.
//!
//! Coverage counts samples, so a matte is right under anti-aliasing and depth of field alike:
//! a defocused object's matte is its soft, bokeh-shaped coverage.

/// Ranks written: three RGBA layers (`CryptoObject00..02`), Blender's default depth.
pub const RANKS: usize = 6;

/// IDs a pixel can tell apart while it accumulates; a sample of a further ID is not counted
/// (Cycles drops it the same way). Far more than [`RANKS`] so the ranking is right.
const SLOTS: usize = 16;

/// MurmurHash3, x86 32-bit variant, seed 0: the hash the specification names.
pub fn murmur3_32(bytes: &[u8]) -> u32 {
    const C1: u32 = 0xcc9e_2d51;
    const C2: u32 = 0x1b87_3593;
    let mut h: u32 = 0;
    let mut blocks = bytes.chunks_exact(4);
    for b in &mut blocks {
        let mut k = u32::from_le_bytes(b.try_into().expect("four bytes"));
        k = k.wrapping_mul(C1).rotate_left(15).wrapping_mul(C2);
        h ^= k;
        h = h.rotate_left(13).wrapping_mul(5).wrapping_add(0xe654_6b64);
    }
    let tail = blocks.remainder();
    if !tail.is_empty() {
        let mut k = 0u32;
        for (i, &b) in tail.iter().enumerate() {
            k |= u32::from(b) << (8 * i);
        }
        h ^= k.wrapping_mul(C1).rotate_left(15).wrapping_mul(C2);
    }
    h ^= bytes.len() as u32;
    h ^= h >> 16;
    h = h.wrapping_mul(0x85eb_ca6b);
    h ^= h >> 13;
    h = h.wrapping_mul(0xc2b2_ae35);
    h ^ (h >> 16)
}

/// The float an ID is stored as, as bits: the hash with its exponent kept away from 0 and
/// 255, so the float is never a denormal, infinity or NaN (the specification's rule). Never 0.
pub fn id_bits(hash: u32) -> u32 {
    let exponent = (hash >> 23) & 255;
    if exponent == 0 || exponent == 255 {
        hash ^ (1 << 23)
    } else {
        hash
    }
}

/// The `<key>` of a layer's `cryptomatte/<key>/…` header attributes: the first seven hex
/// digits of the layer name's hash.
pub fn layer_key(layer: &str) -> String {
    format!("{:08x}", murmur3_32(layer.as_bytes()))[..7].to_owned()
}

/// The manifest: a JSON object from each name to its hash in eight hex digits, names sorted.
pub fn manifest<'a>(names: impl IntoIterator<Item = &'a str>) -> String {
    let mut names: Vec<&str> = names.into_iter().collect();
    names.sort_unstable();
    names.dedup();
    let entries: Vec<String> = names
        .iter()
        .map(|n| format!("{}:\"{:08x}\"", json_string(n), murmur3_32(n.as_bytes())))
        .collect();
    format!("{{{}}}", entries.join(","))
}

/// `s` as a JSON string literal.
fn json_string(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            c if (c as u32) < 0x20 => out.push_str(&format!("\\u{:04x}", c as u32)),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// One pixel's coverage per ID while it accumulates: sample counts per ID bit pattern
/// (0 = empty slot).
#[derive(Debug, Clone, Copy, PartialEq, Default, bytemuck::Zeroable)]
pub struct CryptoPixel {
    ids: [u32; SLOTS],
    counts: [f32; SLOTS],
}

impl CryptoPixel {
    /// Counts one sample of `id` (bits from [`id_bits`]).
    #[inline]
    pub fn add(&mut self, id: u32) {
        for (slot, count) in self.ids.iter_mut().zip(&mut self.counts) {
            if *slot == id {
                *count += 1.0;
                return;
            }
            if *slot == 0 {
                *slot = id;
                *count = 1.0;
                return;
            }
        }
    }

    /// Counts `count` samples of `id` at once (merging the ranks of several renders of the same
    /// pixel); like [`CryptoPixel::add`], an ID beyond the slots is not counted.
    pub fn add_count(&mut self, id: u32, count: f32) {
        for (slot, c) in self.ids.iter_mut().zip(&mut self.counts) {
            if *slot == id {
                *c += count;
                return;
            }
            if *slot == 0 {
                *slot = id;
                *c = count;
                return;
            }
        }
    }

    /// The [`RANKS`] strongest IDs as (ID bits, coverage) with coverage = count / `samples`,
    /// strongest first, ties by ID; missing ranks are (0, 0).
    pub fn ranked(&self, samples: f64) -> [(u32, f32); RANKS] {
        // Insertion into a sorted top list: no allocation, once per pixel at output.
        let mut top = [(0u32, 0.0f32); RANKS];
        let mut n = 0;
        let before = |a: (u32, f32), b: (u32, f32)| a.1 > b.1 || (a.1 == b.1 && a.0 < b.0);
        for (&id, &count) in self.ids.iter().zip(&self.counts) {
            if id == 0 {
                break;
            }
            let entry = (id, count);
            if n == RANKS && !before(entry, top[RANKS - 1]) {
                continue;
            }
            let mut at = n.min(RANKS - 1);
            while at > 0 && before(entry, top[at - 1]) {
                top[at] = top[at - 1];
                at -= 1;
            }
            top[at] = entry;
            n = (n + 1).min(RANKS);
        }
        let mut out = [(0, 0.0); RANKS];
        if samples > 0.0 {
            for (o, &(id, count)) in out.iter_mut().zip(&top[..n]) {
                *o = (id, (f64::from(count) / samples) as f32);
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Hashes as Blender 5.0 wrote them into a Cycles render's manifest and attribute keys.
    #[test]
    fn hashes_match_blender() {
        assert_eq!(format!("{:08x}", murmur3_32(b"Sphere")), "e5e9b0db");
        assert_eq!(format!("{:08x}", murmur3_32(b"L")), "f3397f3f");
        assert_eq!(format!("{:08x}", murmur3_32(b"Mat")), "24f701e8");
        assert_eq!(layer_key("ViewLayer.CryptoObject"), "542cafa");
        assert_eq!(layer_key("CryptoObject"), "3ae39a5");
        assert_eq!(layer_key("CryptoMaterial"), "be359d6");
        // The specification's reference value (MurmurHash3_x86_32 of "" with seed 0).
        assert_eq!(murmur3_32(b""), 0);
    }

    #[test]
    fn ids_are_normal_floats() {
        for h in [
            0u32,
            1,
            0x007f_ffff,
            0x7f80_0000,
            0xff80_0001,
            0x8000_0000,
            12345,
        ] {
            let f = f32::from_bits(id_bits(h));
            assert!(f.is_normal(), "{h:08x} -> {f}");
        }
        assert_eq!(id_bits(0x3f80_0000), 0x3f80_0000);
    }

    #[test]
    fn manifest_is_sorted_escaped_json() {
        let m = manifest(["b", "a \"q\"", "b"]);
        assert_eq!(
            m,
            format!(
                "{{\"a \\\"q\\\"\":\"{:08x}\",\"b\":\"{:08x}\"}}",
                murmur3_32(b"a \"q\""),
                murmur3_32(b"b")
            )
        );
    }

    #[test]
    fn coverage_is_ranked() {
        let mut p = CryptoPixel::default();
        for id in [5, 7, 7, 9, 7, 5] {
            p.add(id);
        }
        let r = p.ranked(8.0);
        assert_eq!(r[0], (7, 3.0 / 8.0));
        assert_eq!(r[1], (5, 2.0 / 8.0));
        assert_eq!(r[2], (9, 1.0 / 8.0));
        assert_eq!(r[3], (0, 0.0));
        for id in [9, 9, 11] {
            p.add(id);
        }
        let r = p.ranked(11.0);
        // 7 and 9 both have three samples: the tie goes to the smaller ID.
        assert_eq!(r[0], (7, 3.0 / 11.0));
        assert_eq!(r[1], (9, 3.0 / 11.0));
        assert_eq!(r[2], (5, 2.0 / 11.0));
        assert_eq!(r[3], (11, 1.0 / 11.0));
        // The top list agrees with a full sort, ties by ID, over many random pixels.
        let mut x = 7u32;
        for _ in 0..500 {
            let mut p = CryptoPixel::default();
            for _ in 0..30 {
                x = x.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                p.add(1 + (x >> 28));
            }
            let mut all: Vec<(u32, f32)> = (0..SLOTS)
                .filter(|&i| p.ids[i] != 0)
                .map(|i| (p.ids[i], p.counts[i]))
                .collect();
            all.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
            let r = p.ranked(30.0);
            for (k, e) in all.iter().take(RANKS).enumerate() {
                assert_eq!(r[k], (e.0, (f64::from(e.1) / 30.0) as f32));
            }
        }
        // More IDs than slots: the extra ones are not counted, nothing panics.
        let mut full = CryptoPixel::default();
        for id in 1..=40 {
            full.add(id);
        }
        assert_eq!(full.ranked(40.0).iter().filter(|r| r.0 != 0).count(), RANKS);
    }
}
