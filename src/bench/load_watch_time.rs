//! The timing of the watch benchmarks' edits ([`super::load_watch`]) in a watch session, and
//! the Ctrl-C that stops a benchmark and lets it remove its files.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, PoisonError};
use std::time::{Duration, Instant};

use super::load_watch::{Edit, Kind};
use crate::output_file;
use crate::watch::{Report, StopHandle, WatchOptions, WatchSession};

/// A Ctrl-C (SIGINT, SIGTERM, SIGHUP) seen by a benchmark: the first one stops the watch
/// session in flight and makes [`Interrupt::check`] fail, so the benchmark returns and its
/// temporary files are removed; a second one exits at once (see
/// [`output_file::stop_on_termination`]).
#[derive(Clone, Default)]
pub struct Interrupt(Arc<(AtomicBool, Mutex<Option<StopHandle>>)>);

impl Interrupt {
    /// Takes over the first termination signal of the process.
    pub fn install() -> Self {
        let interrupt = Self::default();
        let handler = interrupt.clone();
        output_file::stop_on_termination(move || handler.raise());
        interrupt
    }

    fn raise(&self) {
        self.0.0.store(true, Ordering::SeqCst);
        if let Some(stop) = self.session().take() {
            stop.stop();
        }
    }

    fn session(&self) -> std::sync::MutexGuard<'_, Option<StopHandle>> {
        self.0.1.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Makes the signal stop `stop`'s session (at once if it came already).
    fn stops(&self, stop: StopHandle) {
        if self.0.0.load(Ordering::SeqCst) {
            stop.stop();
        }
        *self.session() = Some(stop);
    }

    /// An error once the signal came.
    pub fn check(&self) -> Result<(), String> {
        if self.0.0.load(Ordering::SeqCst) {
            Err("stopped by a signal".into())
        } else {
            Ok(())
        }
    }
}

/// The saves of one kind of edit: from each save to its first image and to the full-quality one.
#[derive(Clone, Debug)]
pub struct Timing {
    /// The edit's kind.
    pub kind: Kind,
    /// What it changed ([`Edit::target`]).
    pub target: String,
    /// Save to the first image written, per save.
    pub first_image: Vec<Duration>,
    /// Save to the full-quality image written, per save.
    pub full: Vec<Duration>,
}

/// Median and minimum of `v` (zero if empty).
pub fn median_min(v: &[Duration]) -> (Duration, Duration) {
    let mut v = v.to_vec();
    v.sort();
    (
        v.get(v.len() / 2).copied().unwrap_or_default(),
        v.first().copied().unwrap_or_default(),
    )
}

/// Longest wait for an image.
const WAIT: Duration = Duration::from_secs(300);

/// Starts a watch session on `options.scene`, whose text is `original`, and times `runs` saves
/// of each edit, `save` writing a text to the scene (alternately the edited text and the
/// original; the original is back on disk at the end). Each save waits for the previous render
/// to finish at full quality. Returns the time from the start to the first image and the
/// timings, as the watch loop reports them (the figures of its `first image … since save`
/// lines: from the file event that completed the save); `log` gets a line per render.
pub fn time_edits(
    options: WatchOptions,
    original: &str,
    edits: &[Edit],
    runs: usize,
    interrupt: &Interrupt,
    mut save: impl FnMut(&str) -> std::io::Result<()>,
    mut log: impl FnMut(&str),
) -> Result<(Duration, Vec<Timing>), String> {
    let scene = options.scene.display().to_string();
    let start = Instant::now();
    let session = WatchSession::start(options).map_err(|e| format!("{scene}: {e}"))?;
    interrupt.stops(session.stop_handle());
    // The first image and the finished render of reload `after` or later: the reload, when its
    // first image was written, and the watch loop's own figures from the save (the file event
    // that completed it) to the first and to the full-quality image.
    let mut image = |after: Option<u64>| -> Result<(u64, Instant, Option<[Duration; 2]>), String> {
        let mut wrote = None;
        loop {
            interrupt.check()?;
            let report = session
                .wait_for(WAIT, |r| {
                    matches!(
                        r,
                        Report::Wrote { .. } | Report::Rendered(_) | Report::Failed { .. }
                    )
                })
                .map_err(|_| {
                    // A signal stops the session, which ends the wait: say so, not a timeout.
                    interrupt
                        .check()
                        .err()
                        .unwrap_or_else(|| format!("{scene}: no image within {} s", WAIT.as_secs()))
                })?;
            interrupt.check()?;
            match report {
                Report::Failed(error) => return Err(error.to_string()),
                Report::Wrote { reload, at, .. }
                    if wrote.is_none() && after.is_none_or(|a| reload > a) =>
                {
                    wrote = Some((reload, at));
                }
                Report::Rendered(r) if r.completed() && wrote.is_some_and(|w| w.0 == r.number) => {
                    log(&r.to_string());
                    let (reload, at) = wrote.ok_or_else(String::new)?;
                    return Ok((reload, at, r.first_image.zip(r.full).map(|(a, b)| [a, b])));
                }
                _ => {}
            }
        }
    };
    let (mut last, at, _) = image(None)?;
    let cold = at.saturating_duration_since(start);
    let mut timings = Vec::new();
    let mut on_disk_is_original = true;
    for edit in edits {
        let (mut first_image, mut full) = (Vec::new(), Vec::new());
        for k in 0..runs.max(1) {
            let text = if k % 2 == 0 { &edit.edited } else { original };
            save(text).map_err(|e| format!("{scene}: {e}"))?;
            let saved = Instant::now();
            on_disk_is_original = k % 2 == 1;
            let (reload, at, figures) = image(Some(last))?;
            let [a, b] =
                figures.unwrap_or_else(|| [at.saturating_duration_since(saved), saved.elapsed()]);
            first_image.push(a);
            full.push(b);
            last = reload;
        }
        if !on_disk_is_original {
            save(original).map_err(|e| format!("{scene}: {e}"))?;
            last = image(Some(last))?.0;
            on_disk_is_original = true;
        }
        timings.push(Timing {
            kind: edit.kind,
            target: edit.target.clone(),
            first_image,
            full,
        });
    }
    session.stop().map_err(|e| format!("{scene}: {e}"))?;
    interrupt.check()?;
    Ok((cold, timings))
}
