//! Posing a loaded document: a [`Scene`] at one time, with what `KHR_animation_pointer`
//! channels animate applied.

use glam::{Affine3A, DAffine3, DVec3, Vec3};

use super::{Animated, LightData, Pose, Shape, LUMENS_PER_WATT};
use crate::camera::{self, CameraData};
use crate::dof::NodeInfo;
use crate::error::Error;
use crate::mesh::LoadedMesh;
use crate::nodes::{finite_world, to_f32, NodeData};
use crate::origin::world_origin;
use crate::pointer::{self, CameraProperty, Pointer};
use crate::types::{Instance, Light, Material, Mesh, Projection, Scene, Texture};
use std::sync::Arc;

/// The stored lights, cameras and materials with a pose's pointer channels applied
/// ([`Animated::pointed`]).
type Pointed = (Vec<LightData>, Vec<CameraData>, Vec<Material>);

impl Animated {
    /// [`Animated::scene_at`] without textures (none is decoded or copied): what a motion step
    /// needs of a pose (placements, cameras, lights, deformed meshes).
    pub fn shape_at(&self, time: Option<f32>) -> Result<Scene, Error> {
        self.build(time, self.static_meshes.clone(), Vec::new())
    }

    /// The selected scene's motion-blur keys (`scenes[i].extras`, SPEC §7).
    pub fn motion_extras(&self) -> crate::shutter_extras::MotionExtras {
        self.stats.motion
    }

    /// The scene at `time`, with the static meshes and textures given.
    pub(super) fn build(
        &self,
        time: Option<f32>,
        static_meshes: Vec<Arc<Mesh>>,
        textures: Vec<Texture>,
    ) -> Result<Scene, Error> {
        let pose = self.pose(time);
        let mut stats = self.stats.clone();
        stats.time = time;
        let mut out = Scene {
            meshes: static_meshes,
            textures,
            ..Scene::default()
        };
        let mut placed: Vec<(u32, DAffine3, u32)> = Vec::new();
        let (light_data, camera_data, materials) = self.pointed(&pose)?;
        let hidden = self.hidden_at(&pose);
        stats.hidden_nodes = self.order.iter().filter(|&&ni| hidden[ni]).count();
        for &ni in self.order.iter().filter(|&&ni| !hidden[ni]) {
            if let Some(mi) = self.graph.nodes[ni].mesh {
                self.place_mesh(ni, mi, &pose, &mut out.meshes, &mut placed)?;
            }
        }

        let origin = world_origin(&out.meshes, &placed, &mut stats);
        out.world_origin = origin;
        out.instances = instances(&placed, origin)?;
        for inst in &mut out.instances {
            inst.materials = self
                .node_materials
                .get(&(inst.node as usize))
                .copied()
                .unwrap_or(0);
        }
        out.material_sets = self.material_sets.clone();
        out.environment = self.environment.clone();
        out.lights = self.posed_lights(&pose, &hidden, &light_data, origin)?;
        out.cameras = self.posed_cameras(&pose, &camera_data, origin)?;
        out.materials = materials;
        if out.cameras.is_empty() {
            let origins = self.node_origins(&pose, origin);
            let info = NodeInfo {
                names: &self.graph.names,
                origins: &origins,
                base_dir: &self.base_dir,
                images: &self.aperture_images,
            };
            out.cameras
                .push(self.automatic_camera(&out, origin, &info)?);
        }
        if self.draws_nothing && out.instances.is_empty() {
            stats
                .warnings
                .push("the selected scene draws no mesh".into());
        }
        out.stats = stats;
        out.node_names = self.graph.names.clone();
        out.source_hash = self.source_hash;
        Ok(out)
    }

    /// Places node `ni`'s mesh `mi` (each of its GPU instances): a static mesh by index, a
    /// deforming one deformed now and pushed to `meshes`. False when the mesh draws nothing
    /// (the node is then skipped).
    fn place_mesh(
        &self,
        ni: usize,
        mi: usize,
        pose: &Pose,
        meshes: &mut Vec<Arc<Mesh>>,
        placed: &mut Vec<(u32, DAffine3, u32)>,
    ) -> Result<bool, Error> {
        let node = &self.graph.nodes[ni];
        let world = pose.world[ni];
        let (mesh, world_from_mesh) = match self.shapes.get(&ni) {
            Some(Shape::Static {
                mesh,
                offset,
                world_space,
            }) => (
                *mesh,
                if *world_space {
                    DAffine3::from_translation(*offset)
                } else {
                    world * DAffine3::from_translation(*offset)
                },
            ),
            Some(Shape::Deforming) => {
                let (m, centre) = self.deform(ni, mi, pose)?;
                meshes.push(Arc::new(m));
                let i = (meshes.len() - 1) as u32;
                (
                    i,
                    match centre {
                        Some(c) => DAffine3::from_translation(c),
                        None => world,
                    },
                )
            }
            None => return Ok(false),
        };
        match &node.instances {
            Some(locals)
                if !matches!(
                    self.shapes.get(&ni),
                    Some(Shape::Static {
                        world_space: true,
                        ..
                    })
                ) =>
            {
                let offset = world.inverse() * world_from_mesh;
                for local in locals {
                    placed.push((mesh, world * *local * offset, ni as u32));
                }
            }
            _ => placed.push((mesh, world_from_mesh, ni as u32)),
        }
        Ok(true)
    }

    /// Every node's origin at this pose, relative to `origin` (a focus object may be any node).
    fn node_origins(&self, pose: &Pose, origin: DVec3) -> Vec<Vec3> {
        (0..pose.world.len())
            .map(|ni| Vec3::from(to_f32(relative_to(pose.world[ni], origin)).translation))
            .collect()
    }

    /// The stored lights, cameras and materials with what this pose's pointer channels set.
    pub(super) fn pointed(&self, pose: &Pose) -> Result<Pointed, Error> {
        let mut lights = self.lights.clone();
        let mut cameras = self.cameras.clone();
        let mut materials = self.materials.clone();
        self.apply_pointers(pose, &mut lights, &mut cameras, &mut materials)?;
        Ok((lights, cameras, materials))
    }

    /// The punctual lights of the shown nodes at this pose, relative to `origin`. A node whose
    /// mesh draws nothing is skipped whole, its light too.
    pub(super) fn posed_lights(
        &self,
        pose: &Pose,
        hidden: &[bool],
        data: &[LightData],
        origin: DVec3,
    ) -> Result<Vec<Light>, Error> {
        let mut lights = Vec::new();
        let mut positions: Vec<(usize, DVec3)> = Vec::new();
        for &ni in self.order.iter().filter(|&&ni| !hidden[ni]) {
            let node = &self.graph.nodes[ni];
            if node.mesh.is_some() && !self.shapes.contains_key(&ni) {
                continue;
            }
            let Some((li, light)) = node.light.and_then(|li| Some((li, data.get(li)?))) else {
                continue;
            };
            let world = pose.world[ni];
            positions.push((ni, world.translation));
            lights.push(punctual_light(li, light, world)?);
        }
        place_lights(&mut lights, &positions, origin)?;
        Ok(lights)
    }

    /// The cameras of the drawn nodes at this pose, in drawing order, relative to `origin`;
    /// whole transforms only for the camera nodes (48 bytes a node less for large scenes).
    pub(super) fn posed_cameras(
        &self,
        pose: &Pose,
        camera_data: &[CameraData],
        origin: DVec3,
    ) -> Result<Vec<crate::types::Camera>, Error> {
        let world_from_node = |ni: usize| to_f32(relative_to(pose.world[ni], origin));
        let origins = self.node_origins(pose, origin);
        let info = NodeInfo {
            names: &self.graph.names,
            origins: &origins,
            base_dir: &self.base_dir,
            images: &self.aperture_images,
        };
        let mut cameras = Vec::new();
        for &ni in &self.order {
            let node = &self.graph.nodes[ni];
            let Some(ci) = node.camera else { continue };
            let Some(data) = camera_data.get(ci) else {
                continue;
            };
            let world = finite_world(ni, world_from_node(ni))?;
            let at = camera::CameraNode {
                camera: ci,
                node: ni,
                name: self.graph.names[ni].as_deref(),
                extras: node.extras.as_ref(),
            };
            cameras.push(camera::camera(data, &at, world, &info, &self.options)?);
        }
        Ok(cameras)
    }

    /// Sets what `KHR_animation_pointer` channels animate at this pose.
    fn apply_pointers(
        &self,
        pose: &Pose,
        lights: &mut [LightData],
        cameras: &mut [CameraData],
        materials: &mut [Material],
    ) -> Result<(), Error> {
        for (p, v) in &pose.pointers {
            let f = |k: usize| v.get(k).copied().unwrap_or(0.0) as f32;
            match p {
                Pointer::Camera(i, prop) => {
                    let Some(c) = cameras.get_mut(*i) else {
                        continue;
                    };
                    match (prop, &mut c.projection) {
                        (CameraProperty::Yfov, Projection::Perspective { yfov, .. }) => {
                            camera::check_yfov(
                                f(0),
                                &format!("cameras[{i}].perspective.yfov (animated)"),
                            )?;
                            *yfov = f(0);
                        }
                        (CameraProperty::Xmag, Projection::Orthographic { xmag, .. }) => {
                            *xmag = f(0)
                        }
                        (CameraProperty::Ymag, Projection::Orthographic { ymag, .. }) => {
                            *ymag = f(0)
                        }
                        _ => {}
                    }
                }
                Pointer::CameraExtra(i, key) => {
                    if let Some(c) = cameras.get_mut(*i) {
                        pointer::apply_camera_extra(&mut c.extras, key, v[0]);
                    }
                }
                Pointer::Light(i, prop) => {
                    if let Some(l) = lights.get_mut(*i) {
                        super::edit::set_light(l, *prop, v);
                    }
                }
                Pointer::Material(i, prop) => {
                    if let Some(&ours) = self.material_index.get(i) {
                        if let Some(m) = materials.get_mut(ours as usize) {
                            pointer::apply_material(m, *prop, v);
                        }
                    }
                }
                // Visibility is read by `hidden_at`; nodes and mesh weights by the pose.
                Pointer::Node(..) | Pointer::MeshWeights(_) | Pointer::NodeVisible(_) => {}
            }
        }
        Ok(())
    }
}

impl Pose {
    /// Morph weights of node `ni` drawing mesh `mi`: animated node weights, else `node.weights`,
    /// else animated mesh weights, else `mesh.weights`.
    pub(super) fn weights(
        &self,
        ni: usize,
        mi: usize,
        node: &NodeData,
        lm: &LoadedMesh,
    ) -> Vec<f32> {
        if let Some(w) = self.node_weights.get(&ni) {
            return w.clone();
        }
        if let Some(w) = &node.weights {
            return w.clone();
        }
        if let Some(w) = self.mesh_weights.get(&mi) {
            return w.clone();
        }
        lm.weights.clone()
    }
}

/// A `KHR_lights_punctual` light of node transform `world`, at the origin until the scene is
/// recentred. Blender's importer divides candela and lux by [`LUMENS_PER_WATT`] (SPEC §4).
fn punctual_light(li: usize, light: &LightData, world: DAffine3) -> Result<Light, Error> {
    let intensity = light.color * light.intensity / LUMENS_PER_WATT;
    if !intensity.is_finite() {
        return Err(Error::NonFinite {
            at: format!("KHR_lights_punctual.lights[{li}]"),
            value: format!("{intensity:?}"),
        });
    }
    Ok(Light {
        name: light.name.clone(),
        kind: light.kind,
        position: Vec3::ZERO,
        direction: world
            .transform_vector3(DVec3::NEG_Z)
            .as_vec3()
            .try_normalize()
            .unwrap_or(Vec3::NEG_Z),
        intensity,
    })
}

/// `m` with `origin` subtracted from its translation (in f64, before rounding to f32).
fn relative_to(m: DAffine3, origin: DVec3) -> DAffine3 {
    DAffine3 {
        matrix3: m.matrix3,
        translation: m.translation - origin,
    }
}

/// The instances of the placed meshes (mesh, world transform, node), relative to `origin`.
fn instances(placed: &[(u32, DAffine3, u32)], origin: DVec3) -> Result<Vec<Instance>, Error> {
    placed
        .iter()
        .map(|&(mesh, world, node)| {
            Ok(Instance {
                mesh,
                world_from_object: finite_world(node as usize, to_f32(relative_to(world, origin)))?,
                node,
                materials: 0,
            })
        })
        .collect()
}

/// Sets each light's position, relative to `origin`, from its node's world position.
fn place_lights(
    lights: &mut [Light],
    positions: &[(usize, DVec3)],
    origin: DVec3,
) -> Result<(), Error> {
    for (light, &(node, p)) in lights.iter_mut().zip(positions) {
        let position = (p - origin).as_vec3();
        finite_world(node, Affine3A::from_translation(position))?;
        light.position = position;
    }
    Ok(())
}
