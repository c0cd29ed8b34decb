//! A few boxes around everything a ray can hit: the top of the trees, cut where a caller's
//! budget says. The root's box alone says little about a scene that surrounds the viewer (a
//! ground plane, an interior) or is mostly empty space between objects; its children's boxes,
//! and theirs, say where geometry is.

use crate::node::Node;
use crate::structure::Accel;
use glam::Vec3;

/// What may replace a box of the cut with finer ones.
#[derive(Debug, Clone, Copy)]
enum Finer {
    /// The children of top-level node `n`.
    Top(u32),
    /// The children of node `node` of the world-space (flattened) tree `blas`.
    Bottom { blas: u32, node: u32 },
    /// Nothing: a leaf, or an instance's box (its tree is in object space).
    Nothing,
}

/// A box of the cut: its corners (world space) and what may replace it.
type Piece = ((Vec3, Vec3), Finer);

impl Accel {
    /// Boxes (world space) whose union holds every triangle a ray can hit: the top of the
    /// BVHs, opened from the root, the box of largest surface area first, while the cut holds
    /// at most `budget` boxes (always at least the root's box). The boxes are the trees' own:
    /// exact unions of the triangles' (or, for instanced meshes, the instances') boxes. Empty
    /// when nothing can be hit.
    ///
    /// ```
    /// use aperture_accel::{Accel, BvhQuality, InstanceInput, MeshInput};
    /// use glam::{Affine3A, Vec3};
    /// // A strip of 20 triangles along x, drawn twice, 100 apart.
    /// let positions: Vec<Vec3> = (0..22).map(|i| Vec3::new((i / 2) as f32, (i % 2) as f32, 0.0)).collect();
    /// let indices: Vec<[u32; 3]> = (0..20).map(|i| [i, i + 1, i + 2]).collect();
    /// let mesh = MeshInput { positions: &positions, indices: &indices };
    /// let at = |x: f32| InstanceInput { mesh: 0, world_from_object: Affine3A::from_translation(Vec3::new(x, 0.0, 0.0)) };
    /// let accel = Accel::build(&[mesh], &[at(0.0), at(100.0)], BvhQuality::default());
    /// assert_eq!(accel.cover(1).len(), 1);
    /// // Opened: no box spans the gap.
    /// let cut = accel.cover(16);
    /// assert!(cut.len() > 1 && cut.len() <= 16);
    /// assert!(cut.iter().all(|(lo, hi)| hi.x - lo.x <= 10.0));
    /// ```
    pub fn cover(&self, budget: usize) -> Vec<(Vec3, Vec3)> {
        let mut cut: Vec<Piece> = Vec::new();
        if self.tlas.is_empty() {
            // No top-level tree: at most one entry, whose box is the scene's.
            if let Some(e) = self.entries.first() {
                cut.push((self.tlas_bounds, self.entry_finer(e.blas, e.identity)));
            }
        } else {
            cut.push((self.tlas_bounds, Finer::Top(0)));
        }
        let mut children = Vec::new();
        loop {
            let open = cut
                .iter()
                .enumerate()
                .filter(|(_, p)| !matches!(p.1, Finer::Nothing))
                .max_by(|a, b| area(a.1 .0).total_cmp(&area(b.1 .0)));
            let Some((k, &(_, finer))) = open else {
                break;
            };
            children.clear();
            self.children(finer, &mut children);
            if children.is_empty() {
                // A node with nothing below it (or out of range): its box stays, unopened.
                cut[k].1 = Finer::Nothing;
                continue;
            }
            if cut.len() - 1 + children.len() > budget {
                break;
            }
            cut.swap_remove(k);
            cut.append(&mut children);
        }
        cut.into_iter().map(|p| p.0).collect()
    }

    /// How an entry's tree may be opened: only a world-space one's boxes are world boxes.
    fn entry_finer(&self, blas: u32, identity: bool) -> Finer {
        let has_nodes = self
            .blases
            .get(blas as usize)
            .is_some_and(|b| !b.nodes.is_empty());
        if identity && has_nodes {
            Finer::Bottom { blas, node: 0 }
        } else {
            Finer::Nothing
        }
    }

    /// Appends the pieces that replace a piece opened as `finer`.
    fn children(&self, finer: Finer, out: &mut Vec<Piece>) {
        match finer {
            Finer::Top(n) => {
                let Some(node) = self.tlas.get(n as usize) else {
                    return;
                };
                for (slot, b) in slots(node) {
                    if node.imask & (1 << slot) != 0 {
                        out.push((b, Finer::Top(node.child(slot as u32))));
                        continue;
                    }
                    // A leaf of up to three instances: a world-space tree is opened further;
                    // the others share the leaf's box.
                    let mut shared = false;
                    for p in node.leaf(slot) {
                        match self.entries.get(p as usize) {
                            Some(e) if e.identity => {
                                let tree = self.blases.get(e.blas as usize);
                                let own = tree.and_then(|t| t.bounds).unwrap_or(b);
                                out.push((own, self.entry_finer(e.blas, true)));
                            }
                            _ => shared = true,
                        }
                    }
                    if shared {
                        out.push((b, Finer::Nothing));
                    }
                }
            }
            Finer::Bottom { blas, node: n } => {
                let Some(node) = self
                    .blases
                    .get(blas as usize)
                    .and_then(|t| t.nodes.get(n as usize))
                else {
                    return;
                };
                for (slot, b) in slots(node) {
                    let finer = if node.imask & (1 << slot) != 0 {
                        Finer::Bottom {
                            blas,
                            node: node.child(slot as u32),
                        }
                    } else {
                        Finer::Nothing
                    };
                    out.push((b, finer));
                }
            }
            Finer::Nothing => {}
        }
    }
}

/// The occupied slots of `node` and their boxes.
fn slots(node: &Node) -> impl Iterator<Item = (usize, (Vec3, Vec3))> + '_ {
    (0..8).filter(|&c| node.child_meta[c] != 0).map(|c| {
        let b = &node.bounds;
        let lo = Vec3::new(b[0][c], b[2][c], b[4][c]);
        let hi = Vec3::new(b[1][c], b[3][c], b[5][c]);
        (c, (lo, hi))
    })
}

/// Half the surface area of a box (what the cut opens first); 0 for an empty or flat-to-a-line
/// box, NaN-free.
fn area((lo, hi): (Vec3, Vec3)) -> f32 {
    let d = (hi - lo).max(Vec3::ZERO);
    let a = d.x * d.y + d.y * d.z + d.z * d.x;
    if a.is_finite() {
        a
    } else {
        f32::MAX
    }
}
