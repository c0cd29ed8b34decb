//! `--motion-blur`, `--no-motion-blur`, `--shutter`, `--shutter-position`, `--motion-steps`
//! (SPEC §7): the command line's say over the file's motion-blur settings.

use crate::number_args::positive_f32;
use aperture_render::motion::{MotionOverrides, MotionSettings, ShutterPosition, MAX_MOTION_STEPS};
use aperture_scene::Animated;

/// Motion blur flags; each overrides the file's `scenes[i].extras` key.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct MotionArgs {
    /// Motion blur on: each sample at its own time in the shutter [default: the file's
    /// `use_motion_blur`, else off].
    #[arg(long, conflicts_with = "no_motion_blur")]
    pub motion_blur: bool,
    /// Motion blur off whatever the file says.
    #[arg(long)]
    pub no_motion_blur: bool,
    /// Shutter open time in frames [default: the file's `motion_blur_shutter`, else 0.5].
    #[arg(long, value_name = "FRAMES", value_parser = positive_f32)]
    pub shutter: Option<f32>,
    /// Where the shutter sits around the frame [default: the file's, else center].
    #[arg(long, value_enum)]
    pub shutter_position: Option<ShutterPosition>,
    /// Poses over the shutter for what moves, interpolated per ray [default: 3].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(2..=MAX_MOTION_STEPS as i64))]
    pub motion_steps: Option<u32>,
}

impl MotionArgs {
    /// What the flags say.
    pub fn overrides(&self) -> MotionOverrides {
        MotionOverrides {
            enabled: match (self.motion_blur, self.no_motion_blur) {
                (true, _) => Some(true),
                (_, true) => Some(false),
                _ => None,
            },
            shutter: self.shutter,
            position: self.shutter_position,
            steps: self.motion_steps,
        }
    }
}

/// The motion-blur settings of a frame at `time` seconds (`None`: the stored pose): the
/// file's keys under the flags; `None` when motion blur is off, and with a warning when it is
/// on without a time to put the shutter around in an animated file.
pub fn settings(
    args: &MotionArgs,
    animated: &Animated,
    time: Option<f64>,
) -> Option<MotionSettings> {
    let settings = MotionSettings::resolve(&animated.motion_extras(), &args.overrides());
    settings.shutter?;
    if time.is_none() {
        if animated.is_animated() {
            eprintln!(
                "warning: motion blur needs a time (--frame N or --time S): the stored pose \
                 is rendered without it"
            );
        }
        return None;
    }
    Some(settings)
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        motion: MotionArgs,
    }

    fn parse(args: &[&str]) -> Result<MotionOverrides, clap::Error> {
        let argv = std::iter::once("t").chain(args.iter().copied());
        Cli::try_parse_from(argv).map(|c| c.motion.overrides())
    }

    #[test]
    fn flags_map_to_overrides() {
        assert_eq!(parse(&[]).unwrap(), MotionOverrides::default());
        let o = parse(&[
            "--motion-blur",
            "--shutter",
            "0.25",
            "--shutter-position",
            "end",
            "--motion-steps",
            "5",
        ])
        .unwrap();
        assert_eq!(o.enabled, Some(true));
        assert_eq!(o.shutter, Some(0.25));
        assert_eq!(o.position, Some(ShutterPosition::End));
        assert_eq!(o.steps, Some(5));
        assert_eq!(parse(&["--no-motion-blur"]).unwrap().enabled, Some(false));
        assert!(parse(&["--motion-blur", "--no-motion-blur"]).is_err());
        assert!(parse(&["--shutter", "0"]).is_err());
        assert!(parse(&["--motion-steps", "1"]).is_err());
        assert!(parse(&["--motion-steps", "65"]).is_err());
    }
}
