//! The `rondo` command line.

use std::path::{Path, PathBuf};
use std::time::Duration;

use anyhow::{Context, Result, bail};
use clap::{Args, Parser, Subcommand};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use rondo::bench::layout;
use rondo::cli::{EXIT_INPUT, check_output_dir, check_output_file};
use rondo::film::OutputKind;
use rondo::geometry::layout::LayoutKind;
use rondo::scene::format::{MAX_DEPTH, MAX_SIDE, MAX_SPP, Method};
use rondo::shading::sampler::SamplerKind;
use rondo::watch::{Report, Watch, WatchOptions, WatchSession};
use rondo::{Overrides, PassPlan, Renderer};

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
    /// accuracy.svg (log-log RMSE against time) and summary.md (equal-time comparison) in --out.
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

#[derive(Args)]
struct RenderArgs {
    /// Samples per pixel (overrides the scene).
    #[arg(long, value_parser = at_most_u32(MAX_SPP))]
    spp: Option<u32>,
    /// Image width (overrides the scene).
    #[arg(long, value_parser = at_most_u32(MAX_SIDE))]
    width: Option<u32>,
    /// Image height (overrides the scene).
    #[arg(long, value_parser = at_most_u32(MAX_SIDE))]
    height: Option<u32>,
    /// Rays per path, camera ray included (overrides the scene).
    #[arg(long, value_parser = at_most_u32(MAX_DEPTH))]
    max_depth: Option<u32>,
    /// Random seed (overrides the scene).
    #[arg(long)]
    seed: Option<u64>,
    /// Worker threads (default: all cores).
    #[arg(long, value_parser = thread_count())]
    threads: Option<usize>,
    /// Light-transport method: naive, nee or mis (overrides the scene).
    #[arg(long)]
    method: Option<Method>,
    /// Sample generator: independent or sobol (overrides the scene).
    #[arg(long)]
    sampler: Option<SamplerKind>,
    /// Geometry layout: soa, aos or soa-simd. Images are bit-identical; only speed differs.
    #[arg(long, default_value_t = LayoutKind::default())]
    layout: LayoutKind,
}

impl RenderArgs {
    /// The scene-setting overrides given on the command line.
    fn overrides(&self) -> Overrides {
        Overrides {
            width: self.width,
            height: self.height,
            spp: self.spp,
            max_depth: self.max_depth,
            seed: self.seed,
            method: self.method,
            sampler: self.sampler,
        }
    }

    fn renderer(&self) -> Result<Renderer> {
        let mut r = Renderer::new(self.threads, PassPlan::Single)?;
        r.set_overrides(self.overrides());
        r.set_layout(self.layout);
        Ok(r)
    }
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

/// `--spp`, `--width`, … : a whole number from 1 to `max`.
fn at_most_u32(max: u32) -> clap::builder::RangedI64ValueParser<u32> {
    clap::value_parser!(u32).range(1..=i64::from(max))
}

/// A whole number ≥ 1.
fn at_least_one_u32() -> clap::builder::RangedI64ValueParser<u32> {
    clap::value_parser!(u32).range(1..)
}

/// `--threads`: at least one.
fn thread_count() -> clap::builder::RangedU64ValueParser<usize> {
    clap::builder::RangedU64ValueParser::<usize>::new().range(1..)
}

/// An image output path: `.png` or `.exr`.
fn image_path(s: &str) -> Result<PathBuf, String> {
    let path = PathBuf::from(s);
    match OutputKind::from_path(&path) {
        Some(_) => Ok(path),
        None => Err("must end in .png or .exr".into()),
    }
}

/// A `.png` output path.
fn png_path(s: &str) -> Result<PathBuf, String> {
    let path = PathBuf::from(s);
    match OutputKind::from_path(&path) {
        Some(OutputKind::Png) => Ok(path),
        _ => Err("must end in .png".into()),
    }
}

/// The workloads `bench layout` knows.
fn workload_names() -> clap::builder::PossibleValuesParser {
    clap::builder::PossibleValuesParser::new(layout::WORKLOADS.iter().map(|w| w.0))
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Check { scene } => check(&scene),
        Command::Render {
            scene,
            output,
            samples,
            resume,
            options,
        } => {
            let part = match (samples, resume) {
                (Some(range), _) => Some(rondo::farm::Samples::Range(range)),
                (None, Some(path)) => Some(rondo::farm::Samples::Resume(path)),
                (None, None) => None,
            };
            render(&scene, &output, &options, part)
        }
        Command::Merge {
            inputs,
            output,
            spp,
            allow_gaps,
        } => merge(&inputs, &output, spp, allow_gaps),
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
        } => farm_slurm(
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
        } => bench_instances(&mesh, &counts, flatten, single),
        Command::Bench {
            what:
                BenchCommand::Render {
                    scene,
                    runs,
                    options,
                },
        } => bench_render(&scene, runs, &options),
        Command::Bench {
            what:
                BenchCommand::Layout {
                    out,
                    max_count,
                    reps,
                    smoke,
                    workloads,
                },
        } => bench_layout(out, max_count, reps, smoke, workloads),
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
        } => diff(&image, &reference, error_image.as_deref()),
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
                },
        } => bench_accuracy(&rondo::bench::accuracy::AccuracyOptions {
            scene,
            reference,
            out,
            spp_list,
            methods,
            samplers,
            threads,
            max_depth,
            seed,
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
            watch(watch_options, serve, allow_host)
        }
        Command::Bench {
            what:
                BenchCommand::Watch {
                    scene,
                    runs,
                    first_spp,
                    options,
                },
        } => bench_watch(&scene, runs, first_spp, &options),
    }
}

fn bench_layout(
    out: PathBuf,
    max_count: usize,
    reps: usize,
    smoke: bool,
    workloads: Vec<String>,
) -> Result<()> {
    check_output_dir(&out)?;
    let mut options = if smoke {
        layout::Options::smoke(out)
    } else {
        layout::Options::full(out, max_count, reps)
    };
    options.command = std::env::args().collect::<Vec<_>>().join(" ");
    options.workloads = workloads;
    layout::run(&options).with_context(|| format!("{}", options.out.display()))?;
    println!(
        "wrote {}/layout.csv, layout.md and layout.svg",
        options.out.display()
    );
    Ok(())
}

fn render(
    scene: &Path,
    output: &Path,
    options: &RenderArgs,
    part: Option<rondo::farm::Samples>,
) -> Result<()> {
    check_output_file(output)?;
    let mut r = options.renderer()?;
    let part = match &part {
        Some(p) => Some(rondo::farm::prepare(
            &mut r,
            options.overrides(),
            scene,
            output,
            p,
        )?),
        None => None,
    };
    let s = match &part {
        Some(p) => p.settings,
        None => r.load(scene)?.settings,
    };
    if part.is_none() {
        r.set_output(Some(output), false);
    }
    let bar =
        ProgressBar::with_draw_target(Some(u64::from(s.height)), ProgressDrawTarget::stderr());
    bar.set_style(
        ProgressStyle::with_template("{spinner} rendering [{bar:40}] {percent}% eta {eta}")
            .context("progress template")?,
    );
    r.set_progress(Some(bar.clone()));
    let wall = r.render_to_completion();
    bar.finish_and_clear();
    if let Some(e) = &r.output().last_error {
        bail!("{e}");
    }
    if let Some(part) = part {
        let ranges = rondo::partial::format_ranges(part.ranges());
        part.finish(&mut r)?;
        eprintln!("{} holds samples {ranges}", output.display());
    }
    eprintln!("{}", summary(&r, wall));
    Ok(())
}

/// `rondo merge`: checks the partials, reports missing samples, merges and writes.
fn merge(inputs: &[PathBuf], output: &Path, spp: Option<u32>, allow_gaps: bool) -> Result<()> {
    check_output_file(output)?;
    let plan = rondo::partial::plan_merge(inputs, spp)?;
    if !plan.missing.is_empty() {
        let missing = rondo::partial::format_ranges(&plan.missing).replace(',', ", ");
        if !allow_gaps {
            bail!(
                "missing samples {missing} (render them, or merge what is there with --allow-gaps)"
            );
        }
        eprintln!("warning: missing samples {missing}; the image averages the samples present");
    }
    let start = std::time::Instant::now();
    let sum = rondo::partial::merge(inputs, &plan)?;
    rondo::partial::write_output(output, &plan.meta, &sum)
        .with_context(|| format!("{}: cannot write", output.display()))?;
    eprintln!(
        "merged {} partials ({}x{}, samples {}) into {} in {:.2} s",
        inputs.len(),
        plan.meta.width,
        plan.meta.height,
        rondo::partial::format_ranges(&plan.meta.ranges),
        output.display(),
        start.elapsed().as_secs_f64()
    );
    Ok(())
}

/// `rondo farm slurm`: prints the sbatch script; `job` carries the Slurm options.
fn farm_slurm(
    scene: &Path,
    output: &Path,
    mut job: rondo::farm::SlurmJob,
    options: &RenderArgs,
) -> Result<()> {
    check_output_file(output)?;
    if options.threads.is_some() {
        bail!("--threads: each task renders with --cpus-per-task threads");
    }
    let loaded =
        rondo::scene::load::load_scene(scene, &mut rondo::scene::load::AssetCache::default())?;
    let mut settings = loaded.settings;
    options
        .overrides()
        .apply(&mut settings)
        .map_err(|m| anyhow::anyhow!("{}: {m}", scene.display()))?;
    job.rondo = std::env::current_exe().context("locating the rondo binary")?;
    job.scene = std::path::absolute(scene)?;
    job.output = std::path::absolute(output)?;
    job.spp = settings.spp;
    let mut overrides = options.overrides();
    overrides.spp = None;
    job.render_flags = rondo::farm::render_flags(&overrides, options.layout);
    print!("{}", rondo::farm::slurm_script(&job)?);
    eprintln!(
        "{} tasks, {} spp; partials in {}; submit with `sbatch <this script>`",
        job.tasks,
        job.spp,
        rondo::farm::parts_dir(&job.output).display()
    );
    Ok(())
}

/// `rondo check`: one line per warning on stdout, then a count; load errors go to `main`.
fn check(scene: &Path) -> Result<()> {
    let loaded =
        rondo::scene::load::load_scene(scene, &mut rondo::scene::load::AssetCache::default())?;
    let warnings = rondo::scene::check::check_scene(&loaded);
    for w in &warnings {
        println!("warning: {w}");
    }
    match warnings.len() {
        0 => println!("{}: no warnings", scene.display()),
        1 => println!("{}: 1 warning", scene.display()),
        n => println!("{}: {n} warnings", scene.display()),
    }
    Ok(())
}

/// The one-line summary printed after a render: the samples per pixel and the rate are those
/// this process rendered (`--samples 1023..1024` renders 1 spp, a resume the samples after its
/// partial's), with their range when it does not start at 0.
fn summary(r: &Renderer, wall: Duration) -> String {
    let s = r.settings();
    let film = r.film();
    let stats = r.stats();
    let secs = wall.as_secs_f64().max(1e-9);
    let spp = film.count();
    let samples = f64::from(s.width) * f64::from(s.height) * spp as f64;
    let range = if film.start > 0 {
        format!(" (samples {}..{})", film.start, film.samples)
    } else {
        String::new()
    };
    format!(
        "{}x{}, {spp} spp{range}, {:.2} s, {:.2} M samples/s, {:.2} M rays/s, BVH {:.2} ms ({} primitives), {} non-finite samples (dropped), {} beyond the film's range (clamped)",
        s.width,
        s.height,
        secs,
        samples / secs / 1e6,
        stats.rays as f64 / secs / 1e6,
        r.timings().bvh.as_secs_f64() * 1e3,
        r.primitive_count(),
        stats.nonfinite,
        stats.clamped,
    )
}

/// `rondo bench instances`: one child process per count, so each reports its own peak memory.
fn bench_instances(
    mesh: &Path,
    counts: &[usize],
    flatten: bool,
    single: Option<usize>,
) -> Result<()> {
    use rondo::bench::instances;
    if let Some(count) = single {
        let run = instances::measure(mesh, count, !flatten).map_err(anyhow::Error::msg)?;
        println!("{}", instances::csv_line(&run));
        return Ok(());
    }
    let exe = std::env::current_exe().context("locating the rondo binary")?;
    println!("{}", instances::CSV_HEADER);
    for &count in counts {
        let mut cmd = std::process::Command::new(&exe);
        cmd.args(["bench", "instances", "--mesh"])
            .arg(mesh)
            .arg("--single")
            .arg(count.to_string());
        if flatten {
            cmd.arg("--flatten");
        }
        let out = cmd.output().context("running a benchmark child")?;
        if !out.status.success() {
            bail!(
                "{count} instances: {}",
                String::from_utf8_lossy(&out.stderr).trim()
            );
        }
        let text = String::from_utf8_lossy(&out.stdout);
        let line = text.lines().last().unwrap_or_default();
        instances::parse_csv_line(line)
            .with_context(|| format!("unexpected child output {line:?}"))?;
        println!("{line}");
    }
    Ok(())
}

fn bench_render(scene: &Path, runs: usize, options: &RenderArgs) -> Result<()> {
    let mut times = Vec::new();
    let mut r = options.renderer()?;
    for run in 0..runs.max(1) {
        r.load(scene)?;
        let wall = r.render_to_completion();
        eprintln!("run {}: {}", run + 1, summary(&r, wall));
        times.push((wall, r.stats().rays));
    }
    times.sort();
    let (wall, rays) = times[times.len() / 2];
    println!("median: {}", summary_from(&r, wall, rays));
    Ok(())
}

fn summary_from(r: &Renderer, wall: Duration, rays: u64) -> String {
    let s = r.settings();
    let secs = wall.as_secs_f64().max(1e-9);
    let samples = f64::from(s.width) * f64::from(s.height) * f64::from(s.spp);
    format!(
        "{}x{}, {} spp, {:.3} s, {:.2} M samples/s, {:.2} M rays/s",
        s.width,
        s.height,
        s.spp,
        secs,
        samples / secs / 1e6,
        rays as f64 / secs / 1e6
    )
}

impl RenderArgs {
    fn watch_options(&self, scene: &Path, output: &Path, first_spp: u32) -> Result<WatchOptions> {
        let mut options = WatchOptions::new(scene, output);
        options.threads = self.threads;
        options.first_pass = first_spp;
        options.layout = self.layout;
        options.overrides = self.overrides();
        Ok(options)
    }
}

/// `rondo watch`: runs until Ctrl-C, one line per reload on stderr; with `serve`, also serves
/// the live viewer.
fn watch(
    options: WatchOptions,
    serve: Option<Option<String>>,
    allowed_hosts: Vec<String>,
) -> Result<()> {
    if let Some(output) = &options.output {
        check_output_file(output)?;
    }
    let mut watch = Watch::new(options)?;
    // Viewer hook: start the server and feed it every reload, pass and report.
    let viewer = match serve {
        Some(addr) => {
            let fall_back = addr.is_none();
            let addr =
                rondo::serve::parse_addr(addr.as_deref().unwrap_or(rondo::serve::DEFAULT_ADDR))?;
            let serve_options = rondo::serve::Options {
                allowed_hosts,
                ..Default::default()
            };
            let (viewer, feed) = rondo::serve::Viewer::start(addr, fall_back, serve_options)?;
            if let Some(warning) = viewer.exposure_warning() {
                eprintln!("warning: {warning}");
            }
            eprintln!("viewer: {}", viewer.url());
            watch.set_observer(feed.observer());
            watch.set_progress(feed.progress_bar());
            Some(viewer)
        }
        None => None,
    };
    let stop = watch.stop_handle();
    // The first SIGINT/SIGTERM ends the session after its current step (an image being written
    // is finished); a second one exits at once, removing the temporary.
    rondo::output_file::stop_on_termination(move || stop.stop());
    watch.run(|report| {
        if let Some(line) = report.line() {
            eprintln!("{line}");
        }
    });
    drop(viewer);
    eprintln!("stopped");
    Ok(())
}

/// `rondo bench watch`: edits a temporary copy of the scene and times each save to the first
/// and to the full-quality image, as seen by the watch loop's own reports.
fn bench_watch(scene: &Path, runs: usize, first_spp: u32, options: &RenderArgs) -> Result<()> {
    let kinds = [
        ("material", "(0.65, 0.05, 0.05)", "(0.05, 0.05, 0.65)"),
        (
            "geometry",
            "translate: (265, 0, 295)",
            "translate: (265, 0, 305)",
        ),
    ];
    let original = std::fs::read_to_string(scene)
        .with_context(|| format!("{}: cannot read", scene.display()))?;
    for (kind, from, _) in kinds {
        if !original.contains(from) {
            bail!(
                "{}: no `{from}` to edit for the {kind} edit",
                scene.display()
            );
        }
    }
    // A private directory of a fresh, unpredictable name (no planted files or symlinks),
    // removed with its contents when dropped.
    let temp = tempfile::Builder::new()
        .prefix("rondo-bench-watch-")
        .tempdir()
        .context("cannot create a temporary directory")?;
    let dir = temp.path().to_path_buf();
    let rows = time_edits(
        &dir,
        &original,
        &kinds,
        runs,
        options.watch_options(&dir.join("scene.ron"), &dir.join("out.png"), first_spp)?,
    );
    drop(temp);
    let rows = rows?;
    let stats = |v: &mut Vec<Duration>| {
        v.sort();
        let ms = |d: Duration| d.as_secs_f64() * 1e3;
        format!("{:8.1} ms (min {:8.1})", ms(v[v.len() / 2]), ms(v[0]))
    };
    println!(
        "watch latency, save -> image written, {} (loaded when the save completes, else after {} ms quiet; first pass {first_spp} spp), median of {} edits:",
        scene.display(),
        rondo::watch::DEBOUNCE.as_millis(),
        runs.max(1)
    );
    for (kind, mut first_image, mut full) in rows {
        println!(
            "  {kind:<8} edit: first image {}, full quality {}",
            stats(&mut first_image),
            stats(&mut full)
        );
    }
    Ok(())
}

/// Per edit kind: the latencies from each save to the first image and to the full-quality one.
type EditTimes = Vec<(&'static str, Vec<Duration>, Vec<Duration>)>;

/// Times `runs` edits of each kind, each replacing `from` by `to` (or back) in a copy of the
/// scene under `dir`.
fn time_edits(
    dir: &Path,
    original: &str,
    kinds: &[(&'static str, &str, &str)],
    runs: usize,
    options: WatchOptions,
) -> Result<EditTimes> {
    const WAIT: Duration = Duration::from_secs(120);
    let copy = dir.join("scene.ron");
    std::fs::write(&copy, original)?;
    let session = WatchSession::start(options)?;
    let finished = |min: u64| {
        session.wait_for(
            WAIT,
            |r| matches!(r, Report::Rendered(r) if r.completed() && r.number >= min),
        )
    };
    let Ok(Report::Rendered(first)) = finished(0) else {
        bail!("the first render did not finish");
    };
    eprintln!("{first}");
    let mut reload = first.number;
    let mut text = original.to_string();
    let mut rows = Vec::new();
    for &(kind, from, to) in kinds {
        let (mut first_image, mut full) = (Vec::new(), Vec::new());
        for _ in 0..runs.max(1) {
            text = if text.contains(from) {
                text.replace(from, to)
            } else {
                text.replace(to, from)
            };
            std::fs::write(&copy, &text)?;
            let saved = std::time::Instant::now();
            let Ok(Report::Wrote { reload: r, at, .. }) = session.wait_for(
                WAIT,
                |r| matches!(r, Report::Wrote { reload: n, .. } if *n > reload),
            ) else {
                bail!("no image after a {kind} edit");
            };
            let Ok(Report::Rendered(report)) = finished(r) else {
                bail!("the render after a {kind} edit did not finish");
            };
            reload = report.number;
            first_image.push(at.saturating_duration_since(saved));
            full.push(saved.elapsed());
            eprintln!("{kind}: {report}");
        }
        rows.push((kind, first_image, full));
    }
    Ok(rows)
}

/// `rondo diff`: prints the metrics of `image` against `reference`, one per line.
fn diff(image: &Path, reference: &Path, error_image: Option<&Path>) -> Result<()> {
    if let Some(path) = error_image {
        check_output_file(path)?;
    }
    let d = rondo::metrics::diff_files(image, reference, error_image)?;
    let m = d.metrics;
    println!("rmse     {:.6e}", m.rmse);
    println!(
        "rel_mse  {:.6e}   (mean of (a - r)^2 / (r^2 + {}))",
        m.rel_mse,
        rondo::metrics::REL_EPSILON
    );
    println!("mae      {:.6e}", m.mae);
    if let (Some(path), Some(scale)) = (error_image, d.error_scale) {
        eprintln!(
            "error image {}: |a - r| averaged over channels, dark blue = 0, yellow >= {scale:.4e} (99th percentile)",
            path.display()
        );
    }
    Ok(())
}

/// `rondo bench accuracy`: runs the sweep, printing a line per render, then the summary.
fn bench_accuracy(options: &rondo::bench::accuracy::AccuracyOptions) -> Result<()> {
    check_output_dir(&options.out)?;
    let report = rondo::bench::accuracy::run(options, |r| {
        eprintln!(
            "{:>5} {:>11} {:>6} spp  {:9.4} s  rmse {:.4e}  rel_mse {:.4e}  mae {:.4e}",
            r.method.to_string(),
            r.sampler.to_string(),
            r.spp,
            r.seconds,
            r.metrics.rmse,
            r.metrics.rel_mse,
            r.metrics.mae
        );
    })?;
    println!("{}", rondo::bench::accuracy::summary_markdown(&report));
    println!(
        "wrote {}/accuracy.csv, accuracy.svg, accuracy_relative.svg, summary.md",
        options.out.display()
    );
    Ok(())
}
