//! The shutter of SPEC §7: when it opens and closes around a frame, and when each row of a
//! rolling shutter sees the scene.

pub use aperture_scene::{RollingShutter, ShutterPosition};

/// Blender's default `motion_blur_shutter`, in frames.
pub const DEFAULT_SHUTTER_FRAMES: f32 = 0.5;

/// How long the shutter is open and where it sits around the frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Shutter {
    /// Open time in frames (> 0).
    pub frames: f32,
    /// Where the interval sits around the frame.
    pub position: ShutterPosition,
    /// Rolling shutter from the top, with Blender's `rolling_shutter_duration` (the fraction of
    /// the shutter each row is exposed for); `None`: every row sees the whole interval.
    pub rolling: Option<f32>,
}

impl Default for Shutter {
    fn default() -> Self {
        Self {
            frames: DEFAULT_SHUTTER_FRAMES,
            position: ShutterPosition::Center,
            rolling: None,
        }
    }
}

impl Shutter {
    /// The interval `(open, close)` in seconds around the frame at `frame_time` seconds,
    /// `fps` frames a second.
    pub fn interval(&self, frame_time: f64, fps: f64) -> (f64, f64) {
        let open = f64::from(self.frames) / fps;
        match self.position {
            ShutterPosition::Start => (frame_time, frame_time + open),
            ShutterPosition::Center => (frame_time - 0.5 * open, frame_time + 0.5 * open),
            ShutterPosition::End => (frame_time - open, frame_time),
        }
    }

    /// The normalised time in `[0, 1]` of a sample whose time value is `u ∈ [0, 1)` and whose
    /// film position is at `row` of `height` rows (0 at the top). Without a rolling shutter
    /// the time is `u`; with one, row `y` is exposed over `[r·(1 − D), r·(1 − D) + D]` of the
    /// shutter (`r = y / height`, `D` the duration): D = 0 is a pure rolling shutter, D = 1 no
    /// rolling at all, as Blender's control reads.
    #[inline]
    pub fn normalised_time(&self, u: f32, row: f32, height: u32) -> f32 {
        match self.rolling {
            None => u,
            Some(d) => {
                let r = (row / height.max(1) as f32).clamp(0.0, 1.0);
                (r * (1.0 - d) + u * d).clamp(0.0, 1.0)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_interval_follows_the_position() {
        let mut s = Shutter::default();
        assert_eq!(
            s.interval(1.0, 24.0),
            (1.0 - 0.25 / 24.0, 1.0 + 0.25 / 24.0)
        );
        s.position = ShutterPosition::Start;
        assert_eq!(s.interval(1.0, 24.0), (1.0, 1.0 + 0.5 / 24.0));
        s.position = ShutterPosition::End;
        assert_eq!(s.interval(1.0, 24.0), (1.0 - 0.5 / 24.0, 1.0));
    }

    #[test]
    fn a_rolling_shutter_opens_row_by_row() {
        let s = Shutter {
            rolling: Some(0.0),
            ..Shutter::default()
        };
        assert_eq!(s.normalised_time(0.7, 0.0, 100), 0.0);
        assert_eq!(s.normalised_time(0.7, 50.0, 100), 0.5);
        let s = Shutter {
            rolling: Some(1.0),
            ..Shutter::default()
        };
        assert_eq!(s.normalised_time(0.7, 50.0, 100), 0.7);
        assert_eq!(Shutter::default().normalised_time(0.3, 99.0, 100), 0.3);
    }
}
