//! The cameras' bokeh images (`aperture_image`, docs/lenses.md), read once with the file from
//! every camera's `extras`, its nodes' `extras` and the command line.

use std::sync::Arc;

use crate::dof::image::ApertureImages;
use crate::error::Error;
use crate::types::LoadOptions;

/// The bokeh images every camera, its node or the command line names (`aperture_image`),
/// loaded once with the file.
pub(super) fn load(
    doc: &gltf::Document,
    buffers: &crate::accessor::Buffers,
    base_dir: &std::path::Path,
    cameras: &[crate::camera::CameraData],
    graph: &crate::nodes::NodeGraph,
    options: &LoadOptions,
) -> Result<Arc<ApertureImages>, Error> {
    let name = |ci: usize, node: Option<usize>| {
        cameras[ci]
            .name
            .clone()
            .or_else(|| node.and_then(|n| graph.names[n].clone()))
            .unwrap_or_else(|| format!("camera {ci}"))
    };
    let own: Vec<_> = (0..cameras.len())
        .map(|ci| (name(ci, None), cameras[ci].extras.as_ref()))
        .collect();
    let nodes: Vec<_> = (graph.nodes.iter().enumerate())
        .filter_map(|(ni, n)| {
            let ci = n.camera.filter(|&ci| ci < cameras.len())?;
            Some((name(ci, Some(ni)), n.extras.as_ref()))
        })
        .collect();
    let src = crate::dof::image::Sources {
        doc,
        buffers,
        base_dir,
        skip: options.skip_textures,
        budget: &options.memory,
    };
    let cli = options.dof_overrides.aperture_image.as_deref();
    crate::dof::image::load_all(&src, &own, &nodes, cli).map(Arc::new)
}
