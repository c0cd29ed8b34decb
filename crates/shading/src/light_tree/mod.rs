//! A light BVH for scenes with many lights (pbrt-v4's `BVHLightSampler`, Cycles' light tree:
//! Conty Estevez & Kulla 2018): its leaves are the point and spot lights and the emissive
//! triangles (one leaf per triangle of each instance: instanced lamps share their mesh), its
//! inner nodes hold the [`LightBounds`] of their subtree.
//!
//! A vertex descends from the root, choosing a child in proportion to its importance there;
//! the pick's probability is the product of these choices, exact, and evaluated again for a
//! light met by a BSDF-sampled ray from the leaf's ancestors
//! ([`LightTree::triangle_probability`]), so MIS sees the same probability. The tree is built
//! binary (pbrt's splits) and read 4-wide: each node weighs four children at once
//! ([`wide`]). Directional lights have no position: they are picked beside the tree
//! ([`pick`]).
//!
//! Below [`PUNCTUAL_THRESHOLD`] point and spot lights the exhaustive choice
//! ([`crate::light_choice`]) is kept: it evaluates every punctual light exactly and takes the
//! emitters as one candidate (a triangle by power), which for fewer lights gives less noise per
//! unit of time than the descent; its images stay as they were. From it on, the tree holds
//! every point and spot light and every emissive triangle, each its own leaf.

mod build;
mod collapse;
pub mod pick;
mod reuse;
mod sample;
mod split;
mod tree;
mod wide;

pub use reuse::TreeMemo;
pub use tree::{Leaf, LightTree, PUNCTUAL_THRESHOLD};
