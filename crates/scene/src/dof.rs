//! Depth of field resolved from every source of SPEC §3.
//!
//! Sources, lowest precedence first: defaults → `EXT_camera_physical` → `cameras[i].extras` →
//! `nodes[j].extras` → command line. Each source is parsed into a [`Layer`] of optional values, and
//! a later layer overrides an earlier one key by key, with two pairs decided per source rather than
//! per key, so that a higher source always wins:
//! - the aperture: the highest source giving `aperture_radius` or `aperture_fstop` decides, and
//!   inside it `aperture_radius` wins over `aperture_fstop`;
//! - the focus: the highest source giving `focus_object` or `focus_distance` decides, and inside it
//!   `focus_object` wins over `focus_distance`.
//!
//! `use_dof` defaults to on when any source gives an aperture. An aperture given on the command
//! line turns depth of field on even if the file says `use_dof: false` (unless `--no-dof`): the
//! user asked for it explicitly.

pub(crate) mod image;
mod layer;
mod prescription;

use glam::{Affine3A, Vec3};
use serde_json::Value;

use crate::error::Error;
use crate::types::{Chromatic, Distortion, Dof, DofOverrides, LensOptions, Projection, SensorFit};
use layer::{parse_extras, parse_overrides, parse_physical, Ctx, FocusTarget, Layer};

/// Blender's default image aspect (36 × 24 mm sensor) when a camera has no `aspectRatio`.
pub const DEFAULT_ASPECT: f32 = 1.5;

/// What the resolver needs to know about the scene's nodes for `focus_object`.
pub(crate) struct NodeInfo<'a> {
    /// Node names by index.
    pub names: &'a [Option<String>],
    /// World-space origin of every node.
    pub origins: &'a [Vec3],
    /// The glTF file's folder, where a `lens_prescription` path starts.
    pub base_dir: &'a std::path::Path,
    /// The bokeh images loaded with the file (`aperture_image`).
    pub images: &'a image::ApertureImages,
}

/// The inputs for one camera.
pub(crate) struct CameraInput<'a> {
    /// Camera name for messages.
    pub name: &'a str,
    /// Projection (for the lens derived from `yfov`).
    pub projection: Projection,
    /// Camera-to-world transform (rotation + translation).
    pub world_from_camera: Affine3A,
    /// `cameras[i].extensions.EXT_camera_physical`.
    pub physical: Option<&'a Value>,
    /// `cameras[i].extras`.
    pub camera_extras: Option<&'a Value>,
    /// `nodes[j].extras`.
    pub node_extras: Option<&'a Value>,
}

/// Blender's focal length for a vertical field of view (SPEC §3, `lens` default).
pub fn lens_from_yfov(
    yfov: f32,
    aspect: f32,
    sensor_width: f32,
    sensor_height: f32,
    fit: SensorFit,
) -> f32 {
    let t = (0.5 * yfov).tan();
    match fit {
        SensorFit::Auto if aspect >= 1.0 => sensor_width / (2.0 * aspect * t),
        SensorFit::Auto => sensor_width / (2.0 * t),
        SensorFit::Horizontal => sensor_width / (2.0 * aspect * t),
        SensorFit::Vertical => sensor_height / (2.0 * t),
    }
}

/// Resolves a camera's depth of field from every source.
pub(crate) fn resolve(
    cam: &CameraInput<'_>,
    overrides: &DofOverrides,
    nodes: &NodeInfo<'_>,
) -> Result<Dof, Error> {
    let ctx = |prefix| Ctx {
        camera: cam.name,
        prefix,
        base_dir: nodes.base_dir,
    };
    let layers = [
        parse_physical(cam.physical, &ctx(PREFIXES[0]))?,
        parse_extras(cam.camera_extras, &ctx(PREFIXES[1]))?,
        parse_extras(cam.node_extras, &ctx(PREFIXES[2]))?,
        parse_overrides(overrides, &ctx(PREFIXES[3]))?,
    ];
    let last = |f: &dyn Fn(&Layer) -> Option<f32>| layers.iter().rev().find_map(f);
    let d = Dof::default();
    let sensor_width = last(&|l| l.sensor_width).unwrap_or(d.sensor_width);
    let sensor_height = last(&|l| l.sensor_height).unwrap_or(d.sensor_height);
    let sensor_fit = layers
        .iter()
        .rev()
        .find_map(|l| l.sensor_fit)
        .unwrap_or_default();
    let lens_mm = match (last(&|l| l.lens), cam.projection) {
        (Some(lens), _) => lens,
        (None, Projection::Perspective { yfov, aspect_ratio }) => {
            let aspect = aspect_ratio
                .filter(|a| a.is_finite() && *a > 0.0)
                .unwrap_or(DEFAULT_ASPECT);
            lens_from_yfov(yfov, aspect, sensor_width, sensor_height, sensor_fit)
        }
        (None, Projection::Orthographic { .. }) => d.lens_mm,
    };
    let (enabled, aperture_radius) = aperture(&layers, lens_mm);
    let (focus_distance, focus_object) = focus(cam, &layers, nodes)?;

    Ok(Dof {
        enabled,
        aperture_radius,
        focus_distance,
        lens_mm,
        sensor_width,
        sensor_height,
        sensor_fit,
        blades: layers
            .iter()
            .rev()
            .find_map(|l| l.blades)
            .unwrap_or(d.blades),
        rotation: last(&|l| l.rotation).unwrap_or(d.rotation),
        ratio: last(&|l| l.ratio).unwrap_or(d.ratio),
        focus_object,
        lens_options: lens_options(&layers, cam.name, nodes.images)?,
        prescription: prescription(&layers),
    })
}

/// Checks camera keys as posing reads them from `cameras[i].extras` (`extras`: the keys to
/// check): a bad value, or a lens file that cannot be read, is the error posing would give.
pub(crate) fn check_extras(
    camera: &str,
    extras: &Value,
    base_dir: &std::path::Path,
) -> Result<(), Error> {
    let ctx = Ctx {
        camera,
        prefix: PREFIXES[1],
        base_dir,
    };
    parse_extras(Some(extras), &ctx).map(drop)
}

/// The highest source's `lens_prescription`, with the f-number of the source that decided the
/// aperture when it gave `aperture_fstop` (its `aperture_radius` leaves the stop as written).
fn prescription(layers: &[Layer; 4]) -> Option<std::sync::Arc<crate::types::LensPrescription>> {
    let (source, surfaces) = layers.iter().rev().find_map(|l| l.prescription.clone())?;
    let fstop = layers
        .iter()
        .rev()
        .find(|l| l.aperture_radius.is_some() || l.aperture_fstop.is_some())
        .and_then(|l| l.aperture_radius.is_none().then_some(l.aperture_fstop)?);
    Some(std::sync::Arc::new(crate::types::LensPrescription {
        source,
        surfaces,
        fstop,
    }))
}

/// The lens options, key by key from the highest source giving each.
fn lens_options(
    layers: &[Layer; 4],
    camera: &str,
    images: &image::ApertureImages,
) -> Result<LensOptions, Error> {
    let last = |f: &dyn Fn(&Layer) -> Option<f32>| layers.iter().rev().find_map(f).unwrap_or(0.0);
    let image = layers
        .iter()
        .enumerate()
        .rev()
        .find_map(|(i, l)| Some((i, l.aperture_image.as_ref()?)));
    let aperture_image = match image {
        None => None,
        Some((i, r)) => Some(images.get(r).cloned().ok_or_else(|| {
            let ctx = Ctx {
                camera,
                prefix: PREFIXES[i],
                // Only names the error: the images were read at load or by an edit.
                base_dir: std::path::Path::new(""),
            };
            ctx.err(
                "aperture_image",
                r,
                "not loaded: a bokeh image is read with the file, or by the edit that sets it",
            )
        })?),
    };
    Ok(LensOptions {
        aperture_image,
        chromatic: Chromatic {
            lateral: last(&|l| l.chromatic[0]),
            longitudinal: last(&|l| l.chromatic[1]),
        },
        vignetting: last(&|l| l.vignetting),
        distortion: Distortion {
            k1: last(&|l| l.distortion[0]),
            k2: last(&|l| l.distortion[1]),
            k3: last(&|l| l.distortion[2]),
            p1: last(&|l| l.distortion[3]),
            p2: last(&|l| l.distortion[4]),
        },
    })
}

/// The key prefixes of the four sources, in precedence order (lowest first).
const PREFIXES: [&str; 4] = [
    "EXT_camera_physical.",
    "cameras.extras.",
    "nodes.extras.",
    "command line ",
];

/// Whether depth of field is on, and the aperture radius: the highest source giving an aperture
/// decides it, its `aperture_radius` winning over its `aperture_fstop`.
fn aperture(layers: &[Layer; 4], lens_mm: f32) -> (bool, f32) {
    let aperture_layer = layers
        .iter()
        .rev()
        .find(|l| l.aperture_radius.is_some() || l.aperture_fstop.is_some());
    let aperture_radius = match aperture_layer {
        Some(Layer {
            aperture_radius: Some(r),
            ..
        }) => *r,
        Some(Layer {
            aperture_fstop: Some(f),
            ..
        }) => lens_mm * 0.001 / (2.0 * f),
        _ => 0.0,
    };
    let enabled = layers
        .iter()
        .rev()
        .find_map(|l| l.use_dof)
        .unwrap_or(aperture_layer.is_some());
    (enabled, aperture_radius)
}

/// The focus distance and the focused node's name: the highest source giving a focus decides
/// it, its `focus_object` winning over its `focus_distance`.
fn focus(
    cam: &CameraInput<'_>,
    layers: &[Layer; 4],
    nodes: &NodeInfo<'_>,
) -> Result<(f32, Option<String>), Error> {
    let d = Dof::default();
    let focus_layer = layers
        .iter()
        .enumerate()
        .rev()
        .find(|(_, l)| l.focus_object.is_some() || l.focus_distance.is_some());
    Ok(match focus_layer {
        Some((i, l)) => match (&l.focus_object, l.focus_distance) {
            (Some(target), _) => {
                let c = Ctx {
                    camera: cam.name,
                    prefix: PREFIXES[i],
                    base_dir: nodes.base_dir,
                };
                let (depth, name) = focus_on_node(cam, target, nodes, &c)?;
                (depth, Some(name))
            }
            (None, Some(dist)) => (dist, None),
            (None, None) => (d.focus_distance, None),
        },
        None => (d.focus_distance, None),
    })
}

/// The depth in front of the camera of the node `target` names, and that node's name.
fn focus_on_node(
    cam: &CameraInput<'_>,
    target: &FocusTarget,
    nodes: &NodeInfo<'_>,
    c: &Ctx<'_>,
) -> Result<(f32, String), Error> {
    let (index, shown) = match target {
        FocusTarget::Name(n) => (
            nodes
                .names
                .iter()
                .position(|m| m.as_deref() == Some(n.as_str()))
                .ok_or_else(|| c.err("focus_object", format!("{n:?}"), "no node has this name"))?,
            format!("{n:?}"),
        ),
        FocusTarget::Index(i) => {
            if *i >= nodes.origins.len() {
                return Err(c.err(
                    "focus_object",
                    i,
                    &format!("no such node (the file has {})", nodes.origins.len()),
                ));
            }
            (*i, i.to_string())
        }
    };
    let p = nodes.origins[index];
    let forward = -cam.world_from_camera.matrix3.z_axis;
    let depth = Vec3::from(forward).dot(p - Vec3::from(cam.world_from_camera.translation));
    if depth.is_nan() || depth <= 0.0 {
        return Err(c.err(
            "focus_object",
            shown,
            &format!("the focus point is not in front of the camera (depth {depth})"),
        ));
    }
    let name = nodes
        .names
        .get(index)
        .cloned()
        .flatten()
        .unwrap_or_else(|| format!("nodes[{index}]"));
    Ok((depth, name))
}

#[cfg(test)]
mod tests;
