//! Truncated and bit-flipped compressed streams (Draco, meshopt): each is a typed error naming
//! the primitive whose data it holds (or, for a flip that still decodes, a scene), never a panic.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};

use aperture_scene::{load, Error, LoadOptions};
use serde_json::{json, Value};

use crate::base::folder;

/// Loads `json` + `bin` (written as `scene.gltf` + `scene.bin` in `dir`): `None` when it panicked.
fn load_pair(dir: &Path, json: &Value, bin: &[u8]) -> Option<Result<aperture_scene::Scene, Error>> {
    let mut json = json.clone();
    json["buffers"][0]["uri"] = json!("scene.bin");
    std::fs::write(dir.join("scene.gltf"), serde_json::to_vec(&json).unwrap()).unwrap();
    std::fs::write(dir.join("scene.bin"), bin).unwrap();
    let opts = LoadOptions {
        skip_textures: true,
        ..LoadOptions::default()
    };
    catch_unwind(AssertUnwindSafe(|| load(&dir.join("scene.gltf"), &opts))).ok()
}

/// Loads damaged copies one after another in one folder and collects what went wrong.
struct Damaged {
    dir: PathBuf,
    report: Vec<String>,
    flips: usize,
}

impl Damaged {
    fn new(name: &str) -> Self {
        let dir = folder().join("compressed").join(name);
        std::fs::create_dir_all(&dir).unwrap();
        Self {
            dir,
            report: Vec::new(),
            flips: 0,
        }
    }

    /// Loads one copy: an error must name the primitive; with `must_fail`, it must be an error.
    fn check(&mut self, name: &str, json: &Value, bin: &[u8], must_fail: bool) {
        match load_pair(&self.dir, json, bin) {
            None => self.report.push(format!("{name}: PANIC")),
            Some(Err(e)) => {
                let msg = e.to_string();
                if !msg.contains("meshes[0].primitives[0]") {
                    self.report
                        .push(format!("{name}: error does not name the primitive: {msg}"));
                }
            }
            Some(Ok(_)) if must_fail => self.report.push(format!("{name}: loaded without error")),
            Some(Ok(_)) => {}
        }
    }

    /// Loads a bit-flipped copy: it may load, but not panic.
    fn flipped(&mut self, name: &str, json: &Value, bin: &[u8]) {
        self.check(name, json, bin, false);
        self.flips += 1;
    }

    fn assert_clean(&self, what: &str) {
        println!(
            "{what}: {} bit flips and every truncation tried",
            self.flips
        );
        assert!(self.report.is_empty(), "{}", self.report.join("\n"));
    }
}

/// Draco: the Box-Draco sample's stream, cut short and with bits flipped.
#[test]
fn damaged_draco_buffers_are_errors_naming_the_primitive() {
    let Some(samples) = aperture_tests::samples_dir() else {
        return;
    };
    let mut damaged = Damaged::new("draco");
    let path = samples.join("unsupported/Box-Draco/Box.gltf");
    let json: Value = serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
    let bin =
        std::fs::read(path.with_file_name(json["buffers"][0]["uri"].as_str().unwrap())).unwrap();
    let view = json["meshes"][0]["primitives"][0]["extensions"]["KHR_draco_mesh_compression"]
        ["bufferView"]
        .as_u64()
        .unwrap() as usize;
    let offset = json["bufferViews"][view]["byteOffset"]
        .as_u64()
        .unwrap_or(0) as usize;
    let length = json["bufferViews"][view]["byteLength"].as_u64().unwrap() as usize;
    damaged.check("draco intact", &json, &bin, false);
    for keep in [0, 1, 4, length / 4, length / 2, length - 8, length - 1] {
        let mut j = json.clone();
        j["bufferViews"][view]["byteLength"] = json!(keep);
        damaged.check(
            &format!("draco cut to {keep} of {length} bytes"),
            &j,
            &bin,
            true,
        );
    }
    for at in (0..length).step_by(3) {
        for bit in [0x01u8, 0x80] {
            let mut b = bin.clone();
            b[offset + at] ^= bit;
            damaged.flipped(&format!("draco byte {at} ^ {bit:#x}"), &json, &b);
        }
    }
    damaged.assert_clean("draco");
}

/// meshopt: a compressed copy of BoxTextured, each stream cut short and flipped.
#[test]
fn damaged_meshopt_buffers_are_errors_naming_the_primitive() {
    let Some(samples) = aperture_tests::samples_dir() else {
        return;
    };
    let mut damaged = Damaged::new("meshopt");
    let glb = std::fs::read(samples.join("correctness/BoxTextured/BoxTextured.glb")).unwrap();
    let (plain, plain_bin) = aperture_tests::meshopt_writer::split_glb(&glb);
    let (json, bin, _) = aperture_tests::meshopt_writer::compress(
        &plain,
        &plain_bin,
        aperture_tests::meshopt_writer::IndexMode::Triangles,
    );
    let json = {
        let mut j = json;
        j["buffers"][0].as_object_mut().unwrap().remove("uri");
        j
    };
    damaged.check("meshopt intact", &json, &bin, false);
    let views = json["bufferViews"].as_array().unwrap().len();
    for v in 0..views {
        let ext = json["bufferViews"][v]["extensions"]["EXT_meshopt_compression"].clone();
        if ext.is_null() {
            continue;
        }
        let (offset, length) = (
            ext["byteOffset"].as_u64().unwrap() as usize,
            ext["byteLength"].as_u64().unwrap() as usize,
        );
        for keep in [0, 1, length / 2, length - 1] {
            let mut j = json.clone();
            j["bufferViews"][v]["extensions"]["EXT_meshopt_compression"]["byteLength"] =
                json!(keep);
            damaged.check(
                &format!("meshopt view {v} cut to {keep} of {length}"),
                &j,
                &bin,
                true,
            );
        }
        for at in (0..length).step_by(2) {
            let mut b = bin.clone();
            b[offset + at] ^= 0x10;
            damaged.flipped(&format!("meshopt view {v} byte {at} ^ 0x10"), &json, &b);
        }
        // A count the compressed bytes cannot hold.
        let mut j = json.clone();
        j["bufferViews"][v]["extensions"]["EXT_meshopt_compression"]["count"] = json!(1u64 << 40);
        damaged.check(&format!("meshopt view {v} count 2^40"), &j, &bin, true);
    }
    damaged.assert_clean("meshopt");
}
