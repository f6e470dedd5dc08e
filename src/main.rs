//! The `rondo` command line.

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};

use rondo::cli::EXIT_INPUT;
use rondo::scene::format::MAX_SPP;

mod commands;

use commands::args::{RenderArgs, at_least_one_u32, at_most_u32, image_path, png_path};
use commands::bench_command::BenchCommand;
use commands::{bench_command, check, diff, export, farm, merge, render, watch};

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
        #[arg(long, value_name = "A..B", value_parser = rondo::farm::partial::parse_range, conflicts_with = "resume")]
        samples: Option<std::ops::Range<u32>>,
        /// Continue the partial PATH (from --samples or `rondo merge`) with the samples after its
        /// last one, up to --spp; the output holds them all.
        #[arg(long, value_name = "PATH")]
        resume: Option<PathBuf>,
        /// Write these feature buffers (albedo, normal; comma-separated) as layers of the .exr
        /// output, beside the colour.
        #[arg(long, value_name = "LIST", value_delimiter = ',')]
        aov: Vec<rondo::film::Aov>,
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
        /// With --serve: make the file:line:col of a picked entity a link that opens it in an
        /// editor, from TEMPLATE with {path}, {line} and {col} filled in, e.g.
        /// 'vscode://file/{path}:{line}:{col}' (VS Code) or
        /// 'idea://open?file={path}&line={line}' (JetBrains).
        #[arg(long, value_name = "TEMPLATE", requires = "serve", value_parser = rondo::serve::parse_editor_url)]
        editor_url: Option<String>,
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
    /// Write a scene for other renderers: DIR/scene.json (camera, settings, sky, materials as
    /// rondo reads them, spheres, planes) and world-space triangles as binary PLY files, one per
    /// material, every mesh placement flattened (benches/suite/).
    Export {
        /// Scene file (.ron).
        scene: PathBuf,
        /// Output directory (created if missing; not a symlink).
        #[arg(short, long)]
        output: PathBuf,
        /// Refuse scenes of more triangles than this, instances flattened.
        #[arg(long, default_value_t = rondo::export::MAX_TRIANGLES,
              value_parser = clap::value_parser!(u64).range(1..=rondo::export::MAX_TRIANGLES))]
        max_triangles: u64,
    },
    /// Serve the Language Server Protocol on standard input and output, for editors: diagnostics
    /// as you type (the loader's errors, `check`'s warnings), completion, hover, go to
    /// definition and the outline of scene and prefab files. Exit status 0 after the client's
    /// `shutdown` and `exit`.
    Lsp,
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

/// Parses the command line (clap exits with status 2 on a usage error) and runs it; any other
/// error exits with status 1. Output cut short by its reader (`| head`) ends quietly, status 0.
fn main() {
    let cli = Cli::parse();
    // SIGINT, SIGTERM or SIGHUP in the middle of a write removes the temporary before exiting.
    let installed = rondo::output_file::remove_temporaries_on_termination()
        .context("cannot install the signal handler");
    if let Err(e) = installed.and_then(|()| run(cli)) {
        // The reader of the output has all it wanted (`| head`): not a failure.
        if rondo::cli::is_closed_pipe(e.as_ref()) {
            return;
        }
        eprintln!("error: {}", rondo::cli::error_text(e.as_ref()));
        std::process::exit(EXIT_INPUT);
    }
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Check { scene } => check::run(&scene),
        Command::Lsp => std::process::exit(rondo::lsp::serve_stdio()),
        Command::Export {
            scene,
            output,
            max_triangles,
        } => export::run(&scene, &output, max_triangles),
        Command::Bench { what } => bench_command::run(what),
        Command::Render {
            scene,
            output,
            samples,
            resume,
            aov,
            options,
        } => render::run(&scene, &output, &options, &aov, samples, resume),
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
        Command::Diff {
            image,
            reference,
            error_image,
        } => diff::run(&image, &reference, error_image.as_deref()),
        Command::Watch {
            scene,
            output,
            serve,
            allow_host,
            editor_url,
            first_spp,
            options,
        } => {
            let serve = serve.map(|addr| watch::Serve {
                addr,
                allowed_hosts: allow_host,
                editor_url,
            });
            watch::run(&scene, output, first_spp, &options, serve)
        }
    }
}
