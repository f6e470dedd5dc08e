//! The targets light paths are aimed at: a bounding sphere per entity that may be a perfect
//! mirror or glass, chosen by `r²` (a sorted cumulative list) and found along a line or ray by a
//! small bounding-volume hierarchy, so that a light path's cost grows with the number of
//! targets its line crosses and the tree's depth, not with the number of targets. No ECS here.

use std::f32::consts::PI;

use glam::Vec3;

use crate::geometry::sphere::cone_one_minus_cos;

/// Targets per leaf of the tree.
const LEAF: usize = 2;

/// Deepest tree the traversal's stack holds: a median split halves the targets at each level,
/// so 64 levels hold any count that fits in memory.
const MAX_DEPTH: usize = 64;

/// A node of the tree: its box and either two children or a range of `order`.
#[derive(Clone, Copy, Debug)]
struct Node {
    lo: Vec3,
    hi: Vec3,
    /// Sum of `r²` of the targets below.
    area: f32,
    /// Leaf: `order[first..first + count]`; inner (`count == 0`): children `first`, `first + 1`.
    first: u32,
    count: u32,
}

/// Bounding spheres (centre, radius) with a choice by `r²` and a tree to find the ones a line
/// or ray meets.
#[derive(Clone, Debug, Default)]
pub struct Targets {
    spheres: Vec<(Vec3, f32)>,
    /// Cumulative `r²`, in `spheres`' order.
    cumulative: Vec<f32>,
    nodes: Vec<Node>,
    /// Target indices, grouped by leaf.
    order: Vec<u32>,
}

/// What a query meets: an infinite line (both ways from its point) or a ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Reach {
    /// The whole line through the point.
    Line,
    /// The half-line from the point on (a sphere around the point counts).
    Ray,
}

impl Targets {
    /// The tree over `spheres`; `O(n log n)`.
    pub fn new(spheres: Vec<(Vec3, f32)>) -> Self {
        let mut sum = 0.0;
        let cumulative = spheres
            .iter()
            .map(|&(_, r)| {
                sum += r * r;
                sum
            })
            .collect();
        let mut order: Vec<u32> = (0..spheres.len() as u32).collect();
        let mut nodes = Vec::with_capacity(2 * spheres.len().div_ceil(LEAF));
        if !spheres.is_empty() {
            nodes.push(node(&spheres, &order, 0));
            let mut pending = vec![(0usize, 0usize, spheres.len())];
            while let Some((at, start, end)) = pending.pop() {
                if end - start <= LEAF {
                    continue;
                }
                let (lo, hi) = (nodes[at].lo, nodes[at].hi);
                let axis = (hi - lo).max_position();
                order[start..end].sort_unstable_by(|&a, &b| {
                    spheres[a as usize].0[axis].total_cmp(&spheres[b as usize].0[axis])
                });
                let mid = start + (end - start) / 2;
                let first = nodes.len();
                nodes.push(node(&spheres, &order[start..mid], start));
                nodes.push(node(&spheres, &order[mid..end], mid));
                nodes[at].first = first as u32;
                nodes[at].count = 0;
                pending.push((first, start, mid));
                pending.push((first + 1, mid, end));
            }
        }
        Self {
            spheres,
            cumulative,
            nodes,
            order,
        }
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.spheres.is_empty()
    }

    /// How many.
    pub fn len(&self) -> usize {
        self.spheres.len()
    }

    /// Target `j`.
    pub fn get(&self, j: usize) -> (Vec3, f32) {
        self.spheres[j]
    }

    /// Sum of `r²`.
    pub fn area(&self) -> f32 {
        self.cumulative.last().copied().unwrap_or(0.0)
    }

    /// The target chosen by `r²` with `u` in `[0, 1)`, and its probability.
    pub fn choose(&self, u: f32) -> (usize, f32) {
        let area = self.area();
        let j = self
            .cumulative
            .partition_point(|&a| a <= u * area)
            .min(self.spheres.len().saturating_sub(1));
        let r = self.spheres.get(j).map_or(0.0, |s| s.1);
        (j, r * r / area)
    }

    /// Calls `f(j)` for every target other than `skip` that the line or ray from `o` along unit
    /// `d` meets; returns the number of tree nodes visited (the query's cost).
    pub fn for_each_met(
        &self,
        o: Vec3,
        d: Vec3,
        reach: Reach,
        skip: usize,
        mut f: impl FnMut(usize),
    ) -> u32 {
        let mut visits = 0;
        let mut stack = [0u32; MAX_DEPTH];
        let mut top = usize::from(!self.nodes.is_empty());
        while top > 0 {
            top -= 1;
            let n = self.nodes[stack[top] as usize];
            visits += 1;
            if !box_met(n.lo, n.hi, o, d, reach) {
                continue;
            }
            if n.count == 0 {
                if top + 2 > MAX_DEPTH {
                    continue;
                }
                stack[top] = n.first;
                stack[top + 1] = n.first + 1;
                top += 2;
                continue;
            }
            for &j in &self.order[n.first as usize..(n.first + n.count) as usize] {
                let (c, r) = self.spheres[j as usize];
                if j as usize != skip && sphere_met(c, r, o, d, reach) {
                    f(j as usize);
                }
            }
        }
        visits
    }

    /// `Σ Ω / 4π` over the targets, Ω the solid angle each subtends from `x` (capped at 1):
    /// exact for targets near `x`, and for a far subtree (its box's centre more than eight
    /// half-diagonals away) `π Σ r² / d²`. A selection weight, so an estimate suffices.
    pub fn share_seen_from(&self, x: Vec3) -> f32 {
        let mut seen = 0.0;
        let mut stack = [0u32; MAX_DEPTH];
        let mut top = usize::from(!self.nodes.is_empty());
        while top > 0 {
            top -= 1;
            let n = self.nodes[stack[top] as usize];
            let centre = 0.5 * (n.lo + n.hi);
            let half = 0.5 * (n.hi - n.lo).length();
            let d2 = (centre - x).length_squared();
            if d2 > 64.0 * half * half {
                seen += PI * n.area / d2;
            } else if n.count == 0 && top + 2 <= MAX_DEPTH {
                stack[top] = n.first;
                stack[top + 1] = n.first + 1;
                top += 2;
            } else {
                for &j in &self.order[n.first as usize..(n.first + n.count) as usize] {
                    let (c, r) = self.spheres[j as usize];
                    seen += cone_solid_angle(c, r, x);
                }
            }
        }
        (seen / (4.0 * PI)).min(1.0)
    }
}

/// The node over the targets `indices` (`order[first..]`), a leaf of them.
fn node(spheres: &[(Vec3, f32)], indices: &[u32], first: usize) -> Node {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    let mut area = 0.0;
    for &j in indices {
        let (c, r) = spheres[j as usize];
        // Widened so that the box test, in floating point, never rejects what the sphere test
        // accepts.
        let pad = r * 1.001 + 1e-6 * c.abs().max_element();
        lo = lo.min(c - Vec3::splat(pad));
        hi = hi.max(c + Vec3::splat(pad));
        area += r * r;
    }
    Node {
        lo,
        hi,
        area,
        first: first as u32,
        count: indices.len() as u32,
    }
}

/// Solid angle of the cone of directions from `p` that meet the sphere (`c`, `r`): 4π from
/// inside it.
pub fn cone_solid_angle(c: Vec3, r: f32, p: Vec3) -> f32 {
    let d2 = (c - p).length_squared();
    if d2 <= r * r {
        4.0 * PI
    } else {
        2.0 * PI * cone_one_minus_cos(r * r / d2)
    }
}

/// Whether the line or ray from `p` along unit `d` meets the sphere (`c`, `r`) (a ray always
/// does from inside it).
pub fn sphere_met(c: Vec3, r: f32, p: Vec3, d: Vec3, reach: Reach) -> bool {
    let to = c - p;
    match reach {
        Reach::Line => d.cross(to).length_squared() <= r * r,
        Reach::Ray => {
            to.length_squared() <= r * r
                || (to.dot(d) > 0.0 && d.cross(to).length_squared() <= r * r)
        }
    }
}

/// Whether the line or ray from `o` along `d` meets the box (slabs; an axis the direction does
/// not move along must hold `o`).
fn box_met(lo: Vec3, hi: Vec3, o: Vec3, d: Vec3, reach: Reach) -> bool {
    let (mut near, mut far) = match reach {
        Reach::Line => (f32::NEG_INFINITY, f32::INFINITY),
        Reach::Ray => (0.0, f32::INFINITY),
    };
    for a in 0..3 {
        if d[a] == 0.0 {
            if o[a] < lo[a] || o[a] > hi[a] {
                return false;
            }
            continue;
        }
        let (t0, t1) = ((lo[a] - o[a]) / d[a], (hi[a] - o[a]) / d[a]);
        near = near.max(t0.min(t1));
        far = far.min(t0.max(t1));
    }
    near <= far
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shading::rng::Rng;
    use crate::shading::sampler::Sampler;

    /// Targets on a 16×16×16 grid of spacing 10, radius 1 (4096 of them).
    fn grid() -> Vec<(Vec3, f32)> {
        (0..4096)
            .map(|i| {
                let p = Vec3::new((i % 16) as f32, ((i / 16) % 16) as f32, (i / 256) as f32);
                (10.0 * p, 1.0)
            })
            .collect()
    }

    #[test]
    fn the_tree_finds_exactly_the_targets_a_brute_force_scan_finds() {
        let spheres = grid();
        let t = Targets::new(spheres.clone());
        let mut rng = Rng::for_sample(5, 0, 0);
        for k in 0..400 {
            let o = 160.0 * Vec3::new(rng.next_1d(), rng.next_1d(), rng.next_1d()) - 5.0;
            let u = rng.next_2d();
            let d = crate::geometry::sphere::sample_sphere_area(u);
            let reach = if k % 2 == 0 { Reach::Line } else { Reach::Ray };
            let skip = k % 7;
            let mut found = Vec::new();
            t.for_each_met(o, d, reach, skip, |j| found.push(j));
            found.sort_unstable();
            let want: Vec<usize> = (0..spheres.len())
                .filter(|&j| j != skip && sphere_met(spheres[j].0, spheres[j].1, o, d, reach))
                .collect();
            assert_eq!(found, want, "{o} {d} {reach:?}");
        }
    }

    #[test]
    fn a_query_visits_far_fewer_nodes_than_there_are_targets() {
        // A ray along one grid row meets 16 targets of 4096: the traversal must not look at
        // each of them (a linear scan visits 4096).
        let t = Targets::new(grid());
        let mut met = 0;
        let visits = t.for_each_met(
            Vec3::new(-5.0, 50.0, 50.0),
            Vec3::X,
            Reach::Ray,
            usize::MAX,
            |_| met += 1,
        );
        assert_eq!(met, 16);
        assert!(visits < 400, "{visits} nodes visited for 4096 targets");
    }

    #[test]
    fn targets_are_chosen_in_proportion_to_r_squared() {
        let t = Targets::new(vec![(Vec3::ZERO, 1.0), (Vec3::X * 5.0, 2.0)]);
        assert_eq!(t.choose(0.1), (0, 0.2));
        assert_eq!(t.choose(0.3).0, 1);
        assert!((t.choose(0.3).1 - 0.8).abs() < 1e-6);
    }

    #[test]
    fn the_share_seen_is_the_sum_of_solid_angles_near_and_its_far_field_estimate_far() {
        let spheres = grid();
        let t = Targets::new(spheres.clone());
        for x in [Vec3::new(35.0, 42.0, 71.0), Vec3::new(-400.0, 80.0, 900.0)] {
            let want: f32 = spheres
                .iter()
                .map(|&(c, r)| cone_solid_angle(c, r, x))
                .sum::<f32>()
                / (4.0 * PI);
            let got = t.share_seen_from(x);
            assert!((got - want).abs() <= 0.2 * want, "{x}: {got} vs {want}");
        }
    }
}
