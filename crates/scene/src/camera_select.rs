//! `--camera NAME|N|node:J`: one camera numbering everywhere. `N` is the glTF camera index
//! (`cameras[N]`, what other tools number cameras by, and the `N` of the generated name
//! `camera N`); `node:J` picks the camera node `J`, for a glTF camera drawn by two nodes.

use crate::error::Error;
use crate::types::{Camera, Scene};

impl Scene {
    /// The index into [`Scene::cameras`] of the camera `wanted` names: its name first, then
    /// `node:J` (the camera carried by node `J`), then `N` (glTF camera `N`; its first node in
    /// drawing order when two nodes carry it).
    pub fn select_camera(&self, wanted: &str) -> Result<usize, Error> {
        let by = |f: &dyn Fn(&Camera) -> bool| self.cameras.iter().position(f);
        let found = by(&|c| c.name == wanted).or_else(|| {
            if let Some(j) = wanted.strip_prefix("node:") {
                let j = j.parse::<u32>().ok()?;
                by(&|c| c.node == Some(j))
            } else {
                let n = wanted.parse::<u32>().ok()?;
                by(&|c| c.index == Some(n))
            }
        });
        found.ok_or_else(|| Error::NoSuchCamera {
            wanted: format!("{wanted:?}"),
            available: self.camera_list(),
        })
    }

    /// How each camera is asked for: `N "name"`, with `node:J` when glTF camera `N` has two
    /// nodes; the automatic camera by its name alone.
    pub fn camera_selector(&self, camera: usize) -> String {
        let Some(c) = self.cameras.get(camera) else {
            return String::new();
        };
        let shared = |n: u32| self.cameras.iter().filter(|o| o.index == Some(n)).count() > 1;
        match (c.index, c.node) {
            (Some(n), Some(j)) if shared(n) => format!("{n} (node:{j})"),
            (Some(n), _) => n.to_string(),
            (None, _) => format!("{:?}", c.name),
        }
    }

    /// Every camera as `--camera` takes it, for messages.
    fn camera_list(&self) -> String {
        (0..self.cameras.len())
            .map(|i| {
                let (sel, name) = (self.camera_selector(i), &self.cameras[i].name);
                if self.cameras[i].index.is_some() {
                    format!("{sel} {name:?}")
                } else {
                    sel
                }
            })
            .collect::<Vec<_>>()
            .join(", ")
    }
}

#[cfg(test)]
mod tests {
    use crate::types::{Camera, Dof, Projection, Scene};

    fn cam(name: &str, node: Option<u32>, index: Option<u32>) -> Camera {
        Camera {
            name: name.into(),
            node,
            index,
            world_from_camera: glam::Affine3A::IDENTITY,
            projection: Projection::Perspective {
                yfov: 1.0,
                aspect_ratio: None,
            },
            dof: Dof::default(),
        }
    }

    /// Cameras listed in drawing order, their glTF indices in another order; camera 1 has two
    /// nodes.
    #[test]
    fn numbers_are_gltf_camera_indices() {
        let scene = Scene {
            cameras: vec![
                cam("camera 1", Some(0), Some(1)),
                cam("camera 0", Some(3), Some(0)),
                cam("camera 1", Some(5), Some(1)),
            ],
            ..Scene::default()
        };
        assert_eq!(scene.select_camera("0").unwrap(), 1);
        assert_eq!(scene.select_camera("1").unwrap(), 0);
        assert_eq!(scene.select_camera("camera 0").unwrap(), 1);
        assert_eq!(scene.select_camera("node:5").unwrap(), 2);
        assert_eq!(scene.select_camera("node:0").unwrap(), 0);
        assert_eq!(scene.camera_selector(2), "1 (node:5)");
        assert_eq!(scene.camera_selector(1), "0");
        let e = scene.select_camera("2").unwrap_err().to_string();
        assert!(
            e.contains(r#"0 "camera 0""#) && e.contains(r#"1 (node:5) "camera 1""#),
            "{e}"
        );
        assert!(scene.select_camera("node:1").is_err());
        assert!(scene.select_camera("node:x").is_err());
    }
}
