//! The changes a watch has seen since its last reload, until they are loaded: which files, and
//! whether they are finished.

use std::collections::HashSet;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use super::files::{Change, Effect, OPEN_WRITER_PATIENCE, REPORTS_CLOSE};

/// Why a load did not give a scene.
pub(super) enum Failure {
    /// The scene file does not exist.
    Missing,
    /// The scene (or a file it reads) is bad: the error and the line it quotes.
    Error(String, Option<String>),
}

/// The changes gathered since the last reload, until they are loaded.
pub(super) struct Pending {
    /// The files concerned.
    pub(super) paths: Vec<PathBuf>,
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
            if !self.paths.contains(&path) {
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
