//! The live viewer of `rondo watch --serve`: an HTTP server that shows every pass in a browser.
//!
//! Routes (anything else is `404 Not Found`; methods other than GET and HEAD are `405`, but for
//! `/camera` and the previews, which take POST only; `HEAD` answers the same headers as `GET`, without a body):
//!
//! | route | content |
//! |---|---|
//! | `GET /` | the viewer page (`page.html`, compiled in: no CDN, works offline) |
//! | `GET /image.png` | the latest image as 8-bit sRGB PNG, byte-identical to what `-o out.png` writes |
//! | `GET /image.exr` | the latest image as linear float OpenEXR (like `-o out.exr`) |
//! | `GET /image.f32` | the latest image as raw linear floats (see [`RAW_MAGIC`]), for the page |
//! | `GET /previous.f32` | the last image of the render before the latest save (the page's A/B) |
//! | `GET /denoised.f32` | the newest denoised pass of the render shown, as raw floats (see [`Feed::denoise_sink`]) |
//! | `GET /albedo.f32` | that pass's mean albedo, as raw floats |
//! | `GET /normal.f32` | that pass's mean shading normal (components in [-1, 1]), as raw floats |
//! | `GET /events` | server-sent events: one JSON object per `data:` line (see [`Feed`]) |
//! | `GET /pick.js`, `/pick/…` | picking: which entity each pixel shows, and where it is written (`pick.rs`) |
//! | `GET /camera.json` | the scene file's camera and the file's version (`camera.rs`) |
//! | `POST /camera` | writes a camera into the scene file: only its `camera:` value changes (`camera.rs`) |
//! | `GET /camera_write.js` | the page's side of the camera write (`window.rondoCamera`) |
//! | `POST /preview.f32`, `/preview.png` | a framing preview through the page's camera; writes nothing (`preview.rs`) |
//! | `GET /frame.js` | the page's side of framing: mouse and keys, Save camera, Undo |
//!
//! The images answer `503` until the first pass exists; the denoised pass's images answer `404`
//! while there is none for the render shown (none yet, denoising off, or no denoiser). Each
//! image route names its pass in the headers `X-Rondo-Reload` and `X-Rondo-Samples`. Query strings are ignored (`/image.png?t=1`
//! is `/image.png`); paths are matched exactly, so `/../image.png` or `//image.png` are 404.
//!
//! Whatever the bound address, the server answers only requests whose `Host` names an IP
//! address (`127.0.0.1`, `192.168.1.5`, `[::1]`), `localhost`, or a name given with
//! `--allow-host` (any port, so SSH port forwards work), and `403` to the rest: a web page
//! elsewhere cannot rebind its own name to the server's address and read the images.
//!
//! The one route that changes a file, `POST /camera`, and the previews, which cost render time,
//! also need the session's secret in `X-Rondo-Token` (`secret.rs`; the page gets it in its HTML)
//! and refuse an `Origin` other than `http://<Host>`; `POST /camera` writes only the watched scene file itself (never a prefab, never through a
//! symbolic link) and only if it is still the version the page read (see `camera.rs`).
//!
//! The server is `http.rs`: std sockets, one thread and one request per connection, every
//! resource bounded by [`Limits`] (head size, time to send it, stalled writes, open
//! connections, event streams); a connection over the limit gets `503` and is closed at once.
//! The render loop's side is [`Feed`] (`feed.rs`: the latest images, the clients and their
//! events); the images and their encodings are in `images.rs`, the events' text in
//! `event_text.rs`.
//!
//! The render loop talks to the server only through the watch loop's event point
//! ([`crate::watch::Observer`], made by [`Feed::observer`]): each report copies what it needs
//! under a short lock and returns. Every event-stream client has its own thread and a bounded
//! queue: a client that stalls loses its oldest queued events, never blocks the render; a
//! closed client is dropped at its next write.

mod camera;
mod event_text;
mod feed;
mod http;
mod images;
mod pick;
mod preview;
mod secret;

use std::io::Write;
use std::net::{IpAddr, Ipv4Addr, Ipv6Addr, SocketAddr, TcpListener, TcpStream, ToSocketAddrs};
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::thread::JoinHandle;
use std::time::Duration;

use crate::watch::Previews;

pub use camera::MAX_BODY;
pub use event_text::{CUT, MAX_MESSAGE, MAX_SOURCE_LINE, changed_text};
pub use feed::{Client, Feed};
pub use images::{DenoisedImages, DenoisedLayer, Encoding, Frame, RAW_MAGIC};
pub use pick::{IDS_MAGIC, MAX_EDITOR_URL, Picks, parse_editor_url};

/// The page, compiled into the binary.
pub const PAGE: &str = include_str!("page.html");

/// The address `--serve` binds without an argument. If its port is taken, a free port is used.
pub const DEFAULT_ADDR: &str = "127.0.0.1:8730";

/// How long an idle event stream waits before writing a keep-alive comment (which is also how a
/// closed client is noticed when nothing happens).
const KEEP_ALIVE: Duration = Duration::from_secs(10);

/// How often the progress of the pass in flight is sent, at most.
const PROGRESS_TICK: Duration = Duration::from_millis(50);

/// What one client can hold of the server.
#[derive(Clone, Debug)]
pub struct Limits {
    /// Longest request head (request line and headers), in bytes; longer ones get `431`.
    pub max_head: usize,
    /// Time from the connection to the end of its request head; a client that sends nothing
    /// in that time is disconnected (one that sent part of a head gets `408`).
    pub head_timeout: Duration,
    /// A write to a client that makes no progress for this long ends its connection (a client
    /// that stopped reading an image or the event stream).
    pub write_timeout: Duration,
    /// Connections open at once, event streams included; more get `503` and are closed.
    pub max_connections: usize,
    /// Event streams open at once; more get `503` (each holds a thread).
    pub max_streams: usize,
}

impl Default for Limits {
    /// 16 KiB heads sent within 10 s, writes stalled for at most 30 s, 128 connections of
    /// which at most 64 are event streams (so images are served even with every stream open).
    fn default() -> Self {
        Self {
            max_head: 16 * 1024,
            head_timeout: Duration::from_secs(10),
            write_timeout: Duration::from_secs(30),
            max_connections: 128,
            max_streams: 64,
        }
    }
}

/// How the viewer serves, besides its address.
#[derive(Clone, Debug, Default)]
pub struct Options {
    /// Host names accepted in `Host` besides IP addresses and `localhost` (`--allow-host`;
    /// compared without regard to case).
    pub allowed_hosts: Vec<String>,
    /// The bounds on every client.
    pub limits: Limits,
    /// The template that turns a `file:line:col` of picking into a link (`--editor-url`,
    /// checked by [`parse_editor_url`]).
    pub editor_url: Option<String>,
    /// The watched scene file, whose camera `POST /camera` may rewrite (`None`: the camera
    /// routes answer `404`).
    pub scene: Option<PathBuf>,
    /// Where framing previews are asked of the render loop ([`crate::watch::Watch::set_previews`]
    /// with a clone; `None`: the preview routes answer `404`).
    pub previews: Option<Previews>,
}

/// Why the server could not start.
#[derive(Debug, thiserror::Error)]
pub enum ServeError {
    /// The address is not `HOST:PORT` or a port.
    #[error("--serve {0:?}: expected HOST:PORT (e.g. 127.0.0.1:8080) or a port")]
    Address(String),
    /// No session secret could be drawn.
    #[error("cannot serve: {0}")]
    Secret(String),
    /// Binding failed.
    #[error("cannot serve on {addr}: {message}")]
    Bind {
        /// The address.
        addr: String,
        /// Why.
        message: String,
    },
}

/// Parses the argument of `--serve`: `HOST:PORT`, `[IPv6]:PORT`, or a bare port (on loopback).
pub fn parse_addr(text: &str) -> Result<SocketAddr, ServeError> {
    let bad = || ServeError::Address(text.to_string());
    if let Ok(port) = text.parse::<u16>() {
        return Ok(SocketAddr::from(([127, 0, 0, 1], port)));
    }
    text.to_socket_addrs()
        .map_err(|_| bad())?
        .next()
        .ok_or_else(bad)
}

/// Checks the argument of `--allow-host`: a DNS name (letters, digits, `-` and `.`, at most
/// 253 characters, no port); returns it in lower case.
pub fn parse_host_name(text: &str) -> Result<String, String> {
    let valid = !text.is_empty()
        && text.len() <= 253
        && text.split('.').all(|label| {
            (1..=63).contains(&label.len())
                && label
                    .bytes()
                    .all(|b| b.is_ascii_alphanumeric() || b == b'-')
        });
    if valid {
        Ok(text.to_ascii_lowercase())
    } else {
        Err(format!(
            "{text:?} is not a host name (letters, digits, '-' and '.', no port; IP addresses and localhost are always accepted)"
        ))
    }
}

/// Whether a `Host` header value may be answered: an IP address (IPv6 in brackets),
/// `localhost` or one of `allowed`, with or without a port.
fn host_allowed(host: &str, allowed: &[String]) -> bool {
    let (name, port) = match host.strip_prefix('[') {
        Some(rest) => match rest.split_once(']') {
            Some((ip, "")) => (ip, None),
            Some((ip, port)) => match port.strip_prefix(':') {
                Some(port) => (ip, Some(port)),
                None => return false,
            },
            None => return false,
        },
        None => match host.split_once(':') {
            Some((name, port)) => (name, Some(port)),
            None => (host, None),
        },
    };
    if port.is_some_and(|p| p.parse::<u16>().is_err() || !p.bytes().all(|b| b.is_ascii_digit())) {
        return false;
    }
    if host.starts_with('[') {
        return name.parse::<Ipv6Addr>().is_ok();
    }
    name.parse::<Ipv4Addr>().is_ok()
        || name.eq_ignore_ascii_case("localhost")
        || allowed.iter().any(|a| a.eq_ignore_ascii_case(name))
}

/// What every connection's thread shares.
struct Context {
    feed: Feed,
    options: Options,
    /// The page, with the session's secret in it.
    page: String,
    /// The secret a write must carry.
    secret: secret::Secret,
    /// The scene file of the camera routes.
    scene: camera::SceneFile,
    /// Connections open now.
    open: AtomicUsize,
}

/// A connection's place in [`Context::open`], given back on drop.
struct Slot(Arc<Context>);

impl Slot {
    /// A place, if fewer than the limit are taken.
    fn take(context: &Arc<Context>) -> Option<Self> {
        let max = context.options.limits.max_connections;
        context
            .open
            .fetch_update(Ordering::AcqRel, Ordering::Acquire, |n| {
                (n < max).then_some(n + 1)
            })
            .ok()
            .map(|_| Self(context.clone()))
    }
}

impl Drop for Slot {
    fn drop(&mut self) {
        self.0.open.fetch_sub(1, Ordering::AcqRel);
    }
}

/// A running viewer server. Dropping it stops accepting connections.
pub struct Viewer {
    addr: SocketAddr,
    stop: Arc<AtomicBool>,
    accept: Option<JoinHandle<()>>,
    ticker: Option<JoinHandle<()>>,
}

impl Viewer {
    /// Binds `addr` and starts serving the returned [`Feed`]'s images and events. With
    /// `fall_back`, a taken port is replaced by a free one (for the default address).
    pub fn start(
        addr: SocketAddr,
        fall_back: bool,
        options: Options,
    ) -> Result<(Self, Feed), ServeError> {
        let bind = |a: SocketAddr| {
            TcpListener::bind(a).map_err(|e| ServeError::Bind {
                addr: a.to_string(),
                message: e.to_string(),
            })
        };
        let listener = match bind(addr) {
            Err(_) if fall_back => bind(SocketAddr::new(addr.ip(), 0))?,
            other => other?,
        };
        let addr = listener.local_addr().map_err(|e| ServeError::Bind {
            addr: addr.to_string(),
            message: e.to_string(),
        })?;
        let feed = Feed::new();
        let stop = Arc::new(AtomicBool::new(false));
        let secret = secret::Secret::new().map_err(ServeError::Secret)?;
        let context = Arc::new(Context {
            feed: feed.clone(),
            page: secret.page_with(PAGE),
            secret,
            scene: camera::SceneFile::new(options.scene.clone()),
            options,
            open: AtomicUsize::new(0),
        });
        let bind_error = |e: std::io::Error| ServeError::Bind {
            addr: addr.to_string(),
            message: format!("cannot start a thread: {e}"),
        };
        let accept = {
            let stop = stop.clone();
            std::thread::Builder::new()
                .name("rondo-serve".into())
                .spawn(move || accept_connections(&listener, &context, &stop))
                .map_err(bind_error)?
        };
        let ticker = {
            let (feed, stop) = (feed.clone(), stop.clone());
            std::thread::Builder::new()
                .name("rondo-serve-progress".into())
                .spawn(move || {
                    while !stop.load(Ordering::Relaxed) {
                        std::thread::sleep(PROGRESS_TICK);
                        feed.send_progress();
                    }
                })
        };
        let mut viewer = Self {
            addr,
            stop,
            accept: Some(accept),
            ticker: None,
        };
        // On an error the viewer is dropped, which stops the accept thread.
        viewer.ticker = Some(ticker.map_err(bind_error)?);
        Ok((viewer, feed))
    }

    /// The bound address (with the real port if 0 was asked for).
    pub fn addr(&self) -> SocketAddr {
        self.addr
    }

    /// The page's URL, `http://127.0.0.1:PORT/`.
    pub fn url(&self) -> String {
        format!("http://{}/", self.addr)
    }

    /// A warning to print if the server is reachable from other machines.
    pub fn exposure_warning(&self) -> Option<String> {
        (!self.addr.ip().is_loopback()).then(|| {
            format!(
                "the viewer listens on {}: anyone who can reach this machine on that network can see the images and rewrite the camera of the scene file",
                self.addr
            )
        })
    }
}

impl Drop for Viewer {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        // Wake the accept loop with a connection of our own; if none can be made, the thread
        // is left to end with the process rather than waited for.
        let ip = match self.addr.ip() {
            IpAddr::V4(ip) if ip.is_unspecified() => IpAddr::V4(Ipv4Addr::LOCALHOST),
            IpAddr::V6(ip) if ip.is_unspecified() => IpAddr::V6(Ipv6Addr::LOCALHOST),
            ip => ip,
        };
        let woken = TcpStream::connect_timeout(
            &SocketAddr::new(ip, self.addr.port()),
            Duration::from_secs(1),
        )
        .is_ok();
        if let Some(accept) = self.accept.take().filter(|_| woken) {
            let _ = accept.join();
        }
        if let Some(ticker) = self.ticker.take() {
            let _ = ticker.join();
        }
    }
}

/// The accept loop: one thread per connection, at most [`Limits::max_connections`] at once.
fn accept_connections(listener: &TcpListener, context: &Arc<Context>, stop: &AtomicBool) {
    for connection in listener.incoming() {
        if stop.load(Ordering::Relaxed) {
            return;
        }
        let Ok(stream) = connection else {
            // Out of descriptors, most likely: give the open connections a moment to end
            // rather than spin.
            std::thread::sleep(Duration::from_millis(10));
            continue;
        };
        let Some(slot) = Slot::take(context) else {
            refuse(stream);
            continue;
        };
        // If no thread can be started, the closure is dropped: the connection closes and its
        // slot is given back.
        let _ = std::thread::Builder::new()
            .name("rondo-serve-connection".into())
            .spawn(move || {
                let context = slot.0.clone();
                serve_connection(stream, &context);
                drop(slot);
            });
    }
}

/// Answers a connection over the limit with `503` without reading it, on the accept thread:
/// the answer fits a fresh socket's buffer, and a write that would block is given up.
fn refuse(mut stream: TcpStream) {
    if stream.set_nonblocking(true).is_ok() {
        let _ = http::respond_text(&mut stream, 503, "too many connections\n", true);
    }
    let _ = stream.shutdown(std::net::Shutdown::Both);
}

/// Reads one request and answers it.
fn serve_connection(mut stream: TcpStream, context: &Context) {
    let limits = &context.options.limits;
    let _ = stream.set_nodelay(true);
    if stream
        .set_write_timeout(Some(limits.write_timeout))
        .is_err()
    {
        return;
    }
    let request = match http::read_head(&mut stream, limits.max_head, limits.head_timeout) {
        Ok(request) => request,
        Err(error) => {
            let (status, text) = match error {
                http::HeadError::Closed | http::HeadError::Timeout { partial: false } => return,
                http::HeadError::Timeout { partial: true } => {
                    (408, "the request head took too long")
                }
                http::HeadError::TooLarge => (431, "the request head is too large"),
                http::HeadError::Version => (505, "only HTTP/1.x"),
                http::HeadError::Malformed(why) => (400, why),
            };
            let _ = http::respond_text(&mut stream, status, &format!("{text}\n"), true);
            return http::finish(stream);
        }
    };
    // A write error means the client is gone: nothing to do then.
    if answer(&mut stream, &request, context).is_ok() {
        http::finish(stream);
    }
}

/// The routes a request can name.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Route {
    Page,
    Png,
    Exr,
    Raw,
    PreviousRaw,
    Denoised(DenoisedLayer),
    Events,
    Pick(pick::Route),
    Camera(camera::Route),
    Frame(preview::Route),
}

impl Route {
    /// The route of a request target: the path before any `?`, matched exactly.
    fn of(url: &str) -> Option<Self> {
        let path = url.split_once('?').map_or(url, |(p, _)| p);
        Some(match path {
            "/" | "/index.html" => Self::Page,
            "/image.png" => Self::Png,
            "/image.exr" => Self::Exr,
            "/image.f32" => Self::Raw,
            "/previous.f32" => Self::PreviousRaw,
            "/denoised.f32" => Self::Denoised(DenoisedLayer::Denoised),
            "/albedo.f32" => Self::Denoised(DenoisedLayer::Albedo),
            "/normal.f32" => Self::Denoised(DenoisedLayer::Normal),
            "/events" => Self::Events,
            _ => {
                return pick::Route::of(path)
                    .map(Self::Pick)
                    .or_else(|| camera::Route::of(path).map(Self::Camera))
                    .or_else(|| preview::Route::of(path).map(Self::Frame));
            }
        })
    }
}

/// Answers a request: the Host check, the route, the method, then the content.
fn answer(
    stream: &mut TcpStream,
    request: &http::Request,
    context: &Context,
) -> std::io::Result<()> {
    let with_body = request.method != "HEAD";
    let text = |stream: &mut TcpStream, status, text: &str| {
        http::respond_text(stream, status, text, with_body)
    };
    let Some(host) = &request.host else {
        return text(stream, 400, "a Host header is required\n");
    };
    if !host_allowed(host, &context.options.allowed_hosts) {
        return text(
            stream,
            403,
            "the viewer answers only to an IP address, localhost or a name given with --allow-host\n",
        );
    }
    let Some(route) = Route::of(&request.target) else {
        return text(stream, 404, "not found\n");
    };
    let posts = match route {
        Route::Camera(route) => route == camera::Route::Write,
        Route::Frame(route) => route.posts(),
        _ => false,
    };
    if posts {
        if request.method != "POST" {
            return http::respond(
                stream,
                405,
                &[
                    ("Content-Type", "text/plain; charset=utf-8"),
                    ("Allow", "POST"),
                ],
                b"only POST\n",
                with_body,
            );
        }
    } else if !matches!(request.method.as_str(), "GET" | "HEAD") {
        return http::respond(
            stream,
            405,
            &[
                ("Content-Type", "text/plain; charset=utf-8"),
                ("Allow", "GET, HEAD"),
            ],
            b"only GET and HEAD\n",
            with_body,
        );
    }
    let feed = &context.feed;
    let (frame, content_type, encoding) = match route {
        Route::Events => return stream_events(stream, context, with_body),
        Route::Pick(route) => {
            let editor_url = context.options.editor_url.as_deref();
            let picks = feed.picks();
            let target = &request.target;
            return pick::answer(
                stream,
                route,
                target,
                picks.as_deref(),
                editor_url,
                with_body,
            );
        }
        Route::Camera(route) => {
            let shared = (&context.scene, &context.secret);
            let timeout = context.options.limits.head_timeout;
            return camera::answer(stream, route, request, shared, host, timeout);
        }
        Route::Frame(route) => {
            let shared = (context.options.previews.as_ref(), &context.secret);
            let timeout = context.options.limits.head_timeout;
            return preview::answer(stream, route, request, shared, host, timeout);
        }
        Route::Page => {
            return http::respond(
                stream,
                200,
                &[("Content-Type", "text/html; charset=utf-8")],
                context.page.as_bytes(),
                with_body,
            );
        }
        Route::Png => (feed.current(), "image/png", Encoding::Png),
        Route::Exr => (feed.current(), "image/x-exr", Encoding::Exr),
        Route::Raw => (feed.current(), "application/octet-stream", Encoding::Raw),
        Route::PreviousRaw => (feed.previous(), "application/octet-stream", Encoding::Raw),
        Route::Denoised(layer) => {
            let images = feed.denoised();
            let Some((images, bytes)) = images.as_ref().and_then(|d| Some((d, d.raw(layer)?)))
            else {
                return text(stream, 404, "no denoised image of this render\n");
            };
            let pass = (images.reload(), images.samples());
            return respond_image(stream, "application/octet-stream", pass, bytes, with_body);
        }
    };
    let Some(frame) = frame else {
        return text(stream, 503, "no image yet\n");
    };
    match frame.bytes(encoding) {
        // Written from the shared frame, no copy.
        Ok(bytes) => {
            let pass = (frame.reload(), frame.samples());
            respond_image(stream, content_type, pass, bytes, with_body)
        }
        Err(e) => text(stream, 500, &format!("cannot encode the image: {e}\n")),
    }
}

/// Answers an image: its bytes, naming its pass `(reload, samples)` in the headers.
fn respond_image(
    stream: &mut TcpStream,
    content_type: &str,
    (reload, samples): (u64, u32),
    bytes: &[u8],
    with_body: bool,
) -> std::io::Result<()> {
    http::respond(
        stream,
        200,
        &[
            ("Content-Type", content_type),
            ("X-Rondo-Reload", &reload.to_string()),
            ("X-Rondo-Samples", &samples.to_string()),
        ],
        bytes,
        with_body,
    )
}

/// Answers `/events`: the response head, then the client's queued events until a write fails
/// (the client closed, or stopped reading for [`Limits::write_timeout`]). `HEAD` gets the head.
fn stream_events(
    stream: &mut TcpStream,
    context: &Context,
    with_body: bool,
) -> std::io::Result<()> {
    let feed = &context.feed;
    let client = if with_body {
        match feed.subscribe(context.options.limits.max_streams) {
            Some(client) => Some(client),
            None => return http::respond_text(stream, 503, "too many event streams\n", true),
        }
    } else {
        None
    };
    let head = http::write_head(stream, 200, &[("Content-Type", "text/event-stream")], None);
    let Some(client) = client else {
        return head.and_then(|()| stream.flush());
    };
    // Tell EventSource to reconnect quickly if the stream breaks.
    let mut result = head.and_then(|()| stream.write_all(b"retry: 500\n\n"));
    while result.is_ok() {
        let events = client.next_batch(KEEP_ALIVE);
        let mut out = String::new();
        if events.is_empty() {
            out.push_str(": keep-alive\n\n");
        }
        for e in &events {
            out.push_str("data: ");
            out.push_str(e);
            out.push_str("\n\n");
        }
        result = stream
            .write_all(out.as_bytes())
            .and_then(|()| stream.flush());
    }
    feed.unsubscribe(&client);
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn routes_match_whole_paths_only() {
        assert_eq!(Route::of("/"), Some(Route::Page));
        assert_eq!(Route::of("/image.png?t=3"), Some(Route::Png));
        assert_eq!(Route::of("/events"), Some(Route::Events));
        assert_eq!(
            Route::of("/denoised.f32?r=2"),
            Some(Route::Denoised(DenoisedLayer::Denoised))
        );
        assert_eq!(
            Route::of("/albedo.f32"),
            Some(Route::Denoised(DenoisedLayer::Albedo))
        );
        assert_eq!(
            Route::of("/normal.f32"),
            Some(Route::Denoised(DenoisedLayer::Normal))
        );
        for bad in [
            "/../denoised.f32",
            "//albedo.f32",
            "/normal.f32/",
            "/DENOISED.F32",
            "/denoised.f32%00",
            "/../image.png",
            "//image.png",
            "/image.png/",
            "/%2e%2e/image.png",
            "/image.png%00",
            "/IMAGE.PNG",
            "image.png",
            "/events/../image.png",
            "http://127.0.0.1/image.png",
        ] {
            assert_eq!(Route::of(bad), None, "{bad}");
        }
    }

    #[test]
    fn ip_addresses_localhost_and_allowed_names_pass() {
        let allowed = ["viewer.lan".to_string()];
        for ok in [
            "127.0.0.1:8730",
            "192.168.1.2",
            "0.0.0.0:80",
            "localhost:9000",
            "LOCALHOST",
            "[::1]:8730",
            "[fe80::1]",
            "viewer.lan",
            "Viewer.LAN:8730",
        ] {
            assert!(host_allowed(ok, &allowed), "{ok}");
        }
        for bad in [
            "evil.example:8730",
            "localhost.evil.example",
            "viewer.lan.evil.example",
            "127.0.0.1.evil.example",
            "localhost:x",
            "localhost:99999",
            "localhost:+80",
            "localhost:",
            "[::1]x",
            "[::1",
            "[localhost]",
            "[127.0.0.1]",
            "::1",
            "127.1",
            "2130706433",
            "",
        ] {
            assert!(!host_allowed(bad, &allowed), "{bad}");
        }
    }

    #[test]
    fn allowed_host_names_are_dns_names() {
        assert_eq!(parse_host_name("My-Box.lan").as_deref(), Ok("my-box.lan"));
        for bad in [
            "",
            "a..b",
            "box:8080",
            "a b",
            "évil",
            ".lan",
            &"a".repeat(64),
            "*.lan",
        ] {
            assert!(parse_host_name(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn addresses_parse_with_loopback_for_a_bare_port() {
        assert_eq!(
            parse_addr("8080").ok(),
            Some(SocketAddr::from(([127, 0, 0, 1], 8080)))
        );
        assert_eq!(
            parse_addr("0.0.0.0:99").ok(),
            Some(SocketAddr::from(([0, 0, 0, 0], 99)))
        );
        assert!(parse_addr("[::1]:80").is_ok());
        assert!(parse_addr("nonsense").is_err());
        assert!(parse_addr("127.0.0.1:99999").is_err());
    }
}
