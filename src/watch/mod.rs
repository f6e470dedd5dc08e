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
//! One file per concept: the loop in `mod.rs`; file events and the watched set in `files.rs`;
//! the changes waiting to be loaded in `pending.rs`; the viewer's framing previews in `preview.rs`; loading them in `reload.rs`; the render of
//! each pass in `job.rs`; [`Report`]s in `report.rs`; the thread harness in `session.rs`.
//! The denoise thread beside the loop is [`crate::denoise::DenoiseWorker`].
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
//! Everything the loop does goes out through one function, `Reporter::emit`, as a [`Report`]:
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

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, Receiver, Sender};
use std::time::Instant;

use crate::app::Renderer;
use crate::denoise::{DenoiseSink, DenoiseWorker, WorkerNews};
use crate::ecs::resources::PassPlan;
use crate::film::{Film, OutputKind};

mod error;
mod files;
mod job;
mod options;
mod pending;
mod pick;
mod preview;
mod reload;
mod report;
mod session;

pub use error::WatchError;
use files::IDLE_POLL;
pub use files::*;
use job::{Job, OnDisk};
use options::Denoising;
pub use options::WatchOptions;
use pending::Pending;
use pick::Picking;
pub use pick::{PickSink, Picked};
pub use preview::{
    MAX_PREVIEW_DIVISOR, MAX_PREVIEW_SPP, PAUSE, PreviewImage, PreviewOutcome, PreviewRequest,
    Previews, preview_size,
};
pub use report::*;
pub use session::WatchSession;

// ------------------------------------------------------------------------------------------------
// The loop: events → Renderer.

/// The one point through which the loop reports (see the module docs, "The event point").
struct Reporter<'a> {
    observer: Option<Observer>,
    report: &'a mut dyn FnMut(Report),
}

impl Reporter<'_> {
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
    /// Where the ids of each scene go (the viewer's picking), if anywhere.
    picking: Option<Picking>,
    /// Where the viewer asks for framing previews, if anywhere.
    previews: Option<Previews>,
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
            picking: None,
            previews: None,
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
        let mut out = Reporter {
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
            let paused = self.serve_previews();
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
            // Render while waiting, unless a change cancelled the pass or the viewer is framing.
            if self.job.is_some() && !self.cancel.load(Ordering::SeqCst) && paused.is_none() {
                self.step(&mut out);
                continue;
            }
            let until = due
                .unwrap_or(now + IDLE_POLL)
                .min(paused.unwrap_or(now + IDLE_POLL));
            if let Ok(event) = self
                .events
                .recv_timeout(until.saturating_duration_since(now))
            {
                Self::absorb(event, &mut pending, &mut out);
            }
        }
    }

    /// Reports what the denoise thread finished.
    fn denoiser_news(&mut self, out: &mut Reporter<'_>) {
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

    /// Folds one event into the pending changes.
    fn absorb(event: FileEvent, pending: &mut Option<Pending>, out: &mut Reporter<'_>) {
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
}
