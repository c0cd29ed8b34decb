//! The automatic camera of an animated file without a camera, framed once on the stored pose
//! (SPEC §3) so that every pose of a shot shares it rather than zooming with the bounds.

use glam::DVec3;

use super::Animated;
use crate::auto_camera::Framing;
use crate::dof::NodeInfo;
use crate::error::Error;
use crate::types::{Camera, Scene};

impl Animated {
    /// Frames the automatic camera on the stored pose, when posing needs one and a time could
    /// change the bounds (a file that animates nothing is always posed as stored, and framed
    /// by that pose as it is built). The stored pose is built once, the static meshes moved
    /// into it and back rather than copied.
    pub(super) fn frame_stored_pose(&mut self) -> Result<(), Error> {
        if !self.is_animated() || self.has_camera() {
            return Ok(());
        }
        let meshes = std::mem::take(&mut self.static_meshes);
        let count = meshes.len();
        // On an error the meshes are gone with it, and so is the load that called this.
        let mut stored = self.build(None, meshes, Vec::new())?;
        self.framing = Some(Framing::of(stored.bounds(), stored.world_origin));
        stored.meshes.truncate(count);
        self.static_meshes = std::mem::take(&mut stored.meshes);
        Ok(())
    }

    /// The automatic camera of `posed` (recentred on `origin`): framed on the stored pose, not
    /// this one, so that a shot's frames share one camera.
    pub(super) fn automatic_camera(
        &self,
        posed: &Scene,
        origin: DVec3,
        info: &NodeInfo<'_>,
    ) -> Result<Camera, Error> {
        let framing = match self.framing {
            Some(f) => f,
            // Nothing animates, or this is the stored pose being framed: the same bounds.
            None => Framing::of(posed.bounds(), origin),
        };
        framing.camera(origin, info, &self.options)
    }

    /// True when a drawn node carries a camera of the file (posing places file cameras then,
    /// never the automatic one, at every time).
    fn has_camera(&self) -> bool {
        self.order.iter().any(|&ni| {
            self.graph.nodes[ni]
                .camera
                .is_some_and(|ci| ci < self.cameras.len())
        })
    }
}
