//! An independent reference evaluation of glTF animation, skinning and morphing for the tests,
//! written from the glTF 2.0 specification (§3.7, Appendix C) without the loader's code: JSON and
//! bytes read directly, every formula in f64, matrices as column-major `[f64; 16]`.
#![allow(dead_code)]

use std::path::Path;

use serde_json::Value;

/// A glTF document: its JSON and its buffers.
pub struct Doc {
    pub json: Value,
    buffers: Vec<Vec<u8>>,
}

pub type M4 = [f64; 16];

/// An accessor's elements, each as its components.
pub type Rows = Vec<Vec<f64>>;

pub fn identity() -> M4 {
    let mut m = [0.0; 16];
    for i in 0..4 {
        m[i * 5] = 1.0;
    }
    m
}

pub fn mul(a: &M4, b: &M4) -> M4 {
    let mut r = [0.0; 16];
    for c in 0..4 {
        for row in 0..4 {
            r[c * 4 + row] = (0..4).map(|k| a[k * 4 + row] * b[c * 4 + k]).sum();
        }
    }
    r
}

pub fn apply(m: &M4, p: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|row| m[row] * p[0] + m[4 + row] * p[1] + m[8 + row] * p[2] + m[12 + row])
}

/// T · R · S as a matrix (quaternion x, y, z, w).
pub fn trs(t: [f64; 3], q: [f64; 4], s: [f64; 3]) -> M4 {
    let n = (q.iter().map(|x| x * x).sum::<f64>()).sqrt();
    let [x, y, z, w] = q.map(|c| c / n);
    let r = [
        1.0 - 2.0 * (y * y + z * z),
        2.0 * (x * y + z * w),
        2.0 * (x * z - y * w),
        2.0 * (x * y - z * w),
        1.0 - 2.0 * (x * x + z * z),
        2.0 * (y * z + x * w),
        2.0 * (x * z + y * w),
        2.0 * (y * z - x * w),
        1.0 - 2.0 * (x * x + y * y),
    ];
    let mut m = identity();
    for c in 0..3 {
        for row in 0..3 {
            m[c * 4 + row] = r[c * 3 + row] * s[c];
        }
        m[12 + c] = t[c];
    }
    m
}

impl Doc {
    pub fn open(path: &Path) -> Doc {
        let bytes = std::fs::read(path).unwrap();
        let (json, bin): (Value, Option<Vec<u8>>) = if bytes.starts_with(b"glTF") {
            let u = |o: usize| u32::from_le_bytes(bytes[o..o + 4].try_into().unwrap()) as usize;
            let jl = u(12);
            let json = serde_json::from_slice(&bytes[20..20 + jl]).unwrap();
            let bo = 20 + jl;
            let bin = (bytes.len() > bo + 8).then(|| bytes[bo + 8..bo + 8 + u(bo)].to_vec());
            (json, bin)
        } else {
            (serde_json::from_slice(&bytes).unwrap(), None)
        };
        let buffers = json["buffers"]
            .as_array()
            .map(|bs| {
                bs.iter()
                    .map(|b| match b["uri"].as_str() {
                        Some(uri) => std::fs::read(path.parent().unwrap().join(uri)).unwrap(),
                        None => bin.clone().unwrap(),
                    })
                    .collect()
            })
            .unwrap_or_default();
        Doc { json, buffers }
    }

    /// An accessor as rows of floats (float, or integers as their value, normalised if marked).
    pub fn accessor(&self, index: u64) -> Vec<Vec<f64>> {
        let a = &self.json["accessors"][index as usize];
        let n = match a["type"].as_str().unwrap() {
            "SCALAR" => 1,
            "VEC2" => 2,
            "VEC3" => 3,
            "VEC4" => 4,
            "MAT4" => 16,
            t => panic!("type {t}"),
        };
        let ct = a["componentType"].as_u64().unwrap();
        let size = match ct {
            5120 | 5121 => 1,
            5122 | 5123 => 2,
            _ => 4,
        };
        let count = a["count"].as_u64().unwrap() as usize;
        let norm = a["normalized"].as_bool().unwrap_or(false);
        let v = &self.json["bufferViews"][a["bufferView"].as_u64().unwrap() as usize];
        let buf = &self.buffers[v["buffer"].as_u64().unwrap() as usize];
        let start = v["byteOffset"].as_u64().unwrap_or(0) as usize
            + a["byteOffset"].as_u64().unwrap_or(0) as usize;
        let stride = v["byteStride"].as_u64().map_or(n * size, |s| s as usize);
        (0..count)
            .map(|i| {
                (0..n)
                    .map(|c| {
                        let o = start + i * stride + c * size;
                        let b = &buf[o..o + size];
                        match (ct, norm) {
                            (5126, _) => f32::from_le_bytes(b.try_into().unwrap()) as f64,
                            (5121, false) => b[0] as f64,
                            (5121, true) => b[0] as f64 / 255.0,
                            (5123, false) => u16::from_le_bytes(b.try_into().unwrap()) as f64,
                            (5123, true) => {
                                u16::from_le_bytes(b.try_into().unwrap()) as f64 / 65535.0
                            }
                            (5125, _) => u32::from_le_bytes(b.try_into().unwrap()) as f64,
                            other => panic!("component {other:?}"),
                        }
                    })
                    .collect()
            })
            .collect()
    }
}

/// The value of a sampler at `t` (rotation: slerp for LINEAR).
pub fn sample(doc: &Doc, sampler: &Value, t: f64, rotation: bool) -> Vec<f64> {
    let times: Vec<f64> = doc
        .accessor(sampler["input"].as_u64().unwrap())
        .into_iter()
        .map(|r| r[0])
        .collect();
    let out: Vec<f64> = doc
        .accessor(sampler["output"].as_u64().unwrap())
        .into_iter()
        .flatten()
        .collect();
    let interp = sampler["interpolation"].as_str().unwrap_or("LINEAR");
    let keys = times.len();
    let per = if interp == "CUBICSPLINE" { 3 } else { 1 };
    let w = out.len() / keys / per;
    let get = |k: usize, part: usize| -> Vec<f64> {
        let o = (k * per + part) * w;
        out[o..o + w].to_vec()
    };
    let vpart = if per == 3 { 1 } else { 0 };
    if t <= times[0] {
        return get(0, vpart);
    }
    if t >= times[keys - 1] {
        return get(keys - 1, vpart);
    }
    let k = (0..keys - 1)
        .find(|&k| times[k] <= t && t < times[k + 1])
        .unwrap();
    let td = times[k + 1] - times[k];
    let u = (t - times[k]) / td;
    match interp {
        "STEP" => get(k, 0),
        "CUBICSPLINE" => {
            let (p0, m0, p1, m1) = (get(k, 1), get(k, 2), get(k + 1, 1), get(k + 1, 0));
            let v: Vec<f64> = (0..w)
                .map(|i| {
                    (2.0 * u.powi(3) - 3.0 * u * u + 1.0) * p0[i]
                        + (u.powi(3) - 2.0 * u * u + u) * td * m0[i]
                        + (-2.0 * u.powi(3) + 3.0 * u * u) * p1[i]
                        + (u.powi(3) - u * u) * td * m1[i]
                })
                .collect();
            if rotation {
                let n = v.iter().map(|x| x * x).sum::<f64>().sqrt();
                v.iter().map(|x| x / n).collect()
            } else {
                v
            }
        }
        _ if rotation => {
            let (a, mut b) = (get(k, 0), get(k + 1, 0));
            let mut d: f64 = (0..4).map(|i| a[i] * b[i]).sum();
            if d < 0.0 {
                b = b.iter().map(|x| -x).collect();
                d = -d;
            }
            if d > 0.9999999 {
                return (0..4).map(|i| a[i] + u * (b[i] - a[i])).collect();
            }
            let th = d.acos();
            (0..4)
                .map(|i| (((1.0 - u) * th).sin() * a[i] + (u * th).sin() * b[i]) / th.sin())
                .collect()
        }
        _ => {
            let (a, b) = (get(k, 0), get(k + 1, 0));
            (0..w).map(|i| a[i] + u * (b[i] - a[i])).collect()
        }
    }
}

/// Local TRS of every node at `t` (`None`: as stored), matrices for nodes with one and no channel.
pub fn locals(doc: &Doc, t: Option<f64>) -> (Vec<M4>, Vec<Option<Vec<f64>>>) {
    let nodes = doc.json["nodes"].as_array().unwrap();
    let mut tr: Vec<[f64; 3]> = Vec::new();
    let mut ro: Vec<[f64; 4]> = Vec::new();
    let mut sc: Vec<[f64; 3]> = Vec::new();
    let mut animated = vec![false; nodes.len()];
    let mut weights: Vec<Option<Vec<f64>>> = nodes
        .iter()
        .map(|n| {
            n["weights"]
                .as_array()
                .map(|w| w.iter().map(|x| x.as_f64().unwrap()).collect())
        })
        .collect();
    let arr = |v: &Value, d: &[f64]| -> Vec<f64> {
        v.as_array().map_or(d.to_vec(), |a| {
            a.iter().map(|x| x.as_f64().unwrap()).collect()
        })
    };
    for n in nodes {
        let t3 = arr(&n["translation"], &[0.0; 3]);
        let r4 = arr(&n["rotation"], &[0.0, 0.0, 0.0, 1.0]);
        let s3 = arr(&n["scale"], &[1.0; 3]);
        tr.push([t3[0], t3[1], t3[2]]);
        ro.push([r4[0], r4[1], r4[2], r4[3]]);
        sc.push([s3[0], s3[1], s3[2]]);
    }
    if let Some(t) = t {
        for anim in doc.json["animations"].as_array().into_iter().flatten() {
            for ch in anim["channels"].as_array().unwrap() {
                let node = ch["target"]["node"].as_u64().unwrap() as usize;
                let path = ch["target"]["path"].as_str().unwrap();
                let s = &anim["samplers"][ch["sampler"].as_u64().unwrap() as usize];
                let v = sample(doc, s, t, path == "rotation");
                match path {
                    "translation" => tr[node] = [v[0], v[1], v[2]],
                    "rotation" => ro[node] = [v[0], v[1], v[2], v[3]],
                    "scale" => sc[node] = [v[0], v[1], v[2]],
                    _ => {
                        weights[node] = Some(v);
                        continue;
                    }
                }
                animated[node] = true;
            }
        }
    }
    let m = nodes
        .iter()
        .enumerate()
        .map(|(i, n)| match n["matrix"].as_array() {
            Some(m) if !animated[i] => std::array::from_fn(|k| m[k].as_f64().unwrap()),
            _ => trs(tr[i], ro[i], sc[i]),
        })
        .collect();
    (m, weights)
}

/// World matrices of every node.
pub fn worlds(doc: &Doc, local: &[M4]) -> Vec<M4> {
    let nodes = doc.json["nodes"].as_array().unwrap();
    let mut world = vec![None; nodes.len()];
    fn visit(doc: &Value, i: usize, parent: M4, local: &[M4], world: &mut Vec<Option<M4>>) {
        let w = mul(&parent, &local[i]);
        world[i] = Some(w);
        for c in doc["nodes"][i]["children"].as_array().into_iter().flatten() {
            visit(doc, c.as_u64().unwrap() as usize, w, local, world);
        }
    }
    let mut is_child = vec![false; nodes.len()];
    for n in nodes {
        for c in n["children"].as_array().into_iter().flatten() {
            is_child[c.as_u64().unwrap() as usize] = true;
        }
    }
    for (i, child) in is_child.iter().enumerate() {
        if !child {
            visit(&doc.json, i, identity(), local, &mut world);
        }
    }
    world.into_iter().map(Option::unwrap).collect()
}

/// World-space bounds of every drawn vertex at `t`: morph targets, then skin, then (unskinned)
/// the node's world matrix.
pub fn bounds(doc: &Doc, t: Option<f64>) -> ([f64; 3], [f64; 3]) {
    let (local, node_weights) = locals(doc, t);
    let world = worlds(doc, &local);
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    let scene = doc.json["scene"].as_u64().unwrap_or(0) as usize;
    let mut stack: Vec<usize> = doc.json["scenes"][scene]["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap() as usize)
        .collect();
    while let Some(ni) = stack.pop() {
        let node = &doc.json["nodes"][ni];
        stack.extend(
            node["children"]
                .as_array()
                .into_iter()
                .flatten()
                .map(|v| v.as_u64().unwrap() as usize),
        );
        let Some(mi) = node["mesh"].as_u64() else {
            continue;
        };
        let mesh = &doc.json["meshes"][mi as usize];
        let weights: Vec<f64> = node_weights[ni].clone().unwrap_or_else(|| {
            mesh["weights"].as_array().map_or(Vec::new(), |w| {
                w.iter().map(|x| x.as_f64().unwrap()).collect()
            })
        });
        let joints = node["skin"]
            .as_u64()
            .map(|s| joint_matrices(doc, s, &world));
        for prim in mesh["primitives"].as_array().unwrap() {
            if prim["mode"].as_u64().is_some_and(|m| m < 4) {
                continue;
            }
            let a = &prim["attributes"];
            let pos = morphed_positions(doc, prim, &weights);
            let sets: Vec<(Rows, Rows)> = (0..)
                .map_while(|s| {
                    Some((
                        doc.accessor(a[format!("JOINTS_{s}")].as_u64()?),
                        doc.accessor(a[format!("WEIGHTS_{s}")].as_u64()?),
                    ))
                })
                .collect();
            for (v, p) in pos.iter().enumerate() {
                let p = [p[0], p[1], p[2]];
                let q = match (&joints, sets.is_empty()) {
                    (Some(jm), false) => skinned(jm, &sets, v, p),
                    _ => apply(&world[ni], p),
                };
                for d in 0..3 {
                    lo[d] = lo[d].min(q[d]);
                    hi[d] = hi[d].max(q[d]);
                }
            }
        }
    }
    (lo, hi)
}

/// Skin `s`'s joint matrices: each joint's world matrix times its inverse bind matrix.
fn joint_matrices(doc: &Doc, s: u64, world: &[M4]) -> Vec<M4> {
    let skin = &doc.json["skins"][s as usize];
    let ibm = skin["inverseBindMatrices"]
        .as_u64()
        .map(|a| doc.accessor(a));
    skin["joints"]
        .as_array()
        .unwrap()
        .iter()
        .enumerate()
        .map(|(k, j)| {
            let b: M4 = ibm
                .as_ref()
                .map_or(identity(), |m| std::array::from_fn(|i| m[k][i]));
            mul(&world[j.as_u64().unwrap() as usize], &b)
        })
        .collect()
}

/// A primitive's positions with its morph targets applied at `weights`.
fn morphed_positions(doc: &Doc, prim: &Value, weights: &[f64]) -> Rows {
    let a = &prim["attributes"];
    let mut pos = doc.accessor(a["POSITION"].as_u64().unwrap());
    for (k, target) in prim["targets"].as_array().into_iter().flatten().enumerate() {
        let w = weights.get(k).copied().unwrap_or(0.0);
        if let (Some(ti), true) = (target["POSITION"].as_u64(), w != 0.0) {
            for (p, d) in pos.iter_mut().zip(doc.accessor(ti)) {
                for c in 0..3 {
                    p[c] += w * d[c];
                }
            }
        }
    }
    pos
}

/// Vertex `v` at `p` skinned by the joint matrices `jm`, its weights normalised to sum to one.
fn skinned(jm: &[M4], sets: &[(Rows, Rows)], v: usize, p: [f64; 3]) -> [f64; 3] {
    let total: f64 = sets.iter().map(|(_, w)| w[v].iter().sum::<f64>()).sum();
    let mut acc = [0.0; 3];
    for (j, w) in sets {
        for c in 0..4 {
            let x = apply(&jm[j[v][c] as usize], p);
            for d in 0..3 {
                acc[d] += w[v][c] / total * x[d];
            }
        }
    }
    acc
}
