//! What a Python `Scene` holds: the render session (SPEC §9) behind a mutex, locked only
//! without the GIL (a thread waiting for it never blocks Python), and the scene's defaults.

use crate::load_opts::SceneDefaults;
use aperture_accel::BvhQuality;
use aperture_render::{Frame, FrameSpec, Session};
use pyo3::PyResult;
use std::sync::{Arc, Mutex, MutexGuard};

/// A session and what renders of it start from.
pub(crate) struct State {
    /// The loaded file, posed and edited.
    pub session: Session,
    /// Load options every render keeps (time, fps, conventions).
    pub defaults: SceneDefaults,
    /// The spec of the last frame rendered, for ray queries to reuse its BVH.
    pub last_spec: Option<FrameSpec>,
}

/// A session shared by a scene and its progressive renders.
pub(crate) type Shared = Arc<Mutex<State>>;

/// The state, locked (a panic in another holder leaves it usable: every change is whole).
pub(crate) fn lock(s: &Shared) -> MutexGuard<'_, State> {
    s.lock().unwrap_or_else(|e| e.into_inner())
}

impl State {
    /// The frame ray queries use: the last rendered one when it is at the scene's time and
    /// still (no motion blur), else the stored pose at the scene's time with a medium BVH.
    pub fn query_frame(&mut self) -> PyResult<&Frame> {
        let time = self.defaults.time;
        let spec = self
            .last_spec
            .clone()
            .filter(|s| s.time == time && s.motion.is_none())
            .unwrap_or(FrameSpec {
                time,
                quality: BvhQuality::Medium,
                ..FrameSpec::default()
            });
        self.last_spec = Some(spec.clone());
        self.session.frame(&spec).map_err(crate::errors::load_error)
    }
}
