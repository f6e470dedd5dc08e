//! The `rondo` command line.

use std::path::{Path, PathBuf};
use std::time::Duration;

use anyhow::{Context, Result, bail};
use clap::{Args, Parser, Subcommand};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use rondo::film::OutputKind;
use rondo::scene::format::Method;
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
        #[arg(short, long)]
        output: PathBuf,
        #[command(flatten)]
        options: RenderArgs,
    },
    /// Measure rendering speed.
    Bench {
        #[command(subcommand)]
        what: BenchCommand,
    },
}

#[derive(Subcommand)]
enum BenchCommand {
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
}

#[derive(Args)]
struct RenderArgs {
    /// Samples per pixel (overrides the scene).
    #[arg(long)]
    spp: Option<u32>,
    /// Image width (overrides the scene).
    #[arg(long)]
    width: Option<u32>,
    /// Image height (overrides the scene).
    #[arg(long)]
    height: Option<u32>,
    /// Rays per path, camera ray included (overrides the scene).
    #[arg(long)]
    max_depth: Option<u32>,
    /// Random seed (overrides the scene).
    #[arg(long)]
    seed: Option<u64>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Light-transport method: naive, nee or mis (overrides the scene).
    #[arg(long)]
    method: Option<Method>,
}

impl RenderArgs {
    fn renderer(&self) -> Result<Renderer> {
        if self.threads == Some(0) {
            bail!("--threads must be at least 1");
        }
        let mut r = Renderer::new(self.threads, PassPlan::Single)?;
        r.set_overrides(Overrides {
            width: self.width,
            height: self.height,
            spp: self.spp,
            max_depth: self.max_depth,
            seed: self.seed,
            method: self.method,
        });
        Ok(r)
    }
}

fn main() {
    if let Err(e) = run(Cli::parse()) {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Render {
            scene,
            output,
            options,
        } => render(&scene, &output, &options),
        Command::Bench {
            what:
                BenchCommand::Render {
                    scene,
                    runs,
                    options,
                },
        } => bench_render(&scene, runs, &options),
    }
}

fn render(scene: &Path, output: &Path, options: &RenderArgs) -> Result<()> {
    if OutputKind::from_path(output).is_none() {
        bail!("{}: output must end in .png or .exr", output.display());
    }
    let mut r = options.renderer()?;
    let s = r.load(scene)?.settings;
    r.set_output(Some(output), false);
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
    eprintln!("{}", summary(&r, wall));
    Ok(())
}

/// The one-line summary printed after a render.
fn summary(r: &Renderer, wall: Duration) -> String {
    let s = r.settings();
    let stats = r.stats();
    let secs = wall.as_secs_f64().max(1e-9);
    let samples = f64::from(s.width) * f64::from(s.height) * f64::from(s.spp);
    format!(
        "{}x{}, {} spp, {:.2} s, {:.2} M samples/s, {:.2} M rays/s, BVH {:.2} ms ({} primitives), {} non-finite samples",
        s.width,
        s.height,
        s.spp,
        secs,
        samples / secs / 1e6,
        stats.rays as f64 / secs / 1e6,
        r.timings().bvh.as_secs_f64() * 1e3,
        r.primitive_count(),
        stats.nonfinite,
    )
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
