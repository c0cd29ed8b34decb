//! The size of an image: a side the user leaves out follows the camera's aspect ratio.

use aperture_scene::Projection;

/// The image height for `width` pixels that keeps the camera's aspect ratio (the file's
/// `aspectRatio`, or `xmag / ymag`; 16:9 when the file gives none).
pub fn default_height(cam: &aperture_scene::Camera, width: u32) -> u32 {
    let aspect = match cam.projection {
        Projection::Perspective {
            aspect_ratio: Some(a),
            ..
        } if a.is_finite() && a > 0.0 => a,
        Projection::Orthographic { xmag, ymag } if xmag != 0.0 && ymag != 0.0 => {
            (xmag / ymag).abs()
        }
        _ => 16.0 / 9.0,
    };
    ((width as f32 / aspect).round() as u32).max(1)
}

/// The image size for `width` and `height` as asked: a missing side (or both, from a width of
/// 960) follows the camera's aspect ([`default_height`]), as `aperture render` and Python's
/// `scene.render` take them.
pub fn image_size(
    cam: &aperture_scene::Camera,
    width: Option<u32>,
    height: Option<u32>,
) -> (u32, u32) {
    match (width, height) {
        (Some(w), Some(h)) => (w, h),
        (Some(w), None) => (w, default_height(cam, w)),
        (None, Some(h)) => {
            // The camera's aspect from the default 960-wide frame.
            let aspect = 960.0 / default_height(cam, 960) as f32;
            (((h as f32 * aspect).round() as u32).max(1), h)
        }
        (None, None) => (960, default_height(cam, 960)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_height_follows_the_aspect() {
        let sc = aperture_scene::Camera {
            name: "c".into(),
            node: None,
            index: None,
            world_from_camera: glam::Affine3A::IDENTITY,
            projection: Projection::Perspective {
                yfov: 0.5,
                aspect_ratio: Some(2.0),
            },
            dof: aperture_scene::Dof::default(),
        };
        assert_eq!(default_height(&sc, 960), 480);
        assert_eq!(image_size(&sc, None, None), (960, 480));
        assert_eq!(image_size(&sc, None, Some(100)), (200, 100));
        assert_eq!(image_size(&sc, Some(64), None), (64, 32));
        assert_eq!(image_size(&sc, Some(7), Some(9)), (7, 9));
    }
}
