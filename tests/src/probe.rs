//! Probing sample renders pixel by pixel: which object each pixel's centre ray hits, and the
//! colours of an object's interior pixels (shared by the sample-model tests).

use aperture_accel::{Accel, Ray};
use aperture_render::{build_accel, render, Camera, CameraSample, Film, RenderOptions};
use aperture_scene::Scene;
use glam::{Vec2, Vec3};
use std::path::{Path, PathBuf};

/// A file of the shared samples (`None`, with a message, when they are missing outside CI).
pub fn sample(rel: &str) -> Option<PathBuf> {
    let p = crate::samples_dir()?.join(rel);
    assert!(p.is_file(), "{} missing", p.display());
    Some(p)
}

/// The glTF JSON of a `.gltf` or `.glb` file.
pub fn gltf_json(path: &Path) -> serde_json::Value {
    let bytes = std::fs::read(path).unwrap();
    let json = if bytes.starts_with(b"glTF") {
        let len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
        bytes[20..20 + len].to_vec()
    } else {
        bytes
    };
    serde_json::from_slice(&json).unwrap()
}

/// Names of the glTF nodes, by node index.
pub fn node_names(path: &Path) -> Vec<String> {
    gltf_json(path)["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| n["name"].as_str().unwrap_or("").to_owned())
        .collect()
}

/// A render with, per pixel, the instance its centre ray hits.
pub struct Probe {
    /// The render.
    pub film: Film,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Instance each pixel's centre ray hits.
    pub hits: Vec<Option<u32>>,
    /// Material of each pixel's centre hit.
    pub materials: Vec<Option<u32>>,
}

impl Probe {
    /// Renders `scene` with `opts` and traces every pixel's centre ray.
    pub fn new(scene: &Scene, opts: &RenderOptions) -> Self {
        let accel = build_accel(scene, Default::default());
        let film = render(scene, &accel, opts, &|_, _| {}).unwrap();
        assert_eq!(film.dropped_samples(), 0, "NaN or infinite samples");
        let camera = Camera::new(&scene.cameras[opts.camera], opts.width, opts.height);
        let full = pixel_hits(&accel, &camera, opts.width, opts.height);
        let hits = full.iter().map(|h| h.map(|(i, _)| i)).collect();
        let materials = full
            .iter()
            .map(|h| {
                h.map(|(i, t)| {
                    // The instance's materials: a mesh shared by meshes of other materials
                    // is drawn with each one's (issue 50).
                    scene.instance_materials(&scene.instances[i as usize])[t as usize]
                })
            })
            .collect();
        Self {
            film,
            width: opts.width,
            height: opts.height,
            hits,
            materials,
        }
    }

    /// Interior pixels of the instances drawn by node `node`.
    pub fn pixels_of(&self, scene: &Scene, node: u32) -> Vec<(u32, u32)> {
        let (w, h) = (self.width as i64, self.height as i64);
        let at = |x: i64, y: i64| -> Option<u32> {
            if x < 0 || y < 0 || x >= w || y >= h {
                None
            } else {
                self.hits[(y * w + x) as usize]
            }
        };
        let mut out = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let Some(i) = at(x, y) else { continue };
                if scene.instances[i as usize].node != node {
                    continue;
                }
                let interior = (-1..=1).all(|dy| (-1..=1).all(|dx| at(x + dx, y + dy) == Some(i)));
                if interior {
                    out.push((x as u32, y as u32));
                }
            }
        }
        out
    }

    /// Interior pixels (all 8 neighbours hit the same material) of the material named `name`,
    /// with their colours.
    pub fn material_pixels(&self, scene: &Scene, name: &str) -> Vec<Vec3> {
        let id = scene
            .materials
            .iter()
            .position(|m| m.name.as_deref() == Some(name))
            .unwrap_or_else(|| panic!("no material {name}")) as u32;
        let (w, h) = (self.width as i64, self.height as i64);
        let at = |x: i64, y: i64| -> Option<u32> {
            if x < 0 || y < 0 || x >= w || y >= h {
                None
            } else {
                self.materials[(y * w + x) as usize]
            }
        };
        let mut out = Vec::new();
        for y in 0..h {
            for x in 0..w {
                if (-1..=1).all(|dy| (-1..=1).all(|dx| at(x + dx, y + dy) == Some(id))) {
                    let p = self.film.pixel(x as u32, y as u32);
                    out.push(Vec3::new(p[0], p[1], p[2]));
                }
            }
        }
        out
    }

    /// Mean colour of a node's interior pixels (and how many there are).
    pub fn mean_of(&self, scene: &Scene, node: u32) -> (Vec3, usize) {
        let px = self.pixels_of(scene, node);
        let sum: Vec3 = px
            .iter()
            .map(|&(x, y)| {
                let p = self.film.pixel(x, y);
                Vec3::new(p[0], p[1], p[2])
            })
            .sum();
        (sum / px.len().max(1) as f32, px.len())
    }
}

/// The (instance, triangle) each pixel's centre ray hits.
pub fn pixel_hits(accel: &Accel, camera: &Camera, w: u32, h: u32) -> Vec<Option<(u32, u32)>> {
    (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| {
            let s = CameraSample {
                p_film: Vec2::new(x as f32 + 0.5, y as f32 + 0.5),
                p_lens: Vec2::ZERO,
                time: 0.0,
            };
            let r = camera.generate_ray(&s)?;
            accel
                .intersect(&Ray::new(r.origin, r.dir))
                .map(|h| (h.instance, h.triangle))
        })
        .collect()
}

/// Node index by name.
pub fn node(names: &[String], name: &str) -> u32 {
    names
        .iter()
        .position(|n| n == name)
        .unwrap_or_else(|| panic!("no node {name}")) as u32
}
