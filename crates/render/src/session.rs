//! A render session (SPEC §9): a file loaded once, posed into [`Frame`]s, and edited in
//! place. What does not depend on the pose is kept for the session's life (the decoded file:
//! meshes, textures, materials; the last frame's bottom-level BVHs; the last light tree); a
//! frame is built once per time and shared by every render of it; an edit redoes only what
//! depends on it, and leaves the session exactly as if the file had stored the edited value.
//!
//! ```
//! use aperture_render::{FrameSpec, RenderOptions, Session};
//! use aperture_scene::Edit;
//! # let path = std::env::temp_dir().join(format!("aperture-session-doc-{}.gltf", std::process::id()));
//! # std::fs::write(&path, r#"{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],
//! #   "nodes":[{"camera":0,"translation":[0,0,3]}],
//! #   "cameras":[{"type":"perspective","perspective":{"yfov":0.8,"znear":0.1}}]}"#).unwrap();
//! let mut session = Session::load(&path, &Default::default())?;
//! let opts = RenderOptions { width: 8, height: 8, spp: 2, ..Default::default() };
//! let before = session.frame(&FrameSpec::default())?.render(&opts, &|_, _| {})?;
//! // Pull focus: only the cameras are posed again, the BVH stays.
//! let focus = Edit::CameraKey { camera: 0, key: "focus_distance".into(), value: 2.0.into() };
//! session.edit(focus)?;
//! let after = session.frame(&FrameSpec::default())?.render(&opts, &|_, _| {})?;
//! assert_eq!(before.window(), after.window());
//! # std::fs::remove_file(&path).ok();
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use crate::frame::{Frame, FrameTimes};
use crate::frame_accel::{build_motion_accel, SceneHints};
use crate::motion::{pose_frame_motion, pose_neighbours, MotionSettings};
use aperture_accel::{Accel, BvhQuality};
use aperture_scene::{Animated, Edit, LoadOptions, Scene, Touched};
use aperture_shading::light_tree::TreeMemo;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

/// Which frame to pose, and what it is built for.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameSpec {
    /// Seconds (`None`: the stored pose, no animation evaluated). Frame N of a shot is at
    /// N / fps (Blender's exporter).
    pub time: Option<f64>,
    /// Frames per second, for the shutter and the neighbouring frames.
    pub fps: f32,
    /// The BVH preset.
    pub quality: BvhQuality,
    /// Motion blur: the shutter around the frame's time (`None`, or no time: every sample at
    /// the frame's instant).
    pub motion: Option<MotionSettings>,
    /// Pose the frames before and after, for the Vector pass (needs a time).
    pub vector: bool,
    /// The camera index and image size that the camera's motion and the Vector pass are for.
    pub view: (usize, u32, u32),
}

impl FrameSpec {
    /// True when `other` is built into the same frame: the view and the frame rate shape only
    /// a frame's camera motion and neighbouring poses, so without motion blur and the Vector
    /// pass any image size shares it (a viewport's small first image and its full passes).
    fn same_frame(&self, other: &FrameSpec) -> bool {
        let follows_view = self.motion.is_some() || self.vector;
        self.time == other.time
            && self.quality == other.quality
            && self.motion == other.motion
            && self.vector == other.vector
            && (!follows_view || (self.view == other.view && self.fps == other.fps))
    }
}

impl Default for FrameSpec {
    fn default() -> Self {
        Self {
            time: None,
            fps: 24.0,
            quality: BvhQuality::default(),
            motion: None,
            vector: false,
            view: (0, 960, 540),
        }
    }
}

/// Why a session could not load, pose or edit.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SessionError {
    /// The file could not be loaded or posed, or an edit was refused.
    #[error(transparent)]
    Scene(#[from] aperture_scene::Error),
    /// An edit needs the file loaded again (visibility, morph weights, skin joints), and this
    /// session was made from a document, not a file.
    #[error("{0:?} needs the file loaded again, but this session was not loaded from a file")]
    NoFile(Edit),
}

/// A file loaded once, posed into frames and edited in place (see the module documentation).
pub struct Session {
    animated: Animated,
    source: Option<(PathBuf, LoadOptions)>,
    /// Every edit so far, for a reload to replay.
    edits: Vec<Edit>,
    memo: Arc<TreeMemo>,
    /// A scene posed ahead of its frame ([`Session::pose`]), with its time.
    pending: Option<(Option<f64>, Scene)>,
    current: Option<(FrameSpec, Frame)>,
    /// The last frame's BVH and its preset, for the next frame to take unchanged meshes from.
    spare: Option<(Accel, BvhQuality)>,
}

impl Session {
    /// Loads `path` (SPEC §5's load options).
    pub fn load(path: &Path, options: &LoadOptions) -> Result<Self, SessionError> {
        let animated = Animated::load(path, options)?;
        let mut session = Self::new(animated);
        session.source = Some((path.to_path_buf(), options.clone()));
        Ok(session)
    }

    /// Loads `path` as if it stored the values `edits` set ([`Animated::load_edited`]): one
    /// load where [`Session::load`] and the edits one by one could load several times (each
    /// [`Edit::MeshGeometry`] loads the file again).
    pub fn load_edited(
        path: &Path,
        options: &LoadOptions,
        edits: Vec<Edit>,
    ) -> Result<Self, SessionError> {
        let animated = Animated::load_edited(path, options, &edits)?;
        let mut session = Self::new(animated);
        session.source = Some((path.to_path_buf(), options.clone()));
        for e in edits {
            session.remember(e);
        }
        Ok(session)
    }

    /// A session of a document already loaded (edits that need a reload are refused).
    pub fn new(animated: Animated) -> Self {
        Self {
            animated,
            source: None,
            edits: Vec::new(),
            memo: Arc::default(),
            pending: None,
            current: None,
            spare: None,
        }
    }

    /// The loaded document.
    pub fn animated(&self) -> &Animated {
        &self.animated
    }

    /// The edits made so far, in order.
    pub fn edits(&self) -> &[Edit] {
        &self.edits
    }

    /// The scene posed at `time`, without building anything for rendering it (to choose a
    /// camera or image size from it): kept for [`Session::frame`] at the same time.
    pub fn pose(&mut self, time: Option<f64>) -> Result<&Scene, SessionError> {
        if let Some((spec, frame)) = &self.current {
            if spec.time == time {
                return Ok(frame.scene());
            }
        }
        if !matches!(&self.pending, Some((t, _)) if *t == time) {
            let scene = self.animated.scene_at(time.map(|t| t as f32))?;
            self.pending = Some((time, scene));
        }
        let (_, scene) = self.pending.as_ref().expect("posed above");
        Ok(scene)
    }

    /// The frame of `spec`: posed and built on the first call, kept while the document and
    /// what the spec shapes stay the same (another image size shares a frame without motion
    /// blur or the Vector pass). A new time poses the scene again and rebuilds only what moved
    /// (the bottom-level BVHs of unchanged meshes are taken from the frame before).
    pub fn frame(&mut self, spec: &FrameSpec) -> Result<&Frame, SessionError> {
        let kept = matches!(&self.current, Some((s, _)) if s.same_frame(spec));
        if !kept {
            self.build_frame(spec)?;
        }
        let (_, frame) = self.current.as_ref().expect("built above");
        Ok(frame)
    }

    fn build_frame(&mut self, spec: &FrameSpec) -> Result<(), SessionError> {
        let t0 = Instant::now();
        let (scene, previous) = self.take_scene(spec)?;
        let pose_secs = t0.elapsed().as_secs_f64();
        let view = spec.view;
        let animated = &self.animated;
        let fps = f64::from(spec.fps);
        let motion = match (&spec.motion, spec.time) {
            (Some(settings), Some(t)) => {
                pose_frame_motion(animated, settings, (t, fps), &scene, view)?.map(Arc::new)
            }
            _ => None,
        };
        let vector = match (spec.vector, spec.time) {
            (true, Some(t)) => pose_neighbours(animated, (t, fps), &scene, view)?.map(Arc::new),
            _ => None,
        };
        // Instances moving and meshes deforming within the shutter need a structure bounding
        // them over it, built whole (nothing of the frame before reused).
        let moving = motion.as_deref().filter(|m| m.moves_geometry());
        let previous = previous.filter(|(_, q)| moving.is_none() && *q == spec.quality);
        let hints = SceneHints::new(animated, &scene);
        let accel = build_motion_accel(&scene, spec.quality, &hints, previous.map(|p| p.0), moving);
        let times = FrameTimes {
            pose_secs,
            build_secs: t0.elapsed().as_secs_f64() - pose_secs,
        };
        let frame = Frame::posed(
            scene,
            accel,
            (motion, vector),
            Arc::clone(&self.memo),
            times,
        );
        self.current = Some((spec.clone(), frame));
        Ok(())
    }

    /// The scene of `spec`'s time (the current frame's or the pending one when they are at
    /// that time, else posed now) and the BVH of the frame before, if any.
    fn take_scene(
        &mut self,
        spec: &FrameSpec,
    ) -> Result<(Scene, Option<(Accel, BvhQuality)>), SessionError> {
        let at_time = |posed: Option<(Option<f64>, Scene)>| posed.filter(|p| p.0 == spec.time);
        let kept = at_time(self.retire()).or_else(|| at_time(self.pending.take()));
        let scene = match kept {
            Some((_, scene)) => scene,
            None => self.animated.scene_at(spec.time.map(|t| t as f32))?,
        };
        Ok((scene, self.spare.take()))
    }

    /// Applies `edit` (SPEC §9): afterwards every render equals one of a cold load of the file
    /// with the edited value, bit for bit. Cameras, lights and materials are changed in the
    /// current frame in place (no BVH work); transforms pose the scene again at the next
    /// [`Session::frame`] (unchanged meshes keep their BVHs); visibility, morph weights and
    /// skin joints load the file again with every edit so far.
    pub fn edit(&mut self, edit: Edit) -> Result<Touched, SessionError> {
        let touched = self.animated.edit(&edit)?;
        self.pending = None;
        match touched {
            Touched::Reload => {
                let Some((path, options)) = &self.source else {
                    return Err(SessionError::NoFile(edit));
                };
                let mut edits = self.edits.clone();
                edits.push(edit.clone());
                self.animated = Animated::load_edited(path, options, &edits)?;
                // The decoded meshes may differ: nothing built from the old ones is kept.
                self.current = None;
                self.spare = None;
            }
            Touched::Placements => drop(self.retire()),
            Touched::Cameras | Touched::Lights | Touched::Materials => self.refresh(touched)?,
        }
        self.remember(edit);
        Ok(touched)
    }

    /// Adds `edit` to the list a reload replays; a mesh's new geometry replaces the one it
    /// was given before (only the last counts, and each holds the mesh's arrays).
    fn remember(&mut self, edit: Edit) {
        if let Edit::MeshGeometry { mesh, .. } = &edit {
            let earlier = |e: &Edit| matches!(e, Edit::MeshGeometry { mesh: m, .. } if m == mesh);
            self.edits.retain(|e| !earlier(e));
        }
        self.edits.push(edit);
    }

    /// The current frame's cameras, lights or materials posed again in place; a frame whose
    /// motion or neighbouring poses follow its cameras is posed again whole instead.
    fn refresh(&mut self, touched: Touched) -> Result<(), SessionError> {
        let Some((spec, frame)) = &mut self.current else {
            return Ok(());
        };
        let follows_cameras = frame.motion().is_some() || spec.vector;
        if touched == Touched::Cameras && follows_cameras {
            self.retire();
            return Ok(());
        }
        self.animated.refresh(frame.scene_mut(), touched)?;
        if touched != Touched::Cameras {
            frame.forget_lights();
        }
        Ok(())
    }

    /// Forgets the current frame, keeping its BVH for the next one; returns its time and
    /// scene.
    fn retire(&mut self) -> Option<(Option<f64>, Scene)> {
        let (spec, frame) = self.current.take()?;
        let (scene, accel) = frame.into_parts();
        self.spare = Some((accel, spec.quality));
        Some((spec.time, scene))
    }
}
