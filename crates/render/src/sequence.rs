//! Frame ranges (SPEC §7, `--frames A..B[:STEP]`). A [`crate::Session`] poses each frame of a
//! shot and rebuilds only what moved: the top-level BVH always, the bottom-level BVHs of
//! deforming meshes; the BVHs of static meshes and the world-space BVH of still instances are
//! kept from the frame before. Each frame's image is the single-frame render of that frame,
//! bit for bit: both build with the same [`crate::SceneHints`].

/// Frames `start`, `start + step`, … up to `end` inclusive (Blender's frame range and step).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FrameRange {
    /// First frame.
    pub start: i64,
    /// Last frame (included when the step lands on it).
    pub end: i64,
    /// Frames between renders, ≥ 1.
    pub step: i64,
}

impl FrameRange {
    /// The frames, in order.
    pub fn frames(self) -> impl Iterator<Item = i64> {
        (self.start..=self.end).step_by(self.step.max(1) as usize)
    }

    /// Parses `A..B` or `A..B:STEP` (frames may be negative; `B ≥ A`, `STEP ≥ 1`).
    pub fn parse(s: &str) -> Result<Self, String> {
        let bad =
            || format!("expected A..B or A..B:STEP (whole frames, A ≤ B, STEP ≥ 1), got {s:?}");
        let (range, step) = match s.split_once(':') {
            Some((r, st)) => (r, st.trim().parse::<i64>().map_err(|_| bad())?),
            None => (s, 1),
        };
        let (a, b) = range.split_once("..").ok_or_else(bad)?;
        let (start, end) = (
            a.trim().parse::<i64>().map_err(|_| bad())?,
            b.trim().parse::<i64>().map_err(|_| bad())?,
        );
        if end < start || step < 1 || end - start > 10_000_000 {
            return Err(bad());
        }
        Ok(Self { start, end, step })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_parse_as_blender_writes_them() {
        let r = FrameRange::parse("1..24").unwrap();
        assert_eq!(r.frames().count(), 24);
        let r = FrameRange::parse("-3..10:4").unwrap();
        assert_eq!(r.frames().collect::<Vec<_>>(), [-3, 1, 5, 9]);
        for bad in ["1..", "5..1", "1..10:0", "a..b", "1-10", "1..10:x"] {
            assert!(FrameRange::parse(bad).is_err(), "{bad}");
        }
    }
}
