//! Writes `EXT_meshopt_compression` copies of GLB files with meshoptimizer's own encoder, for the
//! tests: every buffer view holding only mesh vertex attributes (strides 4 to 64) or only triangle
//! indices is compressed (lossless: no filter) and its plain bytes are zeroed, so a loader that
//! ignored the extension would draw nothing right.

use serde_json::{json, Value};

/// A GLB split into its JSON and BIN chunk.
pub fn split_glb(bytes: &[u8]) -> (Value, Vec<u8>) {
    let u = |o: usize| u32::from_le_bytes(bytes[o..o + 4].try_into().unwrap()) as usize;
    let jl = u(12);
    let json = serde_json::from_slice(&bytes[20..20 + jl]).unwrap();
    let bo = 20 + jl;
    (json, bytes[bo + 8..bo + 8 + u(bo)].to_vec())
}

/// A GLB from JSON and BIN.
pub fn join_glb(json: &Value, bin: &[u8]) -> Vec<u8> {
    let mut j = serde_json::to_vec(json).unwrap();
    while j.len() % 4 != 0 {
        j.push(b' ');
    }
    let mut b = bin.to_vec();
    while b.len() % 4 != 0 {
        b.push(0);
    }
    let mut out = Vec::new();
    out.extend(b"glTF");
    out.extend(2u32.to_le_bytes());
    out.extend(((12 + 8 + j.len() + 8 + b.len()) as u32).to_le_bytes());
    out.extend((j.len() as u32).to_le_bytes());
    out.extend(0x4E4F_534Au32.to_le_bytes());
    out.extend(j);
    out.extend((b.len() as u32).to_le_bytes());
    out.extend(0x004E_4942u32.to_le_bytes());
    out.extend(b);
    out
}

#[derive(Clone, Copy)]
struct Element<const N: usize>([u8; N]);

fn encode<const N: usize>(data: &[u8]) -> Vec<u8> {
    let v: Vec<Element<N>> = data
        .chunks_exact(N)
        .map(|c| Element(c.try_into().unwrap()))
        .collect();
    meshopt::encoding::encode_vertex_buffer(&v).unwrap()
}

impl<const N: usize> Default for Element<N> {
    fn default() -> Self {
        Self([0; N])
    }
}

fn encode_vertices(data: &[u8], stride: usize) -> Option<Vec<u8>> {
    Some(match stride {
        4 => encode::<4>(data),
        8 => encode::<8>(data),
        12 => encode::<12>(data),
        16 => encode::<16>(data),
        20 => encode::<20>(data),
        24 => encode::<24>(data),
        32 => encode::<32>(data),
        48 => encode::<48>(data),
        64 => encode::<64>(data),
        _ => return None,
    })
}

fn size(accessor: &Value) -> usize {
    let c = match accessor["componentType"].as_u64().unwrap() {
        5120 | 5121 => 1,
        5122 | 5123 => 2,
        _ => 4,
    };
    c * match accessor["type"].as_str().unwrap() {
        "SCALAR" => 1,
        "VEC2" => 2,
        "VEC3" => 3,
        "VEC4" => 4,
        _ => 16,
    }
}

/// How triangle indices are compressed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum IndexMode {
    /// `TRIANGLES`: the triangle codec, which may rotate each triangle's corners (same winding).
    Triangles,
    /// `INDICES`: the index sequence codec, which keeps every index in place.
    Indices,
}

/// What a buffer view holds: `Some(true)` vertex data, `Some(false)` triangle indices, `None`
/// mixed or other data.
type Role = Option<bool>;

/// Each buffer view's role, `None` for a view no mesh uses.
fn view_roles(json: &Value, accessors: &Value) -> Vec<Option<Role>> {
    let views = json["bufferViews"].as_array().map_or(0, Vec::len);
    let mut role: Vec<Option<Role>> = vec![None; views];
    let mark = |acc: &Value, vertex: bool, role: &mut Vec<Option<Role>>| {
        if let Some(v) = acc["bufferView"].as_u64() {
            let r = &mut role[v as usize];
            *r = match *r {
                None => Some(Some(vertex)),
                Some(Some(x)) if x == vertex && vertex => Some(Some(x)),
                _ => Some(None),
            };
        }
    };
    for mesh in json["meshes"].as_array().into_iter().flatten() {
        for prim in mesh["primitives"].as_array().into_iter().flatten() {
            for (_, a) in prim["attributes"].as_object().into_iter().flatten() {
                mark(&accessors[a.as_u64().unwrap() as usize], true, &mut role);
            }
            if let Some(i) = prim["indices"].as_u64() {
                let triangles = prim["mode"].as_u64().unwrap_or(4) == 4;
                mark(&accessors[i as usize], false, &mut role);
                if !triangles {
                    role[accessors[i as usize]["bufferView"].as_u64().unwrap() as usize] =
                        Some(None);
                }
            }
        }
    }
    role
}

/// A view's compressed stream with its `byteStride`, `count` and `mode`.
type Stream = (Vec<u8>, usize, usize, &'static str);

/// The vertex view `plain` compressed, if its stride is one the encoder takes and every accessor
/// on it agrees with that stride.
fn vertex_stream(view: &Value, users: &[&Value], plain: &[u8]) -> Option<Stream> {
    let length = plain.len();
    let stride = view["byteStride"]
        .as_u64()
        .map_or_else(|| size(users[0]), |s| s as usize);
    if length % stride != 0
        || users
            .iter()
            .any(|a| view["byteStride"].is_null() && size(a) != stride)
    {
        return None;
    }
    let s = encode_vertices(plain, stride)?;
    Some((s, stride, length / stride, "ATTRIBUTES"))
}

/// The index view `plain` (read by its one accessor `a`) compressed, if it holds 16- or 32-bit
/// indices and nothing else.
fn index_stream(a: &Value, plain: &[u8], index_mode: IndexMode) -> Option<Stream> {
    let stride = size(a);
    let count = a["count"].as_u64().unwrap() as usize;
    if count * stride != plain.len() || stride == 1 {
        return None;
    }
    let indices: Vec<u32> = plain
        .chunks_exact(stride)
        .map(|c| {
            if stride == 2 {
                u16::from_le_bytes([c[0], c[1]]) as u32
            } else {
                u32::from_le_bytes(c.try_into().unwrap())
            }
        })
        .collect();
    let vertices = indices.iter().max().map_or(0, |m| *m as usize + 1);
    Some(match index_mode {
        IndexMode::Triangles => (
            meshopt::encoding::encode_index_buffer(&indices, vertices).unwrap(),
            stride,
            count,
            "TRIANGLES",
        ),
        IndexMode::Indices => (
            meshopt::encoding::encode_index_sequence(&indices, vertices).unwrap(),
            stride,
            count,
            "INDICES",
        ),
    })
}

/// The compressed copy of a GLB (JSON and BIN), and how many views it compressed.
pub fn compress(json: &Value, bin: &[u8], index_mode: IndexMode) -> (Value, Vec<u8>, usize) {
    let mut json = json.clone();
    let mut bin = bin.to_vec();
    let accessors = json["accessors"].clone();
    let role = view_roles(&json, &accessors);
    let mut compressed = 0;
    for (v, r) in role.iter().enumerate() {
        let view = json["bufferViews"][v].clone();
        let (offset, length) = (
            view["byteOffset"].as_u64().unwrap_or(0) as usize,
            view["byteLength"].as_u64().unwrap() as usize,
        );
        let users: Vec<&Value> = accessors
            .as_array()
            .unwrap()
            .iter()
            .filter(|a| a["bufferView"].as_u64() == Some(v as u64))
            .collect();
        let plain = &bin[offset..offset + length];
        let stream = match r {
            Some(Some(true)) => vertex_stream(&view, &users, plain),
            Some(Some(false))
                if users.len() == 1 && users[0]["byteOffset"].as_u64().unwrap_or(0) == 0 =>
            {
                index_stream(users[0], plain, index_mode)
            }
            _ => None,
        };
        let Some((stream, stride, count, mode)) = stream else {
            continue;
        };
        bin[offset..offset + length].fill(0);
        while bin.len() % 4 != 0 {
            bin.push(0);
        }
        let at = bin.len();
        bin.extend(&stream);
        json["bufferViews"][v]["extensions"] = json!({"EXT_meshopt_compression": {
            "buffer": 0, "byteOffset": at, "byteLength": stream.len(),
            "byteStride": stride, "count": count, "mode": mode}});
        compressed += 1;
    }
    json["buffers"][0]["byteLength"] = json!(bin.len());
    for key in ["extensionsUsed", "extensionsRequired"] {
        let mut list = json[key].as_array().cloned().unwrap_or_default();
        list.push(json!("EXT_meshopt_compression"));
        json[key] = Value::Array(list);
    }
    (json, bin, compressed)
}
