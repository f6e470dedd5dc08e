//! Denoising beside a watch loop: a worker thread denoises the newest pass while the loop
//! renders the next one. Once a denoise ends, the newest pass waiting is taken and older waiting
//! ones are dropped. A new reload cancels the denoise in flight and every pass waiting (they show
//! a scene that is gone); a newer pass of the same render does not cancel the one in flight, as
//! passes double their samples: on the Cornell box at 512² the 1- and 2-spp passes end 0.15 and
//! 0.3 s after the save while a denoise beside a running pass takes 0.5–0.9 s, so cancelling on
//! every pass left no image denoised until the 4-spp one, 2.1–2.3 s after the save (measured;
//! BENCHMARKS.md). Each denoised image goes to the sink (the viewer), to the output file when the
//! user asked for a denoised one, and back to the loop as a [`Denoised`] report.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, Receiver, Sender};
use std::sync::{Arc, Mutex, PoisonError};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use glam::Vec3;

use super::{DenoiseError, Denoiser, FilmImages, Quality};
use crate::film::{Durability, Layer, OutputImage, write_output};

/// Passes of fewer samples than this (but the last) are denoised at OIDN's fast quality, the
/// rest at its high quality. On the Cornell box at 512², beside a running pass, a fast denoise
/// takes about half the 0.8–0.9 s of a high one, which brings the first denoised image within a
/// second of the save; from 8 spp on a pass takes longer than a high-quality denoise, and the
/// high quality's error is lower (0.0043 against 0.0050 at 8 spp; BENCHMARKS.md).
pub const HIGH_QUALITY_FROM_SPP: u32 = 8;

/// A denoised pass, as the viewer gets it.
#[derive(Clone, Debug)]
pub struct DenoisedFrame {
    /// The reload the pass belongs to.
    pub reload: u64,
    /// Samples per pixel of the pass.
    pub samples: u32,
    /// The pass's means (colour raw, albedo and normal) and its size.
    pub images: FilmImages,
    /// The denoised colour, one value per pixel.
    pub denoised: Vec<Vec3>,
    /// The denoiser's quality setting.
    pub quality: Quality,
    /// How long the denoiser took.
    pub took: Duration,
    /// The save that started the reload.
    pub saved: Instant,
}

/// Where denoised frames go besides the output file: called on the worker thread, so it must
/// return quickly.
pub type DenoiseSink = Arc<dyn Fn(&DenoisedFrame) + Send + Sync>;

/// What the worker tells the loop.
#[derive(Clone, Debug, PartialEq)]
pub enum WorkerNews {
    /// A pass was denoised (and shown, and written if asked).
    Denoised(Denoised),
    /// Denoising failed; the message says why. The raw images are shown meanwhile.
    Failed(String),
}

/// A pass that was denoised, for the report line.
#[derive(Clone, Debug, PartialEq)]
pub struct Denoised {
    /// The reload.
    pub reload: u64,
    /// Samples per pixel of the pass.
    pub samples: u32,
    /// The denoiser's quality setting.
    pub quality: Quality,
    /// How long the denoiser took.
    pub took: Duration,
    /// From the save to the denoised image being ready.
    pub since_save: Duration,
    /// The file written, if the output is denoised.
    pub wrote: Option<PathBuf>,
}

/// One pass to denoise.
pub struct DenoiseJob {
    /// The reload.
    pub reload: u64,
    /// Samples per pixel.
    pub samples: u32,
    /// The pass's means.
    pub images: FilmImages,
    /// The quality to denoise at.
    pub quality: Quality,
    /// Where to write the denoised image (`None`: the output stays raw).
    pub write: Option<PathBuf>,
    /// The save that started the reload.
    pub saved: Instant,
}

/// The worker thread and its queue.
pub struct DenoiseWorker {
    jobs: Option<Sender<(DenoiseJob, Arc<AtomicBool>)>>,
    news: Receiver<WorkerNews>,
    /// The cancel flag shared by the jobs of the current render.
    current: Arc<Mutex<Arc<AtomicBool>>>,
    thread: Option<JoinHandle<()>>,
}

impl DenoiseWorker {
    /// Starts the worker; denoised frames also go to `sink`, if any.
    pub fn start(sink: Option<DenoiseSink>) -> Self {
        let (jobs, inbox) = mpsc::channel::<(DenoiseJob, Arc<AtomicBool>)>();
        let (tell, news) = mpsc::channel();
        let thread = std::thread::Builder::new()
            .name("rondo-denoise".into())
            .spawn(move || work(&inbox, &tell, sink.as_ref()))
            .ok();
        Self {
            jobs: Some(jobs),
            news,
            current: Arc::new(Mutex::new(Arc::new(AtomicBool::new(false)))),
            thread,
        }
    }

    /// Hands a pass over: denoised once the denoise in flight (if any) ends, unless a newer
    /// pass comes first or [`DenoiseWorker::cancel`] is called.
    pub fn submit(&self, job: DenoiseJob) {
        let cancel = self
            .current
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .clone();
        if let Some(jobs) = &self.jobs {
            // A worker that has gone (it never panics; only at shutdown) drops the job.
            let _ = jobs.send((job, cancel));
        }
    }

    /// Cancels the denoise in flight and every pass waiting (a new reload makes them stale).
    pub fn cancel(&self) {
        let old = std::mem::replace(
            &mut *self.current.lock().unwrap_or_else(PoisonError::into_inner),
            Arc::new(AtomicBool::new(false)),
        );
        old.store(true, Ordering::SeqCst);
    }

    /// What the worker has finished since the last call.
    pub fn news(&self) -> Vec<WorkerNews> {
        self.news.try_iter().collect()
    }
}

impl Drop for DenoiseWorker {
    fn drop(&mut self) {
        self.cancel();
        self.jobs = None;
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

/// The worker's loop: the newest job waiting, denoised unless cancelled.
fn work(
    inbox: &Receiver<(DenoiseJob, Arc<AtomicBool>)>,
    tell: &Sender<WorkerNews>,
    sink: Option<&DenoiseSink>,
) {
    let mut failed = false;
    while let Ok(mut next) = inbox.recv() {
        // Only the newest pass is worth denoising.
        while let Ok(newer) = inbox.try_recv() {
            next = newer;
        }
        let (job, cancel) = next;
        if cancel.load(Ordering::SeqCst) {
            continue;
        }
        let denoiser = match Denoiser::shared() {
            Ok(d) => d,
            Err(e) => {
                if !std::mem::replace(&mut failed, true) {
                    let _ = tell.send(WorkerNews::Failed(e.to_string()));
                }
                continue;
            }
        };
        let start = Instant::now();
        let denoised = match job.images.denoise(denoiser, job.quality, &cancel) {
            Ok(image) => image,
            Err(DenoiseError::Cancelled) => continue,
            Err(e) => {
                let _ = tell.send(WorkerNews::Failed(e.to_string()));
                continue;
            }
        };
        let took = start.elapsed();
        if cancel.load(Ordering::SeqCst) {
            continue;
        }
        let frame = DenoisedFrame {
            reload: job.reload,
            samples: job.samples,
            images: job.images,
            denoised,
            quality: job.quality,
            took,
            saved: job.saved,
        };
        let mut wrote = None;
        if let Some(path) = &job.write {
            let raw = [Layer {
                name: "raw",
                pixels: &frame.images.colour,
            }];
            let (w, h) = (frame.images.width, frame.images.height);
            let image = OutputImage::of_linear(w, h, &frame.denoised, &raw);
            match write_output(path, &image, Durability::Live) {
                Ok(()) => wrote = Some(path.clone()),
                Err(e) => {
                    let message = format!("{}: cannot write image: {e}", path.display());
                    let _ = tell.send(WorkerNews::Failed(message));
                }
            }
        }
        if let Some(sink) = sink {
            sink(&frame);
        }
        let _ = tell.send(WorkerNews::Denoised(Denoised {
            reload: frame.reload,
            samples: frame.samples,
            quality: frame.quality,
            took,
            since_save: frame.saved.elapsed(),
            wrote,
        }));
    }
}
