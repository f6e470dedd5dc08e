//! The binary tree under [`super::Bvh`]: PLOC clustering (Meister and Bittner, "Parallel
//! Locally-Ordered Clustering for Bounding Volume Hierarchy Construction", 2018), step for step
//! as obvhs 0.4's `ploc` module builds it, with one addition: a budget of work after which every
//! round halves the node list, so the build costs O(n log n) for any input.
//!
//! PLOC sorts the boxes by the Morton code of their centres, then repeats rounds: each node
//! picks the neighbour within a small window of the list whose union with it has the least
//! area, and pairs that pick each other merge. Where boxes coincide (the same triangle placed
//! many times, instances of one mesh at one place) or nest (concentric spheres), the picks form
//! a chain instead of pairs: obvhs's tie rule makes every node of a run of equal boxes pick the
//! farthest one ahead, so a round merges one pair, and n boxes take n rounds of up to n nodes
//! (16,384 coincident triangles took 6.5 s). Here the rounds' work is counted, and once it passes
//! [`WORK_PER_BOX`] nodes per box (plus [`WORK_SLACK`]), every round also pairs the nodes it
//! left unmerged, two by two in list order (neighbours in Morton order, as a linear BVH pairs
//! them), which halves the list each round. Builds within that budget are obvhs's exactly (the
//! test `the_tree_is_obvhs_for_boxes_of_real_scenes`).

use std::f32;

use obvhs::aabb::Aabb;
use obvhs::bvh2::{Bvh2, node::Bvh2Node};
use obvhs::ploc::morton::morton_encode_u64_unorm;

/// Nodes per box the rounds may consider before leftovers are paired. obvhs's rounds on real
/// scenes consider 3–5 (the bunny 3.3, meshes of 10⁵–10⁶ triangles 2.9, the files in scenes/ at
/// most 5.2), as each merges a third to a half of its nodes until the last few hundred.
const WORK_PER_BOX: u64 = 8;

/// Work every build may do on top of [`WORK_PER_BOX`]: the rounds of a few dozen boxes, whose
/// worst case (n²/2) stays below it, are always obvhs's.
const WORK_SLACK: u64 = 1024;

/// The binary tree and the work its clustering did.
pub struct Clustered {
    /// obvhs's binary tree: inner nodes before their children, leaves of one primitive each,
    /// `primitive_indices` the identity.
    pub bvh: Bvh2,
    /// Nodes considered over all rounds (each costs one window search): at most
    /// `(WORK_PER_BOX + 2)·n + WORK_SLACK`, where obvhs's rounds take n²/2 on n coincident boxes.
    pub work: u64,
}

/// Builds the binary tree over `aabbs` by PLOC with a neighbour window of `search` nodes on each
/// side (1 to 32), except in the first `narrow_rounds` rounds, which look at one neighbour.
pub fn cluster(aabbs: &[Aabb], search: usize, narrow_rounds: usize) -> Clustered {
    let n = aabbs.len();
    let mut bvh = Bvh2::zeroed(n);
    bvh.primitive_indices = (0..n as u32).collect();
    if n == 0 {
        return Clustered { bvh, work: 0 };
    }
    let search = search.clamp(1, 32);
    let mut total = Aabb::empty();
    for a in aabbs {
        total.extend(a.min);
        total.extend(a.max);
    }
    // Morton order of the box centres over the whole box (obvhs's `sort_nodes_by_morton`);
    // equal codes keep input order, so the tree does not depend on the sort algorithm.
    let scale = 1.0 / total.diagonal().as_dvec3();
    let offset = -total.min.as_dvec3() * scale;
    let mut keys: Vec<(u64, u32)> = aabbs
        .iter()
        .enumerate()
        .map(|(i, a)| {
            let centre = a.center().as_dvec3() * scale + offset;
            (morton_encode_u64_unorm(centre), i as u32)
        })
        .collect();
    keys.sort_unstable();
    let mut current: Vec<Bvh2Node> = keys
        .iter()
        .map(|&(_, i)| Bvh2Node::new(aabbs[i as usize], 1, i))
        .collect();
    drop(keys);
    let mut next = vec![Bvh2Node::default(); n];
    // Per node of the round: the neighbour it would merge with.
    let mut best = vec![0usize; n];
    let mut cache = vec![0.0f32; search * search];
    let budget = WORK_PER_BOX * n as u64 + WORK_SLACK;
    let mut insert = bvh.nodes.len();
    let (mut count, mut round, mut work) = (n, 0usize, 0u64);
    while count > 1 {
        let nodes = &current[..count];
        work += count as u64;
        let cost = |i: usize, j: usize| nodes[i].aabb().union(nodes[j].aabb()).half_area();
        if search == 1 || round < narrow_rounds {
            // Each node leans toward its cheaper side; a tie leans right.
            let mut last = f32::INFINITY;
            for (i, best) in best[..count - 1].iter_mut().enumerate() {
                let c = cost(i, i + 1);
                *best = if last < c { i - 1 } else { i + 1 };
                last = c;
            }
            best[count - 1] = count - 2;
        } else {
            for (i, best) in best[..count].iter_mut().enumerate() {
                *best = best_in_window(i, nodes, search, &mut cache);
            }
        }
        if work > budget {
            let merging: Vec<bool> = (0..count)
                .map(|i| best[i] != i && best[best[i]] == i)
                .collect();
            // Pair the nodes left over, in list order; an odd one out waits for the next round.
            let mut open = None;
            for i in (0..count).filter(|&i| !merging[i]) {
                match open.take() {
                    Some(a) => (best[a], best[i]) = (i, a),
                    None => open = Some(i),
                }
            }
            if let Some(a) = open {
                best[a] = a;
            }
        }
        // Merge each agreeing pair at its later node (obvhs's order, which fixes node indices).
        let mut kept = 0;
        for i in 0..count {
            let b = best[i];
            if b == i || best[b] != i {
                next[kept] = current[i];
                kept += 1;
                continue;
            }
            if b > i {
                continue;
            }
            let (left, right) = (current[i], current[b]);
            insert -= 2;
            bvh.nodes[insert] = left;
            bvh.nodes[insert + 1] = right;
            next[kept] = Bvh2Node::new(left.aabb().union(right.aabb()), 0, insert as u32);
            kept += 1;
        }
        std::mem::swap(&mut current, &mut next);
        count = kept;
        round += 1;
    }
    debug_assert_eq!(insert, 1);
    bvh.nodes[0] = current[0];
    bvh.max_depth = bvh.max_depth.max(round + 1);
    bvh.children_are_ordered_after_parents = true;
    Clustered { bvh, work }
}

/// The node within `search` places of node `i` whose union with it has the least area; among
/// equal areas the last one (obvhs's `find_best_node`). `cache` (`search²` entries) keeps the
/// areas computed looking ahead, which node `i` reads again looking back.
fn best_in_window(i: usize, nodes: &[Bvh2Node], search: usize, cache: &mut [f32]) -> usize {
    let slot = |a: usize, b: usize| (a % search) * search + b % search;
    let (mut best, mut best_cost) = (i, f32::INFINITY);
    for other in i - search.min(i)..i {
        let c = cache[slot(other, i)];
        if c <= best_cost {
            (best, best_cost) = (other, c);
        }
    }
    let own = nodes[i].aabb();
    for other in i + 1..(i + search + 1).min(nodes.len()) {
        let c = own.union(nodes[other].aabb()).half_area();
        cache[slot(i, other)] = c;
        if c <= best_cost {
            (best, best_cost) = (other, c);
        }
    }
    best
}
