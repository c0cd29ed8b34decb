//! Small scenes built in code, for tests, examples and benchmarks: no file needed.

use aperture_scene::{Camera, Dof, Instance, Light, LightKind, Material, Mesh, Projection, Scene};
use glam::{Affine3A, Vec2, Vec3, Vec4};

/// A camera at `eye` looking at `target` (+Y up) with vertical field of view `yfov`.
pub fn look_at_camera(eye: Vec3, target: Vec3, yfov: f32, dof: Dof) -> Camera {
    Camera {
        name: "test camera".into(),
        node: None,
        index: None,
        world_from_camera: {
            let forward = (target - eye).normalize();
            let right = forward.cross(Vec3::Y).normalize();
            let up = right.cross(forward);
            Affine3A::from_cols(right.into(), up.into(), (-forward).into(), eye.into())
        },
        projection: Projection::Perspective {
            yfov,
            aspect_ratio: None,
        },
        dof,
    }
}

/// A mesh with flat per-face data from positions and triangles, one material.
pub fn mesh(
    positions: Vec<Vec3>,
    indices: Vec<[u32; 3]>,
    normals: Vec<Vec3>,
    material: u32,
) -> Mesh {
    let n = indices.len();
    Mesh {
        name: None,
        positions,
        normals,
        indices,
        material_ids: vec![material; n],
        ..Mesh::default()
    }
}

/// A square of side `size` in the plane y = 0, centred on the origin, facing +Y, with UVs.
pub fn quad(size: f32, material: u32) -> Mesh {
    let h = 0.5 * size;
    let positions = vec![
        Vec3::new(-h, 0.0, -h),
        Vec3::new(-h, 0.0, h),
        Vec3::new(h, 0.0, h),
        Vec3::new(h, 0.0, -h),
    ];
    let mut m = mesh(
        positions,
        vec![[0, 1, 2], [0, 2, 3]],
        vec![Vec3::Y; 4],
        material,
    );
    m.uv0 = vec![
        Vec2::new(0.0, 0.0),
        Vec2::new(0.0, 1.0),
        Vec2::new(1.0, 1.0),
        Vec2::new(1.0, 0.0),
    ];
    m
}

/// A closed box centred on the origin with half extents `half`: six faces of two triangles,
/// outward flat normals, counter-clockwise seen from outside.
pub fn cuboid(half: Vec3, material: u32) -> Mesh {
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    let mut indices = Vec::new();
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let mut n = Vec3::ZERO;
            n[axis] = sign;
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let base = positions.len() as u32;
            for (su, sv) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                let mut p = Vec3::ZERO;
                p[axis] = sign * half[axis];
                p[u] = su * sign * half[u];
                p[v] = sv * half[v];
                positions.push(p);
                normals.push(n);
            }
            indices.extend([[base, base + 1, base + 2], [base, base + 2, base + 3]]);
        }
    }
    mesh(positions, indices, normals, material)
}

/// A unit icosphere: an icosahedron subdivided `levels` times (20·4^levels triangles), with
/// smooth normals.
pub fn icosphere(levels: u32, material: u32) -> Mesh {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let mut p: Vec<Vec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| Vec3::new(x, y, z).normalize())
    .collect();
    let mut tris: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..levels {
        let mut mid = std::collections::HashMap::new();
        let mut midpoint = |a: u32, b: u32, p: &mut Vec<Vec3>| -> u32 {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                p.push(((p[a as usize] + p[b as usize]) * 0.5).normalize());
                p.len() as u32 - 1
            })
        };
        let mut next = Vec::with_capacity(tris.len() * 4);
        for [a, b, c] in tris {
            let ab = midpoint(a, b, &mut p);
            let bc = midpoint(b, c, &mut p);
            let ca = midpoint(c, a, &mut p);
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        tris = next;
    }
    let normals = p.clone();
    mesh(p, tris, normals, material)
}

/// A diffuse-looking glTF material: base colour, metallic 0, roughness 1.
pub fn matte(color: Vec3) -> Material {
    Material {
        base_color_factor: color.extend(1.0),
        metallic_factor: 0.0,
        roughness_factor: 1.0,
        ..Material::default()
    }
}

/// A material that only emits `radiance` (black base).
pub fn emitter(radiance: Vec3) -> Material {
    Material {
        base_color_factor: Vec4::new(0.0, 0.0, 0.0, 1.0),
        metallic_factor: 0.0,
        emissive_factor: radiance,
        ..Material::default()
    }
}

/// One instance per mesh, identity transforms unless given.
pub fn scene(meshes: Vec<(Mesh, Affine3A)>, materials: Vec<Material>, camera: Camera) -> Scene {
    let mut s = Scene {
        materials,
        cameras: vec![camera],
        ..Scene::default()
    };
    for (i, (m, xf)) in meshes.into_iter().enumerate() {
        s.meshes.push(m.into());
        s.instances.push(Instance {
            mesh: i as u32,
            world_from_object: xf,
            node: i as u32,
            materials: 0,
        });
    }
    s
}

/// A white furnace: a unit icosphere (1280 triangles) in front of a pinhole camera. Render it
/// with a uniform environment and the diffuse override.
pub fn furnace() -> Scene {
    let cam = look_at_camera(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, 0.8, Dof::default());
    scene(
        vec![(icosphere(3, 0), Affine3A::IDENTITY)],
        vec![matte(Vec3::ONE)],
        cam,
    )
}

/// Height of the point light above the plane in [`lit_plane`].
pub const LIT_PLANE_LIGHT_HEIGHT: f32 = 2.0;

/// A 40 × 40 white-ish matte plane at y = 0 under a point light of `intensity` W/sr at
/// (0, [`LIT_PLANE_LIGHT_HEIGHT`], 0), seen from above at an angle by a pinhole camera.
pub fn lit_plane(intensity: f32) -> Scene {
    let cam = look_at_camera(
        Vec3::new(0.0, 6.0, 6.0),
        Vec3::new(0.0, 0.0, 1.0),
        0.9,
        Dof::default(),
    );
    let mut s = scene(
        vec![(quad(40.0, 0), Affine3A::IDENTITY)],
        vec![matte(Vec3::splat(0.8))],
        cam,
    );
    s.lights.push(Light {
        name: Some("point".into()),
        kind: LightKind::Point,
        position: Vec3::new(0.0, LIT_PLANE_LIGHT_HEIGHT, 0.0),
        direction: Vec3::NEG_Y,
        intensity: Vec3::splat(intensity),
    });
    s
}

/// A small emissive square of side `size` facing the camera at depth `z` on the optical axis
/// of a camera at the origin looking down −Z (yfov `yfov`), with the given depth of field.
pub fn bokeh(size: f32, z: f32, yfov: f32, dof: Dof, radiance: f32) -> Scene {
    let cam = Camera {
        name: "bokeh".into(),
        node: None,
        index: None,
        world_from_camera: Affine3A::IDENTITY,
        projection: Projection::Perspective {
            yfov,
            aspect_ratio: Some(1.0),
        },
        dof,
    };
    // The quad lies in y = 0 facing +Y; turn it to face +Z and move it to depth z.
    let xf = Affine3A::from_translation(Vec3::new(0.0, 0.0, -z))
        * Affine3A::from_rotation_x(std::f32::consts::FRAC_PI_2);
    scene(
        vec![(quad(size, 0), xf)],
        vec![emitter(Vec3::splat(radiance))],
        cam,
    )
}

/// A matte ground, a glossy dielectric ball, a rough gold ball, a mirror ball, an emitter and a
/// point light, seen through a lens; nothing named (see [`passes`] for the named scene).
pub fn balls() -> Scene {
    let dof = Dof {
        enabled: true,
        aperture_radius: 0.05,
        focus_distance: 6.0,
        ..Dof::default()
    };
    let camera = look_at_camera(Vec3::new(0.0, 1.5, 6.0), Vec3::new(0.0, 0.8, 0.0), 0.7, dof);
    let glossy = Material {
        base_color_factor: glam::Vec4::new(0.2, 0.4, 0.8, 1.0),
        metallic_factor: 0.0,
        roughness_factor: 0.3,
        ..Material::default()
    };
    let gold = Material {
        base_color_factor: glam::Vec4::new(1.0, 0.8, 0.3, 1.0),
        metallic_factor: 1.0,
        roughness_factor: 0.5,
        ..Material::default()
    };
    let mirror = Material {
        metallic_factor: 1.0,
        roughness_factor: 0.05,
        ..Material::default()
    };
    let ground = matte(Vec3::new(0.7, 0.6, 0.5));
    let lamp = emitter(Vec3::new(6.0, 5.0, 4.0));
    let ball = |m: u32, x: f32, r: f32| {
        (
            icosphere(3, m),
            Affine3A::from_scale_rotation_translation(
                Vec3::splat(r),
                glam::Quat::IDENTITY,
                Vec3::new(x, r, 0.0),
            ),
        )
    };
    let mut s = scene(
        vec![
            (quad(8.0, 0), Affine3A::IDENTITY),
            ball(1, -1.3, 0.6),
            ball(2, 0.0, 0.7),
            ball(3, 1.3, 0.5),
            ball(4, 0.4, 0.15),
        ],
        vec![ground, glossy, gold, mirror, lamp],
        camera,
    );
    s.instances[4].world_from_object = Affine3A::from_scale_rotation_translation(
        Vec3::splat(0.15),
        glam::Quat::IDENTITY,
        Vec3::new(0.5, 1.9, 0.8),
    );
    s.lights.push(Light {
        name: None,
        kind: LightKind::Point,
        position: Vec3::new(2.0, 4.0, 3.0),
        direction: Vec3::NEG_Y,
        intensity: Vec3::splat(20.0),
    });
    s
}

/// A matte ground, a glossy dielectric ball, a rough gold ball, a mirror ball, an emitter and a
/// point light, seen through a lens (render it under a grey sky): every kind of pass, and
/// silhouettes against the background for Cryptomatte. Its nodes are named (Ground, Blue, Gold,
/// Mirror, Lamp), and so are its materials (Ground, Glossy, Gold, Mirror, Lamp). The camera sees sky
/// above the horizon, so silhouettes against the background exist.
pub fn passes() -> Scene {
    let mut s = balls();
    let names = ["Ground", "Glossy", "Gold", "Mirror", "Lamp"];
    for (material, name) in s.materials.iter_mut().zip(names) {
        material.name = Some(name.into());
    }
    s.node_names = ["Ground", "Blue", "Gold", "Mirror", "Lamp"]
        .map(|n| Some(n.to_string()))
        .into();
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cuboid_is_closed_and_faces_out() {
        let m = cuboid(Vec3::new(1.0, 2.0, 3.0), 0);
        assert!(m.is_closed());
        for t in &m.indices {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            let n = (b - a).cross(c - a);
            assert!(n.dot(a) > 0.0, "inward face {t:?}");
        }
    }
}
