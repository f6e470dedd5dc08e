//! The live viewer of `rondo watch --serve`: an HTTP server that shows every pass in a browser.
//!
//! Routes (anything else is `404 Not Found`; methods other than GET and HEAD are `405`):
//!
//! | route | content |
//! |---|---|
//! | `GET /` | the viewer page (`page.html`, compiled in: no CDN, works offline) |
//! | `GET /image.png` | the latest image as 8-bit sRGB PNG, byte-identical to what `-o out.png` writes |
//! | `GET /image.exr` | the latest image as linear float OpenEXR (like `-o out.exr`) |
//! | `GET /image.f32` | the latest image as raw linear floats (see [`RAW_MAGIC`]), for the page |
//! | `GET /previous.f32` | the last image of the render before the latest save (the page's A/B) |
//! | `GET /events` | server-sent events: one JSON object per `data:` line (see [`Feed`]) |
//!
//! The images answer `503` until the first pass exists. Query strings are ignored (`/image.png?t=1`
//! is `/image.png`); paths are matched exactly, so `/../image.png` or `//image.png` are 404.
//! Bound to loopback, the server answers only requests whose `Host` names a loopback host
//! (`127.0.0.1`, `localhost`, `[::1]`, any port, so SSH port forwards work) and `403` to the rest:
//! a web page elsewhere cannot rebind its own name to 127.0.0.1 and read the images.
//!
//! The render loop talks to the server only through the watch loop's event point
//! ([`crate::watch::Observer`], made by [`Feed::observer`]): each report copies what it needs
//! under a short lock and returns. Every
//! event-stream client has its own thread and a bounded queue: a client that stalls loses its
//! oldest queued events, never blocks the render; a closed client is dropped at its next write.
//!
//! [`tiny_http`] parses the requests. It cannot flush a streamed body part by part (its chunked
//! writer buffers 8 KiB), so the event stream takes the socket over with [`Request::upgrade`]
//! after tiny_http wrote the response head; the body then runs until either side closes.

mod feed;

use std::net::{SocketAddr, ToSocketAddrs};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;
use std::time::Duration;

use tiny_http::{Header, Method, Request, Response, Server, StatusCode};

pub use feed::{Client, Encoding, Feed, Frame, RAW_MAGIC, changed_text, error_location};

/// The page, compiled into the binary.
pub const PAGE: &str = include_str!("page.html");

/// The address `--serve` binds without an argument. If its port is taken, a free port is used.
pub const DEFAULT_ADDR: &str = "127.0.0.1:8730";

/// How long an idle event stream waits before writing a keep-alive comment (which is also how a
/// closed client is noticed when nothing happens).
const KEEP_ALIVE: Duration = Duration::from_secs(10);

/// How often the progress of the pass in flight is sent, at most.
const PROGRESS_TICK: Duration = Duration::from_millis(50);

/// At most this many event streams at once; more get `503` (each holds a thread).
const MAX_STREAMS: usize = 64;

/// Why the server could not start.
#[derive(Debug, thiserror::Error)]
pub enum ServeError {
    /// The address is not `HOST:PORT` or a port.
    #[error("--serve {0:?}: expected HOST:PORT (e.g. 127.0.0.1:8080) or a port")]
    Address(String),
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

/// A running viewer server. Dropping it stops accepting requests.
pub struct Viewer {
    server: Arc<Server>,
    addr: SocketAddr,
    stop: Arc<AtomicBool>,
    threads: Vec<JoinHandle<()>>,
}

impl Viewer {
    /// Binds `addr` and starts serving the returned [`Feed`]'s images and events. With
    /// `fall_back`, a taken port is replaced by a free one (for the default address).
    pub fn start(addr: SocketAddr, fall_back: bool) -> Result<(Self, Feed), ServeError> {
        let bind = |a: SocketAddr| {
            Server::http(a).map_err(|e| ServeError::Bind {
                addr: a.to_string(),
                message: e.to_string(),
            })
        };
        let server = match bind(addr) {
            Err(_) if fall_back => bind(SocketAddr::new(addr.ip(), 0))?,
            other => other?,
        };
        let addr = server
            .server_addr()
            .to_ip()
            .ok_or_else(|| ServeError::Bind {
                addr: addr.to_string(),
                message: "not an IP socket".into(),
            })?;
        let server = Arc::new(server);
        let feed = Feed::new();
        let stop = Arc::new(AtomicBool::new(false));
        let accept = {
            let (server, feed) = (server.clone(), feed.clone());
            std::thread::Builder::new()
                .name("rondo-serve".into())
                .spawn(move || accept_requests(&server, &feed, addr.ip().is_loopback()))
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
        let bind_error = |e: std::io::Error| ServeError::Bind {
            addr: addr.to_string(),
            message: format!("cannot start a thread: {e}"),
        };
        let threads = vec![accept.map_err(bind_error)?, ticker.map_err(bind_error)?];
        Ok((
            Self {
                server,
                addr,
                stop,
                threads,
            },
            feed,
        ))
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
                "the viewer listens on {}: anyone who can reach this machine on that network can see the images",
                self.addr
            )
        })
    }
}

impl Drop for Viewer {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        self.server.unblock();
        for t in self.threads.drain(..) {
            let _ = t.join();
        }
    }
}

/// The accept loop: one short-lived thread per request, so a client that never reads its
/// response holds only its own thread.
fn accept_requests(server: &Server, feed: &Feed, loopback: bool) {
    while let Ok(request) = server.recv() {
        let feed = feed.clone();
        // If no thread can be started, the request is dropped (the client sees a closed
        // connection) and the server goes on.
        let _ = std::thread::Builder::new()
            .name("rondo-serve-request".into())
            .spawn(move || handle(request, &feed, loopback));
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
    Events,
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
            "/events" => Self::Events,
            _ => return None,
        })
    }
}

fn header(name: &str, value: &str) -> Header {
    // Both are ASCII constants or digits here, which tiny_http always accepts.
    Header::from_bytes(name.as_bytes(), value.as_bytes()).expect("ASCII header")
}

fn text(status: u16, body: &str) -> Response<std::io::Cursor<Vec<u8>>> {
    Response::from_string(body)
        .with_status_code(StatusCode(status))
        .with_header(header("Content-Type", "text/plain; charset=utf-8"))
        .with_header(header("Cache-Control", "no-store"))
}

/// Whether a `Host` header value names a loopback host (any port).
fn loopback_host(host: &str) -> bool {
    let name = match host.strip_prefix('[') {
        Some(rest) => rest.split(']').next().unwrap_or(""),
        None => host.rsplit_once(':').map_or(host, |(h, _)| h),
    };
    name.eq_ignore_ascii_case("localhost")
        || name
            .parse::<std::net::IpAddr>()
            .is_ok_and(|ip| ip.is_loopback())
}

fn handle(request: Request, feed: &Feed, loopback: bool) {
    if loopback {
        let host = request
            .headers()
            .iter()
            .find(|h| h.field.equiv("Host"))
            .map(|h| h.value.as_str().to_string());
        if !host.as_deref().is_some_and(loopback_host) {
            let _ = request.respond(text(403, "the viewer answers only to a loopback Host\n"));
            return;
        }
    }
    let route = Route::of(request.url());
    let method_ok = matches!(request.method(), Method::Get | Method::Head);
    let response = match route {
        None => text(404, "not found\n"),
        Some(_) if !method_ok => {
            text(405, "only GET and HEAD\n").with_header(header("Allow", "GET, HEAD"))
        }
        Some(Route::Events) => return stream_events(request, feed),
        Some(Route::Page) => Response::from_string(PAGE)
            .with_header(header("Content-Type", "text/html; charset=utf-8"))
            .with_header(header("Cache-Control", "no-store")),
        Some(route) => {
            let (frame, content_type) = match route {
                Route::PreviousRaw => (feed.previous(), "application/octet-stream"),
                Route::Png => (feed.current(), "image/png"),
                Route::Exr => (feed.current(), "image/x-exr"),
                _ => (feed.current(), "application/octet-stream"),
            };
            let Some(frame) = frame else {
                let _ = request.respond(text(503, "no image yet\n"));
                return;
            };
            let encoding = match route {
                Route::Png => Encoding::Png,
                Route::Exr => Encoding::Exr,
                _ => Encoding::Raw,
            };
            match frame.bytes(encoding).map(<[u8]>::len) {
                Ok(len) => {
                    let headers = vec![
                        header("Content-Type", content_type),
                        header("Cache-Control", "no-store"),
                        header("X-Rondo-Reload", &frame.reload().to_string()),
                        header("X-Rondo-Samples", &frame.samples().to_string()),
                    ];
                    let body = FrameBody {
                        frame,
                        encoding,
                        at: 0,
                    };
                    // A Content-Length body, not 8 KiB chunks; read from the shared frame, no copy.
                    let response = Response::new(StatusCode(200), headers, body, Some(len), None)
                        .with_chunked_threshold(usize::MAX);
                    let _ = request.respond(response);
                    return;
                }
                Err(e) => text(500, &format!("cannot encode the image: {e}\n")),
            }
        }
    };
    // The client may be gone already; nothing to do then.
    let _ = request.respond(response);
}

/// A response body that reads one encoding of a shared frame.
struct FrameBody {
    frame: Arc<feed::Frame>,
    encoding: Encoding,
    at: usize,
}

impl std::io::Read for FrameBody {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let bytes = self.frame.bytes(self.encoding).unwrap_or_default();
        let n = buf.len().min(bytes.len().saturating_sub(self.at));
        buf[..n].copy_from_slice(&bytes[self.at..self.at + n]);
        self.at += n;
        Ok(n)
    }
}

/// Answers `/events`: writes the response head, then hands the socket to a loop that writes
/// the client's queued events until a write fails.
fn stream_events(request: Request, feed: &Feed) {
    let Some(client) = feed.subscribe(MAX_STREAMS) else {
        let _ = request.respond(text(503, "too many event streams\n"));
        return;
    };
    let head = Response::empty(StatusCode(200))
        .with_header(header("Content-Type", "text/event-stream"))
        .with_header(header("Cache-Control", "no-store"));
    let mut stream = request.upgrade("rondo-events", head);
    // Tell EventSource to reconnect quickly if the stream breaks.
    let mut ok = stream.write_all(b"retry: 500\n\n").is_ok();
    while ok {
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
        ok = stream.write_all(out.as_bytes()).is_ok() && stream.flush().is_ok();
    }
    feed.unsubscribe(&client);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn routes_match_whole_paths_only() {
        assert_eq!(Route::of("/"), Some(Route::Page));
        assert_eq!(Route::of("/image.png?t=3"), Some(Route::Png));
        assert_eq!(Route::of("/events"), Some(Route::Events));
        for bad in [
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
    fn only_loopback_host_names_pass() {
        for ok in [
            "127.0.0.1:8730",
            "localhost:9000",
            "LOCALHOST",
            "[::1]:8730",
            "127.1.2.3",
        ] {
            assert!(loopback_host(ok), "{ok}");
        }
        for bad in [
            "evil.example:8730",
            "192.168.1.2:8730",
            "localhost.evil.example",
            "[::2]:80",
            "",
        ] {
            assert!(!loopback_host(bad), "{bad}");
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
