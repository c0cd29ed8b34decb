//! The EXR channels of a render: the beauty unprefixed, then each pass as
//! `<Pass>.<channel>`, in the order of the renderer's values
//! ([`aperture_render::resolve::Resolver`]).

use aperture_imageio::{ChannelSpec, SampleType};
use aperture_render::cryptomatte::RANKS;
use aperture_render::passes::{Pass, PassKind, PassSet};

/// Largest finite half float: colour values beyond it are clamped when written as half.
pub const HALF_MAX: f32 = 65504.0;

/// The passes a file gets: those asked for, plus the sample count when the render needs it
/// said (adaptive, a region, a sample range) or when nothing else would make the file a
/// multilayer one (SPEC §6: at least one dotted pass, so Blender opens it as multilayer).
pub fn file_passes(asked: PassSet, needs_sample_count: bool) -> PassSet {
    if needs_sample_count || asked.is_empty() {
        asked.with(Pass::SampleCount)
    } else {
        asked
    }
}

/// Channels of a file with `passes`, in the order [`aperture_render::resolve::Resolver`]
/// gives values.
pub fn channels(passes: PassSet, half: bool) -> Vec<ChannelSpec> {
    let colour = if half {
        SampleType::F16
    } else {
        SampleType::F32
    };
    let mut out: Vec<ChannelSpec> = ["R", "G", "B", "A"]
        .map(|c| ChannelSpec {
            name: c.into(),
            sample_type: colour,
        })
        .into();
    for pass in passes.iter() {
        let sample_type = if pass.kind() == PassKind::Colour {
            colour
        } else {
            SampleType::F32
        };
        let layers: Vec<String> = if pass.kind() == PassKind::Cryptomatte {
            (0..RANKS / 2)
                .map(|i| format!("{}{i:02}", pass.name()))
                .collect()
        } else {
            vec![pass.name().to_owned()]
        };
        for layer in layers {
            for c in pass.channels() {
                out.push(ChannelSpec {
                    name: format!("{layer}.{c}"),
                    sample_type,
                });
            }
        }
    }
    out
}

/// Clamps the colour values of `values` (pixels of `specs` channels) stored as half floats
/// to the half range; returns how many were clamped.
pub fn clamp_half(values: &mut [f32], specs: &[ChannelSpec]) -> u64 {
    let half: Vec<bool> = specs
        .iter()
        .map(|c| c.sample_type == SampleType::F16)
        .collect();
    if !half.contains(&true) {
        return 0;
    }
    let mut clamped = 0;
    for pixel in values.chunks_exact_mut(specs.len()) {
        for (v, &h) in pixel.iter_mut().zip(&half) {
            if h && v.abs() > HALF_MAX {
                *v = v.clamp(-HALF_MAX, HALF_MAX);
                clamped += 1;
            }
        }
    }
    clamped
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn channel_names_follow_blender() {
        let names: Vec<String> = channels(PassSet::compositing(), false)
            .into_iter()
            .map(|c| c.name)
            .collect();
        let expected = [
            "R",
            "G",
            "B",
            "A",
            "Depth.Z",
            "Normal.X",
            "Normal.Y",
            "Normal.Z",
            "Denoising Albedo.R",
            "Denoising Albedo.G",
            "Denoising Albedo.B",
            "Denoising Normal.X",
            "Denoising Normal.Y",
            "Denoising Normal.Z",
        ];
        assert_eq!(names[..expected.len()], expected);
        assert!(names.contains(&"CryptoObject02.A".to_string()));
        assert!(names.contains(&"CryptoMaterial00.R".to_string()));
        assert_eq!(names.len(), 14 + 2 * 3 * 4);
        // Half applies to colour only.
        let half = channels(PassSet::all(), true);
        let kind = |n: &str| half.iter().find(|c| c.name == n).unwrap().sample_type;
        assert_eq!(kind("R"), SampleType::F16);
        assert_eq!(kind("Glossy Direct.G"), SampleType::F16);
        assert_eq!(kind("Denoising Albedo.B"), SampleType::F16);
        assert_eq!(kind("Depth.Z"), SampleType::F32);
        assert_eq!(kind("Normal.X"), SampleType::F32);
        assert_eq!(kind("CryptoObject00.R"), SampleType::F32);
        // The sample count joins when asked or when the file would have no dotted pass.
        assert!(file_passes(PassSet::NONE, false).contains(Pass::SampleCount));
        assert!(!file_passes(PassSet::compositing(), false).contains(Pass::SampleCount));
        assert!(file_passes(PassSet::compositing(), true).contains(Pass::SampleCount));
    }

    #[test]
    fn only_half_colour_is_clamped() {
        let specs = channels(PassSet::NONE.with(Pass::Depth), true);
        let mut values = vec![1e6, -1e6, 1.0, 1.0, 1e6, 7e4, 0.5, 0.0, 1.0, 2e5];
        // Two pixels (R, G, B, A as half; Depth as f32): R and G of the first, R of the second.
        assert_eq!(clamp_half(&mut values, &specs), 3);
        assert_eq!(values[..5], [HALF_MAX, -HALF_MAX, 1.0, 1.0, 1e6]);
        assert_eq!((values[5], values[9]), (HALF_MAX, 2e5));
        let full = channels(PassSet::NONE, false);
        assert_eq!(clamp_half(&mut [1e9; 4], &full), 0);
    }
}
