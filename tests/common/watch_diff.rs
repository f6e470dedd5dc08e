//! The driver of the differential watch tests (`tests/watch_differential*.rs`): a running watch
//! on a directory of its own, edits saved in the ways editors save, and the oracle: after any
//! sequence of edits the watch must show what a fresh render of the files on disk shows, the
//! same pixels or the same error.
//!
//! Renders are deterministic for any pass split, which makes the fresh render an exact oracle.
//! The watch runs in-process ([`WatchSession`]) on the real notify watcher. Waits are for
//! reports, with a deadline that only guards against hangs; sleeps are gaps between edits, part
//! of the generated input.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use rondo::watch::{ReloadReport, Report, WatchOptions, WatchSession};

use super::TestDir;

/// Upper bound of the wait for the watch to settle after a sequence.
pub const WAIT: Duration = Duration::from_secs(20);

/// splitmix64: a small seeded generator, enough for test inputs.
pub struct Rng(pub u64);

impl Rng {
    /// The next 64 random bits.
    pub fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in `0..n` (`n` > 0).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }

    /// True with `percent` % probability.
    pub fn chance(&mut self, percent: u64) -> bool {
        self.next() % 100 < percent
    }
}

/// The value of the environment variable `name` as a number, else `default`.
pub fn env_number(name: &str, default: u64) -> u64 {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// How a file is saved.
#[derive(Clone, Copy, Debug)]
pub enum Save {
    /// Truncate and write in place (most tools).
    InPlace,
    /// Write a temporary file and rename it over the original (vim, many IDEs).
    Rename,
    /// Delete, then create (some tools, `git checkout`).
    Recreate,
    /// In place, keeping the old modification time (`cp -p`, build tools).
    KeepMtime,
    /// In place in two halves with a pause between (a slow writer).
    Split(u64),
}

impl Save {
    /// A random way, in-place writes the most common.
    pub fn random(rng: &mut Rng) -> Self {
        match rng.below(6) {
            0 | 1 => Self::InPlace,
            2 => Self::Rename,
            3 => Self::Recreate,
            4 => Self::KeepMtime,
            _ => Self::Split(rng.below(90) as u64),
        }
    }

    /// Saves `bytes` as the file `path` in this way.
    pub fn write(self, path: &Path, bytes: &[u8]) {
        use std::io::Write;
        match self {
            Self::InPlace => std::fs::write(path, bytes).expect("write"),
            Self::Rename => {
                let name = path.file_name().expect("name").to_string_lossy();
                let tmp = path.with_file_name(format!(".{name}.tmp~"));
                std::fs::write(&tmp, bytes).expect("write temp");
                std::fs::rename(&tmp, path).expect("rename");
            }
            Self::Recreate => {
                let _ = std::fs::remove_file(path);
                std::fs::write(path, bytes).expect("write");
            }
            Self::KeepMtime => {
                let stamp = std::fs::metadata(path).and_then(|m| m.modified()).ok();
                std::fs::write(path, bytes).expect("write");
                if let Some(stamp) = stamp {
                    set_mtime(path, stamp);
                }
            }
            Self::Split(pause) => {
                let mut file = std::fs::File::create(path).expect("create");
                let (head, tail) = bytes.split_at(bytes.len() / 2);
                file.write_all(head).expect("write");
                file.flush().expect("flush");
                std::thread::sleep(Duration::from_millis(pause));
                file.write_all(tail).expect("write");
            }
        }
    }
}

/// Sets the modification time of the file `path`.
pub fn set_mtime(path: &Path, stamp: std::time::SystemTime) {
    std::fs::File::options()
        .write(true)
        .open(path)
        .and_then(|f| f.set_modified(stamp))
        .expect("set mtime");
}

/// The size and modification time of the file `path`.
pub fn stamp(path: &Path) -> (u64, std::time::SystemTime) {
    let meta = std::fs::metadata(path).expect("stat");
    (meta.len(), meta.modified().expect("mtime"))
}

/// What a fresh render of the files gives: the image, or the error.
pub fn fresh(scene: &Path) -> Result<image::RgbImage, String> {
    let mut r = rondo::Renderer::new(Some(1), rondo::PassPlan::Single).expect("thread pool");
    r.load(scene).map_err(|e| e.to_string())?;
    r.render_to_completion();
    Ok(r.film().to_srgb8())
}

/// What the watch shows, as told by its reports.
#[derive(Clone, Debug, PartialEq)]
pub enum Shown {
    /// Between a change and its outcome.
    Busy,
    /// A complete render: the image on disk.
    Image,
    /// The error of the last save.
    Error(String),
    /// The scene file is missing.
    Missing,
}

/// A watch session on a directory of its own (`scene.ron` in it, the image `out.png`), one
/// render thread.
pub struct Watcher {
    /// The directory of the scene and its files.
    pub dir: TestDir,
    session: Option<WatchSession>,
    shown: Shown,
    /// The lines of the reports since the last [`Watcher::clear`], for failure messages.
    pub reports: Vec<String>,
    /// The completed reloads since the last [`Watcher::clear`].
    pub reloads: Vec<ReloadReport>,
}

impl Watcher {
    /// Starts watching `dir/scene.ron` (the files written) and waits for the first render.
    pub fn start(dir: TestDir) -> Self {
        let mut options = WatchOptions::new(dir.join("scene.ron"), dir.join("out.png"));
        options.threads = Some(1);
        let session = WatchSession::start(options).expect("start watching");
        let mut watcher = Self {
            dir,
            session: Some(session),
            shown: Shown::Busy,
            reports: Vec::new(),
            reloads: Vec::new(),
        };
        watcher
            .settle("the first render")
            .unwrap_or_else(|e| panic!("{e}"));
        watcher
    }

    /// The scene file.
    pub fn scene(&self) -> PathBuf {
        self.dir.join("scene.ron")
    }

    /// Forgets the reports seen so far.
    pub fn clear(&mut self) {
        self.reports.clear();
        self.reloads.clear();
    }

    fn observe(&mut self, report: Report) {
        if let Some(line) = report.line() {
            self.reports.push(line);
        }
        match report {
            Report::Started { .. } | Report::Deferred { .. } => self.shown = Shown::Busy,
            Report::Rendered(r) if r.completed() => {
                self.shown = Shown::Image;
                self.reloads.push(r);
            }
            Report::Failed(error) => self.shown = Shown::Error(error.to_string()),
            Report::SceneMissing { .. } => self.shown = Shown::Missing,
            _ => {}
        }
    }

    fn next_report(&self, timeout: Duration) -> Option<Report> {
        self.session
            .as_ref()
            .expect("session running")
            .next_report(timeout)
    }

    /// Whether what the watch shows is what a fresh render gives.
    fn matches(&self, expected: &Result<image::RgbImage, String>) -> bool {
        match (&self.shown, expected) {
            (Shown::Image, Ok(image)) => {
                image::open(self.dir.join("out.png")).is_ok_and(|shown| shown.to_rgb8() == *image)
            }
            (Shown::Error(shown), Err(error)) => shown == error,
            _ => false,
        }
    }

    /// Waits until the watch shows what a fresh render of the files gives.
    pub fn settle(&mut self, what: &str) -> Result<(), String> {
        let expected = fresh(&self.scene());
        self.settle_on(&expected, what)
    }

    /// Waits until the watch shows `expected`, a fresh render of the files on disk.
    fn settle_on(
        &mut self,
        expected: &Result<image::RgbImage, String>,
        what: &str,
    ) -> Result<(), String> {
        // The reports already sent first: the image on disk may be newer than what they said.
        while let Some(report) = self.next_report(Duration::ZERO) {
            self.observe(report);
        }
        let deadline = Instant::now() + WAIT;
        while !self.matches(expected) {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.next_report(left) {
                Some(report) => self.observe(report),
                None => {
                    return Err(format!(
                        "{what}: the watch shows {:?}, a fresh render gives {}; reports:\n{}",
                        self.shown,
                        match expected {
                            Ok(_) => "an image (different)".to_string(),
                            Err(e) => format!("the error `{e}`"),
                        },
                        self.reports.join("\n")
                    ));
                }
            }
        }
        Ok(())
    }

    /// Makes `edit` to the files, then waits for the watch to show what a fresh render shows.
    pub fn play(&mut self, what: &str, edit: impl FnOnce(&Path)) -> Result<(), String> {
        self.clear();
        edit(&self.dir);
        self.settle(what)
    }

    /// [`Watcher::play`], for an `edit` that changes what a fresh render gives (checked): a
    /// watch that missed it would still show the old result.
    pub fn play_change(&mut self, what: &str, edit: impl FnOnce(&Path)) -> Result<(), String> {
        let before = fresh(&self.scene());
        self.clear();
        edit(&self.dir);
        let after = fresh(&self.scene());
        if after == before {
            return Err(format!("{what} left the fresh render as it was"));
        }
        self.settle_on(&after, what)
    }

    /// [`Watcher::play`] for an `edit` that leaves what a fresh render gives as it was
    /// (checked), waiting for the reload it causes and returning its report (the image alone
    /// cannot tell a reload from none).
    pub fn play_same(
        &mut self,
        what: &str,
        edit: impl FnOnce(&Path),
    ) -> Result<ReloadReport, String> {
        let before = fresh(&self.scene());
        self.clear();
        edit(&self.dir);
        if fresh(&self.scene()) != before {
            return Err(format!("{what} changed the fresh render"));
        }
        let deadline = Instant::now() + WAIT;
        while self.reloads.is_empty() {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.next_report(left) {
                Some(report) => self.observe(report),
                None => {
                    return Err(format!(
                        "{what}: no reload completed; reports:\n{}",
                        self.reports.join("\n")
                    ));
                }
            }
        }
        self.settle_on(&before, what)?;
        Ok(self.reloads.last().cloned().expect("a reload"))
    }

    /// The report of the last completed reload since the last [`Watcher::clear`].
    pub fn last_reload(&self, what: &str) -> Result<&ReloadReport, String> {
        self.reloads.last().ok_or_else(|| {
            format!(
                "{what}: no reload completed; reports:\n{}",
                self.reports.join("\n")
            )
        })
    }
}

impl Drop for Watcher {
    fn drop(&mut self) {
        super::end_watch(self.session.take());
    }
}
