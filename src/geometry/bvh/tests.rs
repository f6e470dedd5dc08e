//! Tests of `geometry/bvh.rs`.

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
fn a_group_is_never_split_between_leaves_and_every_slot_is_in_one() {
    // Groups of one to three slots, as for quads (two triangles) among single triangles.
    let sizes: Vec<u8> = (0..500u32).map(|i| 1 + (i * 7 % 3) as u8).collect();
    let bounds: Vec<Bounds> = (0..sizes.len())
        .map(|i| {
            let c = Vec3::new((i % 8) as f32, (i / 8 % 8) as f32, (i / 64) as f32);
            (c, c + Vec3::splat(0.5))
        })
        .collect();
    let (bvh, order) = Bvh::build_groups(&bounds, |g| sizes[g]);
    let mut sorted = order.clone();
    sorted.sort_unstable();
    assert_eq!(sorted, (0..sizes.len() as u32).collect::<Vec<u32>>());
    // Slot ranges of the groups in BVH order.
    let mut start = 0;
    let ranges: Vec<Range<usize>> = order
        .iter()
        .map(|&g| {
            let r = start..start + sizes[g as usize] as usize;
            start = r.end;
            r
        })
        .collect();
    let mut covered = vec![0u32; start];
    for leaf in bvh.leaves() {
        for s in leaf.clone() {
            covered[s] += 1;
        }
        for r in &ranges {
            let inside = r.start >= leaf.start && r.end <= leaf.end;
            let outside = r.end <= leaf.start || r.start >= leaf.end;
            assert!(inside || outside, "leaf {leaf:?} splits group {r:?}");
        }
    }
    assert!(covered.iter().all(|&c| c == 1));
    assert!(bvh.node_count() > 1);
}

/// Boxes of random size scattered in a cube, and random rays through it.
fn random_boxes_and_rays(n: usize) -> (Vec<Bounds>, Vec<Ray>) {
    let mut rng = crate::shading::rng::Rng::new(9, 4);
    let mut v = || Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
    let boxes = (0..n)
        .map(|_| {
            let c = v() * 20.0;
            (c, c + v() * 2.0)
        })
        .collect();
    let rays = (0..500)
        .map(|k| {
            let mut d = v() * 2.0 - Vec3::ONE;
            if k % 10 == 0 {
                d.y = 0.0; // axis-parallel rays take the slab test's NaN-aware path
            }
            Ray::new(v() * 24.0 - Vec3::splat(2.0), d.normalize())
        })
        .collect();
    (boxes, rays)
}

#[test]
fn wide_traversal_visits_exactly_the_leaves_the_ray_enters() {
    // Brute force over the binary tree's leaves: a leaf must be visited iff the ray enters its
    // box (its ancestors' boxes contain it, and the slab test is monotone in the bounds).
    let (boxes, rays) = random_boxes_and_rays(1000);
    let (bvh, _) = Bvh::build(&boxes);
    assert!(bvh.depth > 1 && bvh.wide.len() * 2 < bvh.node_count());
    for ray in rays {
        let q = RayQuery::new(ray);
        let mut visited = Vec::new();
        let mut t = f32::INFINITY;
        bvh.traverse(&q, &mut t, |slots, _| {
            visited.push(slots.start);
            true
        });
        let mut expected: Vec<usize> = bvh
            .bvh
            .nodes
            .iter()
            .filter(|n| n.is_leaf())
            .filter(|n| {
                q.enter_box(n.aabb().min, n.aabb().max, f32::INFINITY)
                    .is_some()
            })
            .map(|n| n.first_index as usize)
            .collect();
        visited.sort_unstable();
        expected.sort_unstable();
        assert_eq!(visited, expected, "{ray:?}");
    }
}

/// Asserts that for every ray the nearest box entry the traversal finds (leaf by leaf, the
/// boxes in slot order `order`) is a brute-force scan's over all `boxes`.
fn assert_nearest_box_entry_is_brute_force(
    bvh: &Bvh,
    order: &[u32],
    boxes: &[Bounds],
    rays: &[Ray],
) {
    for &ray in rays {
        let q = RayQuery::new(ray);
        let expected = boxes
            .iter()
            .filter_map(|&(a, b)| q.enter_box(a.into(), b.into(), f32::INFINITY))
            .fold(f32::INFINITY, f32::min);
        let mut t = f32::INFINITY;
        bvh.traverse(&q, &mut t, |slots, t| {
            for s in slots {
                let (a, b) = boxes[order[s] as usize];
                if let Some(e) = q.enter_box(a.into(), b.into(), *t) {
                    *t = t.min(e);
                }
            }
            true
        });
        assert_eq!(t, expected, "{ray:?}");
    }
}

#[test]
fn wide_traversal_finds_the_nearest_box_hit_and_stops_when_asked() {
    // Closest "hit" = the nearest entry into a leaf box (leaves of one primitive each).
    let (boxes, rays) = random_boxes_and_rays(300);
    let (bvh, order) = Bvh::build(&boxes);
    assert_nearest_box_entry_is_brute_force(&bvh, &order, &boxes, &rays);
    for ray in rays {
        let q = RayQuery::new(ray);
        let (mut calls, mut t) = (0, f32::INFINITY);
        bvh.traverse(&q, &mut t, |_, _| {
            calls += 1;
            false
        });
        assert!(calls <= 1);
    }
}

/// Boxes of a big mesh (more than the 2¹⁷ primitives from which the BVH takes its big-mesh
/// build and collapses in parallel), and random rays through them.
fn big_mesh_boxes_and_rays() -> (Vec<Bounds>, Vec<Ray>) {
    let mut rng = crate::shading::rng::Rng::new(24, 3);
    let mut v = || Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
    let boxes = (0..(1 << 17) + 5_000)
        .map(|_| {
            let c = v() * 100.0;
            (c, c + v() * 0.5)
        })
        .collect();
    let rays = (0..200)
        .map(|k| {
            let mut d = v() * 2.0 - Vec3::ONE;
            if k % 10 == 0 {
                d.x = 0.0;
            }
            Ray::new(v() * 110.0 - Vec3::splat(5.0), d.normalize())
        })
        .collect();
    (boxes, rays)
}

/// Per ray, the slot ranges of the leaves the traversal visits, in visiting order: a
/// fingerprint of the wide tree's layout and child order.
fn visits(bvh: &Bvh, rays: &[Ray]) -> Vec<Vec<Range<usize>>> {
    rays.iter()
        .map(|&ray| {
            let q = RayQuery::new(ray);
            let mut seen = Vec::new();
            let mut t = f32::INFINITY;
            bvh.traverse(&q, &mut t, |slots, _| {
                seen.push(slots);
                true
            });
            seen
        })
        .collect()
}

#[test]
fn big_mesh_bvh_is_the_same_for_any_thread_count_and_valid() {
    let (boxes, rays) = big_mesh_boxes_and_rays();
    let build = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("thread pool")
            .install(|| Bvh::build(&boxes))
    };
    let (bvh, order) = build(1);
    let leaves: Vec<_> = bvh.leaves().collect();
    let walk = visits(&bvh, &rays);
    for threads in [2, 3] {
        let (other, other_order) = build(threads);
        // `assert!`, not `assert_eq!`: a failure would print 136,072 indices.
        assert!(other_order == order, "{threads} threads: primitive order");
        assert_eq!(other.node_count(), bvh.node_count(), "{threads} threads");
        assert!(
            other.leaves().eq(leaves.iter().cloned()),
            "{threads} threads"
        );
        assert!(
            visits(&other, &rays) == walk,
            "{threads} threads: wide tree"
        );
    }
    // Every primitive is in exactly one leaf.
    let mut sorted = order.clone();
    sorted.sort_unstable();
    assert!(sorted.iter().copied().eq(0..boxes.len() as u32));
    let mut covered = vec![0u8; boxes.len()];
    for leaf in &leaves {
        for s in leaf.clone() {
            covered[s] += 1;
        }
    }
    assert!(covered.iter().all(|&c| c == 1));
    // Boxes enclose what is under them: the nearest box entry the traversal finds is a
    // brute-force scan's, for every ray.
    assert_nearest_box_entry_is_brute_force(&bvh, &order, &boxes, &rays);
}

/// obvhs's own build of `boxes` with the parameters [`Bvh::build`] picks.
fn obvhs_build(boxes: &[Bounds]) -> Bvh2 {
    let aabbs: Vec<Aabb> = boxes
        .iter()
        .map(|&(a, b)| Aabb::new(a.into(), b.into()))
        .collect();
    let params = if aabbs.len() >= LARGE_BUILD {
        LARGE_BUILD_PARAMS
    } else {
        BUILD_PARAMS
    };
    let mut unused = std::time::Duration::ZERO;
    obvhs::bvh2::builder::build_bvh2(&aabbs, params, &mut unused)
}

#[test]
fn the_tree_is_obvhs_for_boxes_of_real_scenes() {
    // A grid of equal boxes, whose union areas tie between neighbours.
    let grid: Vec<Bounds> = (0..1000)
        .map(|i| {
            let c = Vec3::new((i % 10) as f32, (i / 10 % 10) as f32, (i / 100) as f32);
            (c, c + Vec3::splat(0.5))
        })
        .collect();
    for (name, boxes) in [
        ("random", random_boxes_and_rays(1000).0),
        ("grid", grid),
        ("big mesh", big_mesh_boxes_and_rays().0),
    ] {
        let expected = obvhs_build(&boxes);
        // Leaves are slot ranges in `Bvh`, which are obvhs's indices for groups of one.
        let (ours, order) = Bvh::build(&boxes);
        assert!(
            order == expected.primitive_indices,
            "{name}: primitive order"
        );
        assert_eq!(ours.bvh.nodes.len(), expected.nodes.len(), "{name}");
        for (k, (a, b)) in ours.bvh.nodes.iter().zip(&expected.nodes).enumerate() {
            let same = a.aabb() == b.aabb()
                && a.prim_count == b.prim_count
                && a.first_index == b.first_index;
            assert!(same, "{name}: node {k}: {a:?} against obvhs's {b:?}");
        }
    }
}

/// `n` copies of one box, as `n` instances of a mesh at one place.
fn coincident(n: usize) -> Vec<Bounds> {
    vec![(Vec3::new(-1.0, 0.0, 2.0), Vec3::new(3.0, 1.0, 2.5)); n]
}

/// `n` boxes around one centre, each larger than the one before (concentric spheres).
fn nested(n: usize) -> Vec<Bounds> {
    (0..n)
        .map(|i| sphere_bounds(Vec3::new(1.0, 2.0, 3.0), 1.0 + i as f32 * 0.01))
        .collect()
}

#[test]
fn coincident_and_nested_boxes_build_in_n_log_n_work_into_valid_shallow_trees() {
    let (mut rng, mut rays) = (crate::shading::rng::Rng::new(5, 2), Vec::new());
    for _ in 0..300 {
        let mut v = || Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
        let origin = v() * 200.0 - Vec3::splat(100.0);
        rays.push(Ray::new(origin, (v() * 10.0 - origin).normalize()));
    }
    // A balanced binary tree of 8,192 leaves has 13 levels, and a wide node holds at least
    // two of them; a chain of merges has thousands. Nested boxes have no depth bound: SAH's
    // best tree over them is a chain (an inner node is as large as its largest box), which
    // obvhs's reinsertion builds from any start.
    type Boxes = fn(usize) -> Vec<Bounds>;
    let cases: [(&str, Boxes, usize); 2] = [
        ("coincident", coincident, 13),
        ("nested", nested, usize::MAX),
    ];
    for (name, boxes, max_depth) in cases {
        let (small, _) = Bvh::build(&boxes(1024));
        let (bvh, order) = Bvh::build(&boxes(8192));
        // From 1,024 to 8,192 boxes, n·log₂n grows 8·13/10 = 10.4 times, n² 64 times.
        let (a, b) = (small.build_work(), bvh.build_work());
        assert!(
            b * 10 <= a * 104,
            "{name}: work {a} for 1,024 boxes, {b} for 8,192"
        );
        assert!(bvh.depth <= max_depth, "{name}: {} wide levels", bvh.depth);
        let mut covered = vec![0u8; order.len()];
        for leaf in bvh.leaves() {
            for s in leaf {
                covered[s] += 1;
            }
        }
        assert!(covered.iter().all(|&c| c == 1), "{name}");
        assert_nearest_box_entry_is_brute_force(&bvh, &order, &boxes(8192), &rays);
    }
}

#[test]
fn empty_bvh_visits_nothing() {
    let (bvh, order) = Bvh::build(&[]);
    assert!(order.is_empty());
    let q = RayQuery::new(Ray::new(Vec3::ZERO, Vec3::X));
    let mut t = f32::INFINITY;
    bvh.traverse(&q, &mut t, |_, _| panic!("no leaves"));
}
