//! The world-space BVH of many triangles built in pieces: one tree per flattened instance, built
//! in parallel, joined under a tree over their boxes into one node array that traversal walks as
//! any other (issue 59).
//!
//! Why: one PLOC build over every triangle holds, at its peak, the world-space triangles, their
//! boxes, obvhs' binary tree and its CWBVH converter's tables (about 300 bytes a triangle beside
//! the result), and its conversion runs on one thread. Built per instance, those temporaries
//! are a piece's, and two pieces build at once. The joined tree is the same kind of tree: each
//! piece's root becomes an internal child of the node over it, so no level of the walk changes.
//! The price is a top that cannot split an instance: nothing when the instances' boxes barely
//! overlap (tiles, an export of separate objects), a walk of every piece a ray enters when they
//! do, so a set whose [`overlap`] passes [`OVERLAP_LIMIT`] keeps the one build, as do small sets
//! (below [`JOIN_FROM`](crate::JOIN_FROM) triangles), with their exact trees.

use super::bounds::world_bounds;
use super::check::{world_triangles, Kept};
use super::tree::{aabb_of, build_cwbvh, build_ordered, tree_depth, Scratch};
use crate::node::{child_index, Node};
use crate::structure::Blas;
use crate::triangle::Tri;
use crate::types::{BvhQuality, InstanceInput, MeshInput};
use glam::Vec3;
use obvhs::aabb::Aabb;
use rayon::prelude::*;

/// The most [`overlap`] a set may have to be joined. Measured (one build against the joined
/// tree, time a sample, 32 spp): tiles of a terrain (1.37) and a Blender export of 400 objects
/// scattered on a ground plane (2.07, `blender_scatter.py`) are no slower joined (faster: the
/// top tree over whole objects is cleaner than a fast build's); rows of one grid dealt round 4
/// meshes (4.0, `big_scene.py --interleaved`) took 1.7 times as long, and dealt round 64 (59)
/// 4.5 times.
const OVERLAP_LIMIT: f32 = 2.5;

/// How much the instances' world boxes overlap: the sum of their surface areas over the
/// surface area of their union (the number of boxes a random ray through the union enters, on
/// average; 1 for tiles that touch edge to edge).
fn overlap(meshes: &[MeshInput<'_>], flat: &[(u32, InstanceInput)]) -> f32 {
    let area = |b: &Aabb| {
        let e = b.max - b.min;
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    };
    let boxes: Vec<Aabb> = flat
        .par_iter()
        .filter_map(|(_, inst)| {
            let finite = meshes[inst.mesh as usize]
                .positions
                .iter()
                .filter(|p| p.is_finite());
            let (lo, hi) = finite.fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(*p), hi.max(*p))
            });
            (lo.cmple(hi).all()).then(|| world_bounds(&inst.world_from_object, (lo, hi)))
        })
        .collect();
    let all = boxes.iter().fold(Aabb::empty(), |a, b| a.union(b));
    let sum: f32 = boxes.iter().map(area).sum();
    // A union of no area (everything on one point) is no reason to join.
    sum / area(&all).max(f32::MIN_POSITIVE)
}

/// One instance's piece: its tree (nodes over its primitive order) and, per position of that
/// order, the mesh triangle it holds. Its world triangles are not kept: [`piece_triangles`]
/// transforms them again when the pieces are joined (keeping them would hold 40 bytes a
/// triangle for every piece at once, where this holds 4).
struct Piece {
    nodes: Vec<Node>,
    /// Levels of `nodes`.
    depth: usize,
    prims: Vec<u32>,
    bounds: Option<(Vec3, Vec3)>,
    degenerate: usize,
}

/// The piece of flattened instance `inst`: its world triangles checked, its tree built.
fn piece(
    meshes: &[MeshInput<'_>],
    inst: &InstanceInput,
    quality: BvhQuality,
    scratch: &Scratch,
) -> Piece {
    let Kept { tris, degenerate } = world_triangles(&meshes[inst.mesh as usize], inst);
    let aabbs: Vec<Aabb> = tris.iter().map(|t| aabb_of(&t.p)).collect();
    let (nodes, order, bounds) = build_ordered(&aabbs, quality, scratch);
    drop(aabbs);
    let prims = order.iter().map(|&i| tris[i as usize].prim).collect();
    Piece {
        depth: tree_depth(&nodes),
        nodes,
        prims,
        bounds,
        degenerate,
    }
}

/// The world-space BVH of `flat` built per instance and joined, with how many triangles only
/// became degenerate in world space; `None` when the set draws fewer than `join_from`
/// triangles (one build serves it).
pub(super) fn build_joined(
    meshes: &[MeshInput<'_>],
    flat: &[(u32, InstanceInput)],
    quality: BvhQuality,
    join_from: usize,
) -> Option<(Blas, usize)> {
    let drawn: usize = flat
        .iter()
        .map(|(_, i)| meshes[i.mesh as usize].indices.len())
        .sum();
    if flat.len() < 2 || drawn < join_from || overlap(meshes, flat) > OVERLAP_LIMIT {
        return None;
    }
    let scratch = Scratch::default();
    let pieces: Vec<Piece> = flat
        .par_iter()
        .map(|(_, inst)| piece(meshes, inst, quality, &scratch))
        .collect();
    drop(scratch);
    let degenerate = pieces.iter().map(|p| p.degenerate).sum();
    Some((join(meshes, flat, pieces, quality)?, degenerate))
}

/// Joins `pieces` (one per entry of `flat`, in its order) under a tree over their boxes;
/// `None` if the top tree has a leaf of more than one piece (never so with one per leaf).
fn join(
    meshes: &[MeshInput<'_>],
    flat: &[(u32, InstanceInput)],
    pieces: Vec<Piece>,
    quality: BvhQuality,
) -> Option<Blas> {
    // The pieces with triangles, and their boxes.
    let used: Vec<usize> = (0..pieces.len())
        .filter(|&k| pieces[k].bounds.is_some())
        .collect();
    let boxes: Vec<Aabb> = used
        .iter()
        .filter_map(|&k| pieces[k].bounds)
        .map(|(lo, hi)| Aabb::new(lo.into(), hi.into()))
        .collect();
    let (top, top_order) = build_cwbvh(&boxes, quality, 1);
    let top_nodes = top_layout(&top, &top_order, &used)?;
    // Each slot that holds a piece: (its node, the piece), in the order of the nodes; the
    // pieces' nodes and triangles follow in that order too.
    let roots: Vec<(usize, usize)> = top_nodes
        .iter()
        .enumerate()
        .filter(|(_, n)| n.primitive_base_idx == PIECE)
        .map(|(i, n)| (i, n.child_base_idx as usize))
        .collect();
    // A piece under a top node at level i has its node at level j land at level i + j (from
    // 1): at most the top's depth plus the deepest piece's (the walk's stack is sized by it).
    let depth = tree_depth(&top) + used.iter().map(|&k| pieces[k].depth).max().unwrap_or(0);
    let mut pieces: Vec<Option<Piece>> = pieces.into_iter().map(Some).collect();
    let mut placed = Vec::with_capacity(roots.len());
    let (mut base, mut first_tri) = (top_nodes.len(), 0usize);
    for (at, k) in roots {
        let piece = pieces.get_mut(k)?.take()?;
        let (nodes_after, tris_after) = (
            base + piece.nodes.len().saturating_sub(1),
            first_tri + piece.prims.len(),
        );
        placed.push(Placed {
            k,
            at,
            base,
            first_tri,
            piece,
        });
        (base, first_tri) = (nodes_after, tris_after);
    }
    let nodes = piece_nodes(top_nodes, &mut placed, base);
    let (tris, tri_instance) = piece_triangles(meshes, flat, &placed, first_tri);
    let bounds = boxes
        .iter()
        .map(|b| (Vec3::from(b.min), Vec3::from(b.max)))
        .reduce(|a, b| (a.0.min(b.0), a.1.max(b.1)));
    Some(Blas {
        depth,
        nodes,
        tris,
        tri_instance,
        bounds,
        box_bounds: bounds.unwrap_or((Vec3::ZERO, Vec3::ZERO)),
        deform: None,
        pieces: used.len(),
    })
}

/// A piece and where it goes in the joined tree.
struct Placed {
    /// Its entry in the flattened set.
    k: usize,
    /// The node its root replaces (a placeholder of the top).
    at: usize,
    /// Where its nodes 1.. start.
    base: usize,
    /// Where its triangles start.
    first_tri: usize,
    piece: Piece,
}

/// The joined tree's nodes, `total` in all: `top` (the top laid out with placeholders), each
/// placeholder replaced by its piece's root and the pieces' other nodes after it, moved in
/// parallel, a piece at a time (each piece's own nodes freed once copied).
fn piece_nodes(top: Vec<Node>, placed: &mut [Placed], total: usize) -> Vec<Node> {
    // Zeroed: its pages are first touched by the threads that fill them.
    let mut nodes: Vec<Node> = bytemuck::zeroed_vec(total);
    let (head, rest) = nodes.split_at_mut(top.len());
    head.copy_from_slice(&top);
    for p in placed.iter() {
        if let Some(root) = p.piece.nodes.first() {
            head[p.at] = moved(root, p.base, p.first_tri);
        }
    }
    let owned: Vec<Vec<Node>> = placed
        .iter_mut()
        .map(|p| std::mem::take(&mut p.piece.nodes))
        .collect();
    let slots = split_lengths(rest, owned.iter().map(|n| n.len().saturating_sub(1)));
    let places = placed.iter().map(|p| (p.base, p.first_tri));
    let jobs: Vec<_> = places
        .zip(owned)
        .zip(slots)
        .map(|((a, b), c)| (a, b, c))
        .collect();
    jobs.into_par_iter()
        .for_each(|((base, first_tri), own, mine)| {
            for (slot, n) in mine.iter_mut().zip(own.iter().skip(1)) {
                *slot = moved(n, base, first_tri);
            }
        });
    nodes
}

/// The joined tree's triangle store and the instance of each triangle: the pieces' triangles
/// in world space, in the order of `placed`, `total` in all; filled in parallel, a piece at a
/// time.
fn piece_triangles(
    meshes: &[MeshInput<'_>],
    flat: &[(u32, InstanceInput)],
    placed: &[Placed],
    total: usize,
) -> (Vec<Tri>, Vec<u32>) {
    // Zeroed allocations: their pages are first touched by the threads that fill them.
    let mut tris: Vec<Tri> = bytemuck::zeroed_vec(total);
    let mut tri_instance = vec![0u32; total];
    let lengths = || placed.iter().map(|p| p.piece.prims.len());
    let t_slots = split_lengths(&mut tris, lengths());
    let i_slots = split_lengths(&mut tri_instance, lengths());
    let jobs: Vec<_> = placed.iter().zip(t_slots).zip(i_slots).collect();
    jobs.into_par_iter().for_each(|((p, t), i)| {
        let (k, prims) = (p.k, &p.piece.prims);
        let (id, inst) = &flat[k];
        let mesh = &meshes[inst.mesh as usize];
        for (slot, &prim) in t.iter_mut().zip(prims) {
            let v = mesh.indices[prim as usize];
            let p = v.map(|v| {
                inst.world_from_object
                    .transform_point3(mesh.positions[v as usize])
            });
            *slot = Tri { p, prim };
        }
        i.fill(*id);
    });
    (tris, tri_instance)
}

/// `buf` cut into consecutive slices of `lengths` (the rest of it, if any, left out), for
/// pieces to fill in parallel.
fn split_lengths<T>(buf: &mut [T], lengths: impl Iterator<Item = usize>) -> Vec<&mut [T]> {
    let mut rest = buf;
    lengths
        .map(|n| {
            let n = n.min(rest.len());
            let (mine, after) = std::mem::take(&mut rest).split_at_mut(n);
            rest = after;
            mine
        })
        .collect()
}

/// Node `n` of a piece whose nodes 1.. go to `base` on and whose triangles to `first_tri` on.
fn moved(n: &Node, base: usize, first_tri: usize) -> Node {
    let mut n = *n;
    if n.imask != 0 {
        // The piece's node j >= 1 goes to base + j - 1.
        n.child_base_idx = (base as u32).wrapping_add(n.child_base_idx).wrapping_sub(1);
    }
    n.primitive_base_idx = n.primitive_base_idx.wrapping_add(first_tri as u32);
    n
}

/// Marks a placeholder node that a piece's root replaces (its `child_base_idx` names the piece).
const PIECE: u32 = u32::MAX;

/// The top tree laid out again so that each node's children (its internal nodes and the
/// pieces in its leaves, which become internal children) sit together in slot order; the
/// pieces' roots are placeholders ([`PIECE`]). `None` if a leaf holds other than one piece.
fn top_layout(top: &[Node], top_order: &[u32], used: &[usize]) -> Option<Vec<Node>> {
    let first = top.first()?;
    let placeholder = |k: usize| Node {
        child_base_idx: k as u32,
        primitive_base_idx: PIECE,
        ..*first
    };
    let mut out = vec![*first];
    let mut queue = std::collections::VecDeque::from([(0usize, 0usize)]);
    while let Some((t, at)) = queue.pop_front() {
        let mut node = top[t];
        let base = out.len();
        let mut rank = 0;
        for slot in 0..8u32 {
            let meta = node.child_meta[slot as usize];
            if meta == 0 {
                continue;
            }
            if top[t].imask & (1 << slot) != 0 {
                let child = child_index(top[t].child_base_idx, u32::from(top[t].imask), slot);
                queue.push_back((child as usize, base + rank));
                out.push(top[child as usize]);
            } else {
                let leaf = top[t].leaf(slot as usize);
                if leaf.len() != 1 {
                    return None;
                }
                let k = used[*top_order.get(leaf.start as usize)? as usize];
                out.push(placeholder(k));
            }
            // An internal child: the top bits 001 and 24 + its slot (obvhs' encoding).
            node.child_meta[slot as usize] = (1 << 5) | (24 + slot as u8);
            node.imask |= 1 << slot;
            rank += 1;
        }
        node.child_base_idx = base as u32;
        node.primitive_base_idx = 0;
        out[at] = node;
    }
    Some(out)
}
