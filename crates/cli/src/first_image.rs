//! Warnings about a scene whose image would tell the user nothing (SPEC §4): black for want
//! of light, or empty for want of geometry. The render still runs; the warning says why the
//! image looks as it will and what to add.

use aperture_scene::Scene;
use aperture_shading::Environment;

/// The warnings for rendering `scene` under `env` (one line each, no `warning:` prefix).
pub(crate) fn scene_warnings(scene: &Scene, env: &Environment) -> Vec<String> {
    let mut out = Vec::new();
    let drawn = scene.instances.iter().any(|i| {
        scene
            .meshes
            .get(i.mesh as usize)
            .is_some_and(|m| !m.indices.is_empty())
    });
    let env_black = matches!(env, Environment::Constant(c) if c.max_element() <= 0.0);
    if !drawn {
        let shows = if env_black {
            "the image will be empty (black)"
        } else {
            "the image will show only the environment"
        };
        out.push(format!(
            "the scene has no drawable geometry (no node draws a mesh with triangles): {shows}"
        ));
    }
    let emissive = scene.instances.iter().any(|i| {
        scene.instance_materials(i).iter().any(|&id| {
            scene
                .materials
                .get(id as usize)
                .is_some_and(|mat| mat.is_emissive())
        })
    });
    if drawn && scene.lights.is_empty() && !emissive && env_black {
        out.push(
            "the scene has no light, no emissive surface and no environment: the image will be \
             black; light it with an environment, e.g. --env 1,1,1 (a uniform white sky) or \
             --env sky.hdr (an equirectangular HDR/EXR image)"
                .into(),
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use aperture_shading::test_scenes;
    use glam::Vec3;

    #[test]
    fn an_unlit_scene_warns_and_names_env() {
        let mut scene = test_scenes::lit_plane(1.0);
        scene.lights.clear();
        for m in &mut scene.materials {
            m.emissive_factor = Vec3::ZERO;
        }
        let w = scene_warnings(&scene, &Environment::default());
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(w[0].contains("black") && w[0].contains("--env"), "{w:?}");
        // An environment lights it.
        let sky = Environment::Constant(Vec3::ONE);
        assert!(scene_warnings(&scene, &sky).is_empty());
    }

    #[test]
    fn a_lit_scene_does_not_warn() {
        let scene = test_scenes::lit_plane(1.0);
        assert!(scene_warnings(&scene, &Environment::default()).is_empty());
    }

    #[test]
    fn a_scene_without_geometry_warns() {
        let mut scene = test_scenes::lit_plane(1.0);
        scene.instances.clear();
        let w = scene_warnings(&scene, &Environment::default());
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(w[0].contains("no drawable geometry"), "{w:?}");
    }
}
