//! `rondo bench layout`: the packed geometry in SoA, AoS, SoA with SIMD lanes and the hybrid
//! (SIMD spheres, AoS triangles), measured on the same generated scenes.
//!
//! For each primitive kind (spheres, triangles) and count (10² … 10⁶ by default), a scene is
//! generated from a fixed seed: primitives scattered uniformly in a cube whose side grows as
//! ∛n, so density (and the depth a ray travels) stays the same at every size. Workloads:
//!
//! - `kernel`: the leaf kernel alone. The leaf visits of real closest-hit traversals (the rays
//!   of `traverse`), recorded with the `t_max` each visit had, replayed without the traversal.
//!   Unit: primitive tests/s.
//! - `traverse`: closest-hit BVH traversal of incoherent rays (origins uniform in the cube,
//!   directions uniform on the sphere), one thread. Unit: rays/s.
//! - `render`: a whole render pass (`render_pass`, what `render_frame` runs: camera rays, path
//!   tracing with a diffuse material under a white sky, 4 rays per path, shading), one
//!   thread. Unit: rays/s.
//! - `extract`: ECS components → packed arrays, as `rebuild_geometry` does it (query, sort by
//!   name, world-space primitives, lay out in BVH order), minus the BVH build, which is the same
//!   for every layout (its time is reported beside the table). Unit: primitives/s.
//! - `pack`: the layout-dependent part of `extract` alone: primitives → arrays in BVH order.
//!
//! Each point runs the layouts in turn, rotating which goes first, for `reps` rounds; a run lasts
//! at least ~50 ms of CPU time (work is repeated to get there). Times are the CPU time of the
//! process, not wall time: on a shared machine, time spent descheduled would otherwise count. A layout's throughput is the median of its
//! runs, with min and max as the spread; its ratio to AoS is the median (min, max) of the
//! per-round ratios, so slow drifts of the machine cancel within a round.

mod options;
mod report;
mod scenes;
#[cfg(test)]
mod tests;
mod workloads;

use std::hint::black_box;
use std::time::{Duration, Instant};

use bevy_ecs::prelude::*;

use self::report::{Note, markdown, write_csv};
use self::scenes::{generate, incoherent_rays};
use self::workloads::{Leaves, RenderBench, Stopwatch, extract, traverse};
use super::chart;
use super::layout_rows::{Kind, Row, WORKLOADS, spread};
use crate::ecs::components::{EntityName, Transform};
use crate::geometry::layout::{Aos, Hybrid, LayoutKind, Soa, SoaSimd};
use crate::geometry::packed::{BvhPlan, Geometry, Primitive};
use crate::geometry::world::world_primitives;

pub use self::options::Options;

/// Runs the sweep and writes the outputs. Progress goes to stderr.
pub fn run(options: &Options) -> std::io::Result<Vec<Row>> {
    std::fs::create_dir_all(&options.out)?;
    let started = Instant::now();
    let mut rows = Vec::new();
    let mut notes = Vec::new();
    for kind in [Kind::Sphere, Kind::Triangle] {
        for &count in &options.counts {
            let point = Instant::now();
            let (mut point_rows, note) = measure_point(options, kind, count);
            eprintln!(
                "{:>8} {:<8} BVH build {:>8.1} ms, {:.2} primitives per leaf, point {:>6.1} s",
                count,
                kind.name(),
                note.bvh.as_secs_f64() * 1e3,
                note.mean_leaf,
                point.elapsed().as_secs_f64()
            );
            for r in &point_rows {
                let (m, lo, hi) = spread(&r.ratios);
                eprintln!(
                    "         {:<9} {:<9} {:>10.3e} {:<8} ratio/aos {:.3} [{:.3}, {:.3}]",
                    r.workload,
                    r.layout.name(),
                    spread(&r.runs).0,
                    r.unit,
                    m,
                    lo,
                    hi
                );
            }
            notes.push(note);
            rows.append(&mut point_rows);
        }
    }
    write_csv(options, &rows)?;
    crate::output_file::write_bytes(
        &options.out.join("layout.md"),
        markdown(options, &rows, &notes, started.elapsed()).as_bytes(),
    )?;
    chart::layout_chart(&options.out.join("layout.svg"), &rows)
        .map_err(|e| std::io::Error::other(format!("chart: {e}")))?;
    Ok(rows)
}

/// Every workload at one (kind, count), interleaved. Returns the rows and the BVH build time.
fn measure_point(options: &Options, kind: Kind, count: usize) -> (Vec<Row>, Note) {
    let shapes = generate(kind, count, 0x5eed);
    let primitives: Vec<(u32, Primitive)> = shapes
        .iter()
        .enumerate()
        .flat_map(|(i, s)| {
            world_primitives(s, &Transform::default())
                .into_iter()
                .map(move |p| (i as u32, p))
        })
        .collect();
    let start = Instant::now();
    let plan = BvhPlan::new(&primitives);
    let bvh = start.elapsed();
    let soa: Geometry<Soa> = Geometry::pack_with(&primitives, plan.clone());
    let aos: Geometry<Aos> = soa.relayout();
    let simd: Geometry<SoaSimd> = soa.relayout();
    let hybrid: Geometry<Hybrid> = soa.relayout();
    let reps = options.reps_at(count);
    let mut rows = Vec::new();

    // kernel: the leaf visits of a quarter of the traversal rays, replayed.
    let rays = incoherent_rays(count, options.rays);
    let leaves = Leaves::new(&soa, kind, &rays[..rays.len().div_ceil(4)]);
    let per_pass = leaves.tests();
    let note = Note {
        kind,
        count,
        bvh,
        mean_leaf: leaves.mean_leaf(),
    };
    rows.extend(interleave(
        options,
        "kernel",
        kind,
        count,
        reps,
        |layout, passes| {
            let t = Stopwatch::start();
            match layout {
                LayoutKind::Soa => leaves.run(&soa, passes),
                LayoutKind::Aos => leaves.run(&aos, passes),
                LayoutKind::SoaSimd => leaves.run(&simd, passes),
                LayoutKind::Hybrid => leaves.run(&hybrid, passes),
            }
            (t.elapsed(), per_pass * passes as f64)
        },
    ));

    // traverse
    rows.extend(interleave(
        options,
        "traverse",
        kind,
        count,
        reps,
        |layout, passes| {
            let t = Stopwatch::start();
            match layout {
                LayoutKind::Soa => traverse(&soa, &rays, passes),
                LayoutKind::Aos => traverse(&aos, &rays, passes),
                LayoutKind::SoaSimd => traverse(&simd, &rays, passes),
                LayoutKind::Hybrid => traverse(&hybrid, &rays, passes),
            }
            (t.elapsed(), (rays.len() * passes) as f64)
        },
    ));

    // render
    if options.runs("render") {
        let bench = RenderBench::new(&soa, shapes.len(), options.render_size);
        rows.extend(interleave(
            options,
            "render",
            kind,
            count,
            reps,
            |layout, spp| match layout {
                LayoutKind::Soa => bench.run(&soa, spp),
                LayoutKind::Aos => bench.run(&aos, spp),
                LayoutKind::SoaSimd => bench.run(&simd, spp),
                LayoutKind::Hybrid => bench.run(&hybrid, spp),
            },
        ));
    }
    drop((aos, simd, hybrid));

    // extract
    let mut world = World::new();
    world.spawn_batch(shapes.iter().enumerate().map(|(i, s)| {
        (
            EntityName(format!("e{i:08}")),
            s.clone(),
            Transform::default(),
        )
    }));
    let n = primitives.len() as f64;
    rows.extend(interleave(
        options,
        "extract",
        kind,
        count,
        reps,
        |layout, passes| {
            let mut total = Duration::ZERO;
            for _ in 0..passes {
                let plan = plan.clone();
                let t = Stopwatch::start();
                match layout {
                    LayoutKind::Soa => drop(black_box(extract::<Soa>(&mut world, plan))),
                    LayoutKind::Aos => drop(black_box(extract::<Aos>(&mut world, plan))),
                    LayoutKind::SoaSimd => drop(black_box(extract::<SoaSimd>(&mut world, plan))),
                    LayoutKind::Hybrid => drop(black_box(extract::<Hybrid>(&mut world, plan))),
                }
                total += t.elapsed();
            }
            (total, n * passes as f64)
        },
    ));

    // pack
    rows.extend(interleave(
        options,
        "pack",
        kind,
        count,
        reps,
        |layout, passes| {
            let mut total = Duration::ZERO;
            for _ in 0..passes {
                let plan = plan.clone();
                let t = Stopwatch::start();
                match layout {
                    LayoutKind::Soa => {
                        drop(black_box(Geometry::<Soa>::pack_with(&primitives, plan)))
                    }
                    LayoutKind::Aos => {
                        drop(black_box(Geometry::<Aos>::pack_with(&primitives, plan)))
                    }
                    LayoutKind::SoaSimd => {
                        drop(black_box(Geometry::<SoaSimd>::pack_with(&primitives, plan)))
                    }
                    LayoutKind::Hybrid => {
                        drop(black_box(Geometry::<Hybrid>::pack_with(&primitives, plan)))
                    }
                }
                total += t.elapsed();
            }
            (total, n * passes as f64)
        },
    ));
    (rows, note)
}

/// Runs `run(layout, passes)` (which returns the time it measured and the work it did) for every
/// layout in `reps` rounds, rotating the order. `passes` is calibrated once, on a warm-up run of
/// each layout, so that a run lasts at least `options.min_run`.
fn interleave(
    options: &Options,
    workload: &'static str,
    kind: Kind,
    count: usize,
    reps: usize,
    mut run: impl FnMut(LayoutKind, usize) -> (Duration, f64),
) -> Vec<Row> {
    if !options.runs(workload) {
        return Vec::new();
    }
    let unit = WORKLOADS
        .iter()
        .find(|w| w.0 == workload)
        .map_or("", |w| w.1);
    // Warm-up (caches, lazily built copies) and calibration on the slowest layout.
    let slowest = LayoutKind::ALL
        .iter()
        .map(|&l| run(l, 1).0)
        .max()
        .unwrap_or_default();
    let passes = if slowest.is_zero() {
        1
    } else {
        (options.min_run.as_secs_f64() / slowest.as_secs_f64())
            .ceil()
            .clamp(1.0, 1e6) as usize
    };
    let mut runs = LayoutKind::ALL.map(|_| Vec::new());
    let index = |l: LayoutKind| LayoutKind::ALL.iter().position(|&k| k == l).unwrap_or(0);
    for round in 0..reps {
        for j in 0..LayoutKind::ALL.len() {
            let layout = LayoutKind::ALL[(round + j) % LayoutKind::ALL.len()];
            let (time, work) = run(layout, passes);
            runs[index(layout)].push(work / time.as_secs_f64().max(1e-9));
        }
    }
    let aos = runs[index(LayoutKind::Aos)].clone();
    LayoutKind::ALL
        .iter()
        .map(|&layout| {
            let own = &runs[index(layout)];
            Row {
                workload,
                kind,
                count,
                layout,
                unit,
                ratios: own.iter().zip(&aos).map(|(a, b)| a / b).collect(),
                runs: own.clone(),
            }
        })
        .collect()
}
