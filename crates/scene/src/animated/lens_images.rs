//! The cameras' bokeh images (`aperture_image`, docs/lenses.md), read with the file from every
//! camera's `extras`, its nodes' `extras` and the command line, and again after an edit of a
//! camera's key (only the image it names is read; the others are kept).

use std::sync::Arc;

use serde_json::Value;

use crate::camera::CameraData;
use crate::dof::image::{kept_for_edit, load_all, needs_file, ApertureImages, Sources};
use crate::error::Error;
use crate::nodes::NodeGraph;
use crate::types::LoadOptions;

/// The bokeh images every camera, its node or the command line names (`aperture_image`),
/// loaded with the file.
pub(super) fn load(
    doc: &gltf::Document,
    buffers: &crate::accessor::Buffers,
    base_dir: &std::path::Path,
    cameras: &[CameraData],
    graph: &NodeGraph,
    options: &LoadOptions,
) -> Result<Arc<ApertureImages>, Error> {
    let src = sources(Some((doc, buffers)), base_dir, options);
    gather(&src, cameras, graph, options, &ApertureImages::new(), None).map(Arc::new)
}

/// A camera whose `aperture_image` an edit sets: its glTF index and its `extras` with the new
/// value (the nodes carrying it lose theirs).
pub(super) type Edited<'a> = (usize, Option<&'a Value>);

/// The bokeh images once camera `change.0`'s extras are `change.1` (its nodes without the
/// key): the image the new value names read (again, for a path), the others taken from
/// `kept`, those no longer named dropped. `None` when the value names a texture not loaded
/// with the file: only loading the file again reads it.
pub(super) fn edited(
    base_dir: &std::path::Path,
    cameras: &[CameraData],
    graph: &NodeGraph,
    options: &LoadOptions,
    kept: &ApertureImages,
    change: Edited<'_>,
) -> Result<Option<Arc<ApertureImages>>, Error> {
    let value = change.1.and_then(|e| e.get("aperture_image"));
    if value.is_some_and(|v| needs_file(v, kept)) {
        return Ok(None);
    }
    let kept = match value {
        Some(v) => kept_for_edit(v, kept),
        None => kept.clone(),
    };
    let src = sources(None, base_dir, options);
    gather(&src, cameras, graph, options, &kept, Some(change)).map(|m| Some(Arc::new(m)))
}

fn sources<'a>(
    file: Option<(&'a gltf::Document, &'a crate::accessor::Buffers<'a>)>,
    base_dir: &'a std::path::Path,
    options: &'a LoadOptions,
) -> Sources<'a> {
    Sources {
        file,
        base_dir,
        skip: options.skip_textures,
        budget: &options.memory,
    }
}

/// [`load_all`] of every camera's and camera node's extras (`edited`'s in place of the
/// stored ones) and the command line's image.
fn gather(
    src: &Sources<'_>,
    cameras: &[CameraData],
    graph: &NodeGraph,
    options: &LoadOptions,
    kept: &ApertureImages,
    edited: Option<Edited<'_>>,
) -> Result<ApertureImages, Error> {
    let name = |ci: usize, node: Option<usize>| {
        cameras[ci]
            .name
            .clone()
            .or_else(|| node.and_then(|n| graph.names[n].clone()))
            .unwrap_or_else(|| format!("camera {ci}"))
    };
    let is_edited = |ci: usize| edited.is_some_and(|(e, _)| e == ci);
    let own: Vec<_> = (0..cameras.len())
        .map(|ci| {
            let extras = match edited {
                Some((e, extras)) if e == ci => extras,
                _ => cameras[ci].extras.as_ref(),
            };
            (name(ci, None), extras)
        })
        .collect();
    let nodes: Vec<_> = (graph.nodes.iter().enumerate())
        .filter_map(|(ni, n)| {
            let ci = n.camera.filter(|&ci| ci < cameras.len())?;
            // Only `aperture_image` is read, which the edit removed from these nodes.
            let extras = if is_edited(ci) {
                None
            } else {
                n.extras.as_ref()
            };
            Some((name(ci, Some(ni)), extras))
        })
        .collect();
    let cli = options.dof_overrides.aperture_image.as_deref();
    load_all(src, &own, &nodes, cli, kept)
}
