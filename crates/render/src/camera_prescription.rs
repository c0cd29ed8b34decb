//! The camera of a lens prescription (issue 61, `lens_prescription`): [`Camera`]'s methods
//! that route to [`RealisticLens`], kept apart from the thin lens's code.

use crate::camera::{Aperture, Camera, CameraModel, CameraRay, CameraSample};
use crate::realistic::{PupilSampling, RealisticLens};

impl Camera {
    /// This camera with the scene camera's prescription, if it has one: the realistic lens,
    /// and as `model` and `aperture` the thin lens of the same field of view (the film's half
    /// size over the image distance) and entrance pupil.
    pub(crate) fn with_prescription(
        mut self,
        cam: &aperture_scene::Camera,
        width: u32,
        height: u32,
    ) -> Self {
        let Some(p) = &cam.dof.prescription else {
            return self;
        };
        let lens = crate::realistic::intern::interned(p, &cam.dof, width, height);
        if let Ok(r) = lens {
            let film = crate::realistic::film_size(&cam.dof, width, height);
            let (fig, half) = (&r.figures, 0.5 * film);
            if fig.image_distance > 0.0 {
                self.model = CameraModel::ThinLens {
                    tan_half_x: (half.x / fig.image_distance) as f32,
                    tan_half_y: (half.y / fig.image_distance) as f32,
                };
            }
            self.aperture = Aperture::Disc {
                radius: fig.entrance_pupil_radius as f32,
                ratio: 1.0,
            };
        }
        self.realistic = Some(lens);
        self
    }

    /// The prescription's lens, when it has one that images.
    pub fn realistic_lens(&self) -> Option<&RealisticLens> {
        self.realistic.and_then(|r| r.as_ref().ok())
    }

    /// Why the camera's prescription cannot image, if it cannot.
    pub fn lens_error(&self) -> Option<&str> {
        self.realistic
            .and_then(|r| r.as_ref().err())
            .map(String::as_str)
    }

    /// The primary ray for one sample in world space and its weight: 1 through the thin lens,
    /// the film's irradiance estimate through a prescription (`None`: the lens blocks it, a
    /// black sample).
    #[inline(always)]
    pub fn generate_ray_weighted(&self, s: &CameraSample) -> Option<(CameraRay, f32)> {
        self.generate_ray_sampled(s, PupilSampling::ExitPupil)
    }

    /// [`Camera::generate_ray_weighted`] with the lens point drawn `how` (a thin lens ignores it).
    pub fn generate_ray_sampled(
        &self,
        s: &CameraSample,
        how: PupilSampling,
    ) -> Option<(CameraRay, f32)> {
        let Some(realistic) = self.realistic else {
            return self.generate_ray(s).map(|r| (r, 1.0));
        };
        let (o, d, w) = realistic.as_ref().ok()?.ray(s.p_film, s.p_lens, how)?;
        let dir = self.world_from_camera.transform_vector3(d).normalize();
        dir.is_finite().then(|| {
            let origin = self.world_from_camera.transform_point3(o);
            (CameraRay { origin, dir }, w)
        })
    }
}
