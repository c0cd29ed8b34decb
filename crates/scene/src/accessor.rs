//! Accessor reading with strict bounds checks.
//!
//! Every count read from the file is checked against the bytes that back it *before* anything is
//! allocated, so a small file that claims billions of elements is an error, not an out-of-memory.
//! Handles strided views, sparse storage, normalized integers and `KHR_mesh_quantization`'s
//! integer attributes.

use std::collections::HashMap;

use gltf::accessor::{DataType, Dimensions};

use crate::error::Error;

/// Bytes of every buffer, each cut to its `byteLength`.
pub(crate) struct Buffers<'f> {
    /// Per buffer, its bytes: the GLB BIN chunk borrowed from the file's bytes (not copied),
    /// others owned.
    pub data: Vec<std::borrow::Cow<'f, [u8]>>,
    /// Sum of all buffer lengths: the budget for accessors with no bytes behind them.
    pub total: u64,
    /// Bytes of meshopt-compressed buffer views, decoded, by view index: read instead of
    /// the view's own (fallback) bytes.
    pub decoded: HashMap<usize, Vec<u8>>,
    /// Bytes of accessor data read so far, every read counted (a file may have ten thousand
    /// meshes read one large accessor): checked against `budget` before each allocation.
    pub charged: std::sync::atomic::AtomicU64,
    /// The most `charged` may reach.
    pub budget: aperture_budget::MemoryBudget,
}

impl Buffers<'_> {
    /// Counts `bytes` more of decoded data read at `at`, refusing them past the budget.
    pub(crate) fn charge(&self, at: &str, bytes: u64) -> Result<(), Error> {
        use std::sync::atomic::Ordering;
        let before = self.charged.fetch_add(bytes, Ordering::Relaxed);
        let total = before.saturating_add(bytes);
        self.budget
            .check("the geometry and animation data read so far", total)
            .map_err(|source| Error::OverBudget {
                at: at.into(),
                source,
            })
    }
}

/// Accessors without a buffer view are zeros plus optional sparse values: nothing backs their
/// count, so it is capped relative to the data the file really carries.
const UNBACKED_FACTOR: u64 = 16;
const UNBACKED_SLACK: u64 = 1 << 16;

fn component_size(t: DataType) -> usize {
    match t {
        DataType::I8 | DataType::U8 => 1,
        DataType::I16 | DataType::U16 => 2,
        DataType::U32 | DataType::F32 => 4,
    }
}

fn dimension_count(d: Dimensions) -> usize {
    d.multiplicity()
}

/// The bytes of a buffer view, checked against its buffer (decoded, for a compressed view).
pub(crate) fn view_bytes<'a>(
    view: &gltf::buffer::View<'_>,
    buffers: &'a Buffers<'a>,
) -> Result<&'a [u8], Error> {
    if let Some(bytes) = buffers.decoded.get(&view.index()) {
        return Ok(bytes);
    }
    let at = format!("bufferViews[{}]", view.index());
    let buffer = buffers
        .data
        .get(view.buffer().index())
        .ok_or_else(|| Error::Invalid {
            at: at.clone(),
            reason: "buffer missing".into(),
        })?;
    let start = view.offset() as u64;
    let end = start.saturating_add(view.length() as u64);
    if end > buffer.len() as u64 {
        return Err(Error::OutOfBounds {
            at,
            needed: end,
            available: buffer.len() as u64,
        });
    }
    Ok(&buffer[start as usize..end as usize])
}

fn out_of_bounds(at: &str, acc: usize, needed: u64, available: u64) -> Error {
    Error::OutOfBounds {
        at: format!("{at} (accessors[{acc}])"),
        needed,
        available,
    }
}

/// Decodes one component to f32, normalizing integers when asked (glTF 2.0 §3.11).
fn to_f32(t: DataType, b: &[u8], normalized: bool) -> f32 {
    match (t, normalized) {
        (DataType::F32, _) => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
        (DataType::I8, n) => {
            let v = b[0] as i8 as f32;
            if n {
                (v / 127.0).max(-1.0)
            } else {
                v
            }
        }
        (DataType::U8, n) => {
            let v = b[0] as f32;
            if n {
                v / 255.0
            } else {
                v
            }
        }
        (DataType::I16, n) => {
            let v = i16::from_le_bytes([b[0], b[1]]) as f32;
            if n {
                (v / 32767.0).max(-1.0)
            } else {
                v
            }
        }
        (DataType::U16, n) => {
            let v = u16::from_le_bytes([b[0], b[1]]) as f32;
            if n {
                v / 65535.0
            } else {
                v
            }
        }
        (DataType::U32, n) => {
            let v = u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32;
            if n {
                v / u32::MAX as f32
            } else {
                v
            }
        }
    }
}

fn to_u32(t: DataType, b: &[u8]) -> u32 {
    match t {
        DataType::U8 => b[0] as u32,
        DataType::U16 => u16::from_le_bytes([b[0], b[1]]) as u32,
        _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
    }
}

/// An accessor's element layout: component size and count, element size in bytes, elements.
#[derive(Clone, Copy)]
struct Shape {
    csize: usize,
    dims: usize,
    elem: u64,
    count: u64,
}

/// Reads every element of an accessor as `dims` components, converted with `conv`.
fn read<T: Copy + Default>(
    acc: &gltf::Accessor<'_>,
    buffers: &Buffers,
    at: &str,
    conv: impl Fn(&[u8]) -> T,
) -> Result<Vec<T>, Error> {
    let csize = component_size(acc.data_type());
    let dims = dimension_count(acc.dimensions());
    let shape = Shape {
        csize,
        dims,
        elem: (csize * dims) as u64,
        count: acc.count() as u64,
    };
    // Charged once the count is known to be backed (so a lying count gets the precise error).
    let charge = || {
        buffers.charge(
            at,
            shape
                .count
                .saturating_mul(dims as u64)
                .saturating_mul(std::mem::size_of::<T>() as u64),
        )
    };
    let mut out: Vec<T> = match acc.view() {
        Some(view) => read_view(acc, &view, buffers, at, shape, charge, &conv)?,
        None => {
            let budget = buffers.total * UNBACKED_FACTOR + UNBACKED_SLACK;
            let size = shape.count.saturating_mul(shape.elem);
            if size > budget {
                return Err(out_of_bounds(at, acc.index(), size, budget));
            }
            charge()?;
            vec![T::default(); shape.count as usize * dims]
        }
    };
    if let Some(sparse) = acc.sparse() {
        apply_sparse(acc, &sparse, buffers, at, shape, &mut out, &conv)?;
    }
    Ok(out)
}

/// The dense elements of an accessor stored in `view`, checked to lie inside it before
/// anything is allocated (`charge` is called once they do).
fn read_view<T>(
    acc: &gltf::Accessor<'_>,
    view: &gltf::buffer::View<'_>,
    buffers: &Buffers,
    at: &str,
    shape: Shape,
    charge: impl FnOnce() -> Result<(), Error>,
    conv: &impl Fn(&[u8]) -> T,
) -> Result<Vec<T>, Error> {
    let (csize, dims, elem, count) = (shape.csize, shape.dims, shape.elem, shape.count);
    let bytes = view_bytes(view, buffers)?;
    let stride = view.stride().map_or(elem, |s| s as u64);
    if stride < elem {
        return Err(Error::BadAccessor {
            at: at.into(),
            reason: format!(
                "bufferViews[{}].byteStride {stride} is smaller than the {elem}-byte element",
                view.index()
            ),
        });
    }
    let offset = acc.offset() as u64;
    let needed = if count == 0 {
        offset
    } else {
        (count - 1)
            .checked_mul(stride)
            .and_then(|x| x.checked_add(offset.checked_add(elem)?))
            .unwrap_or(u64::MAX)
    };
    if needed > bytes.len() as u64 {
        return Err(out_of_bounds(at, acc.index(), needed, bytes.len() as u64));
    }
    charge()?;
    // Safe to allocate: every element is backed by bytes we hold.
    let (offset, stride, elem) = (offset as usize, stride as usize, elem as usize);
    if stride == elem {
        // Tightly packed (what exporters write): one pass over one slice, allocated once.
        let packed = &bytes[offset..][..count as usize * elem];
        return Ok(packed.chunks_exact(csize).map(conv).collect());
    }
    let mut out = Vec::with_capacity(count as usize * dims);
    for i in 0..count as usize {
        let e = &bytes[offset + i * stride..][..elem];
        out.extend(e.chunks_exact(csize).map(conv));
    }
    Ok(out)
}

/// A little-endian `f32` from a 4-byte component (callers pass `chunks_exact(4)` pieces).
#[inline(always)]
fn le_f32(b: &[u8]) -> f32 {
    b.first_chunk::<4>().map_or(0.0, |c| f32::from_le_bytes(*c))
}

/// A little-endian `u16` index from a 2-byte component.
#[inline(always)]
fn le_u16(b: &[u8]) -> u32 {
    b.first_chunk::<2>()
        .map_or(0, |c| u32::from(u16::from_le_bytes(*c)))
}

/// A little-endian `u32` index from a 4-byte component.
#[inline(always)]
fn le_u32(b: &[u8]) -> u32 {
    b.first_chunk::<4>().map_or(0, |c| u32::from_le_bytes(*c))
}

/// Writes an accessor's sparse values over `out`, indices and values checked against their views
/// and the element count.
fn apply_sparse<T>(
    acc: &gltf::Accessor<'_>,
    sparse: &gltf::accessor::sparse::Sparse<'_>,
    buffers: &Buffers,
    at: &str,
    shape: Shape,
    out: &mut [T],
    conv: &impl Fn(&[u8]) -> T,
) -> Result<(), Error> {
    let (csize, dims, elem, count) = (shape.csize, shape.dims, shape.elem, shape.count);
    let sat = format!("{at} (accessors[{}].sparse)", acc.index());
    let n = sparse.count() as u64;
    if n > count {
        return Err(Error::BadAccessor {
            at: sat,
            reason: format!("{n} sparse values for {count} elements"),
        });
    }
    let indices = sparse.indices();
    let itype = match indices.index_type() {
        gltf::accessor::sparse::IndexType::U8 => DataType::U8,
        gltf::accessor::sparse::IndexType::U16 => DataType::U16,
        gltf::accessor::sparse::IndexType::U32 => DataType::U32,
    };
    let isize = component_size(itype) as u64;
    let ineeded = (indices.offset() as u64).saturating_add(n * isize);
    let ibytes = sparse_bytes(&indices.view(), buffers, ineeded, || {
        format!("{sat}.indices")
    })?;
    let values = sparse.values();
    let vneeded = (values.offset() as u64).saturating_add(n * elem);
    let vbytes = sparse_bytes(&values.view(), buffers, vneeded, || format!("{sat}.values"))?;
    let (isize, elem) = (isize as usize, elem as usize);
    for k in 0..n as usize {
        let target = to_u32(itype, &ibytes[indices.offset() + k * isize..][..isize]) as usize;
        if target as u64 >= count {
            return Err(Error::IndexOutOfRange {
                at: format!("{sat}.indices[{k}]"),
                index: target as u64,
                vertices: count as usize,
            });
        }
        let e = &vbytes[values.offset() + k * elem..][..elem];
        for (c, comp) in e.chunks_exact(csize).enumerate() {
            out[target * dims + c] = conv(comp);
        }
    }
    Ok(())
}

/// The bytes of a sparse accessor's indices or values view, checked to hold `needed` bytes.
fn sparse_bytes<'a>(
    view: &gltf::buffer::View<'_>,
    buffers: &'a Buffers<'a>,
    needed: u64,
    at: impl FnOnce() -> String,
) -> Result<&'a [u8], Error> {
    let bytes = view_bytes(view, buffers)?;
    if needed > bytes.len() as u64 {
        return Err(Error::OutOfBounds {
            at: at(),
            needed,
            available: bytes.len() as u64,
        });
    }
    Ok(bytes)
}

/// Reads an accessor as floats: `dims` components per element, flattened. Normalized integers
/// map to [0, 1] or [−1, 1]; other integers (quantized data) keep their value.
pub(crate) fn read_f32(
    acc: &gltf::Accessor<'_>,
    buffers: &Buffers,
    at: &str,
) -> Result<(Vec<f32>, usize), Error> {
    if matches!(
        acc.dimensions(),
        Dimensions::Mat2 | Dimensions::Mat3 | Dimensions::Mat4
    ) {
        return Err(Error::BadAccessor {
            at: at.into(),
            reason: format!(
                "accessors[{}]: matrix accessors are not used here",
                acc.index()
            ),
        });
    }
    let ctype = acc.data_type();
    let normalized = acc.normalized();
    // Floats (nearly every accessor) get their own loop, free of the per-component type match.
    let v = match ctype {
        DataType::F32 => read(acc, buffers, at, le_f32)?,
        _ => read(acc, buffers, at, |b| to_f32(ctype, b, normalized))?,
    };
    Ok((v, dimension_count(acc.dimensions())))
}

/// Reads a float MAT4 accessor (inverse bind matrices): 16 floats per element, column-major.
pub(crate) fn read_mat4(
    acc: &gltf::Accessor<'_>,
    buffers: &Buffers,
    at: &str,
) -> Result<Vec<f32>, Error> {
    if acc.dimensions() != Dimensions::Mat4 || acc.data_type() != DataType::F32 {
        return Err(Error::BadAccessor {
            at: at.into(),
            reason: format!("accessors[{}] must be a float MAT4", acc.index()),
        });
    }
    read(acc, buffers, at, le_f32)
}

/// Reads a scalar accessor of unsigned integers (vertex indices).
pub(crate) fn read_indices(
    acc: &gltf::Accessor<'_>,
    buffers: &Buffers,
    at: &str,
) -> Result<Vec<u32>, Error> {
    let ctype = acc.data_type();
    if acc.dimensions() != Dimensions::Scalar
        || !matches!(ctype, DataType::U8 | DataType::U16 | DataType::U32)
    {
        return Err(Error::BadAccessor {
            at: at.into(),
            reason: format!(
                "accessors[{}]: indices must be SCALAR u8/u16/u32, found {:?} {:?}",
                acc.index(),
                acc.dimensions(),
                ctype
            ),
        });
    }
    match ctype {
        DataType::U16 => read(acc, buffers, at, le_u16),
        DataType::U32 => read(acc, buffers, at, le_u32),
        _ => read(acc, buffers, at, |b| to_u32(ctype, b)),
    }
}

/// Reads a float accessor and checks it has the expected number of components per element.
pub(crate) fn read_vec<const N: usize>(
    acc: &gltf::Accessor<'_>,
    buffers: &Buffers,
    at: &str,
) -> Result<Vec<[f32; N]>, Error> {
    let (flat, dims) = read_f32(acc, buffers, at)?;
    if dims != N {
        return Err(Error::BadAccessor {
            at: at.into(),
            reason: format!(
                "accessors[{}] has {dims} components per element, {N} expected",
                acc.index()
            ),
        });
    }
    Ok(flat
        .chunks_exact(N)
        .map(|c| {
            let mut a = [0.0; N];
            a.copy_from_slice(c);
            a
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use base64::Engine;
    use serde_json::json;

    /// A document with one buffer holding `bytes` (one view over all of it, with `stride`) and
    /// the given accessors.
    fn doc(
        bytes: &[u8],
        stride: Option<u64>,
        accessors: serde_json::Value,
    ) -> (gltf::Document, Buffers<'static>) {
        let mut view = json!({"buffer": 0, "byteLength": bytes.len()});
        if let Some(s) = stride {
            view["byteStride"] = json!(s);
        }
        let j = json!({
            "asset": {"version": "2.0"},
            "buffers": [{"byteLength": bytes.len(), "uri": format!("data:application/octet-stream;base64,{}",
                base64::engine::general_purpose::STANDARD.encode(bytes))}],
            "bufferViews": [view],
            "accessors": accessors,
        });
        let p = crate::prepass::prepare(&serde_json::to_vec(&j).unwrap()).unwrap();
        let data = vec![bytes.to_vec().into()];
        (
            p.document,
            Buffers {
                total: bytes.len() as u64,
                data,
                decoded: HashMap::new(),
                charged: Default::default(),
                budget: aperture_budget::MemoryBudget::unlimited(),
            },
        )
    }

    #[test]
    fn normalized_and_quantized_integers() {
        let bytes: Vec<u8> = [127i8, -128, 0, 64].iter().map(|&b| b as u8).collect();
        let (d, b) = doc(
            &bytes,
            None,
            json!([
                {"bufferView": 0, "componentType": 5120, "normalized": true, "count": 1, "type": "VEC4"},
                {"bufferView": 0, "componentType": 5120, "count": 1, "type": "VEC4"},
                {"bufferView": 0, "componentType": 5121, "normalized": true, "count": 1, "type": "VEC4"},
            ]),
        );
        let acc: Vec<_> = d.accessors().collect();
        let (n, dims) = read_f32(&acc[0], &b, "a").unwrap();
        assert_eq!(dims, 4);
        assert_eq!(n, [1.0, -1.0, 0.0, 64.0 / 127.0]);
        // KHR_mesh_quantization: non-normalized integers keep their value.
        assert_eq!(
            read_f32(&acc[1], &b, "a").unwrap().0,
            [127.0, -128.0, 0.0, 64.0]
        );
        assert_eq!(
            read_f32(&acc[2], &b, "a").unwrap().0,
            [127.0 / 255.0, 128.0 / 255.0, 0.0, 64.0 / 255.0]
        );
    }

    #[test]
    fn strided_u16_and_bounds() {
        // Two u16 elements with a 4-byte stride: 1, (pad), 2, (pad).
        let bytes = [1u8, 0, 9, 9, 2, 0, 9, 9];
        let (d, b) = doc(
            &bytes,
            Some(4),
            json!([
                {"bufferView": 0, "componentType": 5123, "count": 2, "type": "SCALAR"},
                {"bufferView": 0, "componentType": 5123, "count": 3, "type": "SCALAR"},
                {"bufferView": 0, "byteOffset": 2, "componentType": 5123, "count": 2, "type": "SCALAR"},
            ]),
        );
        let acc: Vec<_> = d.accessors().collect();
        assert_eq!(read_indices(&acc[0], &b, "i").unwrap(), [1, 2]);
        assert!(matches!(
            read_indices(&acc[1], &b, "i"),
            Err(Error::OutOfBounds {
                needed: 10,
                available: 8,
                ..
            })
        ));
        assert_eq!(read_indices(&acc[2], &b, "i").unwrap(), [0x0909, 0x0909]);
    }

    #[test]
    fn sparse_values_replace_the_base() {
        // Base: 4 floats 0..4; sparse: indices [3, 1] (u8) and values [30, 10].
        let mut bytes = Vec::new();
        for x in [0.0f32, 1.0, 2.0, 3.0, 30.0, 10.0] {
            bytes.extend(x.to_le_bytes());
        }
        bytes.extend([3u8, 1, 0, 0]);
        let (d, b) = doc(
            &bytes,
            None,
            json!([
                {"bufferView": 0, "componentType": 5126, "count": 4, "type": "SCALAR",
                 "sparse": {"count": 2, "indices": {"bufferView": 0, "byteOffset": 24, "componentType": 5121},
                            "values": {"bufferView": 0, "byteOffset": 16}}},
                {"componentType": 5126, "count": 4, "type": "SCALAR",
                 "sparse": {"count": 2, "indices": {"bufferView": 0, "byteOffset": 24, "componentType": 5121},
                            "values": {"bufferView": 0, "byteOffset": 16}}},
            ]),
        );
        let acc: Vec<_> = d.accessors().collect();
        assert_eq!(
            read_f32(&acc[0], &b, "s").unwrap().0,
            [0.0, 10.0, 2.0, 30.0]
        );
        assert_eq!(
            read_f32(&acc[1], &b, "s").unwrap().0,
            [0.0, 10.0, 0.0, 30.0]
        );
    }

    #[test]
    fn wrong_component_count_and_index_type_are_errors() {
        let (d, b) = doc(
            &[0; 12],
            None,
            json!([
                {"bufferView": 0, "componentType": 5126, "count": 1, "type": "VEC3"},
            ]),
        );
        let acc = d.accessors().next().unwrap();
        assert!(matches!(
            read_vec::<2>(&acc, &b, "uv"),
            Err(Error::BadAccessor { .. })
        ));
        assert!(matches!(
            read_indices(&acc, &b, "i"),
            Err(Error::BadAccessor { .. })
        ));
    }
}
