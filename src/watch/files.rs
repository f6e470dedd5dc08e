//! The file side of the watch loop (notify → channel): which files a scene depends on, the watches that cover them, and what each event means for a pending reload.

use std::collections::{BTreeSet, HashSet};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::Sender;
use std::sync::{Arc, Mutex, PoisonError};
use std::time::{Duration, Instant};

use notify::event::{AccessKind, AccessMode, MetadataKind, ModifyKind, RenameMode};
use notify::{EventKind, RecommendedWatcher, RecursiveMode, Watcher};

/// How long the files must be quiet before a save that is not known to be complete is loaded,
/// and a third of how long a failed load waits for the rest of its save before it is reported.
///
/// 50 ms: the steps of one save (truncate + write + fsync + chmod, or write a temporary file and
/// rename it, or vim's backup-rename + write + delete) land within about 10 ms of each other
/// (vim here: 8 ms from truncate to the last attribute change, the fsync in between), so 50 ms
/// holds a save together with room to spare on a loaded machine. Saves that end in a close or a
/// rename (every editor on Linux) do not wait for it: they load as soon as that event arrives.
pub const DEBOUNCE: Duration = Duration::from_millis(50);

/// Whether the platform's watcher says when a writer closes a file (inotify's
/// `IN_CLOSE_WRITE`): only then can a load wait for the close of a file being written.
pub(super) const REPORTS_CLOSE: bool = cfg!(any(target_os = "linux", target_os = "android"));

/// How long a file that a writer still holds open may stay quiet before it is loaded anyway
/// (where `REPORTS_CLOSE`): a close that never comes (a `truncate(2)` by path, a close lost
/// while a directory was watched afresh) must not stop reloads for good, and a writer that
/// pauses this long mid-save is taken for having stopped.
pub const OPEN_WRITER_PATIENCE: Duration = Duration::from_secs(10);

/// How often an idle loop wakes to check its stop flag even without events (stopping also sends
/// a wake-up, so this is only a safety net).
pub(super) const IDLE_POLL: Duration = Duration::from_millis(500);

/// What an event says about a file's contents.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Effect {
    /// Attributes only (times, permissions): never cancels a pass; reloads only a scene whose
    /// last load failed.
    Metadata,
    /// The contents may be in the middle of changing: a creation, a removal, a rename away, a
    /// directory created (its files follow).
    Partial,
    /// Data was written (or the file truncated) through a descriptor that is still open: where
    /// the platform reports closes, the file is complete only once the writer closes it.
    Writing,
    /// The contents are final: the writer closed the file or it was renamed into place.
    Complete,
}

/// What an event of `kind` means for the path at `index` of its paths; `None` if it cannot
/// change contents (opening and reading, which the loader's own reads would otherwise turn into
/// reloads forever, and access-time updates).
pub(super) fn effect(kind: &EventKind, index: usize) -> Option<Effect> {
    Some(match kind {
        EventKind::Access(AccessKind::Close(AccessMode::Write)) => Effect::Complete,
        EventKind::Access(_) => return None,
        EventKind::Modify(ModifyKind::Metadata(MetadataKind::AccessTime)) => return None,
        EventKind::Modify(ModifyKind::Metadata(_)) => Effect::Metadata,
        EventKind::Modify(ModifyKind::Name(RenameMode::To)) => Effect::Complete,
        // `[from, to]`: the old name is gone, the new one is in place.
        EventKind::Modify(ModifyKind::Name(RenameMode::Both)) if index > 0 => Effect::Complete,
        EventKind::Modify(ModifyKind::Data(_)) => Effect::Writing,
        _ => Effect::Partial,
    })
}

/// A batch of file events, as the loop receives it.
#[derive(Clone, Debug)]
pub struct Change {
    /// The files concerned, as watched (parent directory canonicalised), with what happened to
    /// each. Empty after an event overflow.
    pub paths: Vec<(PathBuf, Effect)>,
    /// Whether the directories to watch may have changed: a watched directory or one on the way
    /// to a dependency was created, removed or renamed (or events were lost).
    pub rearm: bool,
    /// Events were lost (the kernel queue overflowed): anything may have changed.
    pub overflow: bool,
    /// When the watcher received it.
    pub at: Instant,
}

/// What the file watcher tells the loop.
#[derive(Clone, Debug)]
pub enum FileEvent {
    /// Files the scene depends on (or may come to depend on) changed.
    Changed(Change),
    /// The watcher reported an error (e.g. too many watches).
    Error(String),
    /// Nothing happened; sent to wake the loop (see [`StopHandle::stop`](super::StopHandle::stop)).
    Wake,
}

/// How a path matters.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Class {
    /// A file the scene reads (or a failed load asked for).
    File,
    /// A directory whose creation, removal or rename changes what must be watched.
    Arm,
}

/// Which paths are relevant. Shared with the notify thread.
#[derive(Default)]
pub(super) struct Filter {
    /// Files, as [`watch_key`]s.
    pub(super) files: HashSet<PathBuf>,
    /// Watched directories (seen from their parents, or reporting their own removal) and missing
    /// directories on the way to a file.
    pub(super) arms: HashSet<PathBuf>,
    /// Never relevant (the output image, which we write ourselves).
    ignore: HashSet<PathBuf>,
}

impl Filter {
    fn classify(&self, path: &Path) -> Option<Class> {
        if self.ignore.contains(path) {
            None
        } else if self.files.contains(path) {
            Some(Class::File)
        } else if self.arms.contains(path) {
            Some(Class::Arm)
        } else {
            None
        }
    }

    /// The change `event` makes, if it concerns any path of interest.
    pub(super) fn change(&self, event: &notify::Event) -> Option<Change> {
        let at = Instant::now();
        if event.need_rescan() {
            return Some(Change {
                paths: Vec::new(),
                rearm: true,
                overflow: true,
                at,
            });
        }
        let mut change = Change {
            paths: Vec::new(),
            rearm: false,
            overflow: false,
            at,
        };
        for (i, path) in event.paths.iter().enumerate() {
            let (Some(class), Some(effect)) = (self.classify(path), effect(&event.kind, i)) else {
                continue;
            };
            change.rearm |= class == Class::Arm && effect != Effect::Metadata;
            change.paths.push((path.clone(), effect));
        }
        (!change.paths.is_empty()).then_some(change)
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

/// For a file whose directory does not exist: the nearest existing ancestor (canonical) and the
/// path of the missing directory under it whose creation is to be watched for.
pub(super) fn nearest_ancestor(path: &Path) -> Option<(PathBuf, PathBuf)> {
    let absolute = std::path::absolute(path).ok()?;
    let mut below: Option<&Path> = None;
    for dir in absolute.parent()?.ancestors() {
        if dir.is_dir() {
            let canonical = dir.canonicalize().ok()?;
            let name = below?.file_name()?;
            return Some((canonical.clone(), canonical.join(name)));
        }
        below = Some(dir);
    }
    None
}

/// What to watch for a set of files.
#[derive(Default, PartialEq, Eq)]
pub(super) struct Plan {
    files: HashSet<PathBuf>,
    arms: HashSet<PathBuf>,
    /// Directories holding files (shown to the user).
    dirs: BTreeSet<PathBuf>,
    /// Parents and ancestors watched for arms.
    guards: BTreeSet<PathBuf>,
}

impl Plan {
    fn new(files: &[PathBuf]) -> Self {
        let mut plan = Self::default();
        for file in files {
            match watch_key(file) {
                Ok((dir, key)) => {
                    plan.dirs.insert(dir);
                    plan.files.insert(key);
                    // A symlinked file changes when its target does.
                    let link = std::fs::symlink_metadata(file).is_ok_and(|m| m.is_symlink());
                    if let Some((dir, key)) = link
                        .then(|| std::fs::canonicalize(file).ok())
                        .flatten()
                        .and_then(|target| watch_key(&target).ok())
                    {
                        plan.dirs.insert(dir);
                        plan.files.insert(key);
                    }
                }
                Err(_) => {
                    if let Some((ancestor, missing)) = nearest_ancestor(file) {
                        plan.guards.insert(ancestor);
                        plan.arms.insert(missing);
                    }
                }
            }
        }
        for dir in &plan.dirs {
            plan.arms.insert(dir.clone());
            if let Some(parent) = dir.parent() {
                plan.guards.insert(parent.to_path_buf());
            }
        }
        plan
    }

    fn directories(&self) -> BTreeSet<PathBuf> {
        self.dirs.union(&self.guards).cloned().collect()
    }
}

/// Watches the directories (non-recursively) around a set of files and sends a
/// [`FileEvent::Changed`] for each event that concerns them, after raising the cancel flag if
/// contents may have changed. See the module docs for what is watched.
pub struct FileWatcher {
    watcher: RecommendedWatcher,
    filter: Arc<Mutex<Filter>>,
    /// The files as last given to [`FileWatcher::set_files`].
    files: Vec<PathBuf>,
    /// Directories shown to the user (those holding files).
    dirs: BTreeSet<PathBuf>,
    /// Every directory watched.
    watched: BTreeSet<PathBuf>,
}

impl FileWatcher {
    /// Starts the notify watcher. Relevant events set `cancel` (unless they change only
    /// metadata) and are sent to `events`. Nothing is watched until [`FileWatcher::set_files`].
    pub fn new(cancel: Arc<AtomicBool>, events: Sender<FileEvent>) -> Result<Self, notify::Error> {
        let filter = Arc::new(Mutex::new(Filter::default()));
        let shared = filter.clone();
        let handler = move |result: notify::Result<notify::Event>| match result {
            Ok(event) => {
                let change = shared
                    .lock()
                    .unwrap_or_else(PoisonError::into_inner)
                    .change(&event);
                if let Some(change) = change {
                    if change.overflow || change.paths.iter().any(|(_, e)| *e != Effect::Metadata) {
                        cancel.store(true, Ordering::SeqCst);
                    }
                    let _ = events.send(FileEvent::Changed(change));
                }
            }
            Err(error) => {
                let _ = events.send(FileEvent::Error(error.to_string()));
            }
        };
        Ok(Self {
            watcher: notify::recommended_watcher(handler)?,
            filter,
            files: Vec::new(),
            dirs: BTreeSet::new(),
            watched: BTreeSet::new(),
        })
    }

    fn filter(&self) -> std::sync::MutexGuard<'_, Filter> {
        self.filter.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Makes `files` the watched set: watches the directories it needs that are not watched yet,
    /// unwatches those no longer needed. Returns whether anything is watched now that was not
    /// (a directory, a file or a missing directory on the way to one), and a warning per
    /// directory that cannot be watched (the others still are).
    ///
    /// Until this call, events for the new paths are dropped as irrelevant, so a caller that
    /// read those files before must read them again when this returns `true`: a file deleted or
    /// written between the read and this call would otherwise never be noticed.
    pub fn set_files(&mut self, files: &[PathBuf]) -> (bool, Vec<String>) {
        self.files = files.to_vec();
        let plan = Plan::new(files);
        let wanted = plan.directories();
        let mut added = {
            let mut filter = self.filter();
            let added = !plan.files.is_subset(&filter.files) || !plan.arms.is_subset(&filter.arms);
            filter.files = plan.files;
            filter.arms = plan.arms;
            added
        };
        for dir in self.watched.difference(&wanted) {
            // The directory may be gone already; nothing to do then.
            let _ = self.watcher.unwatch(dir);
        }
        let mut warnings = Vec::new();
        let mut watched = BTreeSet::new();
        for dir in wanted {
            if self.watched.contains(&dir) {
                watched.insert(dir);
                continue;
            }
            match self.watcher.watch(&dir, RecursiveMode::NonRecursive) {
                Ok(()) => {
                    added = true;
                    watched.insert(dir);
                }
                Err(e) => {
                    if plan.dirs.contains(&dir) {
                        warnings.push(format!("{}: cannot watch: {e}", dir.display()));
                    }
                }
            }
        }
        self.watched = watched;
        self.dirs = plan.dirs;
        (added, warnings)
    }

    /// Watches every directory afresh: after a directory was deleted, renamed or replaced, a
    /// watch may follow an inode that is no longer at its path.
    pub fn rearm(&mut self) -> (bool, Vec<String>) {
        for dir in std::mem::take(&mut self.watched) {
            let _ = self.watcher.unwatch(&dir);
        }
        let files = std::mem::take(&mut self.files);
        self.set_files(&files)
    }

    /// Never report `path` (for the output image, which the loop writes itself).
    pub fn ignore(&self, path: &Path) {
        if let Ok((_, key)) = watch_key(path) {
            self.filter().ignore.insert(key);
        }
    }

    /// The directories holding watched files (their parents are watched too, unlisted).
    pub fn directories(&self) -> Vec<PathBuf> {
        self.dirs.iter().cloned().collect()
    }

    /// The number of files watched (symlink targets included).
    pub fn file_count(&self) -> usize {
        self.filter().files.len()
    }
}

#[cfg(test)]
mod tests {
    use notify::event::CreateKind;

    use super::*;

    #[test]
    fn reads_and_opens_do_not_count_as_changes_and_closes_complete_a_file() {
        use notify::event::DataChange;
        let e = |kind| effect(&kind, 0);
        assert_eq!(
            e(EventKind::Access(AccessKind::Open(AccessMode::Any))),
            None
        );
        assert_eq!(
            e(EventKind::Access(AccessKind::Close(AccessMode::Read))),
            None
        );
        assert_eq!(
            e(EventKind::Modify(ModifyKind::Metadata(
                MetadataKind::AccessTime
            ))),
            None
        );
        assert_eq!(
            e(EventKind::Modify(ModifyKind::Metadata(MetadataKind::Any))),
            Some(Effect::Metadata)
        );
        assert_eq!(
            e(EventKind::Access(AccessKind::Close(AccessMode::Write))),
            Some(Effect::Complete)
        );
        assert_eq!(
            e(EventKind::Modify(ModifyKind::Data(DataChange::Any))),
            Some(Effect::Writing)
        );
        assert_eq!(
            e(EventKind::Create(CreateKind::File)),
            Some(Effect::Partial)
        );
        assert_eq!(
            e(EventKind::Create(CreateKind::Folder)),
            Some(Effect::Partial),
            "the files of a new directory follow it"
        );
        let both = EventKind::Modify(ModifyKind::Name(RenameMode::Both));
        assert_eq!(effect(&both, 0), Some(Effect::Partial), "the old name");
        assert_eq!(effect(&both, 1), Some(Effect::Complete), "the new name");
    }

    #[test]
    fn filter_ignores_the_output_and_flags_directories_for_rearming() {
        let mut f = Filter::default();
        f.files.insert(PathBuf::from("/d/scene.ron"));
        f.arms.insert(PathBuf::from("/d/prefabs"));
        f.ignore.insert(PathBuf::from("/d/out.png"));
        assert_eq!(f.classify(Path::new("/d/scene.ron")), Some(Class::File));
        assert_eq!(f.classify(Path::new("/d/prefabs")), Some(Class::Arm));
        assert_eq!(f.classify(Path::new("/d/tex.png")), None);
        assert_eq!(f.classify(Path::new("/d/out.png")), None);
        let event = notify::Event::new(EventKind::Remove(notify::event::RemoveKind::Folder))
            .add_path(PathBuf::from("/d/prefabs"));
        let change = f.change(&event).expect("relevant");
        assert!(change.rearm);
        let event = notify::Event::new(EventKind::Create(CreateKind::File))
            .add_path(PathBuf::from("/d/scene.ron.swp"));
        assert!(f.change(&event).is_none());
    }

    #[test]
    fn a_file_in_missing_directories_arms_the_nearest_existing_ancestor() {
        let dir = std::env::temp_dir();
        let canonical = dir.canonicalize().expect("temp dir exists");
        let file = dir.join("no-such-dir-rondo").join("deeper").join("a.png");
        let (ancestor, missing) = nearest_ancestor(&file).expect("the temp dir exists");
        assert_eq!(ancestor, canonical);
        assert_eq!(missing, canonical.join("no-such-dir-rondo"));
        let plan = Plan::new(&[file, dir.join("b.ron")]);
        assert!(plan.guards.contains(&canonical));
        assert!(plan.arms.contains(&canonical.join("no-such-dir-rondo")));
        assert!(
            plan.arms.contains(&canonical),
            "a watched directory is armed"
        );
        assert!(plan.files.contains(&canonical.join("b.ron")));
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

    #[test]
    fn watching_a_file_not_watched_before_asks_for_a_second_read() {
        // The race behind it (seen in `watch_differential`, seed 14): a reload reads a prefab the
        // last scene did not use, the prefab's directory is deleted before the watcher knows the
        // file, so the deletion's events are dropped and the image shows a prefab that is gone.
        let temp = tempfile::Builder::new()
            .prefix("rondo-set-files-")
            .tempdir()
            .expect("temp dir");
        let dir = temp.path();
        std::fs::create_dir_all(dir.join("prefabs")).expect("mkdir");
        let (scene, wall, door) = (
            dir.join("scene.ron"),
            dir.join("prefabs/wall.ron"),
            dir.join("prefabs/door.ron"),
        );
        let (tx, _rx) = std::sync::mpsc::channel();
        let mut w = FileWatcher::new(Arc::new(AtomicBool::new(false)), tx).expect("watcher");
        assert!(w.set_files(std::slice::from_ref(&scene)).0, "first files");
        assert!(
            !w.set_files(std::slice::from_ref(&scene)).0,
            "the same files"
        );
        assert!(
            w.set_files(&[scene.clone(), wall.clone()]).0,
            "a new directory"
        );
        assert!(
            w.set_files(&[scene.clone(), wall.clone(), door.clone()]).0,
            "a new file in a watched directory"
        );
        assert!(
            !w.set_files(&[scene.clone(), wall.clone()]).0,
            "fewer files"
        );
        // The race itself: the last scene used no prefab, and the prefab read just now has lost
        // its directory before being watched.
        w.set_files(std::slice::from_ref(&scene));
        std::fs::remove_dir_all(dir.join("prefabs")).expect("rm -rf");
        assert!(
            w.set_files(&[scene.clone(), wall.clone()]).0,
            "a new file whose directory is gone: the missing directory is new to watch for"
        );
    }
}
