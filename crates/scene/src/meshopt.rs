//! `KHR_meshopt_compression` and `EXT_meshopt_compression`: buffer views whose bytes are
//! meshoptimizer-compressed (vertex attributes, triangle indices or index sequences), optionally
//! followed by a filter (octahedral normals, quaternions, exponential floats, YCoCg colours).
//!
//! The Khronos extension is the vendor one under its own name, with the same objects; what its
//! text adds (version 1 of the attribute codec, the `COLOR` filter) the same decoder reads under
//! either name, as meshoptimizer's own loaders do.
//!
//! Each compressed view is decoded once, when the buffers are read, into the bytes its accessors
//! then read as if they were stored plainly. Sizes are checked before anything is allocated: the
//! decoded size (`count × byteStride`) must be the view's `byteLength`, and may not exceed
//! [`MAX_EXPANSION`] times the compressed bytes behind it (plus a little), so a small file cannot
//! claim gigabytes. Buffers marked `fallback` (no real bytes) are never read.

use serde_json::Value;

use crate::accessor::Buffers;
use crate::error::Error;

/// Largest accepted ratio of decoded to compressed bytes. meshoptimizer's codecs reach about 10×
/// on real geometry and ~50× on constant streams; 256× leaves room without letting a kilobyte
/// claim a gigabyte.
pub(crate) const MAX_EXPANSION: u64 = 256;
/// Decoded bytes always allowed, whatever the compressed size.
const SLACK: u64 = 1 << 16;

/// The two names of the extension, the Khronos one first (a file may carry both on one object,
/// the vendor one for older readers).
pub(crate) const NAMES: [&str; 2] = ["KHR_meshopt_compression", "EXT_meshopt_compression"];

/// The meshopt extension object of a buffer or buffer view, with the name it is under.
fn extension(object: &Value) -> Option<(&'static str, &Value)> {
    let extensions = object.get("extensions")?;
    NAMES
        .iter()
        .find_map(|&name| extensions.get(name).map(|e| (name, e)))
}

/// Whether `buffers[i]` is a meshopt `fallback` buffer (no real bytes).
pub(crate) fn is_fallback(root: &Value, buffer: usize) -> bool {
    root.get("buffers")
        .and_then(|b| b.get(buffer))
        .and_then(extension)
        .and_then(|(_, e)| e.get("fallback"))
        .and_then(Value::as_bool)
        .unwrap_or(false)
}

fn invalid(at: &str, reason: impl Into<String>) -> Error {
    Error::Invalid {
        at: at.into(),
        reason: reason.into(),
    }
}

fn compressed(at: &str, reason: impl Into<String>) -> Error {
    Error::Compressed {
        at: at.into(),
        reason: reason.into(),
    }
}

/// One vertex of `N` bytes, for the decoder's element type.
#[derive(Clone, Copy)]
struct Element<const N: usize>([u8; N]);

impl<const N: usize> Default for Element<N> {
    fn default() -> Self {
        Self([0; N])
    }
}

fn vertices<const N: usize>(data: &[u8], count: usize) -> Result<Vec<u8>, meshopt::Error> {
    let v = meshopt::encoding::decode_vertex_buffer::<Element<N>>(data, count)?;
    Ok(v.iter().flat_map(|e| e.0).collect())
}

/// Decodes `count` vertices of `stride` bytes (a multiple of 4 up to 256).
fn decode_vertices(
    data: &[u8],
    count: usize,
    stride: usize,
) -> Option<Result<Vec<u8>, meshopt::Error>> {
    macro_rules! by_stride {
        ($($n:literal)*) => {
            match stride {
                $($n => Some(vertices::<$n>(data, count)),)*
                _ => None,
            }
        };
    }
    by_stride!(4 8 12 16 20 24 28 32 36 40 44 48 52 56 60 64 68 72 76 80 84 88 92 96 100 104 108
        112 116 120 124 128 132 136 140 144 148 152 156 160 164 168 172 176 180 184 188 192 196
        200 204 208 212 216 220 224 228 232 236 240 244 248 252 256)
}

fn to_bytes<T: Copy, const K: usize>(v: &[[T; K]], bytes: impl Fn(T) -> [u8; 2]) -> Vec<u8> {
    v.iter().flatten().flat_map(|&c| bytes(c)).collect()
}

/// Applies a filter in place to decoded bytes (`stride` bytes per element).
fn filter(name: &str, bytes: &mut Vec<u8>, stride: usize, at: &str) -> Result<(), Error> {
    match (name, stride) {
        ("NONE", _) => {}
        ("OCTAHEDRAL" | "COLOR", 4) => {
            let mut v: Vec<[i8; 4]> = bytes
                .chunks_exact(4)
                .map(|c| [c[0], c[1], c[2], c[3]].map(|b| b as i8))
                .collect();
            let mut u: Vec<[u8; 4]> = bytes
                .chunks_exact(4)
                .map(|c| [c[0], c[1], c[2], c[3]])
                .collect();
            if name == "OCTAHEDRAL" {
                meshopt::encoding::decode_filter_oct(&mut v);
                *bytes = v.iter().flatten().map(|&b| b as u8).collect();
            } else {
                meshopt::encoding::decode_filter_color(&mut u);
                *bytes = u.concat();
            }
        }
        ("OCTAHEDRAL" | "QUATERNION" | "COLOR", 8) => {
            let read = |c: &[u8]| {
                let s = |k: usize| i16::from_le_bytes([c[2 * k], c[2 * k + 1]]);
                [s(0), s(1), s(2), s(3)]
            };
            let mut v: Vec<[i16; 4]> = bytes.chunks_exact(8).map(read).collect();
            match name {
                "OCTAHEDRAL" => meshopt::encoding::decode_filter_oct(&mut v),
                "QUATERNION" => meshopt::encoding::decode_filter_quat(&mut v),
                _ => {
                    let mut u: Vec<[u16; 4]> = v.iter().map(|a| a.map(|c| c as u16)).collect();
                    meshopt::encoding::decode_filter_color(&mut u);
                    *bytes = to_bytes(&u, u16::to_le_bytes);
                    return Ok(());
                }
            }
            *bytes = to_bytes(&v, i16::to_le_bytes);
        }
        ("EXPONENTIAL", s) if s % 4 == 0 => {
            // meshoptimizer's decodeFilterExp: a 24-bit signed mantissa and an 8-bit signed
            // exponent, value = m · 2^e, with 2^e built from its bits as the reference does.
            for c in bytes.chunks_exact_mut(4) {
                let v = u32::from_le_bytes([c[0], c[1], c[2], c[3]]);
                let m = ((v << 8) as i32) >> 8;
                let e = (v as i32) >> 24;
                let scale = f32::from_bits((e.wrapping_add(127) as u32) << 23);
                c.copy_from_slice(&(m as f32 * scale).to_le_bytes());
            }
        }
        (other, s) => {
            return Err(invalid(
                &format!("{at}.filter"),
                format!("filter {other:?} with byteStride {s} is not defined"),
            ))
        }
    }
    Ok(())
}

/// Decodes one view's extension object.
fn decode_view(
    ext: &Value,
    view_length: u64,
    buffers: &Buffers,
    at: &str,
) -> Result<Vec<u8>, Error> {
    let num = |key: &str| ext.get(key).and_then(Value::as_u64);
    let need = |key: &str| {
        num(key).ok_or_else(|| invalid(&format!("{at}.{key}"), "missing or not a number"))
    };
    let buffer = need("buffer")? as usize;
    let offset = num("byteOffset").unwrap_or(0);
    let length = need("byteLength")?;
    let stride = need("byteStride")?;
    let count = need("count")?;
    let mode = ext.get("mode").and_then(Value::as_str).unwrap_or("");
    let data = buffers.data.get(buffer).ok_or_else(|| {
        invalid(
            &format!("{at}.buffer"),
            format!("buffer {buffer} does not exist"),
        )
    })?;
    let end = offset.saturating_add(length);
    if end > data.len() as u64 {
        return Err(Error::OutOfBounds {
            at: at.into(),
            needed: end,
            available: data.len() as u64,
        });
    }
    let source = &data[offset as usize..end as usize];
    let decoded = count.saturating_mul(stride);
    if decoded != view_length {
        return Err(compressed(
            at,
            format!("count {count} × byteStride {stride} = {decoded} bytes, but the view's byteLength is {view_length}"),
        ));
    }
    if decoded > MAX_EXPANSION * length + SLACK {
        return Err(compressed(
            at,
            format!("{decoded} bytes claimed from {length} compressed bytes (more than {MAX_EXPANSION}×)"),
        ));
    }
    let (count, stride) = (count as usize, stride as usize);
    let mut bytes = decode_stream(mode, source, count, stride, at)?;
    if let Some(f) = ext.get("filter").and_then(Value::as_str) {
        if mode != "ATTRIBUTES" && f != "NONE" {
            return Err(invalid(
                &format!("{at}.filter"),
                "filters apply to ATTRIBUTES only",
            ));
        }
        filter(f, &mut bytes, stride, at)?;
    }
    Ok(bytes)
}

/// The bytes of a compressed stream decoded in `mode` (`ATTRIBUTES`, `TRIANGLES` or `INDICES`).
fn decode_stream(
    mode: &str,
    source: &[u8],
    count: usize,
    stride: usize,
    at: &str,
) -> Result<Vec<u8>, Error> {
    let failed = |e: meshopt::Error| compressed(at, format!("{mode} stream does not decode: {e}"));
    Ok(match (mode, stride) {
        ("ATTRIBUTES", s) => decode_vertices(source, count, s)
            .ok_or_else(|| {
                invalid(
                    &format!("{at}.byteStride"),
                    format!("{s} is not a multiple of 4 up to 256"),
                )
            })?
            .map_err(failed)?,
        ("TRIANGLES", 2) if count % 3 == 0 => {
            meshopt::encoding::decode_index_buffer::<u16>(source, count)
                .map_err(failed)?
                .iter()
                .flat_map(|i| i.to_le_bytes())
                .collect()
        }
        ("TRIANGLES", 4) if count % 3 == 0 => {
            meshopt::encoding::decode_index_buffer::<u32>(source, count)
                .map_err(failed)?
                .iter()
                .flat_map(|i| i.to_le_bytes())
                .collect()
        }
        ("INDICES", 2) => meshopt::encoding::decode_index_sequence::<u16>(source, count)
            .map_err(failed)?
            .iter()
            .flat_map(|i| i.to_le_bytes())
            .collect(),
        ("INDICES", 4) => meshopt::encoding::decode_index_sequence::<u32>(source, count)
            .map_err(failed)?
            .iter()
            .flat_map(|i| i.to_le_bytes())
            .collect(),
        (m, s) => {
            return Err(invalid(
                &format!("{at}.mode"),
                format!("mode {m:?} with byteStride {s} and count {count} is not defined"),
            ))
        }
    })
}

/// ` (read by meshes[0].primitives[1].attributes.POSITION, …)`: the primitives whose data a view
/// holds, so an error names them.
fn users(root: &Value, view: usize) -> String {
    let accessors: Vec<usize> = root
        .get("accessors")
        .and_then(Value::as_array)
        .into_iter()
        .flatten()
        .enumerate()
        .filter(|(_, a)| a.get("bufferView").and_then(Value::as_u64) == Some(view as u64))
        .map(|(i, _)| i)
        .collect();
    let mut uses = Vec::new();
    let meshes = root.get("meshes").and_then(Value::as_array);
    for (m, mesh) in meshes.into_iter().flatten().enumerate() {
        let prims = mesh.get("primitives").and_then(Value::as_array);
        for (p, prim) in prims.into_iter().flatten().enumerate() {
            let uses_view = |v: Option<&Value>| {
                v.and_then(Value::as_u64)
                    .is_some_and(|a| accessors.contains(&(a as usize)))
            };
            if uses_view(prim.get("indices")) {
                uses.push(format!("meshes[{m}].primitives[{p}].indices"));
            }
            let attributes = prim.get("attributes").and_then(Value::as_object);
            for (name, a) in attributes.into_iter().flatten() {
                if uses_view(Some(a)) {
                    uses.push(format!("meshes[{m}].primitives[{p}].attributes.{name}"));
                }
            }
        }
    }
    if uses.is_empty() {
        String::new()
    } else {
        format!(" (read by {})", uses.join(", "))
    }
}

/// Decodes every compressed buffer view of `root` into `buffers.decoded`.
pub(crate) fn decode_views(root: &Value, buffers: &mut Buffers) -> Result<(), Error> {
    let views = root.get("bufferViews").and_then(Value::as_array);
    // Many views may decode the same compressed bytes: the total, too, is held to
    // MAX_EXPANSION times the file's buffers.
    let cap = MAX_EXPANSION
        .saturating_mul(buffers.total)
        .saturating_add(SLACK);
    let mut total = 0u64;
    for (i, view) in views.into_iter().flatten().enumerate() {
        let Some((name, ext)) = extension(view) else {
            continue;
        };
        let length = view.get("byteLength").and_then(Value::as_u64).unwrap_or(0);
        let at = format!("bufferViews[{i}].extensions.{name}");
        // The primitives reading a view are named only in errors: finding them scans every
        // accessor and primitive, which for every view of a large file would be quadratic.
        let with_users = || format!("{at}{}", users(root, i));
        total = total.saturating_add(length);
        if total > cap {
            return Err(compressed(
                &with_users(),
                format!(
                    "the compressed views decode to {total} bytes so far, more than \
                     {MAX_EXPANSION} times the file's {} buffer bytes",
                    buffers.total
                ),
            ));
        }
        buffers.charge(&at, length)?;
        let bytes = match decode_view(ext, length, buffers, &at) {
            Ok(b) => b,
            Err(_) => decode_view(ext, length, buffers, &with_users())?,
        };
        buffers.decoded.insert(i, bytes);
    }
    Ok(())
}
