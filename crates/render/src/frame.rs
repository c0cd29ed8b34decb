//! A frame: a scene posed at one time with everything every render of it shares, built once
//! (SPEC §9): its BVH, what moves within its shutter, its neighbouring poses for the Vector
//! pass, and its lights for each way of shading it. Every band, tile, round and pass of the
//! frame renders from here; nothing is kept between frames but what a [`crate::Session`]
//! keeps.

use crate::camera::Camera;
use crate::film::{Film, Window};
use crate::frame_accel::build_accel;
use crate::frame_lights::FrameLights;
use crate::motion::{FrameMotion, FrameNeighbours};
use crate::options::{RenderError, RenderOptions};
use crate::render::{render_in, scene_camera, Posed};
use aperture_accel::{Accel, BvhQuality};
use aperture_scene::Scene;
use aperture_shading::light_tree::TreeMemo;
use aperture_shading::surface::MaterialOverride;
use aperture_shading::Convention;
use std::sync::{Arc, Mutex};

/// What posing a frame took.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FrameTimes {
    /// Seconds posing the scene (zero when the pose was kept).
    pub pose_secs: f64,
    /// Seconds building what the frame's renders share (its BVH, motion, neighbours).
    pub build_secs: f64,
}

/// The options that change what a surface is, and so which emitters a frame has.
type ShadingKey = (MaterialOverride, Convention, Convention);

/// A posed scene ready to render: built once, rendered from any number of times (any camera,
/// size, window, sample range or options), from any number of threads.
pub struct Frame {
    scene: Scene,
    accel: Accel,
    motion: Option<Arc<FrameMotion>>,
    vector: Option<Arc<FrameNeighbours>>,
    memo: Arc<TreeMemo>,
    lights: Mutex<Vec<(ShadingKey, Arc<FrameLights>)>>,
    times: FrameTimes,
}

impl Frame {
    /// A frame of `scene` as it is (no motion), with `accel` built for it.
    pub fn new(scene: Scene, accel: Accel) -> Self {
        Self::posed(
            scene,
            accel,
            (None, None),
            Arc::default(),
            FrameTimes::default(),
        )
    }

    /// A frame of a scene built by hand, its BVH built here.
    pub fn still(scene: Scene, quality: BvhQuality) -> Self {
        let accel = build_accel(&scene, quality);
        Self::new(scene, accel)
    }

    /// A frame with what moves within its shutter (`accel` built with that motion) and its
    /// neighbouring poses, the memo its light trees come from, and what building it took.
    pub(crate) fn posed(
        scene: Scene,
        accel: Accel,
        (motion, vector): (Option<Arc<FrameMotion>>, Option<Arc<FrameNeighbours>>),
        memo: Arc<TreeMemo>,
        times: FrameTimes,
    ) -> Self {
        Self {
            scene,
            accel,
            motion,
            vector,
            memo,
            lights: Mutex::new(Vec::new()),
            times,
        }
    }

    /// What posing and building the frame took.
    pub fn times(&self) -> FrameTimes {
        self.times
    }

    /// The posed scene.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// Its ray-query structure.
    pub fn accel(&self) -> &Accel {
        &self.accel
    }

    /// What moves within the frame's shutter (`None`: motion blur off).
    pub fn motion(&self) -> Option<&Arc<FrameMotion>> {
        self.motion.as_ref()
    }

    /// `opts` with this frame's motion and neighbouring poses (what every render of the frame
    /// uses; the options' own are kept where the frame has none).
    pub fn options(&self, opts: &RenderOptions) -> RenderOptions {
        RenderOptions {
            motion: self.motion.clone().or_else(|| opts.motion.clone()),
            vector: self.vector.clone().or_else(|| opts.vector.clone()),
            ..opts.clone()
        }
    }

    /// The camera `opts.camera` of the frame, for the options' image size.
    pub fn camera(&self, opts: &RenderOptions) -> Result<Camera, RenderError> {
        scene_camera(&self.scene, opts)
    }

    /// Renders the whole image through the camera `opts.camera`.
    pub fn render(
        &self,
        opts: &RenderOptions,
        progress: &(dyn Fn(usize, usize) + Sync),
    ) -> Result<Film, RenderError> {
        let camera = self.camera(opts)?;
        let whole = Window::whole(opts.width, opts.height);
        self.render_window(&camera, opts, whole, progress)
    }

    /// Renders the pixels of `window` only, through `camera`: each bit-identical to the same
    /// pixel of a whole render.
    pub fn render_window(
        &self,
        camera: &Camera,
        opts: &RenderOptions,
        window: Window,
        progress: &(dyn Fn(usize, usize) + Sync),
    ) -> Result<Film, RenderError> {
        let mut film = Film::for_window(window, opts.width, opts.height, opts.passes);
        self.render_onto(camera, opts, &mut film, progress)?;
        Ok(film)
    }

    /// Renders samples `opts.sample_offset .. + opts.spp` of every pixel of `film`'s window onto
    /// the sums it holds (a progressive render's pass; see [`crate::Progressive`]).
    pub fn render_onto(
        &self,
        camera: &Camera,
        opts: &RenderOptions,
        film: &mut Film,
        progress: &(dyn Fn(usize, usize) + Sync),
    ) -> Result<(), RenderError> {
        let opts = self.options(opts);
        let lights = self.lights(&opts);
        let posed = Posed {
            scene: &self.scene,
            accel: &self.accel,
            lights: &lights,
        };
        render_in(&posed, camera, &opts, film, progress)
    }

    /// The frame's lights for the shading of `opts`: built on first use, then shared.
    pub fn lights(&self, opts: &RenderOptions) -> Arc<FrameLights> {
        let key = (opts.material_override, opts.transmission, opts.single_sided);
        // A poisoned lock only means another render panicked: the list is still whole.
        let mut built = self.lights.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((_, l)) = built.iter().find(|(k, _)| *k == key) {
            return Arc::clone(l);
        }
        let geom = crate::render::geometry(&self.scene, opts);
        let lights = Arc::new(FrameLights::build(&geom, Some(&self.memo)));
        built.push((key, Arc::clone(&lights)));
        lights
    }

    /// Drops the lights built so far (after an edit of materials or lights).
    pub(crate) fn forget_lights(&mut self) {
        self.lights
            .get_mut()
            .unwrap_or_else(|e| e.into_inner())
            .clear();
    }

    /// The scene, for an edit to change in place (its BVH stays: only cameras, lights and
    /// materials may change through it).
    pub(crate) fn scene_mut(&mut self) -> &mut Scene {
        &mut self.scene
    }

    /// Takes the frame apart: its scene and its BVH (for the next frame to reuse).
    pub(crate) fn into_parts(self) -> (Scene, Accel) {
        (self.scene, self.accel)
    }
}
