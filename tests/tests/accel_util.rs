//! Shared scene and ray generators for the `accel_*` tests (included with `#[path]`; as its own
//! test target it holds no tests).
#![allow(dead_code)]

use aperture_accel::{Accel, BvhQuality, FrameHints, InstanceInput, MeshInput, Ray};
use glam::{Affine3A, Quat, Vec3};

/// A small deterministic generator (SplitMix64), so failures reproduce.
pub struct Rng(pub u64);

impl Rng {
    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    pub fn f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }
    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.f32()
    }
    /// Uniform in the box [lo, hi).
    pub fn vec_in(&mut self, lo: Vec3, hi: Vec3) -> Vec3 {
        Vec3::new(
            self.range(lo.x, hi.x),
            self.range(lo.y, hi.y),
            self.range(lo.z, hi.z),
        )
    }
    /// Uniform on the unit sphere.
    pub fn unit_vector(&mut self) -> Vec3 {
        loop {
            let v = self.vec_in(Vec3::splat(-1.0), Vec3::splat(1.0));
            let l = v.length_squared();
            if l > 1e-4 && l <= 1.0 {
                return v / l.sqrt();
            }
        }
    }
    /// Uniform in 0..n.
    pub fn index(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }
}

/// A closed unit icosphere: 20 * 4^subdivisions triangles sharing their vertices (indexed).
pub fn icosphere(subdivisions: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let m = aperture_shading::test_scenes::icosphere(subdivisions, 0);
    (m.positions, m.indices)
}

/// Random triangles of size around `size` in the box `[lo, hi]`.
pub fn soup(rng: &mut Rng, n: usize, lo: Vec3, hi: Vec3, size: f32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut pos = Vec::with_capacity(n * 3);
    let mut idx = Vec::with_capacity(n);
    for i in 0..n {
        let c = rng.vec_in(lo, hi);
        for _ in 0..3 {
            pos.push(c + rng.unit_vector() * size * rng.range(0.2, 1.0));
        }
        let b = 3 * i as u32;
        idx.push([b, b + 1, b + 2]);
    }
    (pos, idx)
}

/// A random rigid-plus-scale transform (mirrored when `mirror`).
pub fn random_transform(rng: &mut Rng, lo: Vec3, hi: Vec3, mirror: bool) -> Affine3A {
    let axis = rng.unit_vector();
    let rot = Quat::from_axis_angle(axis, rng.range(0.0, std::f32::consts::TAU));
    let mut scale = Vec3::new(
        rng.range(0.3, 2.0),
        rng.range(0.3, 2.0),
        rng.range(0.3, 2.0),
    );
    if mirror {
        scale.x = -scale.x;
    }
    Affine3A::from_scale_rotation_translation(scale, rot, rng.vec_in(lo, hi))
}

/// Owned meshes, so scenes can be returned from helpers.
pub struct Scene {
    /// Positions and indices per mesh.
    pub meshes: Vec<(Vec<Vec3>, Vec<[u32; 3]>)>,
    /// Placements.
    pub instances: Vec<InstanceInput>,
}

impl Scene {
    /// Builds the structure with shared meshes kept instanced (a top level over object-space
    /// BVHs), whatever the scene's size: the two-level walk these tests are about.
    pub fn build(&self, quality: BvhQuality) -> Accel {
        let keep = FrameHints {
            flatten_shared_up_to: 0,
            ..FrameHints::STILL
        };
        Accel::build_frame(&self.inputs(), &self.instances, quality, keep, None)
    }

    /// Builds the structure as [`Accel::build`] does: a scene this small has every instance
    /// flattened into one world-space BVH.
    pub fn build_flattened(&self, quality: BvhQuality) -> Accel {
        Accel::build(&self.inputs(), &self.instances, quality)
    }

    fn inputs(&self) -> Vec<MeshInput<'_>> {
        self.meshes
            .iter()
            .map(|(p, i)| MeshInput {
                positions: p,
                indices: i,
            })
            .collect()
    }

    /// World-space vertices of a triangle as given (independent of the structure).
    pub fn world_triangle(&self, instance: u32, triangle: u32) -> [Vec3; 3] {
        let inst = &self.instances[instance as usize];
        let (p, idx) = &self.meshes[inst.mesh as usize];
        idx[triangle as usize].map(|i| inst.world_from_object.transform_point3(p[i as usize]))
    }
}

/// Random rays with origins in `[lo, hi]`; some get finite `tmin`/`tmax`.
pub fn random_rays(rng: &mut Rng, n: usize, lo: Vec3, hi: Vec3) -> Vec<Ray> {
    let diag = (hi - lo).length();
    (0..n)
        .map(|i| {
            let mut r = Ray::new(rng.vec_in(lo, hi), rng.unit_vector() * rng.range(0.5, 2.0));
            if i % 4 == 1 {
                r.tmin = rng.range(0.0, 0.3) * diag;
            }
            if i % 4 == 2 {
                r.tmax = rng.range(0.05, 0.5) * diag;
            }
            r
        })
        .collect()
}

/// Places the unit icosphere at `center` with radius `scale`. Flattened: vertices given in world
/// space. Instanced: drawn twice (so it is not flattened), the second copy far out of the way.
pub fn sphere_scene(sub: u32, scale: f32, center: Vec3, instanced: bool) -> Scene {
    let (pos, idx) = icosphere(sub);
    if instanced {
        let rot = Quat::from_axis_angle(Vec3::new(1.0, 2.0, 3.0).normalize(), 0.7);
        let at = |c: Vec3| Affine3A::from_scale_rotation_translation(Vec3::splat(scale), rot, c);
        Scene {
            meshes: vec![(pos, idx)],
            instances: vec![
                InstanceInput {
                    mesh: 0,
                    world_from_object: at(center),
                },
                InstanceInput {
                    mesh: 0,
                    world_from_object: at(center + Vec3::Y * 1e3 * scale),
                },
            ],
        }
    } else {
        let world = pos.iter().map(|p| center + *p * scale).collect();
        Scene {
            meshes: vec![(world, idx)],
            instances: vec![InstanceInput {
                mesh: 0,
                world_from_object: Affine3A::IDENTITY,
            }],
        }
    }
}
