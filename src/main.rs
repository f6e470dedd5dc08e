//! The `rondo` command line.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};

use rondo::cli::EXIT_INPUT;
use rondo::scene::format::{MAX_DEPTH, MAX_SPP, Method};
use rondo::shading::sampler::SamplerKind;

mod commands;

use commands::args::{
    RenderArgs, at_least_one_u32, at_most_u32, image_path, png_path, thread_count, workload_names,
};
use commands::{bench, check, diff, farm, merge, render, watch};

#[derive(Parser)]
#[command(
    name = "rondo",
    version,
    about = "Path tracer for hand-written RON scenes"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene to a .png (8-bit sRGB) or .exr (linear float) image.
    Render {
        /// Scene file (.ron).
        scene: PathBuf,
        /// Output image (.png or .exr).
        #[arg(short, long, value_parser = image_path)]
        output: PathBuf,
        /// Render only samples A..B of every pixel into a partial (.exr) for `rondo merge`
        /// (docs/farm.md). The range's end takes the place of --spp.
        #[arg(long, value_name = "A..B", value_parser = rondo::partial::parse_range, conflicts_with = "resume")]
        samples: Option<std::ops::Range<u32>>,
        /// Continue the partial PATH (from --samples or `rondo merge`) with the samples after its
        /// last one, up to --spp; the output holds them all.
        #[arg(long, value_name = "PATH")]
        resume: Option<PathBuf>,
        /// Write these feature buffers (albedo, normal; comma-separated) as layers of the .exr
        /// output, beside the colour.
        #[arg(long, value_name = "LIST", value_delimiter = ',')]
        aov: Vec<rondo::layers::Aov>,
        #[command(flatten)]
        options: RenderArgs,
    },
    /// Merge partials (from `render --samples`) in any order into one image: .png, or .exr,
    /// which is a partial again (merges compose, `render --resume` continues it). Refuses
    /// overlapping samples and partials of different renders; reports missing samples.
    Merge {
        /// Partials (.exr).
        #[arg(required = true)]
        inputs: Vec<PathBuf>,
        /// Merged image (.exr or .png).
        #[arg(short, long, value_parser = image_path)]
        output: PathBuf,
        /// The merge must hold samples 0..N (missing ones at the end are reported too).
        #[arg(long, value_parser = at_most_u32(MAX_SPP))]
        spp: Option<u32>,
        /// Merge even with samples missing: the image averages the samples present.
        #[arg(long)]
        allow_gaps: bool,
        /// Write the merged image denoised (a .png output; the partials' albedo and normal
        /// buffers guide the denoiser). An .exr output stays a partial of the raw sums.
        #[arg(long)]
        denoise: bool,
    },
    /// Split a render over a cluster's scheduler.
    Farm {
        #[command(subcommand)]
        what: FarmCommand,
    },
    /// Render a scene, then re-render it on every save of the scene or its textures: a quick
    /// first pass, then passes doubling the samples, rewriting the image after each. Ctrl-C stops.
    Watch {
        /// Scene file (.ron).
        scene: PathBuf,
        /// Output image (.png or .exr); optional with --serve.
        #[arg(short, long, value_parser = image_path, required_unless_present = "serve")]
        output: Option<PathBuf>,
        /// Show every pass in a browser: serve a live viewer on ADDR (HOST:PORT or a port;
        /// default 127.0.0.1:8730, or a free port if that one is taken).
        #[arg(long, value_name = "ADDR")]
        serve: Option<Option<String>>,
        /// With --serve: also answer requests whose Host is NAME (repeatable). IP addresses and
        /// localhost are always answered; any other name is refused (DNS rebinding).
        #[arg(long, value_name = "NAME", requires = "serve", value_parser = rondo::serve::parse_host_name)]
        allow_host: Vec<String>,
        /// Samples per pixel of the first pass.
        #[arg(long, default_value_t = 1, value_parser = at_least_one_u32())]
        first_spp: u32,
        #[command(flatten)]
        options: RenderArgs,
    },
    /// Compare an image with a reference: RMSE, relative MSE (ε = 0.01) and mean absolute
    /// error over all pixels and channels; optionally a false-colour picture of the error.
    Diff {
        /// Image to judge (.exr; a .png is compared as its stored 8-bit values / 255).
        image: PathBuf,
        /// Reference image, of the same size.
        reference: PathBuf,
        /// Write a false-colour picture of the per-pixel error here (.png).
        #[arg(long, value_parser = png_path)]
        error_image: Option<PathBuf>,
    },
    /// Load a scene and list what looks wrong without rendering it: overlapping coplanar
    /// surfaces, lights facing away from everything, non-planar quads, unused materials,
    /// entities far outside the view, albedos above 1. Exit code 0 with warnings, 1 if the scene
    /// does not load.
    Check {
        /// Scene file (.ron).
        scene: PathBuf,
    },
    /// Measure rendering speed.
    Bench {
        #[command(subcommand)]
        what: BenchCommand,
    },
}

#[derive(Subcommand)]
enum FarmCommand {
    /// Print an sbatch script (to stdout) that renders the scene as a Slurm job array of
    /// --tasks sample ranges and merges them after the array succeeded.
    Slurm {
        /// Scene file (.ron).
        scene: PathBuf,
        /// Merged image (.exr or .png); partials go to <output without extension>.parts/.
        #[arg(short, long, value_parser = image_path)]
        output: PathBuf,
        /// Array tasks (sample ranges).
        #[arg(long)]
        tasks: u32,
        /// CPUs, and render threads, per task.
        #[arg(long, default_value_t = 1)]
        cpus_per_task: u32,
        /// Slurm partition.
        #[arg(long)]
        partition: Option<String>,
        /// Time limit per task (Slurm's --time).
        #[arg(long)]
        time: Option<String>,
        #[command(flatten)]
        options: RenderArgs,
    },
}

#[derive(Subcommand)]
enum BenchCommand {
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
        /// Methods compared, comma-separated.
        #[arg(long, value_delimiter = ',', default_value = "naive,nee,mis")]
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
        /// Also time watch mode on the flat scene of this size (cold start, one-entity edits).
        #[arg(long)]
        watch: Option<usize>,
    },
    /// Latency of `watch`: from a saved edit to the first and to the full-quality image, for a
    /// material edit and a geometry edit of the Cornell box (edited in a temporary copy).
    Watch {
        /// Scene file (.ron): the Cornell box, or a scene with the same red material and tall box.
        #[arg(default_value = "scenes/cornell.ron")]
        scene: PathBuf,
        /// Edits per kind.
        #[arg(long, default_value_t = 5)]
        runs: usize,
        /// Samples per pixel of the first pass.
        #[arg(long, default_value_t = 1, value_parser = at_least_one_u32())]
        first_spp: u32,
        #[command(flatten)]
        options: RenderArgs,
    },
}

/// Parses the command line (clap exits with status 2 on a usage error) and runs it; any other
/// error exits with status 1.
fn main() {
    let cli = Cli::parse();
    // SIGINT, SIGTERM or SIGHUP in the middle of a write removes the temporary before exiting.
    let installed = rondo::output_file::remove_temporaries_on_termination()
        .context("cannot install the signal handler");
    if let Err(e) = installed.and_then(|()| run(cli)) {
        eprintln!("error: {}", rondo::cli::error_text(e.as_ref()));
        std::process::exit(EXIT_INPUT);
    }
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Check { scene } => check::run(&scene),
        Command::Render {
            scene,
            output,
            samples,
            resume,
            aov,
            options,
        } => {
            let part = match (samples, resume) {
                (Some(range), _) => Some(rondo::farm::Samples::Range(range)),
                (None, Some(path)) => Some(rondo::farm::Samples::Resume(path)),
                (None, None) => None,
            };
            render::run(&scene, &output, &options, &aov, part)
        }
        Command::Merge {
            inputs,
            output,
            spp,
            allow_gaps,
            denoise,
        } => merge::run(&inputs, &output, spp, allow_gaps, denoise),
        Command::Farm {
            what:
                FarmCommand::Slurm {
                    scene,
                    output,
                    tasks,
                    cpus_per_task,
                    partition,
                    time,
                    options,
                },
        } => farm::slurm(
            &scene,
            &output,
            rondo::farm::SlurmJob {
                rondo: PathBuf::new(),
                scene: PathBuf::new(),
                output: PathBuf::new(),
                spp: 0,
                tasks,
                cpus_per_task,
                partition,
                time,
                render_flags: Vec::new(),
            },
            &options,
        ),
        Command::Bench {
            what:
                BenchCommand::Instances {
                    mesh,
                    counts,
                    flatten,
                    single,
                },
        } => bench::instances(&mesh, &counts, flatten, single),
        Command::Bench {
            what:
                BenchCommand::Render {
                    scene,
                    runs,
                    options,
                },
        } => bench::render(&scene, runs, &options),
        Command::Bench {
            what:
                BenchCommand::Layout {
                    out,
                    max_count,
                    reps,
                    smoke,
                    workloads,
                },
        } => bench::layout(out, max_count, reps, smoke, workloads),
        Command::Bench {
            what:
                BenchCommand::Load {
                    kinds,
                    sizes,
                    watch,
                },
        } => rondo::bench::load::main(&kinds, &sizes, watch).map_err(anyhow::Error::msg),
        Command::Diff {
            image,
            reference,
            error_image,
        } => diff::run(&image, &reference, error_image.as_deref()),
        Command::Bench {
            what:
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
                },
        } => bench::accuracy(&rondo::bench::accuracy::AccuracyOptions {
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
        Command::Watch {
            scene,
            output,
            serve,
            allow_host,
            first_spp,
            options,
        } => {
            let mut watch_options = options.watch_options(
                &scene,
                output.as_deref().unwrap_or(Path::new("")),
                first_spp,
            )?;
            watch_options.output = output;
            watch::run(watch_options, serve, allow_host)
        }
        Command::Bench {
            what:
                BenchCommand::Watch {
                    scene,
                    runs,
                    first_spp,
                    options,
                },
        } => bench::watch(&scene, runs, first_spp, &options),
    }
}
