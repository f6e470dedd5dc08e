//! What the viewer shows: the latest images and the event stream, fed by the render loop.
//!
//! Events, one JSON object each (every one has `kind`; times are milliseconds):
//!
//! ```text
//! {"kind":"reload","reload":3,"trigger":["scene.ron"],"target_spp":64,"since_save_ms":1.2}
//! {"kind":"pass","reload":3,"spp":16,"preview":false,"target_spp":64,"width":512,"height":512,
//!  "changed":"materials","since_save_ms":41.0,"samples_per_s":2.1e6,"trigger":["scene.ron"]}
//! {"kind":"progress","reload":3,"rows":128,"height":512}
//! {"kind":"done","reload":3,"spp":64,"full_ms":812.0,"line":"reload 3: materials | …"}
//! {"kind":"denoised","reload":3,"spp":16,"quality":"balanced","took_ms":210.4,"since_save_ms":380.2}
//! {"kind":"pick","reload":3,"width":512,"height":512,"entities":8}
//! {"kind":"error","file":"scene.ron","line":6,"column":40,"field":"materials.red.albedo",
//!  "message":"material \"red\": …","source_line":"        \"red\": Diffuse(albedo: …","reload":2}
//! ```
//!
//! `reload` starts a render of a good save (and clears an error), `pass` says a new image is
//! at `/image.f32` (and the other image routes), `progress` counts the rows of the pass in
//! flight, `done` ends a render at full quality, `denoised` says a denoised image of a pass of
//! the render shown (`spp` samples, denoised at `quality` in `took_ms`) is at `/denoised.f32`,
//! with that pass's albedo and normal at `/albedo.f32` and `/normal.f32` (see
//! [`Feed::denoise_sink`]), `pick` says the ids and entities of reload `reload`'s scene are
//! at `/pick/ids.u32` and `/pick/table.json` (see [`Feed::pick_sink`]), and `error` is a save
//! that did not load (the last good image stays; `reload` is the number of the render still
//! shown). A new client first gets the latest `reload`, `pass`, `denoised`, `pick`, `done` and
//! `error` that still apply.
//!
//! An error's place is its own fields, as the loader found it: `file`, and `line`, `column` and
//! `field` where known (`null` otherwise); `message` says what is wrong, without the place. Its
//! `message` is at most [`MAX_MESSAGE`] bytes and its `source_line` (the report's,
//! from a scene or prefab file only) at most [`MAX_SOURCE_LINE`] characters, each ending in
//! [`CUT`](super::CUT) when cut, whatever the watch loop sends; events are kept and replayed, so they must
//! stay small. JSON escapes every control character, so an event is always one `data:` line.

use std::collections::VecDeque;
use std::sync::{Arc, Condvar, Mutex, MutexGuard, PoisonError};
use std::time::{Duration, Instant};

use indicatif::ProgressBar;
use serde_json::{Value, json};

use super::event_text::{
    MAX_MESSAGE, MAX_SOURCE_LINE, bounded, bounded_chars, changed_text, ms, names,
};
use super::images::{DenoisedImages, Frame};
use super::pick::Picks;
use crate::denoise::{DenoiseSink, DenoisedFrame};
use crate::film::Film;
use crate::watch::{Observer, PickSink, Picked, Report};

/// Events a stalled client may have queued; older ones are dropped.
const QUEUE: usize = 32;

/// An event-stream client: its queue, filled by the render loop, drained by its own thread.
pub struct Client {
    queue: Mutex<VecDeque<Arc<str>>>,
    ready: Condvar,
}

impl Client {
    fn push(&self, event: &Arc<str>) {
        let mut q = self.queue.lock().unwrap_or_else(PoisonError::into_inner);
        if q.len() == QUEUE {
            // A stalled client skips ahead: the newest events matter, the oldest are stale.
            q.pop_front();
        }
        q.push_back(event.clone());
        drop(q);
        self.ready.notify_one();
    }

    /// Every queued event, waiting at most `timeout` for one (empty on timeout).
    pub fn next_batch(&self, timeout: Duration) -> Vec<Arc<str>> {
        let q = self.queue.lock().unwrap_or_else(PoisonError::into_inner);
        let (mut q, _) = self
            .ready
            .wait_timeout_while(q, timeout, |q| q.is_empty())
            .unwrap_or_else(PoisonError::into_inner);
        q.drain(..).collect()
    }
}

/// The render in progress, for rates and progress.
#[derive(Clone)]
struct Render {
    reload: u64,
    /// When its first frame started (the renderer's clock for samples/s).
    started: Instant,
    height: u32,
    trigger: Vec<String>,
    /// From the save to `started`.
    since_save: Duration,
}

/// The events a new client gets first.
#[derive(Default)]
struct Sticky {
    reload: Option<Arc<str>>,
    pass: Option<Arc<str>>,
    denoised: Option<Arc<str>>,
    pick: Option<Arc<str>>,
    done: Option<Arc<str>>,
    error: Option<Arc<str>>,
}

#[derive(Default)]
struct State {
    current: Option<Arc<Frame>>,
    previous: Option<Arc<Frame>>,
    /// The newest denoised pass of the reload shown.
    denoised: Option<Arc<DenoisedImages>>,
    /// The ids and provenance of the latest scene rendered.
    picks: Option<Arc<Picks>>,
    render: Option<Render>,
    sticky: Sticky,
    clients: Vec<Arc<Client>>,
    /// The progress last sent (rows), to send only changes.
    progress_sent: u64,
}

struct Shared {
    state: Mutex<State>,
    progress: ProgressBar,
}

/// The server's side of the render loop: sees the watch loop's reports (see [`Feed::observer`]),
/// keeps the latest images and broadcasts events. Cheap to clone; all clones share one state.
#[derive(Clone)]
pub struct Feed {
    shared: Arc<Shared>,
}

impl Default for Feed {
    fn default() -> Self {
        Self::new()
    }
}

impl Feed {
    /// An empty feed: no image yet, no clients.
    pub fn new() -> Self {
        Self {
            shared: Arc::new(Shared {
                state: Mutex::new(State::default()),
                progress: ProgressBar::hidden(),
            }),
        }
    }

    fn state(&self) -> MutexGuard<'_, State> {
        self.shared
            .state
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
    }

    /// The latest image.
    pub fn current(&self) -> Option<Arc<Frame>> {
        self.state().current.clone()
    }

    /// The last image of the render before the latest save.
    pub fn previous(&self) -> Option<Arc<Frame>> {
        self.state().previous.clone()
    }

    /// The newest denoised pass of the reload shown, if one arrived (see [`Feed::denoise_sink`]).
    pub fn denoised(&self) -> Option<Arc<DenoisedImages>> {
        self.state().denoised.clone()
    }

    /// The ids and provenance of the latest scene rendered (see [`Feed::pick_sink`]).
    pub fn picks(&self) -> Option<Arc<Picks>> {
        self.state().picks.clone()
    }

    /// This feed as the watch loop's pick sink ([`crate::watch::Watch::set_pick_sink`]): keeps
    /// each scene's ids and provenance in place of the last ones and sends a `pick` event.
    pub fn pick_sink(&self) -> PickSink {
        let feed = self.clone();
        Arc::new(move |picked| feed.take_picked(picked))
    }

    fn take_picked(&self, picked: Picked) {
        let picks = Picks::new(picked);
        let event = picks.event();
        let mut state = self.state();
        state.picks = Some(Arc::new(picks));
        let text = Self::broadcast(&mut state, &event);
        state.sticky.pick = Some(text);
    }

    /// A new event-stream client, already holding the events that describe the present; `None`
    /// if `max` clients are connected.
    pub fn subscribe(&self, max: usize) -> Option<Arc<Client>> {
        let mut state = self.state();
        if state.clients.len() >= max {
            return None;
        }
        let client = Arc::new(Client {
            queue: Mutex::new(VecDeque::new()),
            ready: Condvar::new(),
        });
        let s = &state.sticky;
        for e in [&s.reload, &s.pass, &s.denoised, &s.pick, &s.done, &s.error]
            .into_iter()
            .flatten()
        {
            client.push(e);
        }
        state.clients.push(client.clone());
        Some(client)
    }

    /// Forgets a client (its stream closed).
    pub fn unsubscribe(&self, client: &Arc<Client>) {
        self.state().clients.retain(|c| !Arc::ptr_eq(c, client));
    }

    /// Connected event-stream clients.
    pub fn clients(&self) -> usize {
        self.state().clients.len()
    }

    /// Sends `event` to every client; returns it shared.
    fn broadcast(state: &mut State, event: &Value) -> Arc<str> {
        let text: Arc<str> = event.to_string().into();
        for c in &state.clients {
            c.push(&text);
        }
        text
    }

    /// Sends a `progress` event if rows were rendered since the last one (called by a timer).
    pub fn send_progress(&self) {
        let rows = self.shared.progress.position();
        let mut state = self.state();
        if rows == state.progress_sent {
            return;
        }
        state.progress_sent = rows;
        // The height is known from the render's first image on (the preview comes first).
        let Some(render) = state.render.as_ref().filter(|r| r.height > 0) else {
            return;
        };
        let event = json!({
            "kind": "progress",
            "reload": render.reload,
            "rows": rows.min(u64::from(render.height)),
            "height": render.height,
        });
        Self::broadcast(&mut state, &event);
    }

    fn restart_progress(&self, state: &mut State) {
        self.shared.progress.set_position(0);
        state.progress_sent = 0;
    }

    /// The hidden progress bar the renderer should advance ([`crate::watch::Watch::set_progress`]).
    pub fn progress_bar(&self) -> ProgressBar {
        self.shared.progress.clone()
    }

    /// This feed as the watch loop's [`Observer`].
    pub fn observer(&self) -> Observer {
        let feed = self.clone();
        Box::new(move |report, film| feed.observe(report, film))
    }

    /// This feed as the watch loop's denoise sink ([`crate::watch::Watch::set_denoise_sink`]):
    /// see [`Feed::take_denoised`].
    pub fn denoise_sink(&self) -> DenoiseSink {
        let feed = self.clone();
        Arc::new(move |frame| feed.take_denoised(frame))
    }

    /// Takes a denoised pass from the denoise thread: keeps its denoised colour, albedo and
    /// normal (encoded here, outside the lock) in place of the last ones and sends a `denoised`
    /// event. A pass of an older reload than the image shown, or of an older reload or fewer
    /// samples than the denoised pass kept, arrived late and is dropped.
    pub fn take_denoised(&self, frame: &DenoisedFrame) {
        if !Self::wanted(&self.state(), frame) {
            return;
        }
        let Some(images) = DenoisedImages::of(frame) else {
            return;
        };
        let mut state = self.state();
        // Checked again: an image of a newer reload may have come meanwhile.
        if !Self::wanted(&state, frame) {
            return;
        }
        state.denoised = Some(Arc::new(images));
        let event = json!({
            "kind": "denoised",
            "reload": frame.reload,
            "spp": frame.samples,
            "quality": frame.quality.name(),
            "took_ms": ms(frame.took),
            "since_save_ms": ms(frame.saved.elapsed()),
        });
        let text = Self::broadcast(&mut state, &event);
        state.sticky.denoised = Some(text);
    }

    /// Whether `frame` is newer than what the feed shows and keeps.
    fn wanted(state: &State, frame: &DenoisedFrame) -> bool {
        let shown = state.current.as_ref().map_or(0, |c| c.reload());
        let kept = state
            .denoised
            .as_ref()
            .map_or((0, 0), |d| (d.reload(), d.samples()));
        frame.reload >= shown && (frame.reload, frame.samples) >= kept
    }

    /// Takes one report of the watch loop (with the film of a [`Report::Wrote`]): updates the
    /// images and sends the matching event. Returns at once: the film is copied (~1 ms at 512²),
    /// encodings are made on request.
    pub fn observe(&self, report: &Report, film: Option<&Film>) {
        let mut state = self.state();
        let shown = state.current.as_ref().map(|c| c.reload());
        let event = match (report, film) {
            (
                Report::Started {
                    reload,
                    trigger,
                    spp,
                    saved,
                },
                _,
            ) => {
                self.restart_progress(&mut state);
                let height = state.render.as_ref().map_or(0, |r| r.height);
                let render = state.render.insert(Render {
                    reload: *reload,
                    started: Instant::now(),
                    height,
                    trigger: names(trigger),
                    since_save: saved.elapsed(),
                });
                json!({
                    "kind": "reload",
                    "reload": reload,
                    "trigger": render.trigger,
                    "target_spp": spp,
                    "since_save_ms": ms(render.since_save),
                })
            }
            (
                Report::Wrote {
                    reload,
                    preview,
                    spp,
                    changes,
                    new_scene,
                    ..
                },
                Some(film),
            ) => {
                self.restart_progress(&mut state);
                // A/B's "before": the image before the last save that changed something (a reload
                // that changed nothing, e.g. a touch, goes on with the same image).
                if *new_scene && shown.is_some() {
                    state.previous = state.current.take();
                }
                state.current = Some(Arc::new(Frame::new(*reload, film.clone())));
                // The denoised images of an older reload are not of this image.
                if state
                    .denoised
                    .as_ref()
                    .is_some_and(|d| d.reload() < *reload)
                {
                    state.denoised = None;
                    state.sticky.denoised = None;
                }
                let render = match state.render.as_mut() {
                    Some(r) if r.reload == *reload => r,
                    _ => state.render.insert(Render {
                        reload: *reload,
                        started: Instant::now(),
                        height: film.height,
                        trigger: Vec::new(),
                        since_save: Duration::ZERO,
                    }),
                };
                render.height = film.height;
                let elapsed = render.started.elapsed();
                let pixels = f64::from(film.width) * f64::from(film.height);
                let rate = pixels * f64::from(film.samples) / elapsed.as_secs_f64().max(1e-9);
                json!({
                    "kind": "pass",
                    "reload": reload,
                    "spp": film.samples,
                    "preview": preview,
                    "target_spp": spp,
                    "width": film.width,
                    "height": film.height,
                    "changed": changed_text(changes),
                    "trigger": render.trigger,
                    "since_save_ms": ms(render.since_save + elapsed),
                    "samples_per_s": rate.round(),
                })
            }
            (Report::Rendered(r), _) if r.completed() => json!({
                "kind": "done",
                "reload": r.number,
                "spp": r.spp,
                "full_ms": r.full.map(ms),
                "line": r.to_string(),
            }),
            (Report::Failed(error), _) => json!({
                "kind": "error",
                "file": bounded(&error.path.display().to_string(), MAX_MESSAGE),
                "line": error.location.map(|l| l.line),
                "column": error.location.map(|l| l.col),
                // The column under the name events gave it before `column`, so that scripts
                // reading an error's place keep working.
                "col": error.location.map(|l| l.col),
                "field": error.field.as_deref().map(|f| bounded(f, MAX_MESSAGE)),
                "message": bounded(&error.message, MAX_MESSAGE),
                "source_line": error.source_line.as_deref().map(|l| bounded_chars(l, MAX_SOURCE_LINE)),
                "reload": shown,
            }),
            (Report::SceneMissing { path }, _) => json!({
                "kind": "error",
                "file": bounded(&path.display().to_string(), MAX_MESSAGE),
                "message": "deleted; waiting for it to come back",
                "reload": shown,
            }),
            _ => return,
        };
        let text = Self::broadcast(&mut state, &event);
        let sticky = &mut state.sticky;
        match event["kind"].as_str() {
            // A good save starts afresh: the error and the old render's events no longer apply
            // (its denoised image and its ids do until the new render's replace them).
            Some("reload") => {
                *sticky = Sticky {
                    reload: Some(text),
                    denoised: sticky.denoised.take(),
                    pick: sticky.pick.take(),
                    ..Sticky::default()
                }
            }
            Some("pass") => sticky.pass = Some(text),
            Some("done") => sticky.done = Some(text),
            _ => sticky.error = Some(text),
        }
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::ecs::resources::ChangeSummary;
    use crate::serve::images::{DenoisedLayer, RAW_MAGIC};

    #[test]
    fn a_stalled_client_keeps_only_the_newest_events() {
        let feed = Feed::new();
        let client = feed.subscribe(4).expect("room for a client");
        let mut state = feed.state();
        for i in 0..QUEUE + 5 {
            Feed::broadcast(&mut state, &json!({ "i": i }));
        }
        drop(state);
        let got = client.next_batch(Duration::ZERO);
        assert_eq!(got.len(), QUEUE);
        assert_eq!(&*got[0], r#"{"i":5}"#);
        assert_eq!(&*got[QUEUE - 1], format!(r#"{{"i":{}}}"#, QUEUE + 4));
        assert!(feed.subscribe(1).is_none(), "the limit holds");
    }

    /// A pass of `reload` (the first image of another scene if `new_scene`).
    fn wrote(feed: &Feed, reload: u64, new_scene: bool, film: &Film) {
        let report = Report::Wrote {
            reload,
            samples: 1,
            preview: false,
            spp: 1,
            changes: ChangeSummary::default(),
            new_scene,
            at: Instant::now(),
        };
        feed.observe(&report, Some(film));
    }

    #[test]
    fn the_image_before_a_save_is_the_last_image_of_the_scene_before() {
        // CI's browser test: red (0), blue (1), green loaded by reload 2 but superseded before
        // its first pass by reload 3 of the same file, whose image is the first of green.
        let feed = Feed::new();
        let film = Film::new(1, 1);
        wrote(&feed, 0, true, &film);
        wrote(&feed, 1, true, &film);
        wrote(&feed, 3, true, &film);
        let before = |feed: &Feed| feed.previous().map(|f| f.reload());
        assert_eq!(
            before(&feed),
            Some(1),
            "A/B shows the image before the save"
        );
        // More passes of the same scene, and a touch (a reload of the same scene), keep the pair.
        wrote(&feed, 3, false, &film);
        wrote(&feed, 4, false, &film);
        assert_eq!(before(&feed), Some(1));
        wrote(&feed, 7, true, &film);
        assert_eq!(before(&feed), Some(4));
    }

    /// A denoised pass of `reload` at `samples` spp, 2×1 pixels: denoised colour `samples`
    /// (each channel), albedo `(0.25, 0.5, 0.75)`, normals `±z`.
    fn denoised(reload: u64, samples: u32) -> DenoisedFrame {
        let s = samples as f32;
        DenoisedFrame {
            reload,
            samples,
            images: crate::denoise::FilmImages {
                width: 2,
                height: 1,
                colour: vec![Vec3::ZERO; 2],
                albedo: Some(vec![Vec3::new(0.25, 0.5, 0.75); 2]),
                normal: Some(vec![Vec3::Z, -Vec3::Z]),
            },
            denoised: vec![Vec3::splat(s); 2],
            quality: crate::denoise::Quality::Balanced,
            took: Duration::from_micros(1500),
            saved: Instant::now(),
        }
    }

    /// The header (width, height, reload, samples) and floats of a raw encoding.
    fn decode(raw: &[u8]) -> ([u32; 4], Vec<f32>) {
        assert_eq!(&raw[..8], RAW_MAGIC);
        let u = |i: usize| u32::from_le_bytes(raw[8 + 4 * i..12 + 4 * i].try_into().unwrap());
        let floats = raw[24..]
            .chunks(4)
            .map(|b| f32::from_le_bytes(b.try_into().unwrap()))
            .collect();
        ([u(0), u(1), u(2), u(3)], floats)
    }

    /// `(reload, spp)` of the denoised pass the feed keeps.
    fn kept(feed: &Feed) -> Option<(u64, u32)> {
        feed.denoised().map(|d| (d.reload(), d.samples()))
    }

    #[test]
    fn the_newest_denoised_pass_of_the_reload_shown_is_kept() {
        let feed = Feed::new();
        let sink = feed.denoise_sink();
        let film = Film::new(2, 1);
        wrote(&feed, 2, true, &film);
        assert_eq!(kept(&feed), None, "nothing before a denoised pass");
        sink(&denoised(2, 4));
        assert_eq!(kept(&feed), Some((2, 4)));
        sink(&denoised(2, 2));
        assert_eq!(kept(&feed), Some((2, 4)), "fewer samples arrived late");
        sink(&denoised(1, 64));
        assert_eq!(kept(&feed), Some((2, 4)), "an older reload arrived late");
        sink(&denoised(2, 8));
        assert_eq!(kept(&feed), Some((2, 8)));
        // The next reload's first image: the denoised one is of another image now.
        wrote(&feed, 3, false, &film);
        assert_eq!(kept(&feed), None);
        sink(&denoised(2, 16));
        assert_eq!(
            kept(&feed),
            None,
            "a pass of the reload before is not shown"
        );
        sink(&denoised(3, 1));
        assert_eq!(kept(&feed), Some((3, 1)));
    }

    #[test]
    fn denoised_images_are_raw_floats_of_the_same_pass() {
        let feed = Feed::new();
        wrote(&feed, 5, true, &Film::new(2, 1));
        feed.denoise_sink()(&denoised(5, 3));
        let images = feed.denoised().expect("kept");
        let layer = |l| decode(images.raw(l).expect("present"));
        assert_eq!(layer(DenoisedLayer::Denoised), ([2, 1, 5, 3], vec![3.0; 6]));
        assert_eq!(
            layer(DenoisedLayer::Albedo),
            ([2, 1, 5, 3], [0.25, 0.5, 0.75].repeat(2))
        );
        assert_eq!(
            layer(DenoisedLayer::Normal),
            ([2, 1, 5, 3], vec![0.0, 0.0, 1.0, 0.0, 0.0, -1.0])
        );

        // A pass without features has only the denoised colour; one of the wrong size nothing.
        let mut plain = denoised(5, 4);
        plain.images.albedo = None;
        plain.images.normal = Some(vec![Vec3::Z]);
        feed.take_denoised(&plain);
        let images = feed.denoised().expect("kept");
        assert_eq!(images.samples(), 4);
        assert!(images.raw(DenoisedLayer::Denoised).is_some());
        assert_eq!(images.raw(DenoisedLayer::Albedo), None);
        assert_eq!(
            images.raw(DenoisedLayer::Normal),
            None,
            "1 normal for 2 pixels"
        );
        let mut short = denoised(5, 8);
        short.denoised.pop();
        feed.take_denoised(&short);
        assert_eq!(
            kept(&feed),
            Some((5, 4)),
            "a short denoised image is not kept"
        );
    }

    #[test]
    fn denoised_events_say_which_pass_and_are_replayed_while_they_apply() {
        let feed = Feed::new();
        let early = feed.subscribe(8).expect("room");
        wrote(&feed, 0, true, &Film::new(2, 1));
        feed.denoise_sink()(&denoised(0, 16));
        let events: Vec<Value> = early
            .next_batch(Duration::ZERO)
            .iter()
            .map(|e| serde_json::from_str(e).expect("JSON"))
            .collect();
        let event = events.last().expect("events");
        assert_eq!(event["kind"], "denoised");
        assert_eq!(
            (
                &event["reload"],
                &event["spp"],
                &event["quality"],
                &event["took_ms"]
            ),
            (&json!(0), &json!(16), &json!("balanced"), &json!(1.5))
        );
        assert!(event["since_save_ms"].as_f64().is_some_and(|t| t >= 0.0));
        let replayed = |feed: &Feed| {
            let client = feed.subscribe(8).expect("room");
            let kinds: Vec<String> = client
                .next_batch(Duration::ZERO)
                .iter()
                .map(|e| serde_json::from_str::<Value>(e).expect("JSON")["kind"].to_string())
                .collect();
            feed.unsubscribe(&client);
            kinds.join(" ")
        };
        assert_eq!(replayed(&feed), r#""pass" "denoised""#);
        // A save: the denoised image stays until the new render's first image.
        let started = Report::Started {
            reload: 1,
            trigger: Vec::new(),
            spp: 1,
            saved: Instant::now(),
        };
        feed.observe(&started, None);
        assert_eq!(replayed(&feed), r#""reload" "denoised""#);
        wrote(&feed, 1, true, &Film::new(2, 1));
        assert_eq!(replayed(&feed), r#""reload" "pass""#);
    }
}
