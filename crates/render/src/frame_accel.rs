//! The ray-query structure of a posed scene: built whole for a still frame, or rebuilt from the
//! frame before where only some instances move and some meshes deform (SPEC §7), with the BVH
//! preset chosen for the job's size.

use aperture_accel::{Accel, BvhQuality, FrameHints, InstanceInput, MeshInput};
use aperture_scene::{Animated, Scene};

/// Builds the ray-query structure for a scene.
pub fn build_accel(scene: &Scene, quality: aperture_accel::BvhQuality) -> Accel {
    let still = SceneHints::still();
    build_motion_accel(scene, quality, &still, None, None)
}

/// The BVH preset for a job of `samples` camera samples over `triangles` stored triangles, so a
/// preview does not pay for a build it cannot win back.
///
/// Measured with callgrind (instruction counts, repeatable on a loaded machine): building the
/// 1.04 M-triangle `MetalRoughSpheresNoTextures` takes about 880 fewer instructions per triangle
/// with `fast` than with `medium` (3.17 G against 4.09 G for the whole run), while `fast`'s tree
/// costs 251 more per closest-hit thin-lens ray on `BlenderIO-32bitIndices` (1,406 against
/// 1,155). A path-traced sample casts about three rays, so `fast` wins while
/// `samples < 880 / (3 · 251) · triangles ≈ 1.2 · triangles`; the rule keeps a margin and
/// switches at one half. `high` (1,140 per ray, about four times `medium`'s build) is never
/// chosen: it pays off only for renders far longer than its build, which the user knows better.
pub fn auto_bvh_quality(triangles: usize, samples: u64) -> BvhQuality {
    if samples.saturating_mul(2) < triangles as u64 {
        BvhQuality::Fast
    } else {
        BvhQuality::Medium
    }
}

/// The BVH preset a job asks for (`--bvh-quality`): `auto`, or one [`BvhQuality`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum BvhQualityChoice {
    /// Chosen from the job by [`auto_bvh_quality`].
    #[default]
    Auto,
    /// This preset.
    Preset(BvhQuality),
}

impl BvhQualityChoice {
    /// The preset for a job of `samples` camera samples over `triangles` stored triangles.
    pub fn resolve(self, triangles: usize, samples: u64) -> BvhQuality {
        match self {
            Self::Auto => auto_bvh_quality(triangles, samples),
            Self::Preset(q) => q,
        }
    }
}

/// `auto`, then [`BvhQuality`]'s own values (their spellings and help are its `ValueEnum`'s).
#[cfg(feature = "clap")]
impl clap::ValueEnum for BvhQualityChoice {
    fn value_variants<'a>() -> &'a [Self] {
        &[
            Self::Auto,
            Self::Preset(BvhQuality::Fast),
            Self::Preset(BvhQuality::Medium),
            Self::Preset(BvhQuality::High),
        ]
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        match self {
            Self::Auto => Some(clap::builder::PossibleValue::new("auto").help(
                "Chosen from the job: `fast` when the render takes fewer samples than half the \
                 scene's triangles (a preview of a big scene), else `medium`",
            )),
            Self::Preset(q) => q.to_possible_value(),
        }
    }
}

/// What of a posed scene may change between frames, for [`Accel::build_frame`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SceneHints {
    /// Per instance of the scene: its node moves with time, or its visibility is keyed (it
    /// comes and goes, and kept out of the world-space BVH, it does not make that be rebuilt).
    pub moving: Vec<bool>,
    /// Meshes from this index on deform with time.
    pub deforming_from: usize,
}

impl SceneHints {
    /// A still scene: nothing moves or deforms ([`FrameHints::STILL`]).
    pub fn still() -> Self {
        Self {
            moving: Vec::new(),
            deforming_from: FrameHints::STILL.deforming_from,
        }
    }

    /// The hints of `scene`, posed from `animated`.
    pub fn new(animated: &Animated, scene: &Scene) -> Self {
        let moving_nodes = animated.moving_nodes();
        let toggling_nodes = animated.toggling_nodes();
        let changes = |node: u32| {
            moving_nodes.binary_search(&node).is_ok() || toggling_nodes.binary_search(&node).is_ok()
        };
        Self {
            moving: scene.instances.iter().map(|i| changes(i.node)).collect(),
            deforming_from: animated.static_mesh_count(),
        }
    }
}

/// The scene's meshes and instances as the accel's build takes them.
fn accel_inputs(scene: &Scene) -> (Vec<MeshInput<'_>>, Vec<InstanceInput>) {
    let meshes = (scene.meshes.iter())
        .map(|m| MeshInput {
            positions: &m.positions,
            indices: &m.indices,
        })
        .collect();
    let instances = (scene.instances.iter())
        .map(|i| InstanceInput {
            mesh: i.mesh,
            world_from_object: i.world_from_object,
        })
        .collect();
    (meshes, instances)
}

/// What [`build_accel`] would count of `scene`'s triangles and instances (degenerate, out of
/// range, skipped: [`Accel::input_counts`]), without building it.
pub fn accel_input_counts(scene: &Scene) -> aperture_accel::AccelStats {
    let (meshes, instances) = accel_inputs(scene);
    Accel::input_counts(&meshes, &instances, FrameHints::STILL)
}

/// The ray-query structure of one frame of `scene` (see [`Accel::build_frame`]); `previous`
/// is the frame before's, whose unchanged parts are taken over (the result does not depend on
/// it). The instances that move within the frame's shutter (`motion`) are bounded over it and
/// walked at each ray's time, and the meshes that deform within it are built over their swept
/// triangles and intersected as interpolated at each ray's time. A render of a single frame of
/// an animated file builds with the same hints as a sequence, so its image is the sequence's
/// frame bit for bit.
pub fn build_motion_accel(
    scene: &Scene,
    quality: BvhQuality,
    hints: &SceneHints,
    previous: Option<Accel>,
    motion: Option<&crate::motion::FrameMotion>,
) -> Accel {
    let keys = motion.map(|m| m.instance_keys()).unwrap_or_default();
    let (meshes, instances) = accel_inputs(scene);
    let frame = FrameHints {
        moving: &hints.moving,
        deforming_from: hints.deforming_from,
        motion: &keys,
        deforming: motion.map_or(&[], |m| &m.meshes),
        ..FrameHints::STILL
    };
    Accel::build_frame(&meshes, &instances, quality, frame, previous)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn previews_of_big_scenes_build_fast() {
        // A 1-spp 960×540 preview of a 7.7 M-triangle scene, and of a 130 k one.
        assert_eq!(auto_bvh_quality(7_700_000, 518_400), BvhQuality::Fast);
        assert_eq!(auto_bvh_quality(130_000, 518_400), BvhQuality::Medium);
        // The README's demo render (18 k triangles, 64 spp) and an empty scene.
        assert_eq!(auto_bvh_quality(18_000, 33_177_600), BvhQuality::Medium);
        assert_eq!(auto_bvh_quality(0, 1), BvhQuality::Medium);
        // The switch sits at samples = triangles / 2, and huge jobs do not overflow.
        assert_eq!(auto_bvh_quality(1_000_001, 500_000), BvhQuality::Fast);
        assert_eq!(auto_bvh_quality(1_000_000, 500_000), BvhQuality::Medium);
        assert_eq!(auto_bvh_quality(usize::MAX, u64::MAX), BvhQuality::Medium);
    }

    #[test]
    fn a_chosen_preset_is_kept_and_auto_decides_from_the_job() {
        let preview = (7_700_000, 518_400);
        let high = BvhQualityChoice::Preset(BvhQuality::High);
        assert_eq!(high.resolve(preview.0, preview.1), BvhQuality::High);
        let auto = BvhQualityChoice::default();
        assert_eq!(auto.resolve(preview.0, preview.1), BvhQuality::Fast);
        assert_eq!(auto.resolve(18_000, 33_177_600), BvhQuality::Medium);
    }
}
