//! Cameras: glTF cameras placed by their nodes (scale removed, SPEC §1) with depth of field
//! resolved (SPEC §3); the automatic camera of a scene without one is `crate::auto_camera`.

use glam::{Affine3A, Mat3, Vec3};
use serde_json::Value;

use crate::dof::{self, CameraInput, NodeInfo};
use crate::error::Error;
use crate::types::{Camera, LoadOptions, Projection};

/// Rotation and translation of a world transform: scale and shear removed (SPEC §1), keeping the
/// view axis (−Z) exact and +Y as close to the node's as possible.
pub(crate) fn orthonormal(world: Affine3A) -> Option<Affine3A> {
    let z = Vec3::from(world.matrix3.z_axis).try_normalize()?;
    let y0 = Vec3::from(world.matrix3.y_axis);
    let y = (y0 - z * z.dot(y0)).try_normalize()?;
    let x = y.cross(z);
    Some(Affine3A {
        matrix3: Mat3::from_cols(x, y, z).into(),
        translation: world.translation,
    })
}

/// A glTF camera as stored: what a pose needs to place it and resolve its depth of field.
#[derive(Debug, Clone)]
pub(crate) struct CameraData {
    /// `cameras[i].name`.
    pub name: Option<String>,
    /// Validated projection.
    pub projection: Projection,
    /// `extensions.EXT_camera_physical`.
    pub physical: Option<Value>,
    /// `extras`.
    pub extras: Option<Value>,
}

/// Reads and checks every camera of the document.
pub(crate) fn read_cameras(doc: &gltf::Document) -> Result<Vec<CameraData>, Error> {
    doc.cameras()
        .map(|cam| {
            let at = format!("cameras[{}]", cam.index());
            let projection = match cam.projection() {
                gltf::camera::Projection::Perspective(p) => {
                    check_yfov(p.yfov(), &format!("{at}.perspective.yfov"))?;
                    Projection::Perspective {
                        yfov: p.yfov(),
                        aspect_ratio: p.aspect_ratio(),
                    }
                }
                gltf::camera::Projection::Orthographic(o) => {
                    let (xmag, ymag) = (o.xmag(), o.ymag());
                    if let Some(v) = [xmag, ymag].iter().find(|v| !v.is_finite()) {
                        return Err(Error::NonFinite {
                            at: format!("{at}.orthographic"),
                            value: v.to_string(),
                        });
                    }
                    Projection::Orthographic { xmag, ymag }
                }
            };
            Ok(CameraData {
                name: cam.name().map(str::to_owned),
                projection,
                physical: cam.extension_value("EXT_camera_physical").cloned(),
                extras: raw(cam.extras()),
            })
        })
        .collect()
}

/// `extras` as a JSON value.
pub(crate) fn raw(e: &Option<Box<serde_json::value::RawValue>>) -> Option<Value> {
    e.as_ref()
        .and_then(|r| serde_json::from_str::<Value>(r.get()).ok())
}

/// A vertical field of view in (0, π), or an error at `at`.
pub(crate) fn check_yfov(yfov: f32, at: &str) -> Result<(), Error> {
    if yfov.is_finite() && yfov > 0.0 && yfov < std::f32::consts::PI {
        Ok(())
    } else {
        Err(Error::Invalid {
            at: at.into(),
            reason: format!("{yfov} is not in (0, π)"),
        })
    }
}

/// The node carrying a camera.
pub(crate) struct CameraNode<'a> {
    /// Index of the glTF camera.
    pub camera: usize,
    /// Index of the node.
    pub node: usize,
    /// The node's name.
    pub name: Option<&'a str>,
    /// The node's `extras`.
    pub extras: Option<&'a Value>,
}

/// The camera `data` of node `at` placed at `world`.
pub(crate) fn camera(
    data: &CameraData,
    at: &CameraNode<'_>,
    world: Affine3A,
    info: &NodeInfo<'_>,
    options: &LoadOptions,
) -> Result<Camera, Error> {
    let name = data
        .name
        .as_deref()
        .or(at.name)
        .map(str::to_owned)
        .unwrap_or_else(|| format!("camera {}", at.camera));
    let node = at.node;
    let world_from_camera = orthonormal(world).ok_or_else(|| Error::NodeGraph {
        node,
        reason: "the camera's transform has no rotation (zero scale)".into(),
    })?;
    let dof = dof::resolve(
        &CameraInput {
            name: &name,
            projection: data.projection,
            world_from_camera,
            physical: data.physical.as_ref(),
            camera_extras: data.extras.as_ref(),
            node_extras: at.extras,
        },
        &options.dof_overrides,
        info,
    )?;
    Ok(Camera {
        name,
        node: Some(node as u32),
        index: Some(at.camera as u32),
        world_from_camera,
        projection: data.projection,
        dof,
    })
}
