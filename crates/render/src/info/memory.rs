//! The report's `memory` (`aperture info --memory`): the bytes each stage of loading holds,
//! from the file to the BVH (issue 59), so a big scene shows where its memory goes.

use aperture_accel::AccelStats;
use aperture_scene::{Scene, Texels};
use serde_json::{json, Value};

/// Bytes of `n` values of `T`.
fn bytes<T>(n: usize) -> u64 {
    (n as u64).saturating_mul(size_of::<T>() as u64)
}

/// The scene's meshes, attribute by attribute (the lengths stored, not the capacities), and
/// the per-triangle materials of instances that draw a mesh with other materials.
fn meshes_json(s: &Scene) -> Value {
    let sum = |f: &dyn Fn(&aperture_scene::Mesh) -> u64| s.meshes.iter().map(|m| f(m)).sum::<u64>();
    let positions = sum(&|m| bytes::<glam::Vec3>(m.positions.len()));
    let normals = sum(&|m| bytes::<glam::Vec3>(m.normals.len()));
    let tangents = sum(&|m| bytes::<glam::Vec4>(m.tangents.len()));
    let uvs = sum(&|m| {
        let more: usize = m.uv_more.iter().map(Vec::len).sum();
        bytes::<glam::Vec2>(m.uv0.len() + m.uv1.len() + more)
    });
    let colors = sum(&|m| bytes::<glam::Vec4>(m.colors.len()));
    let indices = sum(&|m| bytes::<[u32; 3]>(m.indices.len()));
    let sets: usize = s.material_sets.iter().map(Vec::len).sum();
    let material_ids = sum(&|m| bytes::<u32>(m.material_ids.len())) + bytes::<u32>(sets);
    json!({
        "positions": positions,
        "normals": normals,
        "tangents": tangents,
        "uvs": uvs,
        "colors": colors,
        "indices": indices,
        "material_ids": material_ids,
        "total": positions + normals + tangents + uvs + colors + indices + material_ids,
    })
}

/// The textures' decoded texels (`null` when the load skipped them, as `info` does) and the
/// environment image's.
fn textures_json(s: &Scene, decoded: bool) -> Value {
    let texels: u64 = (s.textures.iter())
        .map(|t| match &t.texels {
            Texels::Rgba8(v) => bytes::<[u8; 4]>(v.len()),
            Texels::Rgba32F(v) => bytes::<[f32; 4]>(v.len()),
        })
        .sum();
    let environment = s
        .environment
        .as_ref()
        .map(|e| bytes::<glam::Vec3>(e.texels.len()));
    json!({
        "count": s.textures.len(),
        "decoded_bytes": decoded.then_some(texels),
        "environment_bytes": if decoded { environment } else { None },
    })
}

/// The BVH's bytes by part, from a built structure's statistics.
fn accel_json(a: &AccelStats, quality: aperture_accel::BvhQuality) -> Value {
    json!({
        "quality": quality.name(),
        "build_secs": a.build_time.as_secs_f64(),
        "triangles": a.unique_triangles,
        "nodes": a.bvh_nodes,
        "node_bytes": a.node_bytes,
        "triangle_bytes": a.triangle_bytes,
        "instance_bytes": a.instance_bytes,
        "total": a.memory_bytes,
    })
}

/// What [`memory_json`] reports on.
pub struct MemoryInputs<'a> {
    /// The scene as loaded.
    pub scene: &'a Scene,
    /// The size of the file read (`None` when unknown).
    pub file_bytes: Option<u64>,
    /// Whether the load decoded textures (`info` does not: `decoded_bytes` is then `null`).
    pub textures_decoded: bool,
    /// The statistics of a BVH built for the report, and its quality (`None`: not built).
    pub accel: Option<(AccelStats, aperture_accel::BvhQuality)>,
}

/// The `memory` object of the report: the file's bytes, the scene's meshes by attribute,
/// the textures, the BVH's nodes, triangle store and instance data when one was built, and the
/// process's peak resident memory so far (`VmHWM`, Linux; `null` elsewhere).
pub fn memory_json(m: &MemoryInputs<'_>) -> Value {
    json!({
        "file_bytes": m.file_bytes,
        "meshes": meshes_json(m.scene),
        "textures": textures_json(m.scene, m.textures_decoded),
        "accel": m.accel.as_ref().map(|(a, q)| accel_json(a, *q)),
        "peak_resident_bytes": aperture_budget::peak_resident_bytes(),
    })
}
