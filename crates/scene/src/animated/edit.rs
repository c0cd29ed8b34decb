//! [`Edit`]s applied to a loaded document in place, and a posed scene's cameras, lights or
//! materials recomputed after one ([`Animated::refresh`]), exactly as posing would.

use glam::Vec3;
use serde_json::Value;

use super::{lens_images, Animated, LightData};
use crate::camera;
use crate::edit::{
    clear_node_key, load_edit, set_extra, with_component, Edit, Touched, LOADED_KEY,
};
use crate::error::Error;
use crate::nodes::{finite, inherited, LocalTransform};
use crate::pointer::{self, CameraProperty, LightProperty, NodeProperty, Pointer};
use crate::types::{LightKind, Projection, Scene};

impl Animated {
    /// Loads `path` as if it stored the values `edits` set (in order): what a session that
    /// made those edits reloads.
    pub fn load_edited(
        path: &std::path::Path,
        options: &crate::types::LoadOptions,
        edits: &[Edit],
    ) -> Result<Self, Error> {
        let at_load: Vec<Edit> = edits.iter().filter(|e| load_edit(e)).cloned().collect();
        let mut animated = Self::load_path(path, options, &at_load)?;
        for e in edits.iter().filter(|e| !load_edit(e)) {
            animated.edit(e)?;
        }
        Ok(animated)
    }

    /// Applies `edit` to the stored document and says what it touched. An edit this document
    /// cannot take in place ([`Touched::Reload`]) changes nothing here: load the file again
    /// with [`Animated::load_edited`].
    pub fn edit(&mut self, edit: &Edit) -> Result<Touched, Error> {
        match edit {
            Edit::NodeMatrix { node, matrix } => {
                self.check_node(*node)?;
                finite(|| format!("nodes[{node}].matrix"), matrix.as_flattened())?;
                self.set_local(*node, LocalTransform::Matrix(*matrix))
            }
            Edit::NodeVisible { node, .. } => {
                self.check_node(*node)?;
                Ok(Touched::Reload)
            }
            Edit::Pointer { path, value } => self.edit_pointer(path, value),
            Edit::CameraKey { camera, key, value } => self.edit_camera_key(*camera, key, value),
            // Checked by the load it asks for: a mesh the file lacks, or a primitive count
            // that differs, is that load's error.
            Edit::MeshGeometry { .. } => Ok(Touched::Reload),
        }
    }

    /// Sets a depth-of-field key of camera `camera`, checked first as posing reads it: a bad
    /// value, or a lens file or bokeh image that cannot be read, is an error that changes
    /// nothing. A bokeh image is read now; one naming a texture not loaded with the file needs
    /// the file loaded again ([`Touched::Reload`]).
    fn edit_camera_key(
        &mut self,
        camera: usize,
        key: &str,
        value: &Value,
    ) -> Result<Touched, Error> {
        let count = self.cameras.len();
        let data = self.cameras.get(camera).ok_or_else(|| Error::Invalid {
            at: format!("cameras[{camera}]"),
            reason: format!("no such camera (the file has {count})"),
        })?;
        if !value.is_null() {
            let one = serde_json::json!({ key: value });
            crate::dof::check_extras(&self.camera_name(camera), &one, &self.base_dir)?;
        }
        let mut extras = data.extras.clone();
        set_extra(&mut extras, key, value.clone());
        if key == LOADED_KEY {
            let images = lens_images::edited(
                &self.base_dir,
                &self.cameras,
                &self.graph,
                &self.options,
                &self.aperture_images,
                (camera, extras.as_ref()),
            )?;
            let Some(images) = images else {
                return Ok(Touched::Reload);
            };
            self.aperture_images = images;
        }
        self.cameras[camera].extras = extras;
        clear_node_key(&mut self.graph, camera, key);
        Ok(Touched::Cameras)
    }

    /// Camera `camera`'s name for messages, as posing names it: its own, its first node's, or
    /// its index.
    fn camera_name(&self, camera: usize) -> String {
        let node = || {
            let carries = |n: &usize| self.graph.nodes[*n].camera == Some(camera);
            let first = (0..self.graph.nodes.len()).find(carries)?;
            self.graph.names[first].clone()
        };
        (self.cameras.get(camera).and_then(|c| c.name.clone()))
            .or_else(node)
            .unwrap_or_else(|| format!("camera {camera}"))
    }

    /// Recomputes `what` of `scene` (posed from this document at `scene.stats.time`) after an
    /// edit: the cameras, lights or materials, exactly as [`Animated::scene_at`] would pose
    /// them. Anything else needs a new pose.
    pub fn refresh(&self, scene: &mut Scene, what: Touched) -> Result<(), Error> {
        let pose = self.pose(scene.stats.time);
        let (lights, cameras, materials) = self.pointed(&pose)?;
        match what {
            Touched::Cameras => {
                let cameras = self.posed_cameras(&pose, &cameras, scene.world_origin)?;
                // A file without cameras keeps its automatic one (no key to edit).
                if !cameras.is_empty() {
                    scene.cameras = cameras;
                }
            }
            Touched::Lights => {
                let hidden = self.hidden_at(&pose);
                scene.lights = self.posed_lights(&pose, &hidden, &lights, scene.world_origin)?;
            }
            Touched::Materials => scene.materials = materials,
            Touched::Placements | Touched::Reload => {
                return Err(Error::Invalid {
                    at: "refresh".into(),
                    reason: format!("{what:?} needs a new pose, not a refresh"),
                })
            }
        }
        Ok(())
    }

    fn check_node(&self, node: usize) -> Result<(), Error> {
        match node < self.graph.nodes.len() {
            true => Ok(()),
            false => Err(Error::Invalid {
                at: format!("nodes[{node}]"),
                reason: format!("no such node (the file has {})", self.graph.nodes.len()),
            }),
        }
    }

    /// Sets a node's stored local transform; what it touches depends on what hangs below it.
    fn set_local(&mut self, node: usize, t: LocalTransform) -> Result<Touched, Error> {
        let below = self.subtree(node);
        let joint = self.skins.iter().flat_map(|s| &s.joints).any(|j| below[*j]);
        if joint {
            return Ok(Touched::Reload);
        }
        self.graph.nodes[node].transform = t;
        if self.framing.is_some() {
            // The automatic camera is framed on the stored pose, which just changed.
            self.framing = None;
            self.frame_stored_pose()?;
        }
        let g = &self.graph;
        let draws = (0..g.nodes.len()).any(|i| below[i] && g.nodes[i].mesh.is_some());
        let lights = (0..g.nodes.len()).any(|i| below[i] && g.nodes[i].light.is_some());
        Ok(if draws || lights {
            Touched::Placements
        } else {
            Touched::Cameras
        })
    }

    /// Per node: it is `node` or below it.
    fn subtree(&self, node: usize) -> Vec<bool> {
        let g = &self.graph;
        inherited(&g.topological, &g.parent, |i| i == node)
    }

    fn edit_pointer(&mut self, path: &str, v: &[f64]) -> Result<Touched, Error> {
        let bad = |reason: String| Error::Invalid {
            at: path.to_owned(),
            reason,
        };
        let p = pointer::parse(path, &self.counts()).ok_or_else(|| {
            bad("not a pointer aperture edits, or an index the file does not have".into())
        })?;
        if let Some(n) = p.width() {
            if v.len() != n {
                return Err(bad(format!("takes {n} numbers, got {}", v.len())));
            }
        }
        if let Some(x) = v.iter().find(|x| !x.is_finite()) {
            return Err(bad(format!("non-finite value {x}")));
        }
        let f = |k: usize| v[k] as f32;
        match p {
            Pointer::Node(_, NodeProperty::Weights) => Ok(Touched::Reload),
            Pointer::MeshWeights(_) => Err(bad(
                "a mesh's default weights are not edited; set the weights of the nodes that draw it"
                    .into(),
            )),
            Pointer::Node(i, prop) => {
                if prop == NodeProperty::Rotation && v.iter().all(|&x| x == 0.0) {
                    return Err(bad("a rotation of zero length".into()));
                }
                let t = with_component(self.graph.nodes[i].transform, prop, v);
                self.set_local(i, t)
            }
            Pointer::NodeVisible(_) => Ok(Touched::Reload),
            Pointer::Camera(i, prop) => {
                let c = &mut self.cameras[i];
                match (prop, &mut c.projection) {
                    (CameraProperty::Yfov, Projection::Perspective { yfov, .. }) => {
                        camera::check_yfov(f(0), path)?;
                        *yfov = f(0);
                    }
                    (CameraProperty::Xmag, Projection::Orthographic { xmag, .. }) => *xmag = f(0),
                    (CameraProperty::Ymag, Projection::Orthographic { ymag, .. }) => *ymag = f(0),
                    _ => {}
                }
                Ok(Touched::Cameras)
            }
            Pointer::CameraExtra(i, key) => {
                pointer::apply_camera_extra(&mut self.cameras[i].extras, key, v[0]);
                clear_node_key(&mut self.graph, i, key);
                Ok(Touched::Cameras)
            }
            Pointer::Light(i, prop) => {
                set_light(&mut self.lights[i], prop, v);
                Ok(Touched::Lights)
            }
            Pointer::Material(i, prop) => {
                if let Some(&ours) = self.material_index.get(&i) {
                    pointer::apply_material(&mut self.materials[ours as usize], prop, v);
                }
                Ok(Touched::Materials)
            }
        }
    }

    /// A document with as many of each thing as this one, for parsing pointers.
    fn counts(&self) -> Value {
        let n = |k: usize| Value::Array(vec![Value::Null; k]);
        let materials = self.file_materials;
        serde_json::json!({
            "nodes": n(self.graph.nodes.len()),
            "cameras": n(self.cameras.len()),
            "materials": n(materials),
            "meshes": n(0),
            "extensions": {"KHR_lights_punctual": {"lights": n(self.lights.len())}},
        })
    }
}

/// Sets a stored light's value, as an animation sample would.
pub(super) fn set_light(l: &mut LightData, prop: LightProperty, v: &[f64]) {
    let f = |k: usize| v.get(k).copied().unwrap_or(0.0) as f32;
    match prop {
        LightProperty::Color => l.color = Vec3::new(f(0), f(1), f(2)),
        LightProperty::Intensity => l.intensity = f(0),
        LightProperty::InnerCone | LightProperty::OuterCone => {
            if let LightKind::Spot {
                inner_cone,
                outer_cone,
            } = &mut l.kind
            {
                match prop {
                    LightProperty::InnerCone => *inner_cone = f(0),
                    _ => *outer_cone = f(0),
                }
            }
        }
        LightProperty::Range => {}
    }
}
