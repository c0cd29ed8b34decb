//! The `Vector` pass (SPEC §6): the screen-space motion, in pixels, of the surface seen through
//! a pixel's centre towards the previous and the next frame, in Cycles' order and signs.
//!
//! Cycles (`primitive_motion_vector`) projects the surface's point as it is at the previous
//! frame (`pre`), the frame (`center`) and the next frame (`post`), each through that frame's
//! camera, into its raster space (y up), and writes `(pre − center, center − post)`. Our
//! raster space is y down, so the y components change sign.

use crate::camera::{Camera, CameraModel};
use aperture_accel::Hit;
use aperture_scene::{Animated, Error, Mesh, Scene};
use glam::{Affine3A, Vec2, Vec3, Vec3A};
use std::sync::Arc;

/// The cameras and instance placements of the frames before and after the rendered one.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameNeighbours {
    /// The camera at the previous frame.
    pub camera_prev: Camera,
    /// The camera at the next frame.
    pub camera_next: Camera,
    /// Per instance of the frame's scene: `world_from_object` at the previous and next frames
    /// (`None`: the instance is not in those poses; it counts as still).
    pub instances: Vec<Option<(Affine3A, Affine3A)>>,
    /// Per mesh of the frame's scene whose vertices are elsewhere at the previous or next
    /// frame (skins, morph targets): its vertices there; `None` when still.
    pub meshes: Vec<Option<Arc<DeformedNeighbours>>>,
}

/// A deforming mesh's triangles and its vertex positions (object space) at the previous and
/// the next frame.
#[derive(Debug, Clone, PartialEq)]
pub struct DeformedNeighbours {
    /// The mesh's triangles (the frame's, the same at every time).
    pub indices: Vec<[u32; 3]>,
    /// Positions at the previous frame.
    pub prev: Vec<Vec3>,
    /// Positions at the next frame.
    pub next: Vec<Vec3>,
}

/// Where `camera` images world point `p`, in raster coordinates (x right, y down), through the
/// lens's centre ray (distortion included); `None` behind a perspective camera.
pub fn raster_of(camera: &Camera, p: Vec3) -> Option<Vec2> {
    let c = camera.world_from_camera.inverse().transform_point3(p);
    let (sx, sy) = match camera.model {
        CameraModel::ThinLens {
            tan_half_x,
            tan_half_y,
        } => {
            if c.z >= 0.0 {
                return None;
            }
            if camera.lens.distortion.is_some() {
                // Through the lens's centre ray: the direction's screen point, distorted.
                let p = camera.lens.distort(Vec2::new(c.x / -c.z, c.y / -c.z));
                (p.x / tan_half_x, p.y / tan_half_y)
            } else {
                (c.x / (-c.z * tan_half_x), c.y / (-c.z * tan_half_y))
            }
        }
        CameraModel::Orthographic { half_x, half_y } => (c.x / half_x, c.y / half_y),
    };
    let (w, h) = (camera.width as f32, camera.height as f32);
    Some(Vec2::new(0.5 * (sx + 1.0) * w, 0.5 * (1.0 - sy) * h))
}

impl FrameNeighbours {
    /// The pass value of world point `p` seen by `camera` at the frame, the point of `hit` on
    /// an instance of `mesh` (placed by `world_from_object` at the frame), or on nothing (the
    /// background: zero). On a deforming mesh the point is the one of the same barycentric
    /// coordinates on its triangle as the neighbouring frames pose it (Cycles follows the
    /// vertices' motion too).
    pub fn vector(&self, camera: &Camera, hit: Option<(Vec3, Hit, u32, Affine3A)>) -> [f32; 4] {
        let Some((p, hit, mesh, world_from_object)) = hit else {
            return [0.0; 4];
        };
        let placed = self.instances.get(hit.instance as usize).copied().flatten();
        let keys = self.meshes.get(mesh as usize).and_then(Option::as_ref);
        let (p_prev, p_next) = match (placed, keys) {
            (None, None) => (p, p),
            (placed, keys) => {
                let o = world_from_object.inverse().transform_point3(p);
                let (o_prev, o_next) = match keys {
                    Some(k) => (
                        on_triangle(&k.indices, &k.prev, &hit, o),
                        on_triangle(&k.indices, &k.next, &hit, o),
                    ),
                    None => (o, o),
                };
                let (prev, next) = placed.unwrap_or((world_from_object, world_from_object));
                (prev.transform_point3(o_prev), next.transform_point3(o_next))
            }
        };
        let project = |cam: &Camera, q: Vec3| raster_of(cam, q);
        match (
            project(camera, p),
            project(&self.camera_prev, p_prev),
            project(&self.camera_next, p_next),
        ) {
            (Some(c), Some(pre), Some(post)) => {
                let (a, b) = (pre - c, c - post);
                [a.x, -a.y, b.x, -b.y]
            }
            _ => [0.0; 4],
        }
    }
}

/// The point of barycentric coordinates `hit.u`, `hit.v` on `hit`'s triangle of `indices`
/// with vertices at `positions`; `fallback` when the triangle is not there.
fn on_triangle(indices: &[[u32; 3]], positions: &[Vec3], hit: &Hit, fallback: Vec3) -> Vec3 {
    let corner = |k: usize| -> Option<Vec3> {
        let i = *indices.get(hit.triangle as usize)?.get(k)?;
        positions.get(i as usize).copied()
    };
    match (corner(0), corner(1), corner(2)) {
        (Some(a), Some(b), Some(c)) => a * (1.0 - hit.u - hit.v) + b * hit.u + c * hit.v,
        _ => fallback,
    }
}

/// The neighbours of the frame at `frame_time` seconds (`fps` frames a second) posed as
/// `frame`, for camera `camera` and a `width × height` image; `None` when the camera is not
/// in a neighbouring pose.
pub fn pose_neighbours(
    animated: &Animated,
    (frame_time, fps): (f64, f64),
    frame: &Scene,
    (camera, width, height): (usize, u32, u32),
) -> Result<Option<FrameNeighbours>, Error> {
    let mut cameras = Vec::with_capacity(2);
    let mut placements: Vec<Vec<Option<Affine3A>>> = Vec::with_capacity(2);
    let mut positions: Vec<Vec<Vec<Vec3>>> = Vec::with_capacity(2);
    // Meshes before this one never deform: only the others' positions are taken.
    let first = animated.static_mesh_count();
    for dt in [-1.0, 1.0] {
        let mut scene = animated.shape_at(Some((frame_time + dt / fps) as f32))?;
        let may_deform = scene.meshes.iter_mut().skip(first);
        positions.push(
            may_deform
                .map(|m| std::mem::take(&mut Arc::make_mut(m).positions))
                .collect(),
        );
        let offset = Vec3A::from((scene.world_origin - frame.world_origin).as_vec3());
        let Some(cam) = scene.cameras.get(camera) else {
            return Ok(None);
        };
        // The automatic camera frames each pose's bounds: it stays the frame's.
        let mut c = match cam.node {
            Some(_) => Camera::new(cam, width, height),
            None => Camera::new(
                &frame.cameras[camera.min(frame.cameras.len() - 1)],
                width,
                height,
            ),
        };
        c.world_from_camera.translation += if cam.node.is_some() {
            offset
        } else {
            Vec3A::ZERO
        };
        cameras.push(c);
        let same = scene.instances.len() == frame.instances.len();
        placements.push(
            frame
                .instances
                .iter()
                .enumerate()
                .map(|(i, f)| {
                    let s = scene
                        .instances
                        .get(i)
                        .filter(|s| same && s.node == f.node)?;
                    let mut m = s.world_from_object;
                    m.translation += offset;
                    Some(m)
                })
                .collect(),
        );
    }
    let instances = (placements[0].iter().zip(&placements[1]))
        .map(|(a, b)| Some(((*a)?, (*b)?)))
        .collect();
    let [prev, next] = <[_; 2]>::try_from(positions).unwrap_or_default();
    Ok(Some(FrameNeighbours {
        camera_prev: cameras[0],
        camera_next: cameras[1],
        instances,
        meshes: deformed(&frame.meshes, first, prev, next),
    }))
}

/// Per mesh of the frame, its positions at the previous and next frames (`prev`, `next`: of
/// the meshes from `first` on) when either differs from the frame's (with as many vertices).
fn deformed(
    meshes: &[Arc<Mesh>],
    first: usize,
    prev: Vec<Vec<Vec3>>,
    next: Vec<Vec<Vec3>>,
) -> Vec<Option<Arc<DeformedNeighbours>>> {
    let (mut prev, mut next) = (prev.into_iter(), next.into_iter());
    let still = meshes.iter().take(first).map(|_| None);
    still
        .chain(meshes.iter().skip(first).map(|m| {
            let (p, n) = (prev.next()?, next.next()?);
            let fits = p.len() == m.positions.len() && n.len() == m.positions.len();
            (fits && (p != m.positions || n != m.positions)).then(|| {
                Arc::new(DeformedNeighbours {
                    indices: m.indices.clone(),
                    prev: p,
                    next: n,
                })
            })
        }))
        .collect()
}
