//! The changes a watch has seen since its last reload, until they are loaded: which files, and
//! whether they are finished.

use std::collections::HashSet;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use crate::scene::error::SceneError;

use super::files::{Change, Effect, OPEN_WRITER_PATIENCE, REPORTS_CLOSE};

/// Why a load did not give a scene.
pub(super) enum Failure {
    /// The scene file does not exist.
    Missing,
    /// The scene (or a file it reads) is bad.
    Error(Box<SceneError>),
}

/// The changes gathered since the last reload, until they are loaded.
pub(super) struct Pending {
    /// The files concerned, in the order first seen.
    pub(super) paths: Vec<PathBuf>,
    /// The same files as a set: each event's path is looked up once, not along the list.
    listed: HashSet<PathBuf>,
    /// When the latest event happened: about when the save ended.
    pub(super) last: Instant,
    /// Files with an event that leaves them unfinished and no completing event since.
    pub(super) unfinished: HashSet<PathBuf>,
    /// Those of them written through a descriptor still open: their close is waited for.
    pub(super) writing: HashSet<PathBuf>,
    /// Whether an event completed a file.
    pub(super) completed: bool,
    /// Whether anything but metadata may have changed (always, for the first load).
    pub(super) content: bool,
    /// Whether events were lost.
    pub(super) overflow: bool,
    /// Whether the watched directories must be set up afresh.
    pub(super) rearm: bool,
    /// A failed load of these changes, reported at the given time unless another event comes.
    pub(super) failed: Option<(Failure, Instant)>,
}

impl Pending {
    /// The first load: complete by definition.
    pub(super) fn initial() -> Self {
        Self {
            paths: Vec::new(),
            listed: HashSet::new(),
            last: Instant::now(),
            unfinished: HashSet::new(),
            writing: HashSet::new(),
            completed: true,
            content: true,
            overflow: false,
            rearm: false,
            failed: None,
        }
    }

    pub(super) fn add(&mut self, change: Change) {
        self.last = self.last.max(change.at);
        self.failed = None;
        self.overflow |= change.overflow;
        self.rearm |= change.rearm;
        self.content |= change.overflow;
        if change.overflow {
            // Lost events may have held the closes: wait for quiet instead.
            self.writing.clear();
        }
        for (path, effect) in change.paths {
            match effect {
                Effect::Metadata => {}
                Effect::Partial => {
                    // Removed or renamed away: a writer still holding the old file no longer
                    // writes this name.
                    self.writing.remove(&path);
                    self.unfinished.insert(path.clone());
                    self.content = true;
                }
                Effect::Writing => {
                    self.writing.insert(path.clone());
                    self.unfinished.insert(path.clone());
                    self.content = true;
                }
                Effect::Complete => {
                    self.writing.remove(&path);
                    self.unfinished.remove(&path);
                    self.completed = true;
                    self.content = true;
                }
            }
            if self.listed.insert(path.clone()) {
                self.paths.push(path);
            }
        }
    }

    /// When to act: report a failure, load now (every file complete), wait for the close of a
    /// file a writer holds open (where the platform reports closes; at most
    /// [`OPEN_WRITER_PATIENCE`] of quiet), or load once the files have been quiet for `window`.
    pub(super) fn due(&self, window: Duration) -> Instant {
        match &self.failed {
            Some((_, at)) => *at,
            None if self.completed && self.unfinished.is_empty() && !self.overflow => self.last,
            None if REPORTS_CLOSE && !self.writing.is_empty() => self.last + OPEN_WRITER_PATIENCE,
            None => self.last + window,
        }
    }
}

#[cfg(test)]
mod tests {
    use notify::EventKind;
    use notify::event::CreateKind;

    use super::super::files::{DEBOUNCE, Filter};
    use super::*;

    /// A file written through a descriptor still open is loaded at its close
    /// (where the platform reports closes), however long the writer pauses before it; a file
    /// only created or removed, or written where closes are not reported, waits for quiet.
    #[test]
    fn a_file_being_written_is_loaded_at_its_close() {
        let window = DEBOUNCE;
        let t = Instant::now();
        let mut p = Pending::initial();
        p.completed = false;
        p.last = t;
        p.add(change("/d/scene.ron", Effect::Writing, t));
        let held = if REPORTS_CLOSE {
            t + OPEN_WRITER_PATIENCE
        } else {
            t + window
        };
        assert_eq!(p.due(window), held, "held until the writer closes");
        assert!(OPEN_WRITER_PATIENCE > 10 * window);
        p.add(change("/d/scene.ron", Effect::Writing, t));
        assert_eq!(p.due(window), held, "more writes, still open");
        p.add(change("/d/scene.ron", Effect::Complete, t));
        assert_eq!(p.due(window), t, "closed: load at once");

        let mut p = Pending::initial();
        p.completed = false;
        p.last = t;
        p.add(change("/d/scene.ron", Effect::Writing, t));
        p.add(change("/d/scene.ron", Effect::Partial, t));
        assert_eq!(p.due(window), t + window, "removed: no writer of this name");

        let mut p = Pending::initial();
        p.completed = false;
        p.last = t;
        p.add(change("/d/scene.ron", Effect::Writing, t));
        p.add(Change {
            paths: Vec::new(),
            rearm: true,
            overflow: true,
            at: t,
        });
        assert_eq!(
            p.due(window),
            t + window,
            "events lost: the close may be too"
        );
    }

    /// A change to `path` with `effect`, received `at`.
    fn change(path: &str, effect: Effect, at: Instant) -> Change {
        Change {
            paths: vec![(PathBuf::from(path), effect)],
            rearm: false,
            overflow: false,
            at,
        }
    }

    /// A directory created, then a file written into it (a race a test once hit). Were
    /// the creation complete, the loop would arm the directory and read at once, possibly
    /// after the write but before its events arrive; those events then load the same file
    /// again and report a second render, which a waiter takes for the render of its next save.
    /// The directory's files follow it: the read waits for them to be quiet.
    #[test]
    fn a_created_directory_is_read_once_its_files_are_quiet() {
        let mut f = Filter::default();
        f.arms.insert(PathBuf::from("/d/prefabs"));
        f.files.insert(PathBuf::from("/d/prefabs/wall.ron"));
        let event = notify::Event::new(EventKind::Create(CreateKind::Folder))
            .add_path(PathBuf::from("/d/prefabs"));
        let created = f.change(&event).expect("relevant");
        assert!(created.rearm);
        let t = created.at;
        let mut p = Pending::initial();
        p.completed = false;
        p.last = t;
        p.add(created);
        assert_eq!(p.due(DEBOUNCE), t + DEBOUNCE, "not read at the creation");
        // The file's write, its events absorbed before the read.
        let t2 = t + DEBOUNCE / 2;
        p.add(change("/d/prefabs/wall.ron", Effect::Partial, t2));
        p.add(change("/d/prefabs/wall.ron", Effect::Writing, t2));
        p.add(change("/d/prefabs/wall.ron", Effect::Complete, t2));
        assert_eq!(p.due(DEBOUNCE), t2 + DEBOUNCE, "read once, after the write");
    }
}
