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

use std::fmt::Write as _;
use std::hint::black_box;
use std::ops::Range;
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

use bevy_ecs::prelude::*;
use cpu_time::ProcessTime;
use glam::Vec3;

use crate::ecs::components::{EntityName, Shape, Transform};
use crate::film::Film;
use crate::geometry::aabb::RayQuery;
use crate::geometry::layout::{Aos, Hybrid, Layout, LayoutKind, Soa, SoaSimd};
use crate::geometry::packed::{BvhPlan, Geometry, Primitive};
use crate::geometry::ray::Ray;
use crate::geometry::world::world_primitives;
use crate::lights::LightSet;
use crate::render::Method;
use crate::render::camera::Camera;
use crate::render::{SceneView, has_masks, render_pass};
use crate::shading::material::Material;
use crate::shading::rng::Rng;
use crate::shading::sampler::SamplerKind;
use crate::shading::texture::Texture;

use super::chart;
use super::layout_rows::{Kind, Row, WORKLOADS, spread};

/// Mean distance between neighbouring primitive centres.
const SPACING: f32 = 2.0;

/// What to measure and where to write it.
#[derive(Clone, Debug)]
pub struct Options {
    /// Output directory for `layout.csv`, `layout.md` and `layout.svg`.
    pub out: PathBuf,
    /// Primitive counts, ascending.
    pub counts: Vec<usize>,
    /// Rounds per point at counts up to 10⁴ (fewer above: see [`Options::reps_at`]).
    pub reps: usize,
    /// Minimum duration of one run.
    pub min_run: Duration,
    /// Render resolution (square).
    pub render_size: u32,
    /// Rays per traversal run (before repetition).
    pub rays: usize,
    /// The command line that made these results, for the report.
    pub command: String,
    /// Workloads to run (names from [`WORKLOADS`]); empty for all.
    pub workloads: Vec<String>,
}

impl Options {
    /// The full sweep: 10² to `max_count` (powers of ten and their half-decades), `reps`
    /// rounds.
    pub fn full(out: PathBuf, max_count: usize, reps: usize) -> Self {
        let mut counts = Vec::new();
        let mut decade = 100usize;
        while decade <= max_count {
            counts.push(decade);
            let half = (decade as f64 * 10f64.sqrt()).round() as usize;
            if half <= max_count && decade * 10 <= max_count {
                counts.push(half);
            }
            decade *= 10;
        }
        Self {
            out,
            counts,
            reps: reps.max(1),
            min_run: Duration::from_millis(50),
            render_size: 64,
            rays: 20_000,
            command: String::new(),
            workloads: Vec::new(),
        }
    }

    /// Tiny sizes, two rounds, no minimum run time: checks that everything runs and writes its
    /// outputs; measures nothing worth reading.
    pub fn smoke(out: PathBuf) -> Self {
        Self {
            out,
            counts: vec![20, 300],
            reps: 2,
            min_run: Duration::ZERO,
            render_size: 8,
            rays: 200,
            command: String::new(),
            workloads: Vec::new(),
        }
    }

    /// Whether `workload` is to run.
    pub fn runs(&self, workload: &str) -> bool {
        self.workloads.is_empty() || self.workloads.iter().any(|w| w == workload)
    }

    /// Rounds at `count` primitives: fewer at the largest sizes, where one run is long and
    /// its spread small.
    pub fn reps_at(&self, count: usize) -> usize {
        match count {
            0..=10_000 => self.reps,
            10_001..=100_000 => self.reps.min(7),
            _ => self.reps.min(5),
        }
    }
}

/// Measures the CPU time of this process (all its threads), so that time spent descheduled
/// while other jobs share the machine does not count; wall time where there is no CPU clock.
enum Stopwatch {
    Cpu(ProcessTime),
    Wall(Instant),
}

impl Stopwatch {
    fn start() -> Self {
        ProcessTime::try_now().map_or_else(|_| Self::Wall(Instant::now()), Self::Cpu)
    }

    fn elapsed(&self) -> Duration {
        match self {
            Self::Cpu(t) => t.try_elapsed().unwrap_or_default(),
            Self::Wall(t) => t.elapsed(),
        }
    }
}

/// What a point measured besides the rows.
#[derive(Clone, Copy, Debug)]
struct Note {
    kind: Kind,
    count: usize,
    /// BVH build time (both kinds' BVHs; one kind is empty).
    bvh: Duration,
    /// Mean primitives per BVH leaf visited.
    mean_leaf: f64,
}

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

/// `n` shapes of `kind` scattered uniformly in a cube of side `∛n · SPACING` centred on the
/// origin: spheres of radius 0.2–0.5, triangles with vertices within 0.6 of their centre.
pub fn generate(kind: Kind, n: usize, seed: u64) -> Vec<Shape> {
    let mut rng = Rng::new(seed, kind as u64 + 1);
    let side = cube_side(n);
    let unit = |rng: &mut Rng| loop {
        let v = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - Vec3::ONE;
        let l = v.length_squared();
        if l > 1e-3 && l <= 1.0 {
            return v / l.sqrt();
        }
    };
    (0..n)
        .map(|_| {
            let c = (Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) - 0.5) * side;
            match kind {
                Kind::Sphere => Shape::Sphere {
                    center: c,
                    radius: 0.2 + 0.3 * rng.next_f32(),
                },
                Kind::Triangle => Shape::Triangle {
                    a: c + 0.6 * unit(&mut rng),
                    b: c + 0.6 * unit(&mut rng),
                    c: c + 0.6 * unit(&mut rng),
                },
            }
        })
        .collect()
}

fn cube_side(n: usize) -> f32 {
    (n.max(1) as f32).cbrt() * SPACING
}

/// The leaf visits of real closest-hit traversals, recorded to be replayed without the
/// traversal: for each visit, the ray, the leaf's slots and the `t_max` the traversal had then.
struct Leaves {
    kind: Kind,
    work: Vec<(RayQuery, Range<usize>, f32)>,
}

impl Leaves {
    fn new(g: &Geometry<Soa>, kind: Kind, rays: &[Ray]) -> Self {
        let mut work = Vec::new();
        for ray in rays {
            let q = RayQuery::new(*ray);
            let mut t_max = f32::INFINITY;
            match kind {
                Kind::Sphere => g.sphere_bvh.traverse(&q, &mut t_max, |slots, t| {
                    work.push((q, slots.clone(), *t));
                    Soa::closest_sphere(&g.spheres, ray, slots, t);
                    true
                }),
                Kind::Triangle => g.triangle_bvh.traverse(&q, &mut t_max, |slots, t| {
                    work.push((q, slots.clone(), *t));
                    Soa::closest_triangle(&g.triangles, &q, slots, t);
                    true
                }),
            }
        }
        Self { kind, work }
    }

    /// Primitive tests per pass.
    fn tests(&self) -> f64 {
        self.work.iter().map(|(_, l, _)| l.len() as f64).sum()
    }

    /// Mean primitives per leaf visited.
    fn mean_leaf(&self) -> f64 {
        self.tests() / self.work.len().max(1) as f64
    }

    fn run<L: Layout>(&self, g: &Geometry<L>, passes: usize) {
        let mut sum = 0usize;
        for _ in 0..passes {
            match self.kind {
                Kind::Sphere => {
                    for (q, leaf, t_max) in &self.work {
                        let mut t = *t_max;
                        let hit = L::closest_sphere(&g.spheres, &q.ray, leaf.clone(), &mut t);
                        sum += hit.unwrap_or(0);
                    }
                }
                Kind::Triangle => {
                    for (q, leaf, t_max) in &self.work {
                        let mut t = *t_max;
                        let hit = L::closest_triangle(&g.triangles, q, leaf.clone(), &mut t);
                        sum += hit.map_or(0, |h| h.0);
                    }
                }
            }
        }
        black_box(sum);
    }
}

/// Rays with origins uniform in the scene's cube and directions uniform on the sphere.
fn incoherent_rays(count: usize, rays: usize) -> Vec<Ray> {
    let mut rng = Rng::new(0x7a4, 5);
    let side = cube_side(count);
    (0..rays)
        .map(|_| {
            let o = (Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) - 0.5) * side;
            let d = loop {
                let v = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - Vec3::ONE;
                if v.length_squared() > 1e-3 && v.length_squared() <= 1.0 {
                    break v.normalize();
                }
            };
            Ray::new(o, d)
        })
        .collect()
}

fn traverse<L: Layout>(g: &Geometry<L>, rays: &[Ray], passes: usize) {
    let mut hits = 0u32;
    for _ in 0..passes {
        for ray in rays {
            hits += u32::from(g.intersect(ray, f32::INFINITY).is_some());
        }
    }
    black_box(hits);
}

/// A generated scene rendered by `render_pass` (what `render_frame` calls for each pass), on a
/// one-thread pool: a diffuse material under a white sky, 4 rays per path.
struct RenderBench {
    pool: rayon::ThreadPool,
    camera: Camera,
    materials: Vec<Material>,
    owner_material: Vec<u32>,
    lights: LightSet,
    size: u32,
}

impl RenderBench {
    fn new(g: &Geometry<Soa>, owners: usize, size: u32) -> Self {
        let side = cube_side(owners);
        let materials = vec![Material::Diffuse {
            albedo: Texture::Constant(Vec3::splat(0.7)),
        }];
        let owner_material = vec![0; owners];
        let lights = LightSet::build(g, &materials, &owner_material);
        let pool = match rayon::ThreadPoolBuilder::new().num_threads(1).build() {
            Ok(p) => p,
            Err(e) => panic!("one-thread pool: {e}"),
        };
        Self {
            pool,
            camera: Camera::new(
                Vec3::new(0.3, 0.4, -1.6) * side,
                Vec3::new(-0.3, -0.4, 1.6),
                Vec3::Y,
                40.0,
            ),
            materials,
            owner_material,
            lights,
            size,
        }
    }

    /// Renders `spp` samples per pixel of the scene in `geometry`: returns the time and the rays
    /// traced.
    fn run<L: Layout>(&self, geometry: &Geometry<L>, spp: usize) -> (Duration, f64) {
        let view = SceneView {
            geometry,
            materials: &self.materials,
            owner_material: &self.owner_material,
            lights: &self.lights,
            camera: &self.camera,
            background: Vec3::ONE,
            max_depth: 4,
            method: Method::default(),
            roulette: true,
            sampler: SamplerKind::default(),
            masked: has_masks(&self.materials),
        };
        let mut film = Film::new(self.size, self.size);
        let cancel = AtomicBool::new(false);
        let t = Stopwatch::start();
        let stats = self
            .pool
            .install(|| render_pass(&view, &mut film, 1, 0..spp as u32, &cancel, &|_| {}));
        let time = t.elapsed();
        (time, stats.map_or(0.0, |s| s.rays as f64))
    }
}

/// ECS components → packed geometry in layout `L`, as `rebuild_geometry` does it, with the BVHs
/// given.
fn extract<L: Layout>(world: &mut World, plan: BvhPlan) -> Geometry<L> {
    let mut query = world.query::<(&EntityName, &Shape, &Transform)>();
    let mut sorted: Vec<_> = query.iter(world).collect();
    sorted.sort_by(|a, b| a.0.0.cmp(&b.0.0));
    let mut primitives = Vec::with_capacity(sorted.len());
    for (slot, (_, shape, transform)) in sorted.iter().enumerate() {
        for p in world_primitives(shape, transform) {
            primitives.push((slot as u32, p));
        }
    }
    Geometry::pack_with(&primitives, plan)
}

fn write_csv(options: &Options, rows: &[Row]) -> std::io::Result<()> {
    let mut csv = String::from(
        "workload,kind,count,layout,unit,runs,median,min,max,\
         ratio_vs_aos_median,ratio_vs_aos_min,ratio_vs_aos_max\n",
    );
    for r in rows {
        let (m, lo, hi) = spread(&r.runs);
        let (rm, rlo, rhi) = spread(&r.ratios);
        let _ = writeln!(
            csv,
            "{},{},{},{},{},{},{m:.6e},{lo:.6e},{hi:.6e},{rm:.4},{rlo:.4},{rhi:.4}",
            r.workload,
            r.kind.name(),
            r.count,
            r.layout.name(),
            r.unit,
            r.runs.len(),
        );
    }
    crate::output_file::write_bytes(&options.out.join("layout.csv"), csv.as_bytes())
}

/// The model name of the first CPU, from `/proc/cpuinfo` where there is one.
fn cpu_name() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|s| s.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into())
}

/// `layout.md`: per workload and kind, each layout's ratio to AoS at every count.
fn markdown(options: &Options, rows: &[Row], notes: &[Note], elapsed: Duration) -> String {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let mut md = String::new();
    let _ = writeln!(
        md,
        "Measured by `{}` on {} ({} hardware threads; every workload runs on one), {} build, \
         {:.0} s in all. Cells: throughput ratio to AoS, median of the rounds [min, max]; \
         > 1 means faster than AoS. Rounds per point: {} up to 10⁴ primitives, {} up to 10⁵, \
         {} above.\n",
        if options.command.is_empty() {
            "rondo bench layout"
        } else {
            &options.command
        },
        cpu_name(),
        threads,
        if cfg!(debug_assertions) {
            "debug"
        } else {
            "release"
        },
        elapsed.as_secs_f64(),
        options.reps_at(1),
        options.reps_at(100_000),
        options.reps_at(usize::MAX),
    );
    let _ = write!(md, "| workload | kind | layout |");
    for c in &options.counts {
        let _ = write!(md, " {c} |");
    }
    let _ = write!(md, "\n|---|---|---|");
    for _ in &options.counts {
        let _ = write!(md, "---|");
    }
    md.push('\n');
    for (workload, _) in WORKLOADS {
        for kind in [Kind::Sphere, Kind::Triangle] {
            for layout in [LayoutKind::Soa, LayoutKind::SoaSimd, LayoutKind::Hybrid] {
                let _ = write!(
                    md,
                    "| {workload} | {} | {}/aos |",
                    kind.name(),
                    layout.name()
                );
                for &c in &options.counts {
                    let cell = rows
                        .iter()
                        .find(|r| {
                            r.workload == workload
                                && r.kind == kind
                                && r.count == c
                                && r.layout == layout
                        })
                        .map(|r| {
                            let (m, lo, hi) = spread(&r.ratios);
                            format!("{m:.2} [{lo:.2}, {hi:.2}]")
                        })
                        .unwrap_or_default();
                    let _ = write!(md, " {cell} |");
                }
                md.push('\n');
            }
        }
    }
    let _ = write!(
        md,
        "\nAoS throughput (median):\n\n| workload | kind | unit |"
    );
    for c in &options.counts {
        let _ = write!(md, " {c} |");
    }
    let _ = write!(md, "\n|---|---|---|");
    for _ in &options.counts {
        let _ = write!(md, "---|");
    }
    md.push('\n');
    for (workload, unit) in WORKLOADS {
        for kind in [Kind::Sphere, Kind::Triangle] {
            let _ = write!(md, "| {workload} | {} | {unit} |", kind.name());
            for &c in &options.counts {
                let cell = rows
                    .iter()
                    .find(|r| {
                        r.workload == workload
                            && r.kind == kind
                            && r.count == c
                            && r.layout == LayoutKind::Aos
                    })
                    .map(|r| format!("{:.3e}", spread(&r.runs).0))
                    .unwrap_or_default();
                let _ = write!(md, " {cell} |");
            }
            md.push('\n');
        }
    }
    let _ = write!(
        md,
        "\nBVH build (the same for every layout, not in `extract`) in ms, and mean primitives per \
         leaf visited:"
    );
    for n in notes {
        let _ = write!(
            md,
            " {} {}: {:.1} ms, {:.2};",
            n.kind.name(),
            n.count,
            n.bvh.as_secs_f64() * 1e3,
            n.mean_leaf
        );
    }
    md.push('\n');
    md
}

#[cfg(test)]
mod tests;
