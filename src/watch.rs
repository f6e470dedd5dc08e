//! Live editing: re-render a scene whenever a file it depends on is saved.
//!
//! Two halves:
//! - [`FileWatcher`] is the notify debouncer thread. It watches the *parent directories* of the
//!   scene's dependencies and turns relevant file events into [`FileEvent`]s on a channel. It
//!   knows nothing of the ECS or the renderer, only a cancel flag that it raises so the pass in
//!   flight stops within one band of rows.
//! - [`Watch`] is the loop that drives a [`Renderer`] through its public API: reload on an event,
//!   keep the last good scene (and image) when a save is bad, render progressively and write the
//!   image after each pass, and describe each step as a [`Report`]. [`WatchSession`] runs it on a
//!   thread for tests and tools.
//!
//! Directories are watched, not files, because editors save in different ways. Vim and many IDEs
//! write a temporary file and rename it over the original: a watch on the original file (an
//! inode) dies with it, while a watch on the directory sees the new file arrive under the same
//! name. Truncate-then-write and delete-then-recreate look the same from the directory.
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

use std::collections::{BTreeSet, HashSet};
use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender};
use std::sync::{Arc, Mutex, PoisonError};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use notify_debouncer_full::notify::event::{AccessKind, AccessMode, MetadataKind, ModifyKind};
use notify_debouncer_full::notify::{self, EventKind, RecommendedWatcher, RecursiveMode};
use notify_debouncer_full::{DebounceEventResult, Debouncer, RecommendedCache, new_debouncer};

use crate::app::{Overrides, Renderer};
use crate::ecs::resources::{ChangeSummary, Counters, PassPlan};
use crate::film::OutputKind;
use crate::geometry::layout::LayoutKind;
use crate::serve::Observer;

/// How long the debouncer holds a file event before passing it on.
///
/// 50 ms: the steps of one save (truncate + write + fsync + chmod, or write a temporary file and
/// rename it, or vim's backup-rename + write + delete) land within about 10 ms of each other
/// (vim here: 8 ms from truncate to the last attribute change, the fsync in between), so 50 ms
/// turns a save into one reload with room to spare on a loaded machine; and it is half of the
/// ~100 ms within which a response still feels immediate, leaving the rest for the first pass.
///
/// The debouncer (notify-debouncer-full) releases each raw event once it is a window old,
/// checking every [`tick`] (a tenth of the window), so the steps of one save can come out in
/// batches a tick apart; the loop merges batches until a quiet gap of two ticks. A save is thus
/// acted on 60–65 ms after its last write.
pub const DEBOUNCE: Duration = Duration::from_millis(50);

/// How often the debouncer checks for events old enough to release: a tenth of the window.
pub fn tick(window: Duration) -> Duration {
    (window / 10).max(Duration::from_millis(1))
}

/// How often an idle loop wakes to check its stop flag even without events (stopping also sends
/// a wake-up, so this is only a safety net).
const IDLE_POLL: Duration = Duration::from_millis(500);

/// Why watching could not start.
#[derive(Debug, thiserror::Error)]
pub enum WatchError {
    /// The output file has an unsupported extension.
    #[error("{0}: output must end in .png or .exr")]
    Output(PathBuf),
    /// The render thread pool could not be built.
    #[error("cannot start the render threads: {0}")]
    Threads(#[from] rayon::ThreadPoolBuildError),
    /// The file watcher could not be created.
    #[error("cannot watch files: {0}")]
    Notify(#[from] notify::Error),
    /// The scene's directory cannot be watched.
    #[error("{path}: cannot watch: {message}")]
    Directory {
        /// The scene file.
        path: PathBuf,
        /// Why.
        message: String,
    },
    /// The session thread could not be started.
    #[error("cannot start the watch thread: {0}")]
    Thread(#[from] std::io::Error),
    /// The session thread panicked (a bug: please report it).
    #[error("the watch thread panicked")]
    Panicked,
}

// ------------------------------------------------------------------------------------------------
// The file watcher: notify → channel.

/// What the file watcher tells the loop.
#[derive(Clone, Debug)]
pub enum FileEvent {
    /// Files the scene depends on (or, after a failed load, asset files it may come to depend on)
    /// were created, written, renamed or removed.
    Changed {
        /// The files, as watched (parent directory canonicalised); empty after an event overflow.
        paths: Vec<PathBuf>,
        /// Whether a current dependency is among them.
        dependency: bool,
        /// When the latest of the underlying raw events happened: about when the save ended.
        saved: Instant,
    },
    /// The watcher reported an error (e.g. too many watches).
    Error(String),
    /// Nothing happened; sent to wake the loop (see [`StopHandle::stop`]).
    Wake,
}

/// Which paths are relevant. Shared with the debouncer thread.
#[derive(Default)]
struct Filter {
    /// Dependencies, as [`watch_key`]s.
    files: HashSet<PathBuf>,
    /// Also accept asset files (see [`is_asset`]) in the watched directories: after a failed
    /// load, when a missing texture, prefab or mesh may be about to appear.
    assets: bool,
    /// Never relevant (the output image, which we write ourselves).
    ignore: HashSet<PathBuf>,
}

impl Filter {
    /// `Some(true)` for a dependency, `Some(false)` for an accepted asset, `None` to ignore.
    fn classify(&self, path: &Path) -> Option<bool> {
        if self.ignore.contains(path) {
            None
        } else if self.files.contains(path) {
            Some(true)
        } else if self.assets && is_asset(path) {
            Some(false)
        } else {
            None
        }
    }
}

/// Whether `path` looks like a file a scene can load: a scene or prefab (`.ron`), a mesh
/// (`.obj`) or an image. Editors' swap and backup files (`.swp`, `~`, `4913`) are not.
fn is_asset(path: &Path) -> bool {
    let ron_or_obj = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("ron") || e.eq_ignore_ascii_case("obj"));
    ron_or_obj || image::ImageFormat::from_path(path).is_ok()
}

/// Whether an event kind can mean new file contents. Opening and reading are not (the loader's
/// own reads would otherwise trigger reloads forever), nor are access-time updates.
fn changes_content(kind: &EventKind) -> bool {
    match kind {
        EventKind::Access(AccessKind::Close(AccessMode::Write)) => true,
        EventKind::Access(_) => false,
        EventKind::Modify(ModifyKind::Metadata(MetadataKind::AccessTime)) => false,
        _ => true,
    }
}

/// The key under which a file is watched: its parent directory, made absolute with symlinks and
/// `..` resolved (as notify reports paths of a canonical watch root), joined with its name.
/// Returns `(directory, key)`. The file itself need not exist; its directory must.
pub fn watch_key(path: &Path) -> std::io::Result<(PathBuf, PathBuf)> {
    let absolute = std::path::absolute(path)?;
    let name = absolute
        .file_name()
        .ok_or_else(|| std::io::Error::new(std::io::ErrorKind::InvalidInput, "not a file name"))?;
    let dir = absolute.parent().unwrap_or(Path::new("/")).canonicalize()?;
    let key = dir.join(name);
    Ok((dir, key))
}

/// Watches the parent directories (non-recursively) of a set of files and sends a
/// [`FileEvent::Changed`] for each debounced batch of events that touches one of them, after
/// raising the cancel flag.
pub struct FileWatcher {
    debouncer: Debouncer<RecommendedWatcher, RecommendedCache>,
    filter: Arc<Mutex<Filter>>,
    dirs: BTreeSet<PathBuf>,
}

impl FileWatcher {
    /// Starts the debouncer thread with the given window. Relevant events set `cancel` and are
    /// sent to `events`. Nothing is watched until [`FileWatcher::set_files`].
    pub fn new(
        window: Duration,
        cancel: Arc<AtomicBool>,
        events: Sender<FileEvent>,
    ) -> Result<Self, notify::Error> {
        let filter = Arc::new(Mutex::new(Filter::default()));
        let shared = filter.clone();
        let handler = move |result: DebounceEventResult| match result {
            Ok(batch) => {
                let filter = shared.lock().unwrap_or_else(PoisonError::into_inner);
                let mut paths: Vec<PathBuf> = Vec::new();
                let mut relevant = false;
                let mut dependency = false;
                let mut saved: Option<Instant> = None;
                for event in &batch {
                    let mut hit = false;
                    if event.need_rescan() {
                        // Events were lost: anything may have changed.
                        hit = true;
                        dependency = true;
                    } else if changes_content(&event.kind) {
                        for path in &event.paths {
                            if let Some(is_dependency) = filter.classify(path) {
                                hit = true;
                                dependency |= is_dependency;
                                if !paths.contains(path) {
                                    paths.push(path.clone());
                                }
                            }
                        }
                    }
                    if hit {
                        relevant = true;
                        saved = saved.max(Some(event.time));
                    }
                }
                drop(filter);
                if relevant {
                    cancel.store(true, Ordering::SeqCst);
                    let _ = events.send(FileEvent::Changed {
                        paths,
                        dependency,
                        saved: saved.unwrap_or_else(Instant::now),
                    });
                }
            }
            Err(errors) => {
                let text: Vec<String> = errors.iter().map(ToString::to_string).collect();
                let _ = events.send(FileEvent::Error(text.join("; ")));
            }
        };
        // A zero window would make the debouncer thread spin.
        let window = window.max(Duration::from_millis(1));
        let debouncer = new_debouncer(window, Some(tick(window)), handler)?;
        Ok(Self {
            debouncer,
            filter,
            dirs: BTreeSet::new(),
        })
    }

    fn filter(&self) -> std::sync::MutexGuard<'_, Filter> {
        self.filter.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Makes `files` the watched set: watches their directories not yet watched, unwatches
    /// directories no longer needed. Returns a warning per file or directory that cannot be
    /// watched (the others still are).
    pub fn set_files(&mut self, files: &[PathBuf]) -> Vec<String> {
        let mut warnings = Vec::new();
        let mut keys = HashSet::new();
        let mut dirs = BTreeSet::new();
        for file in files {
            match watch_key(file) {
                Ok((dir, key)) => {
                    dirs.insert(dir);
                    keys.insert(key);
                }
                Err(e) => warnings.push(format!("{}: cannot watch: {e}", file.display())),
            }
        }
        self.filter().files = keys;
        for dir in self.dirs.difference(&dirs) {
            // The directory may be gone already; nothing to do then.
            let _ = self.debouncer.unwatch(dir);
        }
        let mut watched = BTreeSet::new();
        for dir in dirs {
            if self.dirs.contains(&dir) {
                watched.insert(dir);
                continue;
            }
            match self.debouncer.watch(&dir, RecursiveMode::NonRecursive) {
                Ok(()) => {
                    watched.insert(dir);
                }
                Err(e) => warnings.push(format!("{}: cannot watch: {e}", dir.display())),
            }
        }
        self.dirs = watched;
        warnings
    }

    /// Also accept any asset file (scene, prefab, mesh or image) in the watched directories,
    /// not only the dependencies (see [`FileEvent::Changed`]).
    pub fn set_accept_assets(&self, on: bool) {
        self.filter().assets = on;
    }

    /// Never report `path` (for the output image, which the loop writes itself).
    pub fn ignore(&self, path: &Path) {
        if let Ok((_, key)) = watch_key(path) {
            self.filter().ignore.insert(key);
        }
    }

    /// The directories being watched.
    pub fn directories(&self) -> Vec<PathBuf> {
        self.dirs.iter().cloned().collect()
    }
}

// ------------------------------------------------------------------------------------------------
// The loop: events → Renderer.

/// What to watch and render.
#[derive(Clone, Debug)]
pub struct WatchOptions {
    /// The scene file.
    pub scene: PathBuf,
    /// The output image (`.png` or `.exr`), rewritten atomically after every pass; `None` to
    /// write no file (when an [`Observer`] shows the images instead).
    pub output: Option<PathBuf>,
    /// Render threads (all cores if `None`).
    pub threads: Option<usize>,
    /// Settings overrides applied to every load.
    pub overrides: Overrides,
    /// Geometry layout (speed only; images are identical).
    pub layout: LayoutKind,
    /// Samples of the first pass; later passes double the total up to the scene's spp.
    pub first_pass: u32,
    /// The debounce window.
    pub debounce: Duration,
}

impl WatchOptions {
    /// Defaults: all cores, no overrides, the default layout, a first pass of 1 sample, the
    /// [`DEBOUNCE`] window.
    pub fn new(scene: impl Into<PathBuf>, output: impl Into<PathBuf>) -> Self {
        Self {
            scene: scene.into(),
            output: Some(output.into()),
            threads: None,
            overrides: Overrides::default(),
            layout: LayoutKind::default(),
            first_pass: 1,
            debounce: DEBOUNCE,
        }
    }
}

/// What one (re)load changed, rebuilt and cost: the line printed per reload.
#[derive(Clone, Debug, PartialEq)]
pub struct ReloadReport {
    /// 0 for the first load, then 1, 2, … for each successful reload.
    pub number: u64,
    /// The changed files that caused it (empty for the first load).
    pub trigger: Vec<PathBuf>,
    /// What the scene diff changed in the world.
    pub changes: ChangeSummary,
    /// Whether the geometry and its BVH were rebuilt.
    pub bvh_rebuilt: bool,
    /// Primitives in the geometry.
    pub primitives: usize,
    /// Whether material assignments were rebuilt.
    pub materials_synced: bool,
    /// Image textures decoded by the load (unchanged textures come from the cache).
    pub textures_decoded: u64,
    /// Reading, parsing and validating the scene, textures included.
    pub parse: Duration,
    /// Applying the scene to the world and assigning materials (the BVH excluded).
    pub ecs: Duration,
    /// Packing geometry and building the BVH (zero if not rebuilt).
    pub bvh: Duration,
    /// The first pass: its sample count and duration.
    pub first_pass: Option<(u32, Duration)>,
    /// From the save to the first image written.
    pub first_image: Option<Duration>,
    /// From the save to the full-quality image written; `None` if superseded by a newer save.
    pub full: Option<Duration>,
    /// Samples per pixel of the last image written.
    pub samples: u32,
    /// Samples per pixel the scene asks for.
    pub spp: u32,
    /// Passes abandoned (cancelled) and started over.
    pub restarts: u32,
    /// The renderer's counters when the report was made.
    pub counters: Counters,
}

impl ReloadReport {
    /// Whether the render reached the scene's spp (not superseded).
    pub fn completed(&self) -> bool {
        self.full.is_some()
    }
}

/// Formats a duration for humans: `0.42 ms`, `12.3 ms`, `2.31 s`.
fn human(d: Duration) -> String {
    let ms = d.as_secs_f64() * 1e3;
    if ms < 10.0 {
        format!("{ms:.2} ms")
    } else if ms < 1000.0 {
        format!("{ms:.1} ms")
    } else {
        format!("{:.2} s", ms / 1e3)
    }
}

impl fmt::Display for ReloadReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let c = &self.changes;
        let mut changed = Vec::new();
        for (n, what) in [
            (c.added, "added"),
            (c.changed, "changed"),
            (c.removed, "removed"),
        ] {
            if n > 0 {
                let s = if n == 1 { "entity" } else { "entities" };
                changed.push(format!("{n} {s} {what}"));
            }
        }
        for (flag, what) in [
            (c.materials, "materials"),
            (c.camera, "camera"),
            (c.settings, "settings"),
        ] {
            if flag {
                changed.push(what.to_string());
            }
        }
        if changed.is_empty() {
            changed.push("no changes".into());
        }
        let mut rebuilt = Vec::new();
        if self.bvh_rebuilt {
            rebuilt.push(format!("BVH ({} primitives)", self.primitives));
        }
        if self.materials_synced {
            rebuilt.push("materials".into());
        }
        if self.textures_decoded > 0 {
            rebuilt.push(format!("{} texture(s) decoded", self.textures_decoded));
        }
        let rebuilt = if rebuilt.is_empty() {
            "nothing".to_string()
        } else {
            rebuilt.join(", ")
        };
        if self.number == 0 {
            write!(f, "loaded: ")?;
        } else {
            write!(f, "reload {}: ", self.number)?;
        }
        write!(f, "{} | rebuilt {rebuilt} | ", changed.join(", "))?;
        write!(f, "parse {}, ECS {}, ", human(self.parse), human(self.ecs))?;
        if self.bvh_rebuilt {
            write!(f, "BVH {}, ", human(self.bvh))?;
        } else {
            write!(f, "BVH -, ")?;
        }
        match self.first_pass {
            Some((spp, d)) => write!(f, "first pass {} ({spp} spp), ", human(d))?,
            None => write!(f, "first pass -, ")?,
        }
        let since = if self.number == 0 {
            "since start"
        } else {
            "since save"
        };
        if let Some(d) = self.first_image {
            write!(f, "first image {} {since}, ", human(d))?;
        }
        match self.full {
            Some(d) => write!(f, "full {} ({} spp)", human(d), self.spp)?,
            None => write!(f, "superseded at {}/{} spp", self.samples, self.spp)?,
        }
        if self.restarts > 0 {
            write!(f, ", {} restart(s)", self.restarts)?;
        }
        Ok(())
    }
}

/// What the loop did, for the command line to print and tests to wait on.
#[derive(Clone, Debug)]
pub enum Report {
    /// The set of watched files changed.
    Watching {
        /// Files watched.
        files: usize,
        /// Their directories.
        directories: Vec<PathBuf>,
    },
    /// An image was written.
    Wrote {
        /// The reload it belongs to ([`ReloadReport::number`]).
        reload: u64,
        /// Samples per pixel in it.
        samples: u32,
        /// Samples per pixel the scene asks for.
        spp: u32,
        /// When the write finished.
        at: Instant,
    },
    /// A render finished, or was superseded by a newer save.
    Rendered(ReloadReport),
    /// A save could not be loaded; the previous scene and image are kept.
    Failed {
        /// The error, starting with `file:line:col` where known.
        message: String,
    },
    /// The scene file is gone; the loop waits for it to come back.
    SceneMissing {
        /// The scene file.
        path: PathBuf,
    },
    /// Something went wrong that does not stop watching (an unwatchable directory, a failed
    /// image write, a watcher error).
    Warning {
        /// What.
        message: String,
    },
}

impl Report {
    /// The line the command line prints, if any (image writes are silent).
    pub fn line(&self) -> Option<String> {
        Some(match self {
            Self::Watching { files, directories } => {
                let dirs: Vec<String> = directories
                    .iter()
                    .map(|d| d.display().to_string())
                    .collect();
                format!(
                    "watching {files} file(s) in {} (Ctrl-C to stop)",
                    dirs.join(", ")
                )
            }
            Self::Wrote { .. } => return None,
            Self::Rendered(r) => r.to_string(),
            Self::Failed { message } => {
                format!("error: {message} (keeping the last good image; fix and save again)")
            }
            Self::SceneMissing { path } => {
                format!("{}: deleted; waiting for it to come back", path.display())
            }
            Self::Warning { message } => format!("warning: {message}"),
        })
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

/// The changes gathered since the last reload.
struct Trigger {
    paths: Vec<PathBuf>,
    dependency: bool,
    saved: Instant,
}

impl Trigger {
    /// Adds a later trigger's changes.
    fn extend(&mut self, later: Self) {
        Self::merge_into(self, later.paths, later.dependency, later.saved);
    }

    fn merge_into(&mut self, paths: Vec<PathBuf>, dependency: bool, saved: Instant) {
        for p in paths {
            if !self.paths.contains(&p) {
                self.paths.push(p);
            }
        }
        self.dependency |= dependency;
        self.saved = self.saved.max(saved);
    }

    /// Adds changes to `this`, creating it if needed.
    fn merge(this: &mut Option<Self>, paths: Vec<PathBuf>, dependency: bool, saved: Instant) {
        match this {
            Some(t) => t.merge_into(paths, dependency, saved),
            None => {
                *this = Some(Self {
                    paths,
                    dependency,
                    saved,
                })
            }
        }
    }
}

/// The render of the current scene, until it completes or a newer save replaces it.
struct Job {
    report: ReloadReport,
    /// When the save happened (the start of the first load).
    saved: Instant,
    /// Counters before the load, to tell what the first frame rebuilt.
    before: Counters,
    /// Whether the first frame (scene applied to the world) has run.
    applied: bool,
    /// Samples per pixel in the image on disk for this scene. After a cancelled pass the film
    /// restarts from zero; images are written again only once they have more samples than this
    /// (passes are deterministic, so fewer samples would only overwrite a better image).
    written: u32,
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
    job: Option<Job>,
    reloads: u64,
    last_error: Option<String>,
    missing: bool,
    /// Whether the user was told that the output is also one of the scene's textures.
    warned_output: bool,
    /// The live viewer (`rondo watch --serve`), told of every reload and pass.
    observer: Option<Box<dyn Observer>>,
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
        // The loop writes the image itself: it knows which writes are worth making (see
        // `Job::written`) and times them apart from the ECS update.
        renderer.set_output(None, false);
        let cancel = renderer.cancel_flag();
        let (tx, events) = mpsc::channel();
        let mut watcher = FileWatcher::new(options.debounce, cancel.clone(), tx.clone())?;
        if let Some(output) = &options.output {
            watcher.ignore(output);
        }
        if let Some(message) = watcher
            .set_files(std::slice::from_ref(&options.scene))
            .into_iter()
            .next()
        {
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
            job: None,
            reloads: 0,
            last_error: None,
            missing: false,
            warned_output: false,
            observer: None,
        })
    }

    /// Tells `observer` of every reload and every improved image from now on (the live viewer).
    pub fn set_observer(&mut self, observer: Box<dyn Observer>) {
        self.renderer.set_progress(observer.progress());
        self.observer = Some(observer);
    }

    /// A handle that stops [`Watch::run`].
    pub fn stop_handle(&self) -> StopHandle {
        self.stop.clone()
    }

    /// Loads and renders the scene, then re-renders on every relevant save until stopped.
    /// Everything that happens is passed to `report`.
    pub fn run(mut self, mut report: impl FnMut(Report)) {
        let report: &mut dyn FnMut(Report) = &mut report;
        report(self.watching_report());
        let mut trigger = Some(Trigger {
            paths: Vec::new(),
            dependency: true,
            saved: Instant::now(),
        });
        loop {
            if trigger.is_none() {
                let first = if self.job.is_some() {
                    self.events.try_recv().ok()
                } else {
                    self.events.recv_timeout(IDLE_POLL).ok()
                };
                if let Some(event) = first {
                    self.absorb(event, &mut trigger, report);
                    // The rest of the same save may follow a debouncer tick later.
                    let quiet = 2 * tick(self.options.debounce);
                    while !self.stop.is_stopped()
                        && let Ok(event) = self.events.recv_timeout(quiet)
                    {
                        self.absorb(event, &mut trigger, report);
                    }
                }
            }
            if self.stop.is_stopped() {
                break;
            }
            if let Some(t) = trigger.take() {
                self.reload(t, report);
                continue;
            }
            self.step(report);
        }
    }

    /// Folds one event into the pending trigger.
    fn absorb(
        &self,
        event: FileEvent,
        trigger: &mut Option<Trigger>,
        report: &mut dyn FnMut(Report),
    ) {
        match event {
            FileEvent::Changed {
                paths,
                dependency,
                saved,
            } => Trigger::merge(trigger, paths, dependency, saved),
            FileEvent::Error(message) => report(Report::Warning { message }),
            FileEvent::Wake => {}
        }
    }

    fn watching_report(&self) -> Report {
        Report::Watching {
            files: self.watched_files(),
            directories: self.watcher.directories(),
        }
    }

    fn watched_files(&self) -> usize {
        self.watcher.filter().files.len()
    }

    /// Waits up to three debounce windows for more changes of the same save. The debouncer
    /// releases each raw event a window (plus at most a tick) after it happened, not after the
    /// last one, so a save spread over more than the quiet gap (truncate now, write later;
    /// delete now, recreate later) can reach us as several batches, and a load between them
    /// sees a half-written or missing file. That is not worth reporting if the rest of the save
    /// follows: anything written within a window of our read arrives within 2.1 windows; three
    /// leave room for a busy machine. Only bad saves pay this delay.
    fn follow_up(&self, report: &mut dyn FnMut(Report)) -> Option<Trigger> {
        let deadline = Instant::now() + 3 * self.options.debounce;
        let mut trigger = None;
        while trigger.is_none() && !self.stop.is_stopped() {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.events.recv_timeout(left) {
                Ok(event) => self.absorb(event, &mut trigger, report),
                Err(RecvTimeoutError::Timeout | RecvTimeoutError::Disconnected) => break,
            }
        }
        trigger
    }

    /// Loads the scene after a change. On success the new scene is queued and a new job starts;
    /// on failure the old scene keeps rendering (if it was not finished) and the image on disk
    /// is left alone.
    fn reload(&mut self, mut trigger: Trigger, report: &mut dyn FnMut(Report)) {
        // The pass this change interrupted is gone; the next one must run.
        self.cancel.store(false, Ordering::SeqCst);
        let scene = self.options.scene.clone();
        let decodes = self.renderer.texture_decodes();
        let before = self.renderer.counters();
        let mut start = Instant::now();
        let result = loop {
            if matches!(std::fs::metadata(&scene), Err(e) if e.kind() == std::io::ErrorKind::NotFound)
            {
                if let Some(more) = self.follow_up(report) {
                    trigger.extend(more);
                    self.cancel.store(false, Ordering::SeqCst);
                    start = Instant::now();
                    continue;
                }
                if !self.missing {
                    self.missing = true;
                    report(Report::SceneMissing { path: scene });
                }
                return;
            }
            self.missing = false;
            match self.renderer.load(&scene) {
                Ok(info) => break Ok(info),
                Err(e) => match self.follow_up(report) {
                    Some(more) => {
                        trigger.extend(more);
                        self.cancel.store(false, Ordering::SeqCst);
                        start = Instant::now();
                    }
                    None => break Err(e),
                },
            }
        };
        let info = match result {
            Ok(info) => info,
            Err(e) => {
                let message = e.to_string();
                // A non-dependency asset appearing while the scene is broken retries the load;
                // the same error again is not news.
                let repeat = !trigger.dependency && self.last_error.as_ref() == Some(&message);
                if !repeat {
                    report(Report::Failed {
                        message: message.clone(),
                    });
                }
                self.last_error = Some(message);
                self.watcher.set_accept_assets(true);
                return;
            }
        };
        let parse = start.elapsed();
        self.last_error = None;
        self.watcher.set_accept_assets(false);

        let mut files = Vec::with_capacity(info.dependencies.len());
        for dep in info.dependencies {
            let is_output = self.output_key.is_some()
                && watch_key(&dep).ok().map(|(_, k)| k) == self.output_key;
            if is_output {
                if !std::mem::replace(&mut self.warned_output, true) {
                    report(Report::Warning {
                        message: format!(
                            "{}: the output image is also a texture of the scene; its writes do not trigger reloads",
                            dep.display()
                        ),
                    });
                }
            } else {
                files.push(dep);
            }
        }
        let (dirs, count) = (self.watcher.directories(), self.watched_files());
        for message in self.watcher.set_files(&files) {
            report(Report::Warning { message });
        }
        if self.watcher.directories() != dirs || self.watched_files() != count {
            report(self.watching_report());
        }

        if let Some(old) = self.job.take() {
            report(Report::Rendered(old.report));
        }
        let number = self.reloads;
        self.reloads += 1;
        self.job = Some(Job {
            report: ReloadReport {
                number,
                trigger: trigger.paths,
                changes: ChangeSummary::default(),
                bvh_rebuilt: false,
                primitives: 0,
                materials_synced: false,
                textures_decoded: self.renderer.texture_decodes().saturating_sub(decodes),
                parse,
                ecs: Duration::ZERO,
                bvh: Duration::ZERO,
                first_pass: None,
                first_image: None,
                full: None,
                samples: 0,
                spp: info.settings.spp,
                restarts: 0,
                counters: before,
            },
            saved: trigger.saved,
            before,
            applied: false,
            written: 0,
        });
        // Viewer hook: a render starts.
        if let (Some(o), Some(job)) = (&self.observer, &self.job) {
            o.reload(&job.report, &info.settings, job.saved);
        }
    }

    /// Runs one frame of the current job: applies the scene if new, renders a pass, writes the
    /// image if it improved, and finishes the job when the film is complete.
    fn step(&mut self, report: &mut dyn FnMut(Report)) {
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
        if !job.applied {
            job.applied = true;
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
        }
        r.counters = counters;
        if counters.passes == passes {
            // Cancelled: a change is on its way (or we are stopping). The film starts over.
            r.restarts += 1;
            return;
        }
        let samples = self.renderer.film().samples;
        if r.first_pass.is_none() {
            r.first_pass = Some((samples, timings.pass));
        }
        if samples > job.written {
            // Viewer hook: the new image goes to the viewer first, then to disk.
            if let Some(o) = &self.observer {
                o.pass(r, self.renderer.film(), job.saved);
            }
            let written = match &self.options.output {
                Some(output) => self.renderer.film().write(output),
                None => Ok(()),
            };
            match written {
                Ok(()) => {
                    let at = Instant::now();
                    job.written = samples;
                    r.samples = samples;
                    if r.first_image.is_none() {
                        r.first_image = Some(at.saturating_duration_since(job.saved));
                    }
                    report(Report::Wrote {
                        reload: r.number,
                        samples,
                        spp: r.spp,
                        at,
                    });
                }
                Err(e) => report(Report::Warning {
                    message: format!(
                        "{}: cannot write image: {e}",
                        self.options
                            .output
                            .as_deref()
                            .unwrap_or(Path::new(""))
                            .display()
                    ),
                }),
            }
        }
        if self.renderer.is_complete() {
            r.full = Some(job.saved.elapsed());
            if let Some(job) = self.job.take() {
                report(Report::Rendered(job.report));
            }
        }
    }
}

/// A [`Watch`] running on its own thread, reporting through a channel: the in-process API for
/// tests and tools. Dropping it stops the loop.
pub struct WatchSession {
    stop: StopHandle,
    reports: Receiver<Report>,
    thread: Option<JoinHandle<()>>,
}

impl WatchSession {
    /// Starts watching (the scene's directory is watched before this returns) and rendering.
    pub fn start(options: WatchOptions) -> Result<Self, WatchError> {
        let watch = Watch::new(options)?;
        let stop = watch.stop_handle();
        let (tx, reports) = mpsc::channel();
        let thread = std::thread::Builder::new()
            .name("rondo-watch".into())
            .spawn(move || {
                watch.run(move |r| {
                    let _ = tx.send(r);
                })
            })?;
        Ok(Self {
            stop,
            reports,
            thread: Some(thread),
        })
    }

    /// The next report, waiting at most `timeout`.
    pub fn next_report(&self, timeout: Duration) -> Option<Report> {
        self.reports.recv_timeout(timeout).ok()
    }

    /// Waits at most `timeout` for a report matching `predicate` and returns it; on timeout,
    /// returns every report seen meanwhile (for the failure message).
    pub fn wait_for(
        &self,
        timeout: Duration,
        mut predicate: impl FnMut(&Report) -> bool,
    ) -> Result<Report, Vec<Report>> {
        let deadline = Instant::now() + timeout;
        let mut seen = Vec::new();
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.reports.recv_timeout(left) {
                Ok(r) if predicate(&r) => return Ok(r),
                Ok(r) => seen.push(r),
                Err(_) => return Err(seen),
            }
        }
    }

    /// A handle that stops the session from elsewhere.
    pub fn stop_handle(&self) -> StopHandle {
        self.stop.clone()
    }

    /// Stops the loop and waits for its thread.
    pub fn stop(mut self) -> Result<(), WatchError> {
        self.shutdown()
    }

    fn shutdown(&mut self) -> Result<(), WatchError> {
        self.stop.stop();
        match self.thread.take() {
            Some(t) => t.join().map_err(|_| WatchError::Panicked),
            None => Ok(()),
        }
    }
}

impl Drop for WatchSession {
    fn drop(&mut self) {
        let _ = self.shutdown();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_and_opens_do_not_count_as_changes() {
        use notify::event::{CreateKind, DataChange};
        assert!(!changes_content(&EventKind::Access(AccessKind::Open(
            AccessMode::Any
        ))));
        assert!(!changes_content(&EventKind::Access(AccessKind::Close(
            AccessMode::Read
        ))));
        assert!(!changes_content(&EventKind::Modify(ModifyKind::Metadata(
            MetadataKind::AccessTime
        ))));
        assert!(changes_content(&EventKind::Access(AccessKind::Close(
            AccessMode::Write
        ))));
        assert!(changes_content(&EventKind::Modify(ModifyKind::Data(
            DataChange::Any
        ))));
        assert!(changes_content(&EventKind::Create(CreateKind::File)));
    }

    #[test]
    fn filter_ignores_the_output_and_accepts_other_assets_only_when_asked() {
        let mut f = Filter::default();
        f.files.insert(PathBuf::from("/d/scene.ron"));
        f.ignore.insert(PathBuf::from("/d/out.png"));
        assert_eq!(f.classify(Path::new("/d/scene.ron")), Some(true));
        assert_eq!(f.classify(Path::new("/d/tex.png")), None);
        f.assets = true;
        assert_eq!(f.classify(Path::new("/d/tex.png")), Some(false));
        assert_eq!(f.classify(Path::new("/d/bunny.OBJ")), Some(false));
        assert_eq!(f.classify(Path::new("/d/prefab.ron")), Some(false));
        assert_eq!(f.classify(Path::new("/d/4913")), None);
        assert_eq!(f.classify(Path::new("/d/scene.ron~")), None);
        assert_eq!(f.classify(Path::new("/d/out.png")), None);
        assert_eq!(f.classify(Path::new("/d/.scene.ron.swp")), None);
    }

    #[test]
    fn watch_keys_are_canonical_directory_plus_name() {
        let dir = std::env::temp_dir();
        let canonical = dir.canonicalize().expect("temp dir exists");
        let (d, key) = watch_key(&dir.join(".").join("a.ron")).expect("temp dir exists");
        assert_eq!(d, canonical);
        assert_eq!(key, canonical.join("a.ron"));
        let missing = watch_key(&dir.join("no-such-dir-rondo").join("a.ron"));
        assert!(
            missing.is_err(),
            "a missing directory is an error, not a panic"
        );
    }
}
