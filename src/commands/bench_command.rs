//! `rondo bench …`: the benchmarks' argument types and their dispatch (their bodies are in
//! [`super::bench`]).

use std::path::PathBuf;

use anyhow::Result;
use clap::Subcommand;

use rondo::scene::format::{MAX_DEPTH, MAX_SPP, Method};
use rondo::shading::sampler::SamplerKind;

use super::args::{RenderArgs, at_least_one_u32, at_most_u32, thread_count, workload_names};

#[derive(Subcommand)]
pub enum BenchCommand {
    /// Build time and peak memory of N placements of one mesh (each count in its own process).
    Instances {
        /// The mesh to place.
        #[arg(long, default_value = "scenes/meshes/bunny.obj")]
        mesh: PathBuf,
        /// Placement counts.
        #[arg(long, value_delimiter = ',', default_value = "1,10,100,1000")]
        counts: Vec<usize>,
        /// Copy every placement's triangles into the scene BVH instead of instancing (to compare).
        #[arg(long)]
        flatten: bool,
        /// Run one count in this process and print its CSV line (used by the parent run).
        #[arg(long, hide = true)]
        single: Option<usize>,
    },
    /// Render a scene several times and report samples/s and rays/s (median of the runs).
    Render {
        /// Scene file (.ron).
        #[arg(default_value = "scenes/cornell.ron")]
        scene: PathBuf,
        /// Number of timed runs.
        #[arg(long, default_value_t = 5)]
        runs: usize,
        #[command(flatten)]
        options: RenderArgs,
    },
    /// SoA against AoS (and SoA with SIMD lanes): leaf kernel, traversal, render and extraction
    /// throughput over primitive counts; writes layout.csv, layout.md and layout.svg.
    Layout {
        /// Output directory.
        #[arg(long, default_value = "bench/layout")]
        out: PathBuf,
        /// Largest primitive count.
        #[arg(long, default_value_t = 1_000_000)]
        max_count: usize,
        /// Interleaved rounds per point (at most 7 above 10⁴ primitives, 5 above 10⁵).
        #[arg(long, default_value_t = 9)]
        reps: usize,
        /// Tiny sizes and two rounds: checks that the command works; measures nothing.
        #[arg(long)]
        smoke: bool,
        /// Run only this workload (kernel, traverse, render, extract, pack); repeatable.
        #[arg(long = "workload", value_parser = workload_names())]
        workloads: Vec<String>,
    },
    /// Error against a reference image as a function of render time, for each light-transport
    /// method and sampler over a sweep of spp (renders interleaved); writes accuracy.csv,
    /// accuracy.svg (log-log RMSE against time), accuracy_relative.svg, accuracy_lamp_out.svg
    /// and summary.md (equal-time comparison) in --out.
    Accuracy {
        /// Scene file (.ron).
        scene: PathBuf,
        /// Reference image (.exr, e.g. `rondo render SCENE -o ref.exr --spp 4096`); the renders
        /// take its size. Make it with a seed below --seed (the scene's default 0 is fine).
        #[arg(long)]
        reference: PathBuf,
        /// Output directory.
        #[arg(long, default_value = "bench/acc")]
        out: PathBuf,
        /// Samples per pixel of the sweep, comma-separated.
        #[arg(long, value_delimiter = ',', default_value = "1,2,4,8,16,32,64", value_parser = at_most_u32(MAX_SPP))]
        spp_list: Vec<u32>,
        /// Methods compared, comma-separated (`caustics` and `photons` render as `mis` where the scene has
        /// no perfect mirror or smooth glass).
        #[arg(
            long,
            value_delimiter = ',',
            default_value = "naive,nee,mis,caustics,photons"
        )]
        methods: Vec<Method>,
        /// Samplers compared with every method, comma-separated.
        #[arg(long, value_delimiter = ',', default_value = "sobol")]
        samplers: Vec<SamplerKind>,
        /// Rays per path, camera ray included (overrides the scene).
        #[arg(long, value_parser = at_most_u32(MAX_DEPTH))]
        max_depth: Option<u32>,
        /// Worker threads (default: all cores).
        #[arg(long, value_parser = thread_count())]
        threads: Option<usize>,
        /// First seed of the sweep (render k uses seed + k).
        #[arg(long, default_value_t = rondo::bench::accuracy::DEFAULT_SEED)]
        seed: u64,
        /// Also measure every render denoised (Open Image Denoise, albedo and normal): its
        /// time is the render with the feature buffers plus the denoise, wall clock. Drawn
        /// dashed; summary.md says from which error on the raw render is the better choice.
        #[arg(long)]
        denoise: bool,
        /// Write every image there as <method>_<sampler>_<spp>spp[_denoised].exr (a denoised
        /// one with the layer `raw`), named in accuracy.csv's `image` column for
        /// benches/flip/flip.py.
        #[arg(long, value_name = "DIR")]
        keep_images: Option<PathBuf>,
    },
    /// Load time and memory of a generated environment map (OpenEXR and Radiance .hdr): read
    /// and decode, building the distribution, and the whole load; prints a Markdown table.
    Environment {
        /// Map width in texels.
        #[arg(long, default_value_t = 4096, value_parser = at_least_one_u32())]
        width: u32,
        /// Map height in texels.
        #[arg(long, default_value_t = 2048, value_parser = at_least_one_u32())]
        height: u32,
        /// Number of timed runs (median and minimum reported).
        #[arg(long, default_value_t = 5)]
        runs: usize,
        /// Also write the table to DIR/environment.md.
        #[arg(long, value_name = "DIR")]
        out: Option<PathBuf>,
    },
    /// Load, first image and `check` of generated scenes over sizes, stage by stage.
    Load {
        /// Scene kinds (flat, unnamed, materials, meshes, textures, placements, prefab, tiles).
        #[arg(
            long,
            value_delimiter = ',',
            default_value = "flat,unnamed,materials,meshes,textures,placements,prefab,tiles"
        )]
        kinds: Vec<String>,
        /// Sizes (what grows in each kind).
        #[arg(
            long,
            value_delimiter = ',',
            default_value = "1000,10000,100000,1000000"
        )]
        sizes: Vec<usize>,
        /// Also time watch mode on the flat scene of this size (as one of --watch-sizes).
        #[arg(long)]
        watch: Option<usize>,
        /// Time watch mode on the flat scenes of these sizes: cold start, and each kind of edit
        /// (material colour, move a sphere, one entity's material; move the mesh with
        /// --big-mesh), save to first image, with the growth per 10×.
        #[arg(long, value_delimiter = ',')]
        watch_sizes: Vec<usize>,
        /// With the watch sizes: measure each again with a generated OBJ of about this many
        /// triangles placed once (1000000: the big mesh, ~80 MB).
        #[arg(long, value_name = "TRIANGLES", value_parser = clap::value_parser!(u64).range(2..=rondo::bench::load_watch_table::MAX_BIG_MESH as u64))]
        big_mesh: Option<u64>,
        /// Saves timed per kind of edit in watch mode.
        #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u64).range(1..=1000))]
        edits: u64,
        /// Skip the load table (only the watch-mode one).
        #[arg(long)]
        no_load: bool,
    },
    /// Latency of `rondo lsp` on a generated scene of N spheres: diagnostics after a keystroke
    /// and after a typo, completion of material names (the server driven in process).
    Lsp {
        /// Entities of the generated scene.
        #[arg(long, default_value_t = 10_000, value_parser = clap::value_parser!(u64).range(2..=1_000_000))]
        entities: u64,
        /// Keystrokes, typos and completions timed.
        #[arg(long, default_value_t = 20, value_parser = clap::value_parser!(u64).range(1..=10_000))]
        edits: u64,
    },
    /// Latency of `watch`: from a saved edit to the first and to the full-quality image, for
    /// each kind of edit the scene has a target for: a material colour (colour), a small sphere
    /// moved, or an entity if there is no sphere (move-small), the biggest mesh moved
    /// (move-mesh), one entity's material (entity-material). The edits are saved to a copy
    /// beside the scene (relative paths resolve), removed at the end.
    Watch {
        /// Scene file (.ron).
        #[arg(default_value = "scenes/cornell.ron")]
        scene: PathBuf,
        /// Edits per kind.
        #[arg(long, default_value_t = 5)]
        runs: usize,
        /// Samples per pixel of the first pass.
        #[arg(long, default_value_t = 1, value_parser = at_least_one_u32())]
        first_spp: u32,
        /// Time only these kinds of edit (comma-separated; each must have a target in the scene).
        #[arg(long, value_delimiter = ',', value_parser = edit_kinds())]
        kinds: Vec<String>,
        #[command(flatten)]
        options: RenderArgs,
    },
}

/// The names of the watch benchmarks' kinds of edit.
fn edit_kinds() -> clap::builder::PossibleValuesParser {
    clap::builder::PossibleValuesParser::new(
        rondo::bench::load_watch::KINDS.map(rondo::bench::load_watch::Kind::name),
    )
}

/// Runs one benchmark.
pub fn run(what: BenchCommand) -> Result<()> {
    match what {
        BenchCommand::Instances {
            mesh,
            counts,
            flatten,
            single,
        } => super::bench::instances(&mesh, &counts, flatten, single),
        BenchCommand::Render {
            scene,
            runs,
            options,
        } => super::bench::render(&scene, runs, &options),
        BenchCommand::Layout {
            out,
            max_count,
            reps,
            smoke,
            workloads,
        } => super::bench::layout(out, max_count, reps, smoke, workloads),
        BenchCommand::Environment {
            width,
            height,
            runs,
            out,
        } => super::bench::environment(width, height, runs, out.as_deref()),
        BenchCommand::Load {
            kinds,
            sizes,
            watch,
            mut watch_sizes,
            big_mesh,
            edits,
            no_load,
        } => {
            watch_sizes.extend(watch);
            let table = rondo::bench::load_watch_table::WatchTable {
                sizes: watch_sizes,
                big_mesh: big_mesh.map(|t| t as usize),
                edits: edits as usize,
            };
            super::bench::load(&kinds, &sizes, !no_load, &table)
        }
        BenchCommand::Accuracy {
            scene,
            reference,
            out,
            spp_list,
            methods,
            samplers,
            max_depth,
            threads,
            seed,
            denoise,
            keep_images,
        } => super::bench::accuracy(&rondo::bench::accuracy::AccuracyOptions {
            scene,
            reference,
            out,
            spp_list,
            methods,
            samplers,
            threads,
            max_depth,
            seed,
            denoise,
            keep_images,
        }),
        BenchCommand::Lsp { entities, edits } => {
            super::bench::lsp(entities as usize, edits as usize)
        }
        BenchCommand::Watch {
            scene,
            runs,
            first_spp,
            kinds,
            options,
        } => super::bench::watch(&scene, runs, first_spp, &kinds, &options),
    }
}
