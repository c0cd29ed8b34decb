//! Shared helpers of the `stress_*` tests (included with `#[path]`; as its own test target it
//! holds no tests): a small glTF writer, so every stress scene goes through the loader as a user's
//! file would, and one render call that checks the dropped-sample count.
#![allow(dead_code)]

use aperture_imageio::{metrics, Image};
use aperture_render::{Film, FilterKind, RenderOptions};
use aperture_scene::{load_bytes, LoadOptions, Scene};
use glam::{Vec2, Vec3};
use serde_json::{json, Value};
use std::path::Path;

/// Standard base64 with padding (the tests crate has no base64 dependency).
pub fn base64(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            chunk.get(1).copied().unwrap_or(0),
            chunk.get(2).copied().unwrap_or(0),
        ];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(A[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// A glTF document under construction: one binary buffer (written as a `data:` URI) and the
/// JSON arrays that refer to it.
pub struct Gltf {
    bin: Vec<u8>,
    /// The JSON document without `buffers` and `scenes` (added by [`Gltf::to_bytes`]).
    pub json: Value,
}

impl Default for Gltf {
    fn default() -> Self {
        Self::new()
    }
}

impl Gltf {
    /// An empty document.
    pub fn new() -> Self {
        Self {
            bin: Vec::new(),
            json: json!({
                "asset": {"version": "2.0"},
                "accessors": [], "bufferViews": [], "meshes": [], "materials": [], "nodes": [],
                "cameras": [], "images": [], "textures": [], "samplers": [],
                "extensionsUsed": []
            }),
        }
    }

    fn push(&mut self, array: &str, v: Value) -> usize {
        let a = self.json[array].as_array_mut().expect("array");
        a.push(v);
        a.len() - 1
    }

    fn view(&mut self, bytes: &[u8]) -> usize {
        while self.bin.len() % 4 != 0 {
            self.bin.push(0);
        }
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        self.push(
            "bufferViews",
            json!({"buffer": 0, "byteOffset": offset, "byteLength": bytes.len()}),
        )
    }

    /// A float accessor of `N`-vectors (`min`/`max` written for POSITION's sake).
    fn floats<const N: usize>(&mut self, values: &[[f32; N]], kind: &str) -> usize {
        let bytes: Vec<u8> = values
            .iter()
            .flatten()
            .flat_map(|x| x.to_le_bytes())
            .collect();
        let view = self.view(&bytes);
        let mut lo = [f32::INFINITY; N];
        let mut hi = [f32::NEG_INFINITY; N];
        for v in values {
            for k in 0..N {
                lo[k] = lo[k].min(v[k]);
                hi[k] = hi[k].max(v[k]);
            }
        }
        self.push(
            "accessors",
            json!({"bufferView": view, "componentType": 5126, "count": values.len(),
                   "type": kind, "min": lo.as_slice(), "max": hi.as_slice()}),
        )
    }

    /// A triangle mesh with one primitive; `None` attributes are left out.
    pub fn mesh(
        &mut self,
        positions: &[Vec3],
        normals: Option<&[Vec3]>,
        uv: Option<&[Vec2]>,
        indices: &[[u32; 3]],
        material: usize,
    ) -> usize {
        let p: Vec<[f32; 3]> = positions.iter().map(|v| v.to_array()).collect();
        let mut attributes = json!({"POSITION": self.floats(&p, "VEC3")});
        if let Some(n) = normals {
            let n: Vec<[f32; 3]> = n.iter().map(|v| v.to_array()).collect();
            attributes["NORMAL"] = json!(self.floats(&n, "VEC3"));
        }
        if let Some(t) = uv {
            let t: Vec<[f32; 2]> = t.iter().map(|v| v.to_array()).collect();
            attributes["TEXCOORD_0"] = json!(self.floats(&t, "VEC2"));
        }
        let bytes: Vec<u8> = indices
            .iter()
            .flatten()
            .flat_map(|i| i.to_le_bytes())
            .collect();
        let view = self.view(&bytes);
        let idx = self.push(
            "accessors",
            json!({"bufferView": view, "componentType": 5125, "count": indices.len() * 3,
                   "type": "SCALAR"}),
        );
        self.push(
            "meshes",
            json!({"primitives": [{"attributes": attributes, "indices": idx, "material": material}]}),
        )
    }

    /// Adds a material (glTF JSON), returning its index.
    pub fn material(&mut self, m: Value) -> usize {
        self.push("materials", m)
    }

    /// Adds a node (glTF JSON), returning its index.
    pub fn node(&mut self, n: Value) -> usize {
        self.push("nodes", n)
    }

    /// Adds a camera (glTF JSON), returning its index.
    pub fn camera(&mut self, c: Value) -> usize {
        self.push("cameras", c)
    }

    /// Declares an extension as used (and so allowed on objects).
    pub fn uses(&mut self, ext: &str) {
        let used = self.json["extensionsUsed"].as_array_mut().expect("array");
        if !used.iter().any(|e| e == ext) {
            used.push(json!(ext));
        }
    }

    /// Adds a `KHR_lights_punctual` light, returning its index.
    pub fn light(&mut self, l: Value) -> usize {
        self.uses("KHR_lights_punctual");
        let ext = &mut self.json["extensions"]["KHR_lights_punctual"]["lights"];
        if ext.is_null() {
            *ext = json!([]);
        }
        let a = ext.as_array_mut().expect("array");
        a.push(l);
        a.len() - 1
    }

    /// A texture of `image` as an embedded 8-bit PNG, with a `sampler` (glTF JSON).
    pub fn png_texture(&mut self, image: &Image, sampler: Value) -> usize {
        let png = aperture_imageio::encode_png(image, &Default::default(), Path::new("texture"))
            .expect("encodes");
        let img = self.push(
            "images",
            json!({"uri": format!("data:image/png;base64,{}", base64(&png))}),
        );
        let s = self.push("samplers", sampler);
        self.push("textures", json!({"source": img, "sampler": s}))
    }

    /// The `.gltf` file with one scene of the given root nodes.
    pub fn to_bytes(&self, roots: &[usize]) -> Vec<u8> {
        let mut j = self.json.clone();
        j["scenes"] = json!([{"nodes": roots}]);
        j["scene"] = json!(0);
        j["buffers"] = json!([{"byteLength": self.bin.len(),
            "uri": format!("data:application/octet-stream;base64,{}", base64(&self.bin))}]);
        serde_json::to_vec(&j).expect("serialises")
    }

    /// Loads the file through the real loader.
    pub fn load(&self, roots: &[usize]) -> Scene {
        load_bytes(
            &self.to_bytes(roots),
            Path::new("."),
            &LoadOptions::default(),
        )
        .unwrap_or_else(|e| panic!("loads: {e}"))
    }
}

/// A unit quaternion (glTF order x, y, z, w) rotating by `angle` about `axis`.
pub fn quat(axis: Vec3, angle: f32) -> [f32; 4] {
    glam::Quat::from_axis_angle(axis.normalize(), angle).to_array()
}

/// Renders camera 0 with a 1-pixel box filter (so pixels are independent) and checks that no
/// sample was dropped as non-finite.
pub fn render_checked(
    scene: &Scene,
    size: (u32, u32),
    spp: u32,
    seed: u32,
    max_bounces: u32,
) -> Film {
    render_camera(scene, size, spp, seed, max_bounces, 0)
}

/// [`render_checked`] through scene camera `camera`.
pub fn render_camera(
    scene: &Scene,
    (width, height): (u32, u32),
    spp: u32,
    seed: u32,
    max_bounces: u32,
    camera: usize,
) -> Film {
    let opts = RenderOptions {
        width,
        height,
        spp,
        seed,
        max_bounces,
        camera,
        filter: FilterKind::Box,
        ..RenderOptions::default()
    };
    let film = aperture_tests::render_checked(scene, &opts);
    assert!(
        film.to_rgba().iter().flatten().all(|c| c.is_finite()),
        "non-finite pixel"
    );
    film
}

/// The film as an image, for the metrics.
pub fn image(film: &Film) -> Image {
    let mut im = Image::new(film.width(), film.height());
    im.rgba = film.to_rgba();
    im
}

/// `rmse(a, b)` of two films.
pub fn rmse(a: &Film, b: &Film) -> f64 {
    metrics::rmse(&image(a), &image(b)).expect("same size")
}

/// Per-channel means of a film.
pub fn mean(a: &Film) -> [f64; 3] {
    metrics::mean_rgb(&image(a)).expect("valid image")
}
