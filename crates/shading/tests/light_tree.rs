//! The light tree's picks: probabilities that sum to one, a sampled pick's probability equal
//! to the one evaluated for its light (as MIS evaluates it for a met emitter), unbiased
//! estimates against the exhaustive sum, and a tree that does not depend on the input order.

use aperture_scene::{Instance, Light, LightKind};
use aperture_shading::light_bounds::LightBounds;
use aperture_shading::light_choice::{punctual_importance, Pick};
use aperture_shading::light_tree::{Leaf, LightTree, TreeMemo};
use aperture_shading::lights::EmissiveLights;
use aperture_shading::{test_scenes, Geometry, MaterialOverride, TransmissionModel};
use glam::{Affine3A, Vec3};

/// A small deterministic generator (64-bit LCG, top bits).
struct Rng(u64);

impl Rng {
    fn f(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
    fn v(&mut self, scale: f32) -> Vec3 {
        Vec3::new(self.f() - 0.5, self.f() - 0.5, self.f() - 0.5) * scale
    }
    fn dir(&mut self) -> Vec3 {
        loop {
            let v = self.v(2.0);
            if let Some(d) = v.try_normalize() {
                return d;
            }
        }
    }
}

/// Random lights: points, spots and two directional ones.
fn lights(rng: &mut Rng, n: usize) -> Vec<Light> {
    (0..n)
        .map(|i| {
            let kind = match i % 5 {
                0 if i < 10 => LightKind::Directional,
                1 | 3 => LightKind::Spot {
                    inner_cone: 0.2 * rng.f(),
                    outer_cone: 0.3 + rng.f(),
                },
                _ => LightKind::Point,
            };
            Light {
                name: None,
                kind,
                position: rng.v(20.0),
                direction: rng.dir(),
                intensity: Vec3::new(rng.f(), rng.f(), rng.f()) * 10.0 + 0.1,
            }
        })
        .collect()
}

/// Random emissive triangles as `(corners, power)`.
fn triangles(rng: &mut Rng, n: usize) -> Vec<([Vec3; 3], f32)> {
    (0..n)
        .map(|_| {
            let c = rng.v(20.0);
            ([c, c + rng.v(1.0), c + rng.v(1.0)], 0.1 + rng.f())
        })
        .collect()
}

fn leaves(lights: &[Light], tris: &[([Vec3; 3], f32)]) -> Vec<(LightBounds, Leaf)> {
    let mut out = Vec::new();
    for (i, l) in lights.iter().enumerate() {
        let phi = aperture_shading::color::luminance(l.intensity);
        if let Some(b) = LightBounds::punctual(l, phi) {
            out.push((b, Leaf::Punctual(i as u32)));
        }
    }
    for (i, &(p, phi)) in tris.iter().enumerate() {
        out.push((
            LightBounds::triangle(p, phi).unwrap(),
            Leaf::Triangle(i as u32),
        ));
    }
    out
}

struct Case {
    lights: Vec<Light>,
    tris: Vec<([Vec3; 3], f32)>,
    tree: LightTree,
}

fn case(seed: u64, n_lights: usize, n_tris: usize) -> Case {
    let mut rng = Rng(seed);
    let lights = lights(&mut rng, n_lights);
    let tris = triangles(&mut rng, n_tris);
    let tree = LightTree::from_leaves(leaves(&lights, &tris), &lights, tris.len()).unwrap();
    Case { lights, tris, tree }
}

/// Sum over every light of its pick probability.
fn total_probability(c: &Case, p: Vec3, n: Vec3, two_sided: bool) -> f32 {
    let punctual: f32 = (0..c.lights.len())
        .map(|i| c.tree.punctual_probability(&c.lights, p, n, two_sided, i))
        .sum();
    let tris: f32 = (0..c.tris.len())
        .map(|i| c.tree.triangle_probability(&c.lights, p, n, two_sided, i))
        .sum();
    punctual + tris
}

/// Where every light can reach the receiver (both sides count, no spot lights) the
/// probabilities over all lights sum to one.
#[test]
fn probabilities_sum_to_one() {
    let mut c = case(1, 300, 700);
    for l in &mut c.lights {
        if matches!(l.kind, LightKind::Spot { .. }) {
            l.kind = LightKind::Point;
        }
    }
    let tree = LightTree::from_leaves(leaves(&c.lights, &c.tris), &c.lights, c.tris.len());
    c.tree = tree.unwrap();
    let mut rng = Rng(7);
    for _ in 0..200 {
        let (p, n) = (rng.v(30.0), rng.dir());
        let sum = total_probability(&c, p, n, true);
        assert!((sum - 1.0).abs() < 1e-4, "sum {sum} at {p} {n}");
    }
}

/// With one-sided receivers and spot lights, a descent may end where neither child can light
/// the point (nothing is picked, correctly: no light there is lost); the probabilities then
/// sum to one less the frequency of such ends.
#[test]
fn probabilities_sum_to_the_descent_frequency() {
    let c = case(6, 300, 700);
    let mut rng = Rng(8);
    let mut short = 0;
    for _ in 0..40 {
        let (p, n) = (rng.v(30.0), rng.dir());
        let sum = total_probability(&c, p, n, false);
        let count = 4000;
        let none = (0..count)
            .filter(|_| c.tree.pick(&c.lights, p, n, false, rng.f()).pick.is_none())
            .count();
        let q = f64::from(1.0 - sum).max(0.0);
        let sigma = (q * (1.0 - q) / count as f64).sqrt();
        let rate = none as f64 / count as f64;
        assert!(sum <= 1.0 + 1e-4, "sum {sum}");
        assert!(
            (rate - q).abs() < 5.0 * sigma + 2e-3,
            "rate {rate}, 1 - sum {q}"
        );
        short += usize::from(sum < 0.999);
    }
    // The test covers such ends at all.
    assert!(short > 0);
}

#[test]
fn sampled_probability_is_the_evaluated_one() {
    let c = case(2, 200, 500);
    let mut rng = Rng(11);
    let (mut punctual, mut tris) = (0, 0);
    for k in 0..2000 {
        let (p, n) = (rng.v(30.0), rng.dir());
        let two_sided = k % 2 == 0;
        let choice = c.tree.pick(&c.lights, p, n, two_sided, rng.f());
        assert!((0.0..1.0).contains(&choice.u));
        let evaluated = match choice.pick {
            Some(Pick::Punctual(i)) => {
                punctual += 1;
                c.tree.punctual_probability(&c.lights, p, n, two_sided, i)
            }
            Some(Pick::Triangle(i)) => {
                tris += 1;
                c.tree.triangle_probability(&c.lights, p, n, two_sided, i)
            }
            Some(Pick::Emitters) => panic!("the tree picks single triangles"),
            None => continue,
        };
        let rel = (choice.probability - evaluated).abs() / evaluated;
        assert!(rel < 1e-6, "{} vs {evaluated}", choice.probability);
    }
    assert!(punctual > 100 && tris > 100, "{punctual} {tris}");
}

/// What a light sends to `p` (normal `n`, one side) in the importance's units: exact for
/// punctual lights, a triangle as a point at its centroid.
fn contribution(c: &Case, pick: Pick, p: Vec3, n: Vec3) -> f32 {
    match pick {
        Pick::Punctual(i) => punctual_importance(&c.lights[i], p, n, false),
        Pick::Triangle(i) => {
            let ([a, b, d], phi) = c.tris[i];
            let centre = (a + b + d) / 3.0;
            let ng = (b - a).cross(d - a).normalize();
            let to = centre - p;
            let d2 = to.length_squared();
            let w = to / d2.sqrt();
            phi * ng.dot(w).abs() * n.dot(w).max(0.0) / d2
        }
        Pick::Emitters => unreachable!(),
    }
}

#[test]
fn estimates_are_unbiased() {
    let c = case(3, 150, 350);
    let mut rng = Rng(5);
    for _ in 0..4 {
        let (p, n) = (rng.v(25.0), rng.dir());
        let exact: f64 = (0..c.lights.len())
            .map(|i| contribution(&c, Pick::Punctual(i), p, n) as f64)
            .chain((0..c.tris.len()).map(|i| contribution(&c, Pick::Triangle(i), p, n) as f64))
            .sum();
        let count = 200_000;
        let (mut sum, mut sum2) = (0.0f64, 0.0f64);
        for _ in 0..count {
            let choice = c.tree.pick(&c.lights, p, n, false, rng.f());
            let x = choice.pick.map_or(0.0, |k| {
                contribution(&c, k, p, n) as f64 / choice.probability as f64
            });
            sum += x;
            sum2 += x * x;
        }
        let mean = sum / count as f64;
        let stderr = ((sum2 / count as f64 - mean * mean) / count as f64).sqrt();
        assert!(
            (mean - exact).abs() < 5.0 * stderr + 1e-4 * exact,
            "mean {mean} exact {exact} stderr {stderr}"
        );
    }
}

#[test]
fn tree_does_not_depend_on_the_input_order() {
    let c = case(4, 120, 300);
    let mut reversed = leaves(&c.lights, &c.tris);
    reversed.reverse();
    let other = LightTree::from_leaves(reversed, &c.lights, c.tris.len()).unwrap();
    assert_eq!(c.tree.leaves(), other.leaves());
    let mut rng = Rng(9);
    for _ in 0..100 {
        let (p, n, u) = (rng.v(30.0), rng.dir(), rng.f());
        let (a, b) = (
            c.tree.pick(&c.lights, p, n, false, u),
            other.pick(&c.lights, p, n, false, u),
        );
        assert_eq!(
            (a.pick, a.probability.to_bits()),
            (b.pick, b.probability.to_bits())
        );
    }
}

/// Large subtrees are built in parallel: the tree is the same on one thread as on three, and
/// its probabilities still sum to one (the parts are joined where they belong).
#[test]
fn tree_does_not_depend_on_the_thread_count() {
    let mut rng = Rng(11);
    let mut lights = lights(&mut rng, 1500);
    for l in &mut lights {
        l.kind = LightKind::Point;
    }
    let tris = triangles(&mut rng, 6000);
    let build = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let all = leaves(&lights, &tris);
        pool.install(|| LightTree::from_leaves(all, &lights, tris.len()).unwrap())
    };
    let (one, three) = (build(1), build(3));
    assert_eq!(one.leaves(), three.leaves());
    let c = Case {
        lights: lights.clone(),
        tris: tris.clone(),
        tree: three,
    };
    for _ in 0..40 {
        let (p, n, u) = (rng.v(30.0), rng.dir(), rng.f());
        let (a, b) = (
            one.pick(&lights, p, n, false, u),
            c.tree.pick(&lights, p, n, false, u),
        );
        assert_eq!(
            (a.pick, a.probability.to_bits()),
            (b.pick, b.probability.to_bits())
        );
        let sum = total_probability(&c, p, n, true);
        assert!((sum - 1.0).abs() < 1e-3, "sum {sum} at {p} {n}");
    }
}

/// One emissive ball instanced many times: a leaf per triangle of each instance, all of the
/// same mesh.
#[test]
fn instanced_emitters_are_leaves_per_instance() {
    let mut scene = test_scenes::lit_plane(1.0);
    scene.materials.push(test_scenes::emitter(Vec3::ONE));
    scene.meshes.push(test_scenes::icosphere(1, 1).into());
    let per_mesh = scene.meshes[1].indices.len();
    for k in 0..50 {
        scene.instances.push(Instance {
            mesh: 1,
            world_from_object: Affine3A::from_translation(Vec3::new(k as f32 * 3.0, 2.0, 0.0)),
            node: 1,
            materials: 0,
        });
    }
    let geom = Geometry::with_transmission(&scene, MaterialOverride::None, TransmissionModel::Gltf);
    let em = EmissiveLights::build(&geom).unwrap();
    assert_eq!(em.triangles.len(), 50 * per_mesh);
    let tree = LightTree::build(&geom, Some(&em)).unwrap();
    let triangles = tree
        .leaves()
        .iter()
        .filter(|l| matches!(l, Leaf::Triangle(_)));
    assert_eq!(triangles.count(), 50 * per_mesh);
    let lights = &scene.lights;
    let (p, n) = (Vec3::new(10.0, 0.0, 1.0), Vec3::Y);
    let sum: f32 = (0..em.triangles.len())
        .map(|i| tree.triangle_probability(lights, p, n, false, i))
        .chain((0..lights.len()).map(|i| tree.punctual_probability(lights, p, n, false, i)))
        .sum();
    assert!((sum - 1.0).abs() < 1e-4, "{sum}");
}

/// The memo hands out the tree it built while the leaves stay the same (a frame's next band,
/// a still sequence's next frame), builds again when a light moves, and what it hands out
/// picks as a fresh build does.
#[test]
fn the_memo_rebuilds_only_when_a_light_moves() {
    let mut scene = test_scenes::lit_plane(1.0);
    let n = aperture_shading::light_tree::PUNCTUAL_THRESHOLD;
    scene.lights = lights(&mut Rng(7), n + 2); // two are directional
    let memo = TreeMemo::new();
    let tree_of = |scene: &aperture_scene::Scene| {
        let geom =
            Geometry::with_transmission(scene, MaterialOverride::None, TransmissionModel::Gltf);
        (memo.for_scene(&geom, None), LightTree::build(&geom, None))
    };
    let first = tree_of(&scene).0.unwrap();
    let again = tree_of(&scene).0.unwrap();
    assert!(std::sync::Arc::ptr_eq(&first, &again));
    assert_eq!(memo.builds(), 1);
    scene.lights[3].position += Vec3::new(0.0, 0.5, 0.0);
    let (moved, fresh) = tree_of(&scene);
    let (moved, fresh) = (moved.unwrap(), fresh.unwrap());
    assert!(!std::sync::Arc::ptr_eq(&first, &moved));
    assert_eq!(memo.builds(), 2);
    let (p, normal) = (Vec3::new(1.0, 0.0, 2.0), Vec3::Y);
    for u in [0.01, 0.3, 0.77] {
        let (a, b) = (
            moved.pick(&scene.lights, p, normal, false, u),
            fresh.pick(&scene.lights, p, normal, false, u),
        );
        assert_eq!(format!("{a:?}"), format!("{b:?}"));
    }
    // Fewer lights than the tree's threshold: no tree, no build.
    scene.lights.truncate(n);
    assert!(tree_of(&scene).0.is_none());
    assert_eq!(memo.builds(), 2);
}

/// The tree serves a scene from its count of point and spot lights (directional ones do not
/// count); emissive triangles alone, however many, keep the exhaustive choice.
#[test]
fn the_tree_is_wanted_from_the_punctual_threshold() {
    use aperture_shading::light_tree::PUNCTUAL_THRESHOLD;
    let point = |k: usize| Light {
        name: None,
        kind: LightKind::Point,
        position: Vec3::new(k as f32, 1.0, 0.0),
        direction: Vec3::NEG_Y,
        intensity: Vec3::ONE,
    };
    let sun = Light {
        kind: LightKind::Directional,
        ..point(0)
    };
    let with = |n: usize| -> Vec<Light> { (0..n).map(point).chain([sun.clone()]).collect() };
    assert!(!LightTree::wanted(&with(PUNCTUAL_THRESHOLD - 1)));
    assert!(LightTree::wanted(&with(PUNCTUAL_THRESHOLD)));
    assert!(!LightTree::wanted(&vec![sun.clone(); PUNCTUAL_THRESHOLD]));
    // One emissive ball of 1,280 triangles and one point light: no tree.
    let mut scene = test_scenes::lit_plane(1.0);
    scene.materials.push(test_scenes::emitter(Vec3::ONE));
    scene.meshes.push(test_scenes::icosphere(3, 1).into());
    scene.instances.push(Instance {
        mesh: 1,
        world_from_object: Affine3A::from_translation(Vec3::new(0.0, 2.0, 0.0)),
        node: 1,
        materials: 0,
    });
    let geom = Geometry::with_transmission(&scene, MaterialOverride::None, TransmissionModel::Gltf);
    let em = EmissiveLights::build(&geom).unwrap();
    assert_eq!(em.triangles.len(), 1280);
    assert!(LightTree::for_scene(&geom, Some(&em)).is_none());
}

/// A single-sided emitter whose back glTF's culling hides lights only its front: from inside
/// a ball of outward faces the tree picks none of its triangles; with both sides shown (or
/// from outside) it does.
#[test]
fn culled_emitters_light_only_their_front() {
    use aperture_shading::SidesModel;
    let mut scene = test_scenes::lit_plane(1.0);
    scene.materials.push(aperture_scene::Material {
        double_sided: false,
        ..test_scenes::emitter(Vec3::ONE)
    });
    let material = scene.materials.len() as u32 - 1;
    scene
        .meshes
        .push(test_scenes::icosphere(1, material).into());
    let centre = Vec3::new(0.0, 3.0, 0.0);
    scene.instances.push(Instance {
        mesh: 1,
        world_from_object: Affine3A::from_translation(centre),
        node: 1,
        materials: 0,
    });
    for (model, inside) in [(SidesModel::Gltf, false), (SidesModel::Both, true)] {
        let geom =
            Geometry::with_transmission(&scene, MaterialOverride::None, TransmissionModel::Gltf)
                .with_sides(model);
        let em = EmissiveLights::build(&geom).unwrap();
        let tree = LightTree::build(&geom, Some(&em)).unwrap();
        let total = |p: Vec3, n: Vec3| -> f32 {
            (0..em.triangles.len())
                .map(|i| tree.triangle_probability(&scene.lights, p, n, true, i))
                .sum()
        };
        assert_eq!(total(centre, Vec3::Y) > 0.0, inside, "{model:?}");
        assert!(
            total(centre + Vec3::new(0.0, 4.0, 0.0), Vec3::NEG_Y) > 0.0,
            "{model:?}"
        );
    }
}
