//! A thin wrapper over obvhs's binary BVH: build presets and robust closure traversal.
//!
//! obvhs builds the tree (PLOC + reinsertion + leaf collapse). Traversal is ours, because it must
//! use the robust slab test of [`RayQuery::enter_box`]: obvhs's own box test is not conservative
//! for grazing rays. Leaves hand a contiguous range of primitive slots to a closure; the caller
//! stores its primitives in BVH order (see [`Bvh::build`], which returns the order) so that range indexes them directly.

use std::ops::Range;

use glam::Vec3;
use obvhs::{BvhBuildParams, aabb::Aabb, bvh2::Bvh2};

use super::aabb::RayQuery;

/// Traversal stack size that needs no heap allocation; deeper trees fall back to a `Vec`.
const INLINE_STACK: usize = 64;

/// A bounding volume hierarchy over primitives stored in BVH order.
#[derive(Clone, Default)]
pub struct Bvh {
    bvh: Bvh2,
    depth: usize,
}

/// An axis-aligned box as `(min, max)`.
pub type Bounds = (Vec3, Vec3);

impl Bvh {
    /// Builds a BVH over primitive boxes. Returns it with `order`: slot `i` of the BVH holds
    /// input primitive `order[i]`, so the caller must permute its primitive arrays by `order`.
    pub fn build(bounds: &[Bounds]) -> (Self, Vec<u32>) {
        if bounds.is_empty() {
            return (Self::default(), Vec::new());
        }
        let aabbs: Vec<Aabb> = bounds
            .iter()
            .map(|&(min, max)| Aabb::new(min.into(), max.into()))
            .collect();
        let mut unused = std::time::Duration::ZERO;
        let bvh =
            obvhs::bvh2::builder::build_bvh2(&aabbs, BvhBuildParams::medium_build(), &mut unused);
        let order = bvh.primitive_indices.clone();
        let depth = if bvh.nodes.is_empty() {
            0
        } else {
            bvh.depth(0)
        };
        (Self { bvh, depth }, order)
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
    /// stop the traversal (any-hit queries).
    #[inline]
    pub fn traverse(
        &self,
        q: &RayQuery,
        t_max: &mut f32,
        mut leaf: impl FnMut(Range<usize>, &mut f32) -> bool,
    ) {
        if self.depth < INLINE_STACK {
            let mut stack = [0u32; INLINE_STACK];
            self.traverse_with(&mut stack, q, t_max, &mut leaf);
        } else {
            let mut stack = vec![0u32; self.depth + 1];
            self.traverse_with(&mut stack, q, t_max, &mut leaf);
        }
    }

    #[inline(always)]
    fn traverse_with(
        &self,
        stack: &mut [u32],
        q: &RayQuery,
        t_max: &mut f32,
        leaf: &mut impl FnMut(Range<usize>, &mut f32) -> bool,
    ) {
        let nodes = &self.bvh.nodes;
        let Some(root) = nodes.first() else { return };
        let enter = |i: usize, t_max: f32| {
            let b = nodes[i].aabb();
            q.enter_box(b.min, b.max, t_max)
        };
        if enter(0, *t_max).is_none() {
            return;
        }
        let range = |i: usize| {
            let n = &nodes[i];
            n.first_index as usize..(n.first_index + n.prim_count) as usize
        };
        if root.is_leaf() {
            leaf(range(0), t_max);
            return;
        }
        let mut top = 0usize;
        let mut current = root.first_index as usize;
        loop {
            let (mut near, mut far) = (current, current + 1);
            let mut t_near = enter(near, *t_max);
            let mut t_far = enter(far, *t_max);
            if t_far.unwrap_or(f32::INFINITY) < t_near.unwrap_or(f32::INFINITY) {
                std::mem::swap(&mut near, &mut far);
                std::mem::swap(&mut t_near, &mut t_far);
            }
            let mut next = None;
            for (child, entered) in [(near, t_near), (far, t_far)] {
                let Some(t_enter) = entered else { continue };
                if t_enter > *t_max {
                    continue;
                }
                if nodes[child].is_leaf() {
                    if !leaf(range(child), t_max) {
                        return;
                    }
                } else if next.is_none() {
                    next = Some(nodes[child].first_index as usize);
                } else {
                    stack[top] = nodes[child].first_index;
                    top += 1;
                }
            }
            current = match next {
                Some(n) => n,
                None if top > 0 => {
                    top -= 1;
                    stack[top] as usize
                }
                None => return,
            };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::ray::Ray;

    #[test]
    fn every_primitive_lands_in_exactly_one_leaf() {
        let bounds: Vec<Bounds> = (0..1000)
            .map(|i| {
                let c = Vec3::new((i % 10) as f32, (i / 10 % 10) as f32, (i / 100) as f32);
                (c, c + Vec3::splat(0.5))
            })
            .collect();
        let (bvh, order) = Bvh::build(&bounds);
        let mut sorted = order.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..1000).collect::<Vec<u32>>());
        assert!(bvh.node_count() > 1);
    }

    #[test]
    fn empty_bvh_visits_nothing() {
        let (bvh, order) = Bvh::build(&[]);
        assert!(order.is_empty());
        let q = RayQuery::new(Ray::new(Vec3::ZERO, Vec3::X));
        let mut t = f32::INFINITY;
        bvh.traverse(&q, &mut t, |_, _| panic!("no leaves"));
    }
}
