//! The environment a render uses (SPEC §4): the one asked for (a colour, or an image's
//! texels), else the file's own image light, else black; turned and scaled as asked. The
//! command line's `--env` and Python's `env=` both come here.

use crate::environment::{EnvImage, EnvSampling, Environment};
use aperture_scene::Scene;
use glam::Vec3;
use std::sync::Arc;

/// An environment the user asks for instead of the file's.
#[derive(Debug, Clone, PartialEq)]
pub enum EnvLight {
    /// Uniform radiance (linear RGB).
    Color(Vec3),
    /// An equirectangular image, rows top (up) to bottom, as read from its file.
    Image {
        /// Width in texels.
        width: u32,
        /// Height in texels.
        height: u32,
        /// Linear RGBA (alpha unused).
        rgba: Vec<[f32; 4]>,
    },
}

/// The environment of a render of `scene`: `asked`, else the file's image light, else black;
/// turned by `rotation_deg` about +Y and scaled by `strength`. Non-finite or negative texels
/// of an asked image become 0: they would poison every sample that sees them.
pub fn choose_environment(
    asked: Option<EnvLight>,
    scene: &Scene,
    rotation_deg: f32,
    strength: f32,
) -> Environment {
    let image = |width, height, texels, strength| {
        Environment::Image(Arc::new(EnvImage {
            width,
            height,
            texels,
            rotation: rotation_deg.to_radians(),
            strength,
            sampling: EnvSampling::Importance,
        }))
    };
    match asked {
        None => match &scene.environment {
            Some(e) => image(e.width, e.height, e.texels.clone(), e.intensity * strength),
            None => Environment::Constant(Vec3::ZERO),
        },
        Some(EnvLight::Color(c)) => Environment::Constant(c * strength),
        Some(EnvLight::Image {
            width,
            height,
            rgba,
        }) => {
            let texel = |p: &[f32; 4]| {
                let t = Vec3::new(p[0], p[1], p[2]);
                if t.is_finite() {
                    t.max(Vec3::ZERO)
                } else {
                    Vec3::ZERO
                }
            };
            image(width, height, rgba.iter().map(texel).collect(), strength)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn asked_light_wins_and_bad_texels_become_black() {
        let scene = Scene::default();
        let black = choose_environment(None, &scene, 0.0, 2.0);
        assert_eq!(black, Environment::Constant(Vec3::ZERO));
        let c = choose_environment(Some(EnvLight::Color(Vec3::ONE)), &scene, 0.0, 2.0);
        assert_eq!(c, Environment::Constant(Vec3::splat(2.0)));
        // Negative components clamp to 0; a texel with a non-finite component is black.
        let rgba = vec![[1.0, -1.0, 0.5, 1.0], [f32::INFINITY, 0.5, 2.0, 0.0]];
        let asked = EnvLight::Image {
            width: 2,
            height: 1,
            rgba,
        };
        let Environment::Image(im) = choose_environment(Some(asked), &scene, 90.0, 3.0) else {
            panic!("an image environment");
        };
        assert_eq!(im.texels, [Vec3::new(1.0, 0.0, 0.5), Vec3::ZERO]);
        assert_eq!((im.strength, im.rotation), (3.0, 90f32.to_radians()));
    }
}
