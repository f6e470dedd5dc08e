//! [`WatchSession`]: a [`Watch`] on a thread of its own, for tests and tools.

use std::sync::mpsc::{self, Receiver};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use super::{Report, StopHandle, Watch, WatchError, WatchOptions};

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
