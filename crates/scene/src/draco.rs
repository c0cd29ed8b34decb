//! `KHR_draco_mesh_compression`: a primitive's triangles and attributes decoded from a Draco
//! stream (draco-core, a pure-Rust decoder bit-exact with Google's Draco 1.5.7).
//!
//! The primitive's accessors keep their meaning (count, type, component type, `normalized`); the
//! extension maps each compressed attribute to a Draco attribute id. Before decoding, the decoder
//! is limited to the point and face counts the accessors state, so a stream claiming more is an
//! error before anything is allocated; after decoding, the counts must match exactly.

use std::collections::HashMap;

use draco_core::{DataType, DecodeLimits, DecoderBuffer, FaceIndex, MeshDecoder};
use serde_json::Value;

use crate::accessor::{view_bytes, Buffers};
use crate::error::Error;

/// A decoded primitive: triangle indices and the compressed attributes, by glTF semantic name.
pub(crate) struct Decoded {
    /// Vertex indices, three per triangle.
    pub indices: Vec<u32>,
    /// Flat values (`dims` per vertex) of each compressed attribute.
    pub attributes: HashMap<String, (Vec<f32>, usize)>,
}

fn invalid(at: &str, reason: impl Into<String>) -> Error {
    Error::Invalid {
        at: at.into(),
        reason: reason.into(),
    }
}

/// The largest value of an integer type, for normalised attributes.
fn norm_divisor(t: DataType) -> Option<f32> {
    Some(match t {
        DataType::Int8 => 127.0,
        DataType::Uint8 => 255.0,
        DataType::Int16 => 32767.0,
        DataType::Uint16 => 65535.0,
        DataType::Int32 => i32::MAX as f32,
        DataType::Uint32 => u32::MAX as f32,
        _ => return None,
    })
}

/// Decodes the Draco stream of `prim` (`ext` is its `KHR_draco_mesh_compression` object).
pub(crate) fn decode(
    doc: &gltf::Document,
    prim: &gltf::Primitive<'_>,
    ext: &Value,
    buffers: &Buffers,
    at: &str,
) -> Result<Decoded, Error> {
    let eat = format!("{at}.extensions.KHR_draco_mesh_compression");
    let bytes = stream_bytes(doc, ext, buffers, &eat)?;
    let ids = ext
        .get("attributes")
        .and_then(Value::as_object)
        .ok_or_else(|| invalid(&format!("{eat}.attributes"), "missing"))?;

    let points = prim
        .get(&gltf::Semantic::Positions)
        .ok_or_else(|| invalid(&format!("{at}.attributes.POSITION"), "missing"))?
        .count();
    let corners = match prim.indices() {
        Some(acc) => acc.count(),
        None => points,
    };
    if corners % 3 != 0 {
        return Err(Error::IndexCount {
            at: format!("{at}.indices"),
            count: corners,
        });
    }
    let mesh = decode_mesh(bytes, points, corners, &eat)?;
    let mut indices = Vec::with_capacity(corners);
    for f in 0..mesh.num_faces() {
        indices.extend(mesh.face(FaceIndex(f as u32)).map(|p| p.0));
    }
    let mut attributes = HashMap::new();
    for (semantic, id) in ids {
        let values = read_attribute(prim, &mesh, semantic, id, points, at, &eat)?;
        attributes.insert(semantic.clone(), values);
    }
    Ok(Decoded {
        indices,
        attributes,
    })
}

/// The bytes of the buffer view holding the Draco stream (`eat` names the extension object).
fn stream_bytes<'a>(
    doc: &gltf::Document,
    ext: &Value,
    buffers: &'a Buffers,
    eat: &str,
) -> Result<&'a [u8], Error> {
    let view_index = ext
        .get("bufferView")
        .and_then(Value::as_u64)
        .ok_or_else(|| invalid(&format!("{eat}.bufferView"), "missing or not an index"))?;
    let view = doc.views().nth(view_index as usize).ok_or_else(|| {
        invalid(
            &format!("{eat}.bufferView"),
            format!("bufferView {view_index} does not exist"),
        )
    })?;
    view_bytes(&view, buffers)
}

/// The decoded Draco mesh, limited to and checked against the counts the accessors state.
fn decode_mesh(
    bytes: &[u8],
    points: usize,
    corners: usize,
    eat: &str,
) -> Result<draco_core::Mesh, Error> {
    // The accessors state the decoded sizes: the decoder may not allocate more.
    let limits = DecodeLimits::default()
        .with_max_points(points as u64)
        .with_max_faces((corners / 3) as u64);
    let mut input = DecoderBuffer::new(bytes).with_limits(limits);
    let mut mesh = draco_core::Mesh::new();
    MeshDecoder::new()
        .decode(&mut input, &mut mesh)
        .map_err(|e| Error::Compressed {
            at: eat.into(),
            reason: format!("Draco stream: {e}"),
        })?;
    if mesh.num_points() != points || mesh.num_faces() * 3 != corners {
        return Err(Error::Compressed {
            at: eat.into(),
            reason: format!(
                "the Draco stream holds {} points and {} triangles; the accessors say {points} \
                 and {}",
                mesh.num_points(),
                mesh.num_faces(),
                corners / 3
            ),
        });
    }
    Ok(mesh)
}

/// The values of the compressed attribute `semantic` (Draco attribute `id`), `dims` per point as
/// its accessor says, normalised integers mapped to [0, 1] or [-1, 1].
fn read_attribute(
    prim: &gltf::Primitive<'_>,
    mesh: &draco_core::Mesh,
    semantic: &str,
    id: &Value,
    points: usize,
    at: &str,
    eat: &str,
) -> Result<(Vec<f32>, usize), Error> {
    let aat = format!("{eat}.attributes.{semantic}");
    let id = id
        .as_u64()
        .and_then(|i| u32::try_from(i).ok())
        .ok_or_else(|| invalid(&aat, format!("{id} is not an attribute id")))?;
    let accessor = prim
        .attributes()
        .find(|(s, _)| s.to_string() == *semantic)
        .map(|(_, a)| a)
        .ok_or_else(|| invalid(&aat, "the primitive has no such attribute"))?;
    if accessor.count() != points {
        return Err(Error::BadAccessor {
            at: format!("{at}.attributes.{semantic}"),
            reason: format!(
                "accessors[{}] has {} elements, POSITION has {points}",
                accessor.index(),
                accessor.count()
            ),
        });
    }
    let attr = mesh
        .attribute_by_unique_id(id)
        .ok_or_else(|| Error::Compressed {
            at: aat.clone(),
            reason: format!("the Draco stream has no attribute {id}"),
        })?;
    let dims = accessor.dimensions().multiplicity();
    let mut values = attr.read_f32s(points, dims);
    if accessor.normalized() || attr.normalized() {
        if let Some(d) = norm_divisor(attr.data_type()) {
            for v in &mut values {
                *v = (*v / d).max(-1.0);
            }
        }
    }
    Ok((values, dims))
}
