//! `EXT_lights_image_based` (issue 50): the selected scene's image-based light, its level-0
//! specular cube map decoded and resampled to an equirectangular [`ImageEnvironment`] (the
//! renderer's mapping: centre along +X, u towards +Z, top row straight up), turned by the
//! light's rotation, with its intensity. Only the radiance is read; the irradiance
//! coefficients and the prefiltered mips are what a rasteriser needs, not a path tracer.
//!
//! Faces come in the extension's order (+X, −X, +Y, −Y, +Z, −Z) with the usual cube-map
//! orientation (OpenGL's, first row of each image at the top). A 4-channel image is RGBD as
//! Babylon.js writes it (`rgb = (gamma-2.2 value / 255)^2.2 / (alpha / 255)`); a 3-channel one
//! has alpha 255 and decodes as plain gamma-2.2 colour.

use std::path::Path;

use glam::{Quat, Vec3};
use serde_json::Value;

use crate::accessor::Buffers;
use crate::error::Error;
use crate::types::{ImageEnvironment, Texels};

/// The image-based light of the scene `options` select (the file's default scene, else the
/// first), shared between poses; none when textures are skipped (`info`).
pub(crate) fn scene_environment(
    doc: &gltf::Document,
    root: &Value,
    options: &crate::types::LoadOptions,
    buffers: &Buffers,
    base_dir: &Path,
) -> Result<Option<std::sync::Arc<ImageEnvironment>>, Error> {
    if options.skip_textures {
        return Ok(None);
    }
    let selected = options
        .scene
        .or_else(|| doc.default_scene().map(|s| s.index()))
        .or((doc.scenes().len() > 0).then_some(0));
    let env = read(doc, root, selected, buffers, base_dir, &options.memory)?;
    Ok(env.map(std::sync::Arc::new))
}

/// The image-based light the selected scene (`scene`, a `scenes` index) names, if any.
fn read(
    doc: &gltf::Document,
    root: &Value,
    scene: Option<usize>,
    buffers: &Buffers,
    base_dir: &Path,
    budget: &aperture_budget::MemoryBudget,
) -> Result<Option<ImageEnvironment>, Error> {
    let ext = "EXT_lights_image_based";
    let Some(s) = scene else { return Ok(None) };
    let Some(li) = root["scenes"][s]["extensions"][ext]["light"].as_u64() else {
        return Ok(None);
    };
    let lights = &root["extensions"][ext];
    // The extension's text names the array `lights`; its first example `ibls`.
    let list = if lights["lights"].is_array() {
        "lights"
    } else {
        "ibls"
    };
    let at = format!("extensions.{ext}.{list}[{li}]");
    let light = &lights[list][li as usize];
    if !light.is_object() {
        return Err(Error::Invalid {
            at: format!("scenes[{s}].extensions.{ext}.light"),
            reason: format!("{at} does not exist"),
        });
    }
    let faces: Vec<usize> = light["specularImages"][0]
        .as_array()
        .map(|a| {
            a.iter()
                .filter_map(|v| v.as_u64().map(|i| i as usize))
                .collect()
        })
        .unwrap_or_default();
    if faces.len() != 6 || faces.iter().any(|&i| i >= doc.images().len()) {
        return Err(Error::Invalid {
            at: format!("{at}.specularImages[0]"),
            reason: "six image indices expected (+X, −X, +Y, −Y, +Z, −Z)".into(),
        });
    }
    let decoded = crate::texels::decode_images(doc, buffers, base_dir, &faces, &[1; 6], budget)?;
    let size = decoded[0].0;
    if size == 0 || decoded.iter().any(|d| d.0 != size || d.1 != size) {
        return Err(Error::Invalid {
            at: format!("{at}.specularImages[0]"),
            reason: "the six faces must be square and of one size".into(),
        });
    }
    let faces: Vec<Vec<Vec3>> = decoded.into_iter().map(|(_, _, t)| rgbd(&t)).collect();
    let rotation = quat(&light["rotation"]);
    let intensity = light["intensity"].as_f64().unwrap_or(1.0) as f32;
    if !intensity.is_finite() || intensity < 0.0 {
        return Err(Error::Invalid {
            at: format!("{at}.intensity"),
            reason: format!("{intensity} is not a finite number ≥ 0"),
        });
    }
    Ok(Some(equirect(&faces, size, rotation, intensity)))
}

/// `rotation` as a unit quaternion (identity when absent or unusable).
fn quat(v: &Value) -> Quat {
    let c: Vec<f32> = v
        .as_array()
        .map(|a| {
            a.iter()
                .filter_map(|x| x.as_f64().map(|x| x as f32))
                .collect()
        })
        .unwrap_or_default();
    match c.as_slice() {
        [x, y, z, w] => {
            let q = glam::Vec4::new(*x, *y, *z, *w);
            q.try_normalize().map_or(Quat::IDENTITY, Quat::from_vec4)
        }
        _ => Quat::IDENTITY,
    }
}

/// Linear radiance of RGBD texels.
fn rgbd(t: &Texels) -> Vec<Vec3> {
    let decode = |c: [f32; 4]| {
        let d = c[3].max(1.0 / 255.0);
        Vec3::new(c[0], c[1], c[2]).max(Vec3::ZERO).powf(2.2) / d
    };
    match t {
        Texels::Rgba8(v) => v
            .iter()
            .map(|p| decode(p.map(|c| f32::from(c) / 255.0)))
            .collect(),
        Texels::Rgba32F(v) => v.iter().map(|&p| decode(p)).collect(),
    }
}

/// The face (+X, −X, +Y, −Y, +Z, −Z) and its texel that direction `d` sees.
fn cube_texel(d: Vec3, size: u32) -> (usize, usize) {
    let a = d.abs();
    let (face, sc, tc, ma) = if a.x >= a.y && a.x >= a.z {
        if d.x > 0.0 {
            (0, -d.z, -d.y, a.x)
        } else {
            (1, d.z, -d.y, a.x)
        }
    } else if a.y >= a.z {
        if d.y > 0.0 {
            (2, d.x, d.z, a.y)
        } else {
            (3, d.x, -d.z, a.y)
        }
    } else if d.z > 0.0 {
        (4, d.x, -d.y, a.z)
    } else {
        (5, -d.x, -d.y, a.z)
    };
    let texel = |c: f32| {
        let f = 0.5 * (c / ma.max(f32::MIN_POSITIVE) + 1.0);
        ((f * size as f32) as usize).min(size as usize - 1)
    };
    (face, texel(tc) * size as usize + texel(sc))
}

/// The cube map resampled to a `4·size × 2·size` equirectangular image.
fn equirect(faces: &[Vec<Vec3>], size: u32, rotation: Quat, intensity: f32) -> ImageEnvironment {
    let (w, h) = (4 * size, 2 * size);
    let to_light = rotation.inverse();
    let mut texels = Vec::with_capacity((w * h) as usize);
    for y in 0..h {
        let theta = (y as f32 + 0.5) / h as f32 * std::f32::consts::PI;
        for x in 0..w {
            let phi = ((x as f32 + 0.5) / w as f32 - 0.5) * std::f32::consts::TAU;
            let d = Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            );
            let (face, i) = cube_texel(to_light * d, size);
            texels.push(faces[face][i]);
        }
    }
    ImageEnvironment {
        width: w,
        height: h,
        texels,
        intensity,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_axis_sees_its_face_centre() {
        let axes = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
        for (k, a) in axes.into_iter().enumerate() {
            let (face, i) = cube_texel(a * 3.0, 4);
            assert_eq!(face, k);
            assert_eq!(i, 2 * 4 + 2, "face {k}");
        }
    }
}
