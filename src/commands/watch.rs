//! `rondo watch`: the live loop, printed and optionally served.

use std::path::{Path, PathBuf};

use anyhow::Result;

use super::args::RenderArgs;
use rondo::cli::check_output_file;
use rondo::watch::Watch;

/// How `rondo watch --serve` serves.
pub struct Serve {
    /// `--serve ADDR` (`None`: the default address).
    pub addr: Option<String>,
    /// `--allow-host`.
    pub allowed_hosts: Vec<String>,
    /// `--editor-url`.
    pub editor_url: Option<String>,
}

/// `rondo watch`: runs until Ctrl-C, one line per reload on stderr; with `serve`, also serves
/// the live viewer, which shows each pass denoised too and what each pixel shows (picking).
/// `--denoise` needs the denoiser: it is loaded before anything else, so that a missing library
/// is an error, not a warning later.
pub fn run(
    scene: &Path,
    output: Option<PathBuf>,
    first_spp: u32,
    args: &RenderArgs,
    serve: Option<Serve>,
) -> Result<()> {
    let mut options =
        args.watch_options(scene, output.as_deref().unwrap_or(Path::new("")), first_spp)?;
    options.output = output;
    if let Some(output) = &options.output {
        check_output_file(output)?;
    }
    if options.denoise == Some(true) {
        rondo::denoise::Denoiser::shared()?;
    }
    let mut watch = Watch::new(options)?;
    // Viewer hook: start the server and feed it every reload, pass and report.
    let viewer = match serve {
        Some(Serve {
            addr,
            allowed_hosts,
            editor_url,
        }) => {
            let fall_back = addr.is_none();
            let addr =
                rondo::serve::parse_addr(addr.as_deref().unwrap_or(rondo::serve::DEFAULT_ADDR))?;
            let previews = rondo::watch::Previews::default();
            watch.set_previews(previews.clone());
            let serve_options = rondo::serve::Options {
                allowed_hosts,
                editor_url,
                scene: Some(scene.to_path_buf()),
                previews: Some(previews),
                ..Default::default()
            };
            let (viewer, feed) = rondo::serve::Viewer::start(addr, fall_back, serve_options)?;
            if let Some(warning) = viewer.exposure_warning() {
                eprintln!("warning: {warning}");
            }
            eprintln!("viewer: {}", viewer.url());
            watch.set_observer(feed.observer());
            watch.set_progress(feed.progress_bar());
            // Denoised passes reach the viewer only when a denoise is asked for (`--denoise` or
            // the scene's setting): the library is loaded for nothing else.
            watch.set_denoise_sink(feed.denoise_sink());
            watch.set_pick_sink(feed.pick_sink());
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
