//! Live editing: re-render a scene whenever a file it depends on is saved.
//!
//! Two halves:
//! - [`FileWatcher`] turns notify's raw file events into [`FileEvent`]s on a channel, the moment
//!   they happen. It knows nothing of the ECS or the renderer, only a cancel flag that it raises
//!   so the pass in flight stops within one band of rows.
//! - [`Watch`] is the loop that drives a [`Renderer`] through its public API: reload on an event,
//!   keep the last good scene (and image) when a save is bad, render progressively and write the
//!   image after each pass, and describe each step as a [`Report`]. [`WatchSession`] runs it on a
//!   thread for tests and tools.
//!
//! One file per concept: the loop and the render of each pass in `mod.rs`; file events and the
//! watched set in `files.rs`; the changes waiting to be loaded in `pending.rs`; loading them in
//! `reload.rs`; [`Report`]s in `report.rs`; the denoise thread in `denoiser.rs`; the thread
//! harness in `session.rs`.
//!
//! # What is watched
//!
//! Directories, not files, because editors save in different ways. Vim and many IDEs write a
//! temporary file and rename it over the original: a watch on the original file (an inode) dies
//! with it, while a watch on the directory sees the new file arrive under the same name.
//! Truncate-then-write and delete-then-recreate look the same from the directory. Beyond the
//! directories of the dependencies:
//! - the *parent* of each of them, so that a directory deleted, renamed or replaced
//!   (`mv prefabs old && cp -r old prefabs`) is seen and watched again (the old watch follows the
//!   old inode);
//! - for a dependency whose directory does not exist (yet), the nearest existing ancestor, so
//!   that creating the directory arms a watch on it;
//! - for a symlinked dependency, the directory of its target as well;
//! - after a failed load, every file that load asked for (a texture, mesh or prefab that does not
//!   exist yet), not only the dependencies of the last good load.
//!
//! Whenever the set of watched directories grows, the scene is read once more right away: a
//! file written between the load and the new watch would otherwise go unnoticed.
//!
//! # When a save is loaded
//!
//! As soon as it is complete. On Linux the kernel says when: the writer closed the file
//! (`IN_CLOSE_WRITE`) or renamed it into place (`IN_MOVED_TO`). The loop then loads at once.
//! A file written through a descriptor that is still open (a write event without its close)
//! holds the load back until the writer closes it, however long it pauses mid-save (bounded
//! only by [`OPEN_WRITER_PATIENCE`] of quiet, for a close that never comes). Other unfinished
//! changes (a file created or removed, a directory created: its files follow) wait until
//! [`DEBOUNCE`] has passed without events, which is also the fallback where the platform
//! reports no close. A load that fails is not reported at once: the rest of the save may follow
//! (a delete-then-recreate), so the error waits three windows for more events and is
//! reported only if none come ([`Report::Deferred`] says that it waits). A half-written save is
//! therefore never loaded on Linux (its close has not happened) and never reported as an
//! error that the complete save then replaces. A newer event cancels the pass in flight and
//! starts over. A metadata-only event (`touch`, the `chmod` at the end of a vim save) neither
//! cancels nor reloads, unless the last load failed (a `chmod +r` may fix it); and a reload that
//! changes nothing keeps the render going.
//!
//! # The event point
//!
//! Everything the loop does goes out through one function, `Emitter::emit`, as a [`Report`]:
//! [`Report::Started`] when a reload has loaded and its render begins, [`Report::Wrote`] after
//! each pass that improved the image (with the [`Film`] it came from), [`Report::Failed`] with a
//! `file:line:col` message, [`Report::Rendered`] when the render is done (complete or
//! superseded), plus [`Report::Watching`], [`Report::SceneMissing`], [`Report::Deferred`] and
//! [`Report::Warning`]. Each report goes first to the [`Observer`] set with
//! [`Watch::set_observer`] (which also gets the film for `Wrote`), then to the callback of
//! [`Watch::run`]. An observer runs on the render thread: it must return quickly (copy what it
//! needs and hand it to its own thread).
//!
//! ```no_run
//! use std::time::Duration;
//! use rondo::watch::{Report, WatchOptions, WatchSession};
//!
//! let session = WatchSession::start(WatchOptions::new("scene.ron", "out.png"))?;
//! // The first render; then edit scene.ron and wait for the next `Rendered`.
//! let done = session.wait_for(Duration::from_secs(20), |r| {
//!     matches!(r, Report::Rendered(r) if r.completed())
//! });
//! assert!(done.is_ok());
//! session.stop()?;
//! # Ok::<(), rondo::watch::WatchError>(())
//! ```

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, Receiver, Sender};
use std::time::{Duration, Instant};

use crate::app::Renderer;
use crate::ecs::resources::{Counters, PassPlan};
use crate::film::{Film, OutputKind};

mod denoiser;
mod error;
mod files;
mod options;
mod pending;
mod reload;
mod report;
mod session;

pub use denoiser::{DenoiseSink, Denoised, DenoisedFrame, HIGH_QUALITY_FROM_SPP};
use denoiser::{DenoiseWorker, Denoising, WorkerNews};
pub use error::WatchError;
use files::IDLE_POLL;
pub use files::*;
pub use options::WatchOptions;
use pending::Pending;
pub use report::*;
pub use session::WatchSession;

// ------------------------------------------------------------------------------------------------
// The loop: events → Renderer.

/// The one point through which the loop reports (see the module docs, "The event point").
struct Emitter<'a> {
    observer: Option<Observer>,
    report: &'a mut dyn FnMut(Report),
}

impl Emitter<'_> {
    fn emit(&mut self, report: Report, film: Option<&Film>) {
        if let Some(observer) = &mut self.observer {
            observer(&report, film);
        }
        (self.report)(report);
    }
}

/// Stops a running [`Watch`] from any thread (a Ctrl-C handler, a test).
#[derive(Clone)]
pub struct StopHandle {
    stopped: Arc<AtomicBool>,
    cancel: Arc<AtomicBool>,
    wake: Sender<FileEvent>,
}

impl StopHandle {
    /// Asks the loop to stop: the pass in flight is cancelled and the loop returns promptly. The
    /// image on disk is the last one fully written.
    pub fn stop(&self) {
        self.stopped.store(true, Ordering::SeqCst);
        self.cancel.store(true, Ordering::SeqCst);
        let _ = self.wake.send(FileEvent::Wake);
    }

    /// Whether [`StopHandle::stop`] was called.
    pub fn is_stopped(&self) -> bool {
        self.stopped.load(Ordering::SeqCst)
    }
}

/// The samples of the image on disk for the current scene. After a cancelled pass the film
/// restarts from zero; images are written again only once they are better than this (passes are
/// deterministic, so fewer samples would only overwrite a better image).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord)]
struct OnDisk {
    /// Samples per pixel.
    samples: u32,
    /// Whether it is real samples and not the preview (ordered after the preview of the same
    /// count: a 1-spp scene's real pass replaces its 1-sample preview).
    real: bool,
}

/// The render of the current scene, until it completes or a newer save replaces it.
struct Job {
    report: ReloadReport,
    /// When the save happened.
    saved: Instant,
    /// Counters before the load, to tell what the first frame rebuilt.
    before: Counters,
}

/// The watch loop: owns a [`Renderer`] and a [`FileWatcher`]. Create with [`Watch::new`] (files
/// are watched from then on), then call [`Watch::run`], on this thread or another.
pub struct Watch {
    options: WatchOptions,
    renderer: Renderer,
    watcher: FileWatcher,
    events: Receiver<FileEvent>,
    stop: StopHandle,
    cancel: Arc<AtomicBool>,
    output_key: Option<PathBuf>,
    observer: Option<Observer>,
    job: Option<Job>,
    /// The image on disk (for the scene in the world).
    on_disk: OnDisk,
    /// The files of the last good load.
    good_files: Vec<PathBuf>,
    reloads: u64,
    last_error: Option<String>,
    missing: bool,
    /// Whether the user was told that the output is also one of the scene's textures.
    warned_output: bool,
    /// Where denoised passes are shown (the viewer), if anywhere.
    denoise_sink: Option<DenoiseSink>,
    /// What the current scene denoises.
    denoising: Denoising,
    /// The denoise thread, started with the first pass to denoise.
    denoiser: Option<DenoiseWorker>,
}

impl Watch {
    /// Checks the options, builds the renderer and starts watching the scene's directory.
    pub fn new(options: WatchOptions) -> Result<Self, WatchError> {
        if let Some(output) = &options.output
            && OutputKind::from_path(output).is_none()
        {
            return Err(WatchError::Output(output.clone()));
        }
        let plan = PassPlan::Progressive {
            first: options.first_pass.max(1),
        };
        let mut renderer = Renderer::new(options.threads, plan)?;
        renderer.set_overrides(options.overrides);
        renderer.set_layout(options.layout);
        // Every change to a dependency comes as an event, passed on before each load.
        renderer.set_reported_changes(true);
        // The loop writes the image itself: it knows which writes are worth making (see
        // `OnDisk`) and times them apart from the ECS update.
        renderer.set_output(None, false);
        let cancel = renderer.cancel_flag();
        let (tx, events) = mpsc::channel();
        let mut watcher = FileWatcher::new(cancel.clone(), tx.clone())?;
        if let Some(output) = &options.output {
            watcher.ignore(output);
        }
        let scene = vec![options.scene.clone()];
        if watch_key(&options.scene).is_err() {
            let message = "its directory does not exist".to_string();
            return Err(WatchError::Directory {
                path: options.scene,
                message,
            });
        }
        if let Some(message) = watcher.set_files(&scene).1.into_iter().next() {
            return Err(WatchError::Directory {
                path: options.scene,
                message,
            });
        }
        let output_key = options
            .output
            .as_deref()
            .and_then(|o| watch_key(o).ok())
            .map(|(_, key)| key);
        let stop = StopHandle {
            stopped: Arc::new(AtomicBool::new(false)),
            cancel: cancel.clone(),
            wake: tx,
        };
        Ok(Self {
            options,
            renderer,
            watcher,
            events,
            stop,
            cancel,
            output_key,
            observer: None,
            job: None,
            on_disk: OnDisk::default(),
            good_files: scene,
            reloads: 0,
            last_error: None,
            missing: false,
            warned_output: false,
            denoise_sink: None,
            denoising: Denoising::Off,
            denoiser: None,
        })
    }

    /// Shows denoised passes through `sink` (the viewer): from now on every pass is denoised
    /// on a thread of its own unless the scene or the options turn the denoiser off.
    pub fn set_denoise_sink(&mut self, sink: DenoiseSink) {
        self.denoise_sink = Some(sink);
    }

    /// A handle that stops [`Watch::run`].
    pub fn stop_handle(&self) -> StopHandle {
        self.stop.clone()
    }

    /// Sets the observer that sees every report, with the film of each written pass.
    pub fn set_observer(&mut self, observer: Observer) {
        self.observer = Some(observer);
    }

    /// Attaches a (hidden) progress bar that the renderer advances by rows rendered (the live
    /// viewer's progress indicator).
    pub fn set_progress(&mut self, bar: indicatif::ProgressBar) {
        self.renderer.set_progress(Some(bar));
    }

    /// Loads and renders the scene, then re-renders on every relevant save until stopped.
    /// Everything that happens is passed to `report` (after the observer, if any).
    pub fn run(mut self, mut report: impl FnMut(Report)) {
        let mut out = Emitter {
            observer: self.observer.take(),
            report: &mut report,
        };
        out.emit(self.watching_report(), None);
        let window = self.options.debounce;
        let mut pending = Some(Pending::initial());
        loop {
            while let Ok(event) = self.events.try_recv() {
                Self::absorb(event, &mut pending, &mut out);
            }
            self.denoiser_news(&mut out);
            if self.stop.is_stopped() {
                break;
            }
            // Times and permissions cannot change what a good scene renders (a `touch`, or the
            // `chmod` that ends a vim save); they matter only to a load that failed.
            if self.last_error.is_none() && !self.missing {
                pending.take_if(|p| !p.content && p.failed.is_none());
            }
            if let Some(p) = pending.as_mut()
                && std::mem::take(&mut p.rearm)
            {
                let (_, warnings) = self.watcher.rearm();
                for message in warnings {
                    out.emit(Report::Warning { message }, None);
                }
            }
            let now = Instant::now();
            let due = pending.as_ref().map(|p| p.due(window));
            if let Some(p) = pending.take_if(|_| due.is_some_and(|d| d <= now)) {
                pending = self.act(p, &mut out);
                continue;
            }
            // Render while waiting, unless a change cancelled the pass.
            if self.job.is_some() && !self.cancel.load(Ordering::SeqCst) {
                self.step(&mut out);
                continue;
            }
            let until = due.unwrap_or(now + IDLE_POLL);
            if let Ok(event) = self
                .events
                .recv_timeout(until.saturating_duration_since(now))
            {
                Self::absorb(event, &mut pending, &mut out);
            }
        }
    }

    /// Reports what the denoise thread finished.
    fn denoiser_news(&mut self, out: &mut Emitter<'_>) {
        let Some(worker) = &self.denoiser else {
            return;
        };
        for news in worker.news() {
            match news {
                WorkerNews::Denoised(d) => out.emit(Report::Denoised(d), None),
                WorkerNews::Failed(message) => out.emit(
                    Report::Warning {
                        message: format!("{message}; showing the raw image"),
                    },
                    None,
                ),
            }
        }
    }

    /// Hands the pass in the film to the denoise thread, if the scene denoises.
    fn denoise_pass(&mut self, reload: u64, saved: Instant) {
        if self.denoising == Denoising::Off {
            return;
        }
        let film = self.renderer.film();
        let quality = if film.samples < HIGH_QUALITY_FROM_SPP && !self.renderer.is_complete() {
            crate::denoise::Quality::Fast
        } else {
            crate::denoise::Quality::High
        };
        let job = denoiser::Job {
            reload,
            samples: film.samples,
            images: crate::denoised::FilmImages::of(film),
            quality,
            write: match self.denoising {
                Denoising::Output => self.options.output.clone(),
                _ => None,
            },
            saved,
        };
        let sink = self.denoise_sink.clone();
        self.denoiser
            .get_or_insert_with(|| DenoiseWorker::start(sink))
            .submit(job);
    }

    /// Folds one event into the pending changes.
    fn absorb(event: FileEvent, pending: &mut Option<Pending>, out: &mut Emitter<'_>) {
        match event {
            FileEvent::Changed(change) => match pending {
                Some(p) => p.add(change),
                None => {
                    let mut p = Pending::initial();
                    p.completed = false;
                    p.content = false;
                    p.last = change.at;
                    p.add(change);
                    *pending = Some(p);
                }
            },
            FileEvent::Error(message) => out.emit(Report::Warning { message }, None),
            FileEvent::Wake => {}
        }
    }

    fn watching_report(&self) -> Report {
        Report::Watching {
            files: self.watcher.file_count(),
            directories: self.watcher.directories(),
        }
    }

    /// Runs one frame of the current job: applies the scene if new, renders a pass, writes the
    /// image if it improved, and finishes the job when the film is complete.
    fn step(&mut self, out: &mut Emitter<'_>) {
        let Some(job) = self.job.as_mut() else {
            return;
        };
        let passes = self.renderer.counters().passes;
        let start = Instant::now();
        self.renderer.run_once();
        let wall = start.elapsed();
        let counters = self.renderer.counters();
        let timings = self.renderer.timings();
        let r = &mut job.report;
        if !r.applied {
            r.applied = true;
            r.changes = self.renderer.change_summary();
            r.bvh_rebuilt = counters.bvh_builds > job.before.bvh_builds;
            r.bvh = if r.bvh_rebuilt {
                timings.bvh
            } else {
                Duration::ZERO
            };
            r.materials_synced = counters.material_syncs > job.before.material_syncs;
            r.primitives = self.renderer.primitive_count();
            r.ecs = wall.saturating_sub(timings.pass + r.bvh);
            if !r.changes.is_empty() || r.number == 0 {
                // A new image; the one on disk is of another scene.
                self.on_disk = OnDisk::default();
            }
        }
        r.counters = counters;
        let complete = self.renderer.is_complete();
        if counters.passes == passes && !complete {
            // Cancelled: a change is on its way (or we are stopping). The film starts over.
            r.restarts += 1;
            return;
        }
        let mut denoise = None;
        if counters.passes > passes {
            let film = self.renderer.film();
            let now = OnDisk {
                samples: film.samples,
                real: !self.renderer.film_is_preview(),
            };
            if r.first_pass.is_none() {
                r.first_pass = Some((now.samples, timings.pass));
                r.preview = !now.real;
            }
            if now > self.on_disk {
                // No output file with `--serve` alone: the observer shows the image. A
                // denoised output is written by the denoise thread.
                let written = match self.options.output.as_deref() {
                    Some(o) if self.denoising != Denoising::Output => film.write_live(o),
                    _ => Ok(()),
                };
                match written {
                    Ok(()) => {
                        let at = Instant::now();
                        let new_scene = self.on_disk == OnDisk::default();
                        self.on_disk = now;
                        r.samples = now.samples;
                        if r.first_image.is_none() {
                            r.first_image = Some(at.saturating_duration_since(job.saved));
                        }
                        let report = Report::Wrote {
                            reload: r.number,
                            samples: now.samples,
                            preview: !now.real,
                            spp: r.spp,
                            changes: r.changes.clone(),
                            new_scene,
                            at,
                        };
                        out.emit(report, Some(film));
                        if now.real {
                            denoise = Some((r.number, job.saved));
                        }
                    }
                    Err(e) => {
                        let output = self.options.output.as_deref().unwrap_or(Path::new(""));
                        let message = format!("{}: cannot write image: {e}", output.display());
                        out.emit(Report::Warning { message }, None);
                    }
                }
            }
        }
        if complete {
            // (Also when the reload changed nothing and the film was already complete.)
            r.samples = self.on_disk.samples;
            r.full = Some(job.saved.elapsed());
            if let Some(job) = self.job.take() {
                out.emit(Report::Rendered(job.report), None);
            }
        }
        if let Some((reload, saved)) = denoise {
            self.denoise_pass(reload, saved);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_reload_superseded_after_applying_its_change_makes_the_next_image_a_new_scene() {
        // The sequence of CI's browser failure: red, blue, then green applied by a reload whose
        // pass is cancelled by the next file event, and a reload of the same file that
        // therefore changes nothing itself. Its image is still of another scene than the last
        // one written (what the viewer's A/B keys on).
        let temp = tempfile::Builder::new()
            .prefix("rondo-watch-unit-")
            .tempdir()
            .expect("temp dir");
        let dir = temp.path();
        let scene = dir.join("scene.ron");
        let save = |colour: &str| {
            let text = format!(
                "Scene(camera: Camera(position: (0, 0, -5), look_at: (0, 0, 0), fov: 40.0),
                 settings: Settings(width: 8, height: 8, spp: 2, max_depth: 2),
                 materials: {{ \"wall\": Light(emit: Constant({colour}), intensity: 1.0) }},
                 entities: [Entity(material: \"wall\", shape: Sphere(center: (0, 0, 0), radius: 1))])"
            );
            std::fs::write(&scene, text).expect("write scene");
        };
        save("(1, 0, 0)");
        let mut w = Watch::new(WatchOptions::new(&scene, dir.join("out.png"))).expect("watch");
        let mut reports = Vec::new();
        let mut sink = |r: Report| reports.push(r);
        let mut out = Emitter {
            observer: None,
            report: &mut sink,
        };
        let render = |w: &mut Watch, out: &mut Emitter<'_>| {
            assert!(w.reload(&Pending::initial(), out).is_ok(), "loads");
            while w.job.is_some() {
                w.step(out);
            }
        };
        render(&mut w, &mut out);
        save("(0, 0, 1)");
        render(&mut w, &mut out);
        save("(0, 1, 0)");
        assert!(w.reload(&Pending::initial(), &mut out).is_ok(), "loads");
        w.cancel.store(true, Ordering::SeqCst);
        w.step(&mut out);
        render(&mut w, &mut out);
        drop(out);
        let firsts: Vec<(u64, bool, bool)> = reports
            .iter()
            .filter_map(|r| match r {
                Report::Wrote {
                    reload,
                    changes,
                    new_scene,
                    ..
                } => Some((*reload, changes.is_empty(), *new_scene)),
                _ => None,
            })
            .filter(|&(_, _, new_scene)| new_scene)
            .collect();
        assert_eq!(
            firsts,
            [(0, false, true), (1, false, true), (3, true, true)],
            "the first image of each scene, with whether its reload changed nothing"
        );
    }
}
