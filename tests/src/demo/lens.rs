//! The demo camera: its lens and Blender depth-of-field keys, where it stands, and where a point
//! of its image lies in the world.

use super::math::{add, atan, quat_axis_angle, quat_rotate, Quat, V3};

/// Name of the camera node (and of the glTF camera).
pub const CAMERA_NAME: &str = "Camera";
/// The node the camera focuses on (`cameras[0].extras.focus_object`): the middle of the row.
pub const FOCUS_OBJECT: &str = "Row3_Sphere";
/// Focal length written to `extras.lens`, mm.
pub const LENS_MM: f64 = 50.0;
/// f-number written to `extras.aperture_fstop`.
pub const FSTOP: f64 = 1.4;
/// Blade count written to `extras.aperture_blades`.
pub const BLADES: u32 = 6;
/// Sensor width for the `lens`/`yfov` relation (Blender's default, `sensor_fit` AUTO), mm.
pub const SENSOR_WIDTH_MM: f64 = 36.0;
/// Image aspect ratio written to the camera (`aspectRatio`).
pub const ASPECT: f64 = 16.0 / 9.0;

/// Camera position in the world, metres.
pub(super) const CAMERA_POS: [f64; 3] = [0.0, 0.32, 0.0];
/// Camera pitch (rotation about +X), degrees: negative looks down.
const CAMERA_PITCH_DEG: f64 = -7.0;

/// The vertical field of view that matches [`LENS_MM`] on a [`SENSOR_WIDTH_MM`] sensor fitted to
/// the wider side of a [`ASPECT`] image, as Blender computes it (radians).
pub fn yfov() -> f64 {
    2.0 * atan(SENSOR_WIDTH_MM / 2.0 / LENS_MM / ASPECT)
}

/// The camera frame: pitch about +X; looks down its local −Z.
pub(super) struct View {
    /// The camera's rotation.
    pub(super) rot: Quat,
    /// `tan(xfov / 2)`.
    pub(super) tan_x: f64,
    /// `tan(yfov / 2)`.
    tan_y: f64,
}

impl View {
    pub(super) fn new() -> Self {
        let tan_y = SENSOR_WIDTH_MM / 2.0 / LENS_MM / ASPECT; // tan(yfov / 2)
        Self {
            rot: quat_axis_angle([1.0, 0.0, 0.0], CAMERA_PITCH_DEG),
            tan_x: tan_y * ASPECT,
            tan_y,
        }
    }

    /// World point at normalised image position (nx, ny) ∈ [−1, 1]² and depth d along the view
    /// axis.
    pub(super) fn at_image(&self, nx: f64, ny: f64, d: f64) -> V3 {
        let local = [nx * self.tan_x * d, ny * self.tan_y * d, -d];
        add(CAMERA_POS, quat_rotate(self.rot, local))
    }
}
