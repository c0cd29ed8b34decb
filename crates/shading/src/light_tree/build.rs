//! Building the light tree: leaves from the scene's lights, then a binary tree of top-down
//! splits where [`super::split`] says (large subtrees in parallel, the result the same for any
//! thread count), collapsed into the 4-wide tree the descent reads ([`super::collapse`]).

use super::split::{self, Item, Split};
use super::tree::{Leaf, LightTree};
use crate::color::luminance;
use crate::light_bounds::LightBounds;
use crate::lights::EmissiveLights;
use crate::surface::Geometry;
use aperture_scene::{Light, LightKind};

/// Subtrees of this many lights or more are built beside their sibling (`rayon::join`, on the
/// caller's pool): the tree is the same as one thread's, node for node.
const PARALLEL_MIN: usize = 2048;

impl LightTree {
    /// The tree of the scene's point and spot lights and of its emissive triangles; `None`
    /// when none of them sends light.
    pub fn build(geom: &Geometry<'_>, emissive: Option<&EmissiveLights>) -> Option<Self> {
        let (leaves, triangles) = Self::leaves_of(geom, emissive);
        Self::from_leaves(leaves, &geom.scene.lights, triangles)
    }

    /// What [`LightTree::build`] builds from: the leaves (the scene's point and spot lights
    /// and its emissive triangles, with their bounds) and the number of emissive triangles.
    /// Linear in the lights; the build that follows is the costly part.
    pub fn leaves_of(
        geom: &Geometry<'_>,
        emissive: Option<&EmissiveLights>,
    ) -> (Vec<(LightBounds, Leaf)>, usize) {
        let lights = &geom.scene.lights;
        let mut leaves = Vec::new();
        for (i, l) in lights.iter().enumerate() {
            if let Some(b) = LightBounds::punctual(l, luminance(l.intensity)) {
                leaves.push((b, Leaf::Punctual(i as u32)));
            }
        }
        let mut triangles = 0;
        if let Some(em) = emissive {
            triangles = em.triangles.len();
            for (i, (t, &phi)) in em.triangles.iter().zip(&em.power).enumerate() {
                let [s0, s1, s2] = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)]
                    .map(|(b1, b2)| geom.emitter_surface(t.instance, t.triangle, b1, b2));
                // A single-sided emitter whose back rays do not see (glTF's culling) lights
                // only the side its normal points to.
                let one_sided = geom.has_back_culled(&s0);
                if let Some(mut b) = LightBounds::triangle([s0.p, s1.p, s2.p], phi) {
                    // The front is where the surface's normal points (mirrored instances
                    // included); a degenerate triangle keeps its whole sphere.
                    if one_sided && b.axis != glam::Vec3::ZERO {
                        b.axis = s0.ng;
                        b.two_sided = false;
                    }
                    leaves.push((b, Leaf::Triangle(i as u32)));
                }
            }
        }
        (leaves, triangles)
    }

    /// The tree over `leaves` (bounds and lights) of a scene with these punctual `lights` and
    /// `triangles` emissive triangles; `None` without leaves.
    pub fn from_leaves(
        leaves: Vec<(LightBounds, Leaf)>,
        lights: &[Light],
        triangles: usize,
    ) -> Option<Self> {
        if leaves.is_empty() {
            return None;
        }
        let directional = (0..lights.len() as u32)
            .filter(|&i| matches!(lights[i as usize].kind, LightKind::Directional))
            .collect();
        let mut items: Vec<Item> = leaves
            .into_iter()
            .map(|(b, l)| (b, l, b.centre()))
            .collect();
        // One order whatever the caller's, so that the tree (whose bucket bounds depend on the
        // order of their unions) is the same.
        items.sort_unstable_by_key(|it| it.1);
        let mut binary = Binary::part();
        binary.nodes.reserve(2 * items.len());
        binary.leaves.reserve(items.len());
        binary.split(&mut items, 0);
        let mut tree = Self::collapse(binary, lights);
        tree.directional = directional;
        tree.punctual_leaf = vec![u32::MAX; lights.len()];
        tree.triangle_leaf = vec![u32::MAX; triangles];
        for (i, leaf) in tree.leaves.iter().enumerate() {
            let slot = match *leaf {
                Leaf::Punctual(l) => tree.punctual_leaf.get_mut(l as usize),
                Leaf::Triangle(t) => tree.triangle_leaf.get_mut(t as usize),
            };
            if let Some(s) = slot {
                *s = i as u32;
            }
        }
        Some(tree)
    }
}

/// One node of the binary tree: an inner node's first child follows it, `second` is its other
/// child; a leaf's `second` is its index in [`Binary::leaves`].
#[derive(Debug, Clone, Copy)]
pub(super) struct Node {
    pub bounds: LightBounds,
    pub second: u32,
    pub leaf: bool,
}

/// The binary tree the build makes first, depth first from its root.
pub(super) struct Binary {
    pub nodes: Vec<Node>,
    /// Every leaf's light.
    pub leaves: Vec<Leaf>,
}

impl Binary {
    /// An empty tree, or one for a subtree built beside its sibling ([`Binary::split`]).
    fn part() -> Self {
        Self {
            nodes: Vec::new(),
            leaves: Vec::new(),
        }
    }

    /// Appends a subtree built apart, its node and leaf indices moved past this tree's, where
    /// the one-thread build would have placed it; returns the index of its root.
    fn append(&mut self, part: Self) -> u32 {
        let root = self.nodes.len() as u32;
        let first_leaf = self.leaves.len() as u32;
        self.nodes.extend(part.nodes.into_iter().map(|mut n| {
            n.second += if n.leaf { first_leaf } else { root };
            n
        }));
        self.leaves.extend(part.leaves);
        root
    }

    /// Appends the subtree of `items` (not empty) at `depth`, depth first (a node's first
    /// child follows it); returns its bound.
    fn split(&mut self, items: &mut [Item], depth: u32) -> LightBounds {
        let at = self.nodes.len();
        if let [(bounds, leaf, _)] = items {
            self.nodes.push(Node {
                bounds: *bounds,
                second: self.leaves.len() as u32,
                leaf: true,
            });
            self.leaves.push(*leaf);
            return *bounds;
        }
        self.nodes.push(Node {
            bounds: items[0].0,
            second: 0,
            leaf: false,
        });
        let Split { axis, count: mid } = split::choose(items, depth);
        // The `mid` items of smallest centre go first (buckets follow the coordinate); ties
        // broken by the light, so that the order never depends on the input's.
        items.select_nth_unstable_by(mid, |a, b| {
            a.2[axis].total_cmp(&b.2[axis]).then(a.1.cmp(&b.1))
        });
        let parallel = items.len() >= PARALLEL_MIN;
        let (left, right) = items.split_at_mut(mid);
        let (a, second, b) = if parallel {
            let (a, (b, sub)) = rayon::join(
                || self.split(left, depth + 1),
                || {
                    let mut sub = Self::part();
                    let b = sub.split(right, depth + 1);
                    (b, sub)
                },
            );
            (a, self.append(sub), b)
        } else {
            let a = self.split(left, depth + 1);
            let second = self.nodes.len() as u32;
            (a, second, self.split(right, depth + 1))
        };
        let bounds = a.union(&b);
        self.nodes[at] = Node {
            bounds,
            second,
            leaf: false,
        };
        bounds
    }
}
