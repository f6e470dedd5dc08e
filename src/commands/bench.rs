//! `rondo bench …`: the benchmark drivers (layout, instances, render, watch, accuracy,
//! environment).

use std::path::{Path, PathBuf};
use std::time::Duration;

use anyhow::{Context, Result, bail};

use super::args::RenderArgs;
use super::render::summary;
use rondo::Renderer;
use rondo::bench::layout;
use rondo::cli::check_output_dir;
use rondo::watch::{Report, WatchOptions, WatchSession};

pub fn layout(
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

/// `rondo bench environment`: checks the output directory, if any, before measuring.
pub fn environment(width: u32, height: u32, runs: usize, out: Option<&Path>) -> Result<()> {
    if let Some(dir) = out {
        check_output_dir(dir)?;
    }
    let command = std::env::args().collect::<Vec<_>>().join(" ");
    rondo::bench::environment::main(width, height, runs, out, &command).map_err(anyhow::Error::msg)
}

/// `rondo bench instances`: one child process per count, so each reports its own peak memory.
pub fn instances(
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

pub fn render(scene: &Path, runs: usize, options: &RenderArgs) -> Result<()> {
    let mut times = Vec::new();
    let mut r = options.renderer()?;
    for run in 0..runs.max(1) {
        // A renderer per run: reloading an unchanged scene into a finished film renders nothing.
        if run > 0 {
            r = options.renderer()?;
        }
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

pub fn summary_from(r: &Renderer, wall: Duration, rays: u64) -> String {
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

/// `rondo bench watch`: edits a temporary copy of the scene and times each save to the first
/// and to the full-quality image, as seen by the watch loop's own reports.
pub fn watch(scene: &Path, runs: usize, first_spp: u32, options: &RenderArgs) -> Result<()> {
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
pub type EditTimes = Vec<(&'static str, Vec<Duration>, Vec<Duration>)>;

/// Times `runs` edits of each kind, each replacing `from` by `to` (or back) in a copy of the
/// scene under `dir`.
pub fn time_edits(
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

/// `rondo bench accuracy`: runs the sweep, printing a line per render, then the summary.
pub fn accuracy(options: &rondo::bench::accuracy::AccuracyOptions) -> Result<()> {
    check_output_dir(&options.out)?;
    if let Some(dir) = &options.keep_images {
        check_output_dir(dir)?;
    }
    let report = rondo::bench::accuracy::run(options, |r| {
        eprintln!(
            "{:>5} {:>11}{} {:>6} spp  {:9.4} s  rmse {:.4e}  rel_mse {:.4e}  mae {:.4e}  lamp-out rmse {:.4e}",
            r.method.to_string(),
            r.sampler.to_string(),
            if r.denoised {
                " + denoiser"
            } else {
                "           "
            },
            r.spp,
            r.seconds,
            r.metrics.rmse,
            r.metrics.rel_mse,
            r.metrics.mae,
            r.lamp_out_rmse
        );
    })?;
    println!("{}", rondo::bench::accuracy::summary_markdown(&report));
    println!(
        "wrote {}/accuracy.csv, accuracy.svg, accuracy_relative.svg, accuracy_lamp_out.svg, summary.md{}",
        options.out.display(),
        options
            .keep_images
            .as_ref()
            .map_or(String::new(), |d| format!(
                " and the images in {}",
                d.display()
            ))
    );
    Ok(())
}
