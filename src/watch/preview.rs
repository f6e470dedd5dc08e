//! Framing previews for a viewer: quick images of the world as it is through a camera the
//! viewer asks for (the user orbiting with the mouse), without touching the scene file.
//!
//! The viewer's connection threads hand a [`PreviewRequest`] to [`Previews`] and wait; the
//! watch loop, which owns the world, takes the newest request between passes and renders it
//! on its threads ([`crate::Renderer::render_camera`]: the last applied scene, only the camera
//! and the size differ) into a fresh film, never the accumulation.
//!
//! - Newest wins: a request replaces the one waiting (whose waiter is told it was superseded)
//!   and cancels the one in flight, so the image of an old position never delays the next.
//! - The main render pauses while framing: the pass in flight when the first request comes is
//!   finished (its samples are kept), then no main pass starts until [`PAUSE`] has passed
//!   without a request, so that each preview has the threads to itself. The progressive render
//!   then goes on where it was, for the scene's own camera.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard, PoisonError};
use std::time::{Duration, Instant};

use super::Watch;
use crate::film::Film;
use crate::scene::format::CameraDesc;

/// How long after the last preview request the main render stays paused.
pub const PAUSE: Duration = Duration::from_millis(400);

/// Most samples per pixel a preview may ask for.
pub const MAX_PREVIEW_SPP: u32 = 16;

/// The largest divisor of the scene's width and height a preview may ask for.
pub const MAX_PREVIEW_DIVISOR: u32 = 8;

/// What a viewer asks for: the world through `camera` at the scene's width and height divided
/// by `divisor` ([`preview_size`]) with samples `0..spp`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PreviewRequest {
    /// The camera, checked as a written `Camera(…)` is.
    pub camera: CameraDesc,
    /// Samples per pixel, 1..=[`MAX_PREVIEW_SPP`].
    pub spp: u32,
    /// The divisor of the width and height, 1..=[`MAX_PREVIEW_DIVISOR`].
    pub divisor: u32,
}

/// The size of the preview of a `width` × `height` image at `divisor`: each divided (rounded
/// down), at least 1.
pub fn preview_size(width: u32, height: u32, divisor: u32) -> (u32, u32) {
    let divisor = divisor.max(1);
    ((width / divisor).max(1), (height / divisor).max(1))
}

/// A rendered preview.
pub struct PreviewImage {
    /// The reload whose world it shows.
    pub reload: u64,
    /// Its film (`spp` samples of every pixel).
    pub film: Film,
}

/// What became of a request.
pub enum PreviewOutcome {
    /// The image.
    Image(PreviewImage),
    /// A newer request replaced it before it was done.
    Superseded,
    /// No frame of a scene has run yet (or the loop stopped).
    NotReady,
    /// The loop did not answer within the time given.
    TimedOut,
}

#[derive(Default)]
struct State {
    /// The number of the newest request.
    newest: u64,
    pending: Option<(u64, PreviewRequest)>,
    /// The number and cancel flag of the request in flight.
    in_flight: Option<(u64, Arc<AtomicBool>)>,
    /// The newest answer, until its one waiter takes it: its request number and image
    /// (`None`: not ready).
    answer: Option<(u64, Option<PreviewImage>)>,
    last_request: Option<Instant>,
    /// The scene's image size and the reload whose world is in the renderer, once a frame
    /// has run.
    scene: Option<((u32, u32), u64)>,
}

struct Shared {
    state: Mutex<State>,
    answered: Condvar,
    wake: Mutex<Option<Box<dyn Fn() + Send + Sync>>>,
}

/// The meeting point of the viewer's requests and the watch loop (see the module docs). Cheap
/// to clone; all clones share one state.
#[derive(Clone)]
pub struct Previews {
    shared: Arc<Shared>,
}

impl Default for Previews {
    fn default() -> Self {
        Self {
            shared: Arc::new(Shared {
                state: Mutex::new(State::default()),
                answered: Condvar::new(),
                wake: Mutex::new(None),
            }),
        }
    }
}

impl std::fmt::Debug for Previews {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Previews").finish_non_exhaustive()
    }
}

impl Previews {
    fn state(&self) -> MutexGuard<'_, State> {
        self.shared
            .state
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
    }

    /// Asks for a preview and waits at most `timeout` for it (on a viewer's thread). The
    /// request replaces any waiting one and cancels the one in flight.
    pub fn request(&self, request: PreviewRequest, timeout: Duration) -> PreviewOutcome {
        let number = {
            let mut state = self.state();
            state.newest += 1;
            let number = state.newest;
            state.pending = Some((number, request));
            state.last_request = Some(Instant::now());
            if let Some((_, cancel)) = &state.in_flight {
                cancel.store(true, Ordering::Relaxed);
            }
            number
        };
        // Waiters of older requests learn they were superseded.
        self.shared.answered.notify_all();
        if let Some(wake) = &*self
            .shared
            .wake
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
        {
            wake();
        }
        let deadline = Instant::now() + timeout;
        let mut state = self.state();
        loop {
            if state.newest != number {
                return PreviewOutcome::Superseded;
            }
            if let Some((n, _)) = &state.answer
                && *n == number
                && let Some((_, image)) = state.answer.take()
            {
                return image.map_or(PreviewOutcome::NotReady, PreviewOutcome::Image);
            }
            let left = deadline.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return PreviewOutcome::TimedOut;
            }
            state = self
                .shared
                .answered
                .wait_timeout(state, left)
                .unwrap_or_else(PoisonError::into_inner)
                .0;
        }
    }

    /// Whether the main render should wait: a preview was asked for less than [`PAUSE`] ago.
    /// Returns when the pause ends, if it has not.
    fn paused_until(&self) -> Option<Instant> {
        let state = self.state();
        let until = state.last_request? + PAUSE;
        (state.pending.is_some() || until > Instant::now()).then_some(until)
    }
}

impl Watch {
    /// Renders the previews asked through `previews` from now on (the viewer's framing), and
    /// keeps the scene's camera there.
    pub fn set_previews(&mut self, previews: Previews) {
        let wake = self.stop.wake.clone();
        *previews
            .shared
            .wake
            .lock()
            .unwrap_or_else(PoisonError::into_inner) = Some(Box::new(move || {
            let _ = wake.send(super::FileEvent::Wake);
        }));
        self.previews = Some(previews);
    }

    /// Renders the waiting preview request, if any, after noting the scene's size. Returns
    /// until when the main render waits for more requests (`None`: it does not).
    pub(super) fn serve_previews(&mut self) -> Option<Instant> {
        let previews = self.previews.clone()?;
        if self.renderer.scene_version() != 0 {
            let s = self.renderer.settings();
            previews.state().scene = Some(((s.width, s.height), self.reloads));
        }
        loop {
            let (number, request, cancel, scene) = {
                let mut state = previews.state();
                let Some((number, request)) = state.pending.take() else {
                    break;
                };
                let cancel = Arc::new(AtomicBool::new(false));
                state.in_flight = Some((number, cancel.clone()));
                let scene = state.scene;
                (number, request, cancel, scene)
            };
            let image = scene.and_then(|((width, height), reload)| {
                let size = preview_size(width, height, request.divisor);
                match self
                    .renderer
                    .render_camera(&request.camera, size, request.spp, &cancel)?
                {
                    Ok(film) => Some(Ok(PreviewImage { reload, film })),
                    Err(_) => Some(Err(())),
                }
            });
            let mut state = previews.state();
            state.in_flight = None;
            match image {
                // Cancelled by a newer request, which is pending now.
                Some(Err(())) => continue,
                Some(Ok(image)) => state.answer = Some((number, Some(image))),
                None => state.answer = Some((number, None)),
            }
            drop(state);
            previews.shared.answered.notify_all();
        }
        previews.paused_until()
    }
}
