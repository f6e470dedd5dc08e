//! An 8-wide BVH collapsed from obvhs's binary BVH, with robust closure traversal.
//!
//! The binary tree is obvhs's (PLOC + reinsertion + leaf collapse), with the clustering of
//! the `ploc` submodule, which cannot degrade on coincident boxes; [`Bvh::build`] then
//! collapses it into nodes of up to eight children (each inner node absorbs the children of its
//! largest inner children, as in Wald et al.'s "Getting Rid of Packets", 2008), whose boxes are
//! stored lane by lane so one call of [`RayQuery::enter_boxes`] tests all eight (two SIMD slab
//! tests of four lanes, or one of eight with AVX). The leaves are the binary tree's leaves,
//! unchanged. Traversal is ours, because it must use the
//! robust slab test of [`RayQuery::enter_box`]: obvhs's own box test is not conservative for
//! grazing rays. Leaves hand a contiguous range of primitive slots to a closure; the caller
//! stores its primitives in BVH order (see [`Bvh::build`], which returns the order) so that range
//! indexes them directly.

mod ploc;

use std::ops::Range;

use glam::Vec3;
use obvhs::bvh2::{leaf_collapser, reinsertion::ReinsertionOptimizer};
use obvhs::{BvhBuildParams, aabb::Aabb, bvh2::Bvh2, ploc::PlocSearchDistance};

use super::aabb::RayQuery;
use crate::cpu::{Lanes, Sse};

/// Traversal stack size that needs no heap allocation; deeper trees fall back to a `Vec`.
const INLINE_STACK: usize = 64;
/// Stack size for trees of at most three levels (a few hundred primitives).
const SHORT_STACK: usize = 22;

/// Children per wide node.
const WIDTH: usize = 8;

/// obvhs's medium build, with leaves collapsed for a node visit that costs about as much as
/// one primitive test (obvhs assumes 3×): a wide node tests four or eight boxes per SIMD slab
/// test, while a watertight triangle test is tens of instructions. Fewer primitives per leaf:
/// −5.7 % instructions on the Cornell box, −3.5 % on `bunnies.ron`, −3 % on 2,000 random
/// spheres, +1.2 % on `stress.ron`; leaves then hold ~1.03–1.08 primitives (BENCHMARKS.md).
const BUILD_PARAMS: BvhBuildParams = BvhBuildParams {
    collapse_traversal_cost: 1.0,
    ..BvhBuildParams::medium_build()
};

/// Primitives from which a build takes [`LARGE_BUILD_PARAMS`]: above every hand-made scene and
/// the bunny (3,674 triangles), so those keep the trees of [`BUILD_PARAMS`] exactly.
const LARGE_BUILD: usize = 1 << 17;

/// The build of big meshes: PLOC pairs over a shorter window and a fifth of the reinsertion
/// work. Reinsertion was most of obvhs's time on a 1M-triangle sphere; this build takes about
/// half the time of [`BUILD_PARAMS`] for an SAH cost within 0.5 % (BENCHMARKS.md).
const LARGE_BUILD_PARAMS: BvhBuildParams = BvhBuildParams {
    ploc_search_distance: PlocSearchDistance::VeryLow,
    reinsertion_batch_ratio: 0.01,
    ..BUILD_PARAMS
};

/// A wide node: the boxes of up to eight children lane by lane (`[min_x, min_y, min_z, max_x,
/// max_y, max_z]`, eight lanes each, a row per AVX register), and what each child is. 256 bytes
/// aligned to 64: a visit reads exactly four cache lines, the boxes in three and the rest (read at
/// every visit for the mask) in the fourth.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
struct WideNode {
    bounds: [[f32; WIDTH]; 6],
    /// Per child: a wide node index (`count == 0`) or the first slot of a leaf.
    child: [u32; WIDTH],
    /// Per child: slots in the leaf, 0 for an inner child. A leaf holds at most 255 groups (as
    /// obvhs's leaves do) of at most 255 slots ([`Bvh::build_groups`]), so at most 65,025.
    count: [u16; WIDTH],
    /// Bit `k` set if child `k` exists.
    valid: u8,
}

const _: () = assert!(std::mem::size_of::<WideNode>() == 256);

/// A bounding volume hierarchy over primitives stored in BVH order.
#[derive(Clone, Default)]
pub struct Bvh {
    bvh: Bvh2,
    /// Levels of the wide tree.
    depth: usize,
    /// The 8-wide tree traversal runs over; node 0 is the root.
    wide: Vec<WideNode>,
    /// Nodes the clustering considered over all its rounds (see [`Bvh::build_work`]).
    work: u64,
}

/// The slot count of a leaf of `prim_count` slots in a wide node. At most 255 groups (the leaf
/// collapse's bound) of at most 255 slots (`Bvh::build_groups`'s `u8`): at most 65,025.
fn leaf_slots(prim_count: u32) -> u16 {
    debug_assert!(prim_count <= 255 * 255, "a leaf of {prim_count} slots");
    prim_count as u16
}

/// Binary nodes from which the collapse builds the subtrees under the wide root in parallel.
const PARALLEL_COLLAPSE: usize = LARGE_BUILD;

/// Collapses binary node `n` of `bvh` (an inner node) into wide nodes appended to `wide`;
/// returns the index of the node made for `n` and the depth of its wide subtree.
///
/// With `parallel`, the subtrees of `n`'s inner wide children are collapsed at once, each into
/// its own vector, and appended in child order with their indices moved by where they land:
/// the same nodes at the same indices as one after the other, whatever the thread count.
fn collapse(bvh: &Bvh2, n: usize, wide: &mut Vec<WideNode>, parallel: bool) -> (u32, usize) {
    let nodes = &bvh.nodes;
    let first = nodes[n].first_index as usize;
    // The children so far, in `slots[..len]` (no allocation: this runs once per wide node).
    let mut slots = [0usize; WIDTH];
    slots[..2].copy_from_slice(&[first, first + 1]);
    let mut len = 2;
    // Open the inner child of largest area until eight children (or only leaves) remain.
    while len < WIDTH {
        let Some((k, _)) = slots[..len]
            .iter()
            .enumerate()
            .filter(|&(_, &c)| !nodes[c].is_leaf())
            .max_by(|a, b| {
                nodes[*a.1]
                    .aabb()
                    .half_area()
                    .total_cmp(&nodes[*b.1].aabb().half_area())
            })
        else {
            break;
        };
        // As `Vec::swap_remove` then two pushes.
        let f = nodes[slots[k]].first_index as usize;
        slots[k] = slots[len - 1];
        slots[len - 1] = f;
        slots[len] = f + 1;
        len += 1;
    }
    let children = &mut slots[..len];
    // Children in binary-tree order, so slot order and traversal stay close to the binary tree's.
    children.sort_unstable();
    let index = wide.len();
    wide.push(WideNode {
        bounds: [[0.0; WIDTH]; 6],
        child: [0; WIDTH],
        count: [0; WIDTH],
        valid: 0,
    });
    let mut node = wide[index];
    let mut depth = 1;
    let mut subtrees = if parallel {
        use rayon::prelude::*;
        children
            .par_iter()
            .filter(|&&c| !nodes[c].is_leaf())
            .map(|&c| {
                let mut sub = Vec::new();
                let depth = collapse(bvh, c, &mut sub, false).1;
                (sub, depth)
            })
            .collect()
    } else {
        Vec::new()
    }
    .into_iter();
    for (k, &c) in children.iter().enumerate() {
        let b = nodes[c].aabb();
        for axis in 0..3 {
            node.bounds[axis][k] = b.min[axis];
            node.bounds[3 + axis][k] = b.max[axis];
        }
        node.valid |= 1 << k;
        if nodes[c].is_leaf() {
            node.child[k] = nodes[c].first_index;
            node.count[k] = leaf_slots(nodes[c].prim_count);
        } else if let Some((sub, d)) = subtrees.next() {
            // The subtree's root is its node 0, and its inner children index its own vector.
            let base = wide.len() as u32;
            wide.extend(sub.into_iter().map(|mut w| {
                for j in 0..WIDTH {
                    if w.valid >> j & 1 == 1 && w.count[j] == 0 {
                        w.child[j] += base;
                    }
                }
                w
            }));
            node.child[k] = base;
            depth = depth.max(d + 1);
        } else {
            let (child, d) = collapse(bvh, c, wide, false);
            node.child[k] = child;
            depth = depth.max(d + 1);
        }
    }
    wide[index] = node;
    (index as u32, depth)
}

/// What a traversal does at each leaf it enters: [`Leaf::visit`] gets the leaf's slot range and
/// the current `t_max`, lowers `t_max` when it finds a closer hit, and returns `false` to stop.
/// Closures are leaves; a hot kernel implements it with an always-inlined `visit`, which a
/// closure cannot have, so the leaf test is compiled into the traversal loop (and into each
/// copy of the render loop, see [`crate::cpu`]).
pub trait Leaf {
    /// Tests the primitives in `slots` against the ray.
    fn visit(&mut self, slots: Range<usize>, t_max: &mut f32) -> bool;
}

impl<F: FnMut(Range<usize>, &mut f32) -> bool> Leaf for F {
    #[inline(always)]
    fn visit(&mut self, slots: Range<usize>, t_max: &mut f32) -> bool {
        self(slots, t_max)
    }
}

/// An axis-aligned box as `(min, max)`.
pub type Bounds = (Vec3, Vec3);

/// The box that grows to any other: the start of a union.
pub const EMPTY: Bounds = (Vec3::INFINITY, Vec3::NEG_INFINITY);

/// The box around `a` and `b`.
#[inline]
pub fn union(a: Bounds, b: Bounds) -> Bounds {
    (a.0.min(b.0), a.1.max(b.1))
}

/// The box of the sphere of centre `c` and radius `r`.
#[inline]
pub fn sphere_bounds(c: Vec3, r: f32) -> Bounds {
    (c - Vec3::splat(r), c + Vec3::splat(r))
}

/// The box of the triangle `p`.
#[inline]
pub fn triangle_bounds(p: [Vec3; 3]) -> Bounds {
    (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]))
}

impl Bvh {
    /// The box around everything in the tree (its root's), or `None` for an empty tree.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let b = self.bvh.nodes.first()?.aabb();
        Some((b.min.into(), b.max.into()))
    }

    /// Builds a BVH over primitive boxes. Returns it with `order`: slot `i` of the BVH holds
    /// input primitive `order[i]`, so the caller must permute its primitive arrays by `order`.
    pub fn build(bounds: &[Bounds]) -> (Self, Vec<u32>) {
        Self::build_groups(bounds, |_| 1)
    }

    /// Builds a BVH over groups of primitives that a leaf never splits: group `g` has box
    /// `bounds[g]` and `size(g)` slots. Returns it with the group `order`: the BVH's slots hold
    /// the primitives of group `order[0]`, then those of `order[1]`, and so on, so a leaf's slot
    /// range covers whole groups. A group has at most 255 slots (`u8`), so a leaf of at most 255
    /// groups counts its slots in a `u16`.
    pub fn build_groups(bounds: &[Bounds], size: impl Fn(usize) -> u8) -> (Self, Vec<u32>) {
        if bounds.is_empty() {
            return (Self::default(), Vec::new());
        }
        let aabbs: Vec<Aabb> = bounds
            .iter()
            .map(|&(min, max)| Aabb::new(min.into(), max.into()))
            .collect();
        let params = if aabbs.len() >= LARGE_BUILD {
            LARGE_BUILD_PARAMS
        } else {
            BUILD_PARAMS
        };
        let search = match params.ploc_search_distance {
            PlocSearchDistance::Minimum => 1,
            PlocSearchDistance::VeryLow => 2,
            PlocSearchDistance::Low => 6,
            PlocSearchDistance::Medium => 14,
            PlocSearchDistance::High => 24,
            PlocSearchDistance::VeryHigh => 32,
        };
        // obvhs's `build_bvh2`, with clustering that cannot degrade on coincident boxes.
        let ploc::Clustered { mut bvh, work } =
            ploc::cluster(&aabbs, search, params.search_depth_threshold);
        let mut reinsertion = ReinsertionOptimizer::default();
        reinsertion.run(&mut bvh, params.reinsertion_batch_ratio, None);
        leaf_collapser::collapse(
            &mut bvh,
            params.max_prims_per_leaf.clamp(1, 255),
            params.collapse_traversal_cost,
        );
        reinsertion.run(
            &mut bvh,
            params.reinsertion_batch_ratio
                * params.post_collapse_reinsertion_batch_ratio_multiplier,
            None,
        );
        let order = bvh.primitive_indices.clone();
        // The leaves index groups in BVH order; make them slot ranges.
        let mut first_slot = Vec::with_capacity(order.len() + 1);
        first_slot.push(0u32);
        for &g in &order {
            first_slot.push(first_slot[first_slot.len() - 1] + u32::from(size(g as usize)));
        }
        for node in bvh.nodes.iter_mut().filter(|n| n.is_leaf()) {
            let (first, end) = (
                node.first_index as usize,
                (node.first_index + node.prim_count) as usize,
            );
            node.first_index = first_slot[first];
            node.prim_count = first_slot[end] - first_slot[first];
        }
        let mut wide = Vec::new();
        let depth = if bvh.nodes.first().is_some_and(|root| !root.is_leaf()) {
            collapse(&bvh, 0, &mut wide, bvh.nodes.len() >= PARALLEL_COLLAPSE).1
        } else {
            0
        };
        (
            Self {
                bvh,
                depth,
                wide,
                work,
            },
            order,
        )
    }

    /// Refits every box of the tree to new primitive positions, keeping its shape: `leaf(slots)`
    /// gives the box around the primitives now in a leaf's slots. Linear in the nodes; nothing
    /// is rebuilt, so a primitive that moved far leaves the tree valid but looser than a fresh
    /// build's.
    pub fn refit(&mut self, leaf: impl Fn(Range<usize>) -> Bounds) {
        for node in self.bvh.nodes.iter_mut().filter(|n| n.is_leaf()) {
            let first = node.first_index as usize;
            let (min, max) = leaf(first..first + node.prim_count as usize);
            node.set_aabb(Aabb::new(min.into(), max.into()));
        }
        self.bvh.refit_all();
        // A wide node's inner children come after it (see `collapse`): children first.
        for w in (0..self.wide.len()).rev() {
            let mut node = self.wide[w];
            for k in (0..WIDTH).filter(|k| node.valid >> k & 1 == 1) {
                let child = node.child[k] as usize;
                let (min, max) = if node.count[k] > 0 {
                    leaf(child..child + node.count[k] as usize)
                } else {
                    let c = &self.wide[child];
                    let lanes = (0..WIDTH).filter(|j| c.valid >> j & 1 == 1);
                    lanes.fold(EMPTY, |all, j| {
                        let b = |axis: usize| c.bounds[axis][j];
                        let lane = (Vec3::new(b(0), b(1), b(2)), Vec3::new(b(3), b(4), b(5)));
                        union(all, lane)
                    })
                };
                for axis in 0..3 {
                    node.bounds[axis][k] = min[axis];
                    node.bounds[3 + axis][k] = max[axis];
                }
            }
            self.wide[w] = node;
        }
    }

    /// The work of the build's clustering: nodes considered over all its rounds, each by one
    /// search of a window of neighbours. At most ten per box plus 1,024 for any boxes (coincident
    /// or nested ones included), so a build costs O(n log n) with the sort.
    pub fn build_work(&self) -> u64 {
        self.work
    }

    /// Number of nodes (0 for an empty BVH).
    pub fn node_count(&self) -> usize {
        self.bvh.nodes.len()
    }

    /// The slot range of every leaf, in node order (for benchmarks and statistics).
    pub fn leaves(&self) -> impl Iterator<Item = Range<usize>> + '_ {
        self.bvh.nodes.iter().filter(|n| n.is_leaf()).map(|n| {
            let first = n.first_index as usize;
            first..first + n.prim_count as usize
        })
    }

    /// Calls `leaf(slots, t_max)` for every leaf the ray of `q` enters before `*t_max`, nearest
    /// child first. The closure shrinks `*t_max` when it finds a closer hit and returns `false` to
    /// stop the traversal.
    #[inline]
    pub fn traverse(
        &self,
        q: &RayQuery,
        t_max: &mut f32,
        leaf: impl FnMut(Range<usize>, &mut f32) -> bool,
    ) {
        self.traverse_in::<true, _>(Sse, q, t_max, leaf);
    }

    /// [`Bvh::traverse`] with a [`Leaf`] instead of a closure, and box tests as wide as `lanes`.
    #[inline]
    pub fn traverse_leaves<W: Lanes>(
        &self,
        lanes: W,
        q: &RayQuery,
        t_max: &mut f32,
        leaf: impl Leaf,
    ) {
        self.traverse_in::<true, W>(lanes, q, t_max, leaf);
    }

    /// [`Bvh::traverse`] for any-hit queries, whose answer does not depend on the order of the
    /// leaves: children in node order, unsorted. The closure returns `false` to stop.
    #[inline]
    pub fn traverse_any(
        &self,
        q: &RayQuery,
        t_max: &mut f32,
        leaf: impl FnMut(Range<usize>, &mut f32) -> bool,
    ) {
        self.traverse_in::<false, _>(Sse, q, t_max, leaf);
    }

    /// [`Bvh::traverse_any`] with a [`Leaf`] instead of a closure, and box tests as wide as
    /// `lanes`.
    #[inline]
    pub fn traverse_any_leaves<W: Lanes>(
        &self,
        lanes: W,
        q: &RayQuery,
        t_max: &mut f32,
        leaf: impl Leaf,
    ) {
        self.traverse_in::<false, W>(lanes, q, t_max, leaf);
    }

    #[inline(always)]
    fn traverse_in<const NEAREST_FIRST: bool, W: Lanes>(
        &self,
        lanes: W,
        q: &RayQuery,
        t_max: &mut f32,
        mut leaf: impl Leaf,
    ) {
        let nodes = &self.bvh.nodes;
        let Some(root) = nodes.first() else { return };
        // A ray that misses the root box misses every box inside it (the slab test is monotone
        // in the bounds), so the wide root's test of its children rejects it too. With eight
        // lanes that is one test, as cheap as the root box's; with four, the root box's spares
        // misses the second half.
        if root.is_leaf() || W::WIDTH < WIDTH {
            let b = root.aabb();
            if q.enter_box(b.min, b.max, *t_max).is_none() {
                return;
            }
        }
        if root.is_leaf() {
            let first = root.first_index as usize;
            leaf.visit(first..first + root.prim_count as usize, t_max);
            return;
        }
        let entered = q.enter_boxes(lanes, &self.wide[0].bounds, *t_max);
        if entered.0 & u32::from(self.wide[0].valid) == 0 {
            return;
        }
        // Each level pushes at most eight children after popping one. The stack is zeroed at
        // every query, so a shallow tree gets a short one.
        let needed = (WIDTH - 1) * self.depth + 1;
        if needed <= SHORT_STACK {
            let mut stack = [0u64; SHORT_STACK];
            self.traverse_wide::<NEAREST_FIRST, W>(lanes, entered, &mut stack, q, t_max, &mut leaf);
        } else if needed <= INLINE_STACK {
            let mut stack = [0u64; INLINE_STACK];
            self.traverse_wide::<NEAREST_FIRST, W>(lanes, entered, &mut stack, q, t_max, &mut leaf);
        } else {
            let mut stack = vec![0u64; needed];
            self.traverse_wide::<NEAREST_FIRST, W>(lanes, entered, &mut stack, q, t_max, &mut leaf);
        }
    }

    /// Traversal of the wide tree from its root, whose children `root` tested. The stack holds
    /// each pushed node's entry distance (its bits above its index); a node popped beyond the
    /// `t_max` of that moment is dropped unread, and one within tests its children against that
    /// `t_max`, which culls what a closer hit has put out of reach. Dropping it changes nothing
    /// but the work: its children's boxes lie inside its own, so (the slab test being monotone
    /// in the bounds) none of them could be entered before its own entry distance. A node's
    /// entered leaves are visited first, then its inner children still in reach are pushed; with
    /// `NEAREST_FIRST` both go nearest first (inner children pushed farthest deepest), without,
    /// in node order.
    #[inline(always)]
    fn traverse_wide<const NEAREST_FIRST: bool, W: Lanes>(
        &self,
        lanes: W,
        root: (u32, [f32; WIDTH]),
        stack: &mut [u64],
        q: &RayQuery,
        t_max: &mut f32,
        leaf: &mut impl Leaf,
    ) {
        let mut top = 0usize;
        let mut node = &self.wide[0];
        let (mut mask, mut near) = root;
        loop {
            let mut hits = mask & u32::from(node.valid);
            // The entered children, nearest first (insertion sort of at most eight) or as they
            // come. A key is the entry distance's bits above the child's index: distances are
            // never negative (nor NaN), so keys order as (distance, index) do, and equal
            // distances keep node order.
            let mut order = [0u64; WIDTH];
            let mut n = 0;
            while hits != 0 {
                // `hits` has bits below `WIDTH` only; the mask tells the compiler so.
                let k = hits.trailing_zeros() as usize & (WIDTH - 1);
                hits &= hits - 1;
                let key = u64::from(near[k].to_bits()) << 32 | k as u64;
                let mut j = n;
                while NEAREST_FIRST && j > 0 && order[j - 1] > key {
                    order[j] = order[j - 1];
                    j -= 1;
                }
                order[j] = key;
                n += 1;
            }
            let child = |key: u64| {
                (
                    key as usize & (WIDTH - 1),
                    f32::from_bits((key >> 32) as u32),
                )
            };
            // Leaves first, nearest first, each against the `t_max` its predecessors left.
            for &key in &order[..n] {
                let (k, t) = child(key);
                if node.count[k] > 0 && t <= *t_max {
                    let first = node.child[k] as usize;
                    if !leaf.visit(first..first + node.count[k] as usize, t_max) {
                        return;
                    }
                }
            }
            // Then the inner children still in reach, farthest deepest. A child the leaves'
            // hits put out of reach would only have been popped and culled later.
            for &key in order[..n].iter().rev() {
                let (k, t) = child(key);
                if node.count[k] == 0 && t <= *t_max {
                    stack[top] = (key >> 32) << 32 | u64::from(node.child[k]);
                    top += 1;
                }
            }
            // The nearest pushed node still in reach; the ones a closer hit put beyond it go.
            let next = loop {
                if top == 0 {
                    return;
                }
                top -= 1;
                let entry = stack[top];
                if f32::from_bits((entry >> 32) as u32) <= *t_max {
                    break entry as u32;
                }
            };
            node = &self.wide[next as usize];
            (mask, near) = q.enter_boxes(lanes, &node.bounds, *t_max);
        }
    }
}

#[cfg(test)]
mod tests;
