//! `rondo bench …`: the benchmark drivers (layout, instances, render, watch, load, accuracy,
//! environment).

use rondo::cli::print_line;
use std::path::{Path, PathBuf};
use std::time::Duration;

use anyhow::{Context, Result, bail};

use super::args::RenderArgs;
use super::render::summary;
use rondo::Renderer;
use rondo::bench::layout;
use rondo::bench::load_watch_table::WatchTable;
use rondo::cli::check_output_dir;

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
    print_line(format_args!(
        "wrote {}/layout.csv, layout.md and layout.svg",
        options.out.display()
    ))?;
    Ok(())
}

/// `rondo bench environment`: checks the output directory, if any, before measuring.
pub fn environment(width: u32, height: u32, runs: usize, out: Option<&Path>) -> Result<()> {
    if let Some(dir) = out {
        check_output_dir(dir)?;
    }
    let command = std::env::args().collect::<Vec<_>>().join(" ");
    let (table, written) = rondo::bench::environment::main(width, height, runs, out, &command)
        .map_err(anyhow::Error::msg)?;
    print_line(table)?;
    if let Some(path) = written {
        print_line(format_args!("wrote {}", path.display()))?;
    }
    Ok(())
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
        print_line(instances::csv_line(&run))?;
        return Ok(());
    }
    let exe = std::env::current_exe().context("locating the rondo binary")?;
    print_line(instances::CSV_HEADER)?;
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
        print_line(format_args!("{line}"))?;
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
    print_line(format_args!("median: {}", summary_from(&r, wall, rays)))?;
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

/// `rondo bench watch`: times each kind of edit the scene has a target for (or those of
/// `kinds`), from each save to the first and to the full-quality image, as seen by the watch
/// loop's own reports.
///
/// The edits are saved to a copy beside the scene, so that its relative paths (meshes,
/// textures, prefabs, glTF files) resolve as in the original: a file created exclusively under
/// an unpredictable name (`.rondo-bench-XXXXXX.ron`, never an existing file), written through a
/// handle checked to be that file, and removed when the benchmark ends, fails or is stopped by
/// Ctrl-C. The image goes to a private temporary directory.
pub fn watch(
    scene: &Path,
    runs: usize,
    first_spp: u32,
    kinds: &[String],
    options: &RenderArgs,
) -> Result<()> {
    use rondo::bench::load_watch::{self, Kind};
    use rondo::bench::load_watch_time::{self, Interrupt};
    let original = rondo::scene::bounded_read::read_text(scene)
        .map_err(|e| anyhow::anyhow!("{}: cannot read: {e}", scene.display()))?;
    let mut edits = load_watch::find_edits(scene, &original).map_err(anyhow::Error::msg)?;
    if !kinds.is_empty() {
        for name in kinds {
            let kind = Kind::from_name(name).context("checked by the argument parser")?;
            if !edits.iter().any(|e| e.kind == kind) {
                bail!("{}: nothing to edit for a {name} edit", scene.display());
            }
        }
        edits.retain(|e| kinds.iter().any(|k| k == e.kind.name()));
    }
    if edits.is_empty() {
        bail!(
            "{}: nothing to edit (no material colour, sphere, moved entity, mesh or second material)",
            scene.display()
        );
    }
    let dir = match scene.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let mut copy = tempfile::Builder::new()
        .prefix(".rondo-bench-")
        .suffix(".ron")
        .tempfile_in(dir)
        .with_context(|| {
            format!(
                "cannot create the edited copy of the scene in {}",
                dir.display()
            )
        })?;
    {
        use std::io::Write as _;
        copy.write_all(original.as_bytes())
            .and_then(|()| copy.flush())
            .with_context(|| format!("{}: cannot write", copy.path().display()))?;
    }
    // A private directory of a fresh, unpredictable name (no planted files or symlinks) for the
    // image, removed with its contents when dropped.
    let temp = tempfile::Builder::new()
        .prefix("rondo-bench-watch-")
        .tempdir()
        .context("cannot create a temporary directory")?;
    let watch_options =
        options.watch_options(copy.path(), &temp.path().join("out.png"), first_spp)?;
    let interrupt = Interrupt::install();
    let save = |text: &str| {
        use std::io::Write as _;
        // Opened again by path and checked to be the file created above (tempfile's `reopen`),
        // then truncated and written: an in-place save that ends with a close, as an editor's.
        let mut file = copy.reopen()?;
        file.set_len(0)?;
        file.write_all(text.as_bytes())
    };
    let timed = load_watch_time::time_edits(
        watch_options,
        &original,
        &edits,
        runs,
        &interrupt,
        save,
        |line| eprintln!("{line}"),
    );
    drop(copy);
    drop(temp);
    let (_, timings) = timed.map_err(anyhow::Error::msg)?;
    let stats = |v: &[Duration]| {
        let (median, min) = load_watch_time::median_min(v);
        let ms = |d: Duration| d.as_secs_f64() * 1e3;
        format!("{:8.1} ms (min {:8.1})", ms(median), ms(min))
    };
    print_line(format_args!(
        "watch latency, save -> image written, {} (loaded when the save completes, else after {} ms quiet; first pass {first_spp} spp), median of {} edits:",
        scene.display(),
        rondo::watch::DEBOUNCE.as_millis(),
        runs.max(1)
    ))?;
    for t in timings {
        print_line(format_args!(
            "  {:<15} edit: first image {}, full quality {}  ({})",
            t.kind.name(),
            stats(&t.first_image),
            stats(&t.full),
            t.target
        ))?;
    }
    Ok(())
}

/// `rondo bench load`: a line per scene on stderr as it is measured, then the table on stdout
/// (unless `with_load` is false); then, for `watch`'s sizes, the watch-mode table. Scenes are
/// written to a private temporary directory (a fresh, unpredictable name: no planted files or
/// symlinks), removed at the end, on an error, or after Ctrl-C (whose first press stops the
/// benchmark).
pub fn load(kinds: &[String], sizes: &[usize], with_load: bool, watch: &WatchTable) -> Result<()> {
    use rondo::bench::{load, load_watch_table, load_watch_time::Interrupt};
    if let Some(k) = kinds
        .iter()
        .find(|k| !load::KINDS.iter().any(|(n, _)| n == k))
    {
        let known: Vec<&str> = load::KINDS.iter().map(|k| k.0).collect();
        bail!("unknown kind {k:?} (expected {})", known.join(", "));
    }
    let temp = tempfile::Builder::new()
        .prefix("rondo-bench-load-")
        .tempdir()
        .context("cannot create a temporary directory")?;
    let interrupt = Interrupt::install();
    if with_load {
        let rows = load::run(kinds, sizes, &temp.path().join("load"), |r| {
            eprintln!(
                "{} {}: first image {:.1} ms CPU ({:.1} ms wall), check {:.1} ms CPU",
                r.kind,
                r.count,
                r.first_image.as_secs_f64() * 1e3,
                r.first_image_wall.as_secs_f64() * 1e3,
                r.check.as_secs_f64() * 1e3
            );
            interrupt.check()
        });
        print_line(load::markdown(&rows.map_err(anyhow::Error::msg)?))?;
    }
    if !watch.sizes.is_empty() {
        let rows = load_watch_table::watch_rows(watch, &temp.path().join("watch"), &interrupt)
            .map_err(anyhow::Error::msg)?;
        print_line(load_watch_table::watch_markdown(&rows, watch.edits))?;
    }
    Ok(())
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
    print_line(rondo::bench::accuracy::summary_markdown(&report))?;
    print_line(format_args!(
        "wrote {}/accuracy.csv, accuracy.svg, accuracy_relative.svg, accuracy_lamp_out.svg, summary.md{}",
        options.out.display(),
        options
            .keep_images
            .as_ref()
            .map_or(String::new(), |d| format!(
                " and the images in {}",
                d.display()
            ))
    ))?;
    Ok(())
}

/// `rondo bench lsp`: the language server's latencies on a generated scene, as a Markdown table.
pub fn lsp(entities: usize, edits: usize) -> Result<()> {
    let temp = tempfile::Builder::new()
        .prefix("rondo-bench-lsp-")
        .tempdir()
        .context("cannot create a temporary directory")?;
    let timings =
        rondo::bench::lsp::run(entities, edits, temp.path()).map_err(anyhow::Error::msg)?;
    print_line(rondo::bench::lsp::markdown(entities, &timings))?;
    Ok(())
}
