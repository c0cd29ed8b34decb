//! Writes the seed corpora `fuzz/corpus/<target>/seed-*` (run by hand, then minimise with
//! `tools/fuzz.sh TARGET 0 --minimise`):
//!
//! ```text
//! cargo test -p aperture-fuzz-harness --test seeds -- --ignored
//! ```
//!
//! Seeds come from the small samples of `APERTURE_SAMPLES` (CC-BY 4.0, CC0 and MIT files: see
//! `fuzz/corpus/CREDITS.md`), with external buffers and images inlined as `data:` URIs so the
//! fuzzer mutates one file, and from images and compressed streams written here.

use std::io::Cursor;
use std::path::{Path, PathBuf};

use aperture_fuzz_harness::{draco_input, meshopt_input, MeshoptMode};
use base64::Engine as _;
use serde_json::Value;

fn samples() -> PathBuf {
    std::env::var_os("APERTURE_SAMPLES")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/gltf-samples")
        })
}

fn corpus(target: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../corpus")
        .join(target);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn put(target: &str, name: &str, bytes: &[u8]) {
    std::fs::write(corpus(target).join(format!("seed-{name}")), bytes).unwrap();
}

/// A `.gltf` with every external buffer and image inlined as a `data:` URI.
fn inline(path: &Path) -> Vec<u8> {
    let dir = path.parent().unwrap();
    let mut j: Value = serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap();
    for key in ["buffers", "images"] {
        if let Some(list) = j.get_mut(key).and_then(Value::as_array_mut) {
            for item in list {
                let Some(uri) = item.get("uri").and_then(Value::as_str) else {
                    continue;
                };
                if uri.starts_with("data:") {
                    continue;
                }
                let file = percent_decode(uri);
                let bytes = std::fs::read(dir.join(&file)).unwrap();
                let mime = if key == "images" {
                    "image/png"
                } else {
                    "application/octet-stream"
                };
                item["uri"] = Value::from(format!(
                    "data:{mime};base64,{}",
                    base64::engine::general_purpose::STANDARD.encode(bytes)
                ));
            }
        }
    }
    serde_json::to_vec(&j).unwrap()
}

fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' && i + 2 < b.len() {
            out.push(u8::from_str_radix(&s[i + 1..i + 3], 16).unwrap());
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    String::from_utf8(out).unwrap()
}

#[test]
#[ignore = "writes the seed corpora; run by hand"]
fn write_seeds() {
    let s = samples();
    seed_load(&s);
    seed_draco(&s);
    seed_meshopt();
    seed_texture();
    seed_env_and_exr();
}

/// `load`: glTF samples, as they are (GLB) or inlined (`.gltf`).
fn seed_load(s: &Path) {
    // The loader: small samples covering GLB, sparse accessors, skins, morphs, animation,
    // instancing, cameras, lights, textures, quantization and primitive modes.
    for f in [
        "correctness/Box/Box.glb",
        "correctness/BoxInterleaved/BoxInterleaved.glb",
        "correctness/BoxVertexColors/BoxVertexColors.glb",
        "correctness/BoxTextured/BoxTextured.glb",
        "correctness/Cubes-PointLight/Cubes.glb",
        "correctness/SimpleInstancing/SimpleInstancing.glb",
        "correctness/AnimatedMorphCube/AnimatedMorphCube.glb",
        "correctness/UnlitTest/UnlitTest.glb",
        "animation/BoxAnimated/BoxAnimated.glb",
    ] {
        let name = Path::new(f).file_name().unwrap().to_str().unwrap();
        put("load", name, &std::fs::read(s.join(f)).unwrap());
    }
    for f in [
        "correctness/Triangle/Triangle.gltf",
        "correctness/TriangleWithoutIndices/TriangleWithoutIndices.gltf",
        "correctness/SimpleSparseAccessor/SimpleSparseAccessor.gltf",
        "correctness/SimpleSkin/SimpleSkin.gltf",
        "correctness/SimpleMorph/SimpleMorph.gltf",
        "correctness/Cameras/Cameras.gltf",
        "correctness/MultipleScenes/MultipleScenes.gltf",
        "correctness/Magnum-LightsCamerasJSON/camera.gltf",
        "correctness/Magnum-LightsCamerasJSON/light.gltf",
        "correctness/AnimatedMorphCube-Quantized/AnimatedMorphCube.gltf",
        "correctness/MeshPrimitiveModes/MeshPrimitiveModes.gltf",
    ] {
        let name = Path::new(f).file_name().unwrap().to_str().unwrap();
        put("load", name, &inline(&s.join(f)));
    }
}

/// `draco` (and `load`, the Draco box as a whole file).
fn seed_draco(s: &Path) {
    // Draco: Box-Draco's and Avocado's streams with their real counts and attribute ids.
    let bin = std::fs::read(s.join("unsupported/Box-Draco/Box.bin")).unwrap();
    put(
        "draco",
        "box",
        &draco_input(24, 12, [Some(0), Some(1), None], &bin),
    );
    let bin = std::fs::read(s.join("compression/Avocado-Draco/Avocado.bin")).unwrap();
    put(
        "draco",
        "avocado",
        &draco_input(406, 682, [Some(3), Some(1), Some(0)], &bin),
    );
    put(
        "load",
        "box-draco.gltf",
        &inline(&s.join("unsupported/Box-Draco/Box.gltf")),
    );
}

/// `meshopt`: one stream per mode and filter.
fn seed_meshopt() {
    // meshopt: a cube's positions, normals (octahedral filter) and indices, each mode.
    let positions: Vec<u8> = (0..24u32)
        .flat_map(|i| {
            [
                (i & 1) as f32,
                ((i >> 1) & 1) as f32,
                ((i >> 2) & 1) as f32,
                1.0,
            ]
        })
        .flat_map(f32::to_le_bytes)
        .collect();
    let v = meshopt::encoding::encode_vertex_buffer(
        &positions
            .chunks_exact(16)
            .map(|c| <[u8; 16]>::try_from(c).unwrap())
            .collect::<Vec<_>>(),
    )
    .unwrap();
    put(
        "meshopt",
        "positions",
        &meshopt_input(MeshoptMode::Attributes, 0, 16, 24, &v),
    );
    put(
        "meshopt",
        "exponential",
        &meshopt_input(MeshoptMode::Attributes, 3, 16, 24, &v),
    );
    let normals: Vec<[u8; 4]> = (0..24u8).map(|i| [i * 9, 255 - i * 7, 127, 0]).collect();
    let n = meshopt::encoding::encode_vertex_buffer(&normals).unwrap();
    put(
        "meshopt",
        "octahedral",
        &meshopt_input(MeshoptMode::Attributes, 1, 4, 24, &n),
    );
    put(
        "meshopt",
        "color",
        &meshopt_input(MeshoptMode::Attributes, 4, 4, 24, &n),
    );
    let quats: Vec<[u8; 8]> = (0..24u8).map(|i| [i, 2 * i, 3, 4, 5, 6, 7, 3]).collect();
    let q = meshopt::encoding::encode_vertex_buffer(&quats).unwrap();
    put(
        "meshopt",
        "quaternion",
        &meshopt_input(MeshoptMode::Attributes, 2, 8, 24, &q),
    );
    let tris: Vec<u32> = (0..12u32)
        .flat_map(|t| [t, (t + 1) % 24, (t + 5) % 24])
        .collect();
    let t = meshopt::encoding::encode_index_buffer(&tris, 24).unwrap();
    put(
        "meshopt",
        "triangles32",
        &meshopt_input(MeshoptMode::Triangles, 0, 4, 36, &t),
    );
    put(
        "meshopt",
        "triangles16",
        &meshopt_input(MeshoptMode::Triangles, 0, 2, 36, &t),
    );
    let seq = meshopt::encoding::encode_index_sequence(&tris, 24).unwrap();
    put(
        "meshopt",
        "indices",
        &meshopt_input(MeshoptMode::Indices, 0, 4, 36, &seq),
    );
}

/// `img` encoded as `f`.
fn enc(img: image::DynamicImage, f: image::ImageFormat) -> Vec<u8> {
    let mut out = Vec::new();
    img.write_to(&mut Cursor::new(&mut out), f).unwrap();
    out
}

/// `texture`: PNG, JPEG and WebP images.
fn seed_texture() {
    // Textures: 8-bit, 16-bit, grey, palette-free PNGs, a JPEG and a lossless WebP.
    let rgba = image::RgbaImage::from_fn(8, 6, |x, y| {
        image::Rgba([x as u8 * 30, y as u8 * 40, 7, 200])
    });
    let d = image::DynamicImage::ImageRgba8(rgba);
    put(
        "texture",
        "rgba8.png",
        &enc(d.clone(), image::ImageFormat::Png),
    );
    put(
        "texture",
        "rgb16.png",
        &enc(
            image::DynamicImage::ImageRgb16(d.to_rgb16()),
            image::ImageFormat::Png,
        ),
    );
    put(
        "texture",
        "grey.png",
        &enc(
            image::DynamicImage::ImageLuma8(d.to_luma8()),
            image::ImageFormat::Png,
        ),
    );
    put(
        "texture",
        "rgb.jpg",
        &enc(
            image::DynamicImage::ImageRgb8(d.to_rgb8()),
            image::ImageFormat::Jpeg,
        ),
    );
    put(
        "texture",
        "rgba.webp",
        &enc(d.clone(), image::ImageFormat::WebP),
    );
}

/// `env` and `exr`: Radiance HDR, and EXRs in several compressions and layouts.
fn seed_env_and_exr() {
    // Environment maps and EXR: RGBE, and EXRs in several compressions and layouts.
    let sky = image::Rgb32FImage::from_fn(8, 4, |x, y| image::Rgb([x as f32 * 0.3, y as f32, 5.0]));
    let hdr = enc(
        image::DynamicImage::ImageRgb32F(sky),
        image::ImageFormat::Hdr,
    );
    put("env", "sky.hdr", &hdr);
    let mut im = aperture_imageio::Image::new(8, 4);
    im.rgba = (0..32).map(|i| [i as f32, 0.5, 2.0, 1.0]).collect();
    let plain = aperture_imageio::encode_exr(&im, Path::new("s.exr")).unwrap();
    put("env", "sky.exr", &plain);
    put("exr", "zip.exr", &plain);
    im.layers
        .push(aperture_imageio::Layer::new("Depth", &["Z"], vec![3.0; 32]));
    im.metadata
        .push(("aperture:spp".into(), aperture_imageio::MetaValue::Int(4)));
    put(
        "exr",
        "layers.exr",
        &aperture_imageio::encode_exr(&im, Path::new("l.exr")).unwrap(),
    );
    use exr::prelude::*;
    for (name, c) in [
        ("none", Compression::Uncompressed),
        ("rle", Compression::RLE),
        ("zips", Compression::ZIP1),
        ("piz", Compression::PIZ),
        ("pxr24", Compression::PXR24),
        ("b44", Compression::B44),
    ] {
        let layer = Layer::new(
            (8, 4),
            LayerAttributes::named("part"),
            Encoding {
                compression: c,
                ..Encoding::default()
            },
            SpecificChannels::rgba(|p: Vec2<usize>| {
                (p.x() as f32, 0.5f32, f16::from_f32(2.0), 1.0f32)
            }),
        );
        let mut out = Vec::new();
        Image::from_layer(layer)
            .write()
            .to_buffered(Cursor::new(&mut out))
            .unwrap();
        put("exr", &format!("{name}.exr"), &out);
    }
}
