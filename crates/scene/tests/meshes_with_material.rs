//! `Scene::meshes_with_material` (which meshes some instance draws with a wanted material)
//! against its definition, a call of `wanted` for every triangle, on scenes of random ids:
//! the material table it asks once per material settles the same meshes, also with ids past
//! the materials (the default material's, and ones no loader writes).

use aperture_scene::{Instance, Material, Mesh, Scene};
use glam::Affine3A;

/// The definition: per mesh, a triangle's own id wanted, or a set some instance draws it
/// with holding a wanted id.
fn reference(s: &Scene, wanted: &dyn Fn(u32) -> bool) -> Vec<bool> {
    s.meshes
        .iter()
        .enumerate()
        .map(|(k, m)| {
            m.material_ids.iter().any(|&id| wanted(id))
                || s.instances.iter().any(|i| {
                    i.mesh as usize == k
                        && i.materials > 0
                        && s.material_sets[i.materials as usize - 1]
                            .iter()
                            .any(|&id| wanted(id))
                })
        })
        .collect()
}

struct Lcg(u64);

impl Lcg {
    fn below(&mut self, n: u32) -> u32 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((self.0 >> 33) % u64::from(n)) as u32
    }
}

/// Meshes of runs of ids (mostly among 4 materials, some the default 4, a few far past),
/// some empty; instances drawing them with their own ids or one of two sets.
fn scene(r: &mut Lcg) -> Scene {
    let mut s = Scene {
        materials: vec![Material::default(); 4],
        material_sets: vec![vec![r.below(5)], vec![r.below(5), r.below(5)]],
        ..Scene::default()
    };
    for _ in 0..6 {
        let mut ids = Vec::new();
        for _ in 0..r.below(4) {
            let id = match r.below(10) {
                0 => 4,
                1 => 70 + r.below(3),
                2 => u32::MAX,
                _ => r.below(4),
            };
            ids.extend(std::iter::repeat_n(id, 1 + r.below(50) as usize));
        }
        s.meshes.push(
            Mesh {
                material_ids: ids,
                ..Mesh::default()
            }
            .into(),
        );
    }
    for k in 0..8 {
        s.instances.push(Instance {
            mesh: r.below(6),
            world_from_object: Affine3A::IDENTITY,
            node: k,
            materials: r.below(3),
        });
    }
    s
}

#[test]
fn the_meshes_found_are_the_definitions() {
    let mut r = Lcg(7);
    let (mut some, mut none) = (0, 0);
    for _ in 0..400 {
        let s = scene(&mut r);
        // Which ids are wanted: a random subset of the materials and the default, and
        // sometimes every id past them.
        let subset = r.below(32);
        let past = r.below(2) == 1;
        let wanted = move |id: u32| match id {
            0..=4 => subset & (1 << id) != 0,
            _ => past,
        };
        let got = s.meshes_with_material(wanted);
        assert_eq!(
            got,
            reference(&s, &wanted),
            "subset {subset:05b}, past {past}"
        );
        some += got.iter().filter(|&&w| w).count();
        none += got.iter().filter(|&&w| !w).count();
    }
    assert!(some > 100 && none > 100, "{some} meshes found, {none} not");
}
