//! The live viewer over HTTP: the real `rondo watch --serve` binary on a scene in a temporary
//! directory, or the library's server with small limits, talked to through plain sockets (so
//! request targets and heads reach the server exactly as written, `/../` included, and a client
//! can refuse to read or to send). Waits are bounded (an event or a timeout), never sleeps;
//! nothing here times the render.

use std::io::{BufRead, BufReader, Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{Receiver, channel};
use std::time::{Duration, Instant};

use rondo::serve::{CUT, Limits, MAX_MESSAGE, MAX_SOURCE_LINE, Options, Viewer};
use serde_json::Value;

mod common;

/// Upper bound of every wait; a passing run takes a small fraction of it.
const WAIT: Duration = Duration::from_secs(60);

const RED: &str = "(1.0, 0.0, 0.0)";
const BLUE: &str = "(0.0, 0.0, 1.0)";
const GREEN: &str = "(0.0, 1.0, 0.0)";

/// A scene whose centre pixel sees only the `wall` emitter, so its colour is exactly the wall's
/// emission whatever the sample count. Line 5 holds the wall material.
fn scene(wall: &str, size: u32, spp: u32) -> String {
    format!(
        r#"Scene(
    camera: Camera(position: (0, 0, -5), look_at: (0, 0, 0), fov: 40.0),
    settings: Settings(width: {size}, height: {size}, spp: {spp}, max_depth: 3),
    materials: {{
        "wall": Light(emit: Constant({wall}), intensity: 1.0, two_sided: true),
        "ball": Diffuse(albedo: Constant((0.5, 0.5, 0.5))),
    }},
    entities: [
        Entity(name: "wall", material: "wall", shape: Quad(a: (-10, -10, 5), b: (10, -10, 5), c: (10, 10, 5), d: (-10, 10, 5))),
        Entity(name: "ball", material: "ball", shape: Sphere(center: (0, 1.4, 0), radius: 0.3)),
    ],
)
"#
    )
}

/// `rondo watch scene.ron --serve 127.0.0.1:0 ARGS` in a fresh directory (`{dir}` in an
/// argument names it); killed on drop. `addr` is the address to connect to (loopback for a
/// server bound to all addresses).
struct Rondo {
    child: Child,
    dir: common::TestDir,
    scene: PathBuf,
    addr: SocketAddr,
    stderr: Receiver<String>,
}

impl Rondo {
    fn start(name: &str, text: &str, args: &[&str]) -> Self {
        Self::start_on(name, text, "127.0.0.1:0", args)
    }

    /// As [`Rondo::start`], serving on `serve`.
    fn start_on(name: &str, text: &str, serve: &str, args: &[&str]) -> Self {
        Self::start_with(name, text, serve, &[], args)
    }

    /// As [`Rondo::start_on`], with the environment variables `env` set.
    fn start_with(
        name: &str,
        text: &str,
        serve: &str,
        env: &[(&str, &std::path::Path)],
        args: &[&str],
    ) -> Self {
        let dir = common::temp_dir(&format!("serve-{name}"));
        let scene = dir.join("scene.ron");
        std::fs::write(&scene, text).expect("write scene");
        let mut child = Command::new(env!("CARGO_BIN_EXE_rondo"))
            .envs(env.iter().copied())
            .arg("watch")
            .arg(&scene)
            .args(["--serve", serve, "--threads", "2"])
            .args(
                args.iter()
                    .map(|a| a.replace("{dir}", &dir.to_string_lossy())),
            )
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("start rondo");
        let (tx, stderr) = channel();
        let pipe = child.stderr.take().expect("piped stderr");
        std::thread::spawn(move || {
            for line in BufReader::new(pipe).lines().map_while(Result::ok) {
                if tx.send(line).is_err() {
                    break;
                }
            }
        });
        let mut rondo = Self {
            child,
            dir,
            scene,
            addr: SocketAddr::from(([127, 0, 0, 1], 0)),
            stderr,
        };
        let line = rondo.line("the viewer line", |l| l.starts_with("viewer: "));
        let url = line
            .trim_start_matches("viewer: http://")
            .trim_end_matches('/');
        let addr: SocketAddr = url.parse().expect("viewer: http://ADDR/");
        rondo.addr = if addr.ip().is_unspecified() {
            SocketAddr::from(([127, 0, 0, 1], addr.port()))
        } else {
            addr
        };
        rondo
    }

    /// Waits for a line of stderr matching `predicate`.
    fn line(&self, what: &str, mut predicate: impl FnMut(&str) -> bool) -> String {
        wait_on(&self.stderr, what, |l| predicate(l)).0
    }

    fn save(&self, text: &str) {
        std::fs::write(&self.scene, text).expect("write scene");
    }

    fn get(&self, target: &str) -> Reply {
        request(self.addr, "GET", target)
    }

    fn events(&self) -> Events {
        Events::open(self.addr)
    }
}

impl Drop for Rondo {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Waits at most [`WAIT`] for an item matching `predicate`; returns it and the items before it.
fn wait_on<T: std::fmt::Debug>(
    rx: &Receiver<T>,
    what: &str,
    mut predicate: impl FnMut(&T) -> bool,
) -> (T, Vec<T>) {
    let deadline = Instant::now() + WAIT;
    let mut seen = Vec::new();
    while let Ok(item) = rx.recv_timeout(deadline.saturating_duration_since(Instant::now())) {
        if predicate(&item) {
            return (item, seen);
        }
        seen.push(item);
    }
    panic!("timed out waiting for {what}; seen meanwhile: {seen:#?}");
}

/// An HTTP reply: the server answers one request per connection and closes, so reading to the
/// end and splitting off the head is the whole client.
struct Reply {
    status: u16,
    head: String,
    body: Vec<u8>,
}

impl Reply {
    fn header(&self, name: &str) -> Option<&str> {
        self.head.lines().skip(1).find_map(|l| {
            let (n, v) = l.split_once(':')?;
            n.eq_ignore_ascii_case(name).then(|| v.trim())
        })
    }
}

fn request(addr: SocketAddr, method: &str, target: &str) -> Reply {
    request_as(addr, method, target, &addr.to_string())
}

fn request_as(addr: SocketAddr, method: &str, target: &str, host: &str) -> Reply {
    let mut s = TcpStream::connect(addr).expect("connect");
    // A server that refuses the connection may close it before the request is sent.
    let _ = write!(s, "{method} {target} HTTP/1.0\r\nHost: {host}\r\n\r\n");
    reply(s)
}

/// Reads a reply to the end. A server that refuses a request without reading it may reset the
/// connection after its answer: what arrived before the reset is the reply.
fn reply(mut s: TcpStream) -> Reply {
    let deadline = Instant::now() + WAIT;
    let mut all = Vec::new();
    let mut buf = [0; 64 * 1024];
    loop {
        let left = deadline.saturating_duration_since(Instant::now());
        assert!(
            !left.is_zero(),
            "the reply did not end: {:?}",
            String::from_utf8_lossy(&all[..all.len().min(300)])
        );
        s.set_read_timeout(Some(left)).expect("timeout");
        match s.read(&mut buf) {
            Ok(0) => break,
            Ok(n) => all.extend_from_slice(&buf[..n]),
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) if e.kind() == std::io::ErrorKind::ConnectionReset && !all.is_empty() => break,
            Err(e) => panic!("no whole reply: {e} after {} bytes", all.len()),
        }
    }
    let split = all
        .windows(4)
        .position(|w| w == b"\r\n\r\n")
        .expect("a head");
    let head = String::from_utf8_lossy(&all[..split]).into_owned();
    let status = head
        .split(' ')
        .nth(1)
        .and_then(|s| s.parse().ok())
        .expect("a status");
    Reply {
        status,
        head,
        body: all[split + 4..].to_vec(),
    }
}

/// An event-stream client: a thread reads `data:` lines and parses them as JSON.
struct Events {
    rx: Receiver<Value>,
}

impl Events {
    fn open(addr: SocketAddr) -> Self {
        let mut s = TcpStream::connect(addr).expect("connect");
        write!(s, "GET /events HTTP/1.1\r\nHost: {addr}\r\n\r\n").expect("send");
        let (tx, rx) = channel();
        std::thread::spawn(move || {
            let mut head = true;
            for line in BufReader::new(s).lines().map_while(Result::ok) {
                if head {
                    assert!(
                        !line.starts_with("HTTP/") || line.contains(" 200 "),
                        "{line}"
                    );
                    head = !line.is_empty();
                    continue;
                }
                if let Some(data) = line.strip_prefix("data: ") {
                    let event = serde_json::from_str(data).expect("each event is JSON");
                    if tx.send(event).is_err() {
                        break;
                    }
                }
            }
        });
        Self { rx }
    }

    /// Waits for an event matching `predicate`; returns it and the events before it.
    fn wait(&self, what: &str, predicate: impl FnMut(&Value) -> bool) -> (Value, Vec<Value>) {
        wait_on(&self.rx, what, predicate)
    }

    fn done(&self, reload: u64) -> (Value, Vec<Value>) {
        self.wait(&format!("done of reload {reload}"), |e| {
            e["kind"] == "done" && e["reload"] == reload
        })
    }
}

/// The linear RGB of pixel (x, y) of a `/image.f32` body, after checking its header.
fn raw_pixel(body: &[u8], x: usize, y: usize) -> [f32; 3] {
    assert_eq!(&body[..8], b"RONDOF32");
    let u = |i: usize| u32::from_le_bytes(body[8 + 4 * i..12 + 4 * i].try_into().expect("u32"));
    let (w, h) = (u(0) as usize, u(1) as usize);
    assert_eq!(body.len(), 24 + w * h * 12, "header and pixel count agree");
    let at = 24 + 12 * (y * w + x);
    let f =
        |k: usize| f32::from_le_bytes(body[at + 4 * k..at + 4 * k + 4].try_into().expect("f32"));
    [f(0), f(1), f(2)]
}

#[test]
fn routes_have_their_content_types_and_everything_else_is_404() {
    let rondo = Rondo::start("routes", &scene(RED, 32, 4), &["-o", "{dir}/out.png"]);
    let out = rondo.dir.join("out.png");
    // `done` follows the last image's write to disk.
    rondo.events().done(0);

    let page = rondo.get("/");
    assert_eq!(page.status, 200);
    assert_eq!(
        page.header("Content-Type"),
        Some("text/html; charset=utf-8")
    );
    let html = String::from_utf8_lossy(&page.body);
    assert!(html.contains("<canvas") && html.contains("new EventSource(\"/events\")"));
    assert!(
        !html.contains("src=\"http"),
        "no outside scripts: the page works offline"
    );

    let png = rondo.get("/image.png");
    assert_eq!(png.status, 200);
    assert_eq!(png.header("Content-Type"), Some("image/png"));
    let on_disk = std::fs::read(&out).expect("-o image written");
    assert!(png.body == on_disk, "/image.png is the bytes -o wrote");
    let decoded = image::load_from_memory(&png.body).expect("a PNG").to_rgb8();
    assert_eq!(decoded.get_pixel(16, 16).0, [255, 0, 0]);

    let exr = rondo.get("/image.exr");
    assert_eq!(exr.status, 200);
    assert_eq!(exr.header("Content-Type"), Some("image/x-exr"));
    let linear = image::load_from_memory_with_format(&exr.body, image::ImageFormat::OpenExr)
        .expect("an EXR")
        .to_rgb32f();
    assert_eq!(linear.get_pixel(16, 16).0, [1.0, 0.0, 0.0]);

    let raw = rondo.get("/image.f32");
    assert_eq!(raw.status, 200);
    assert_eq!(raw.header("Content-Type"), Some("application/octet-stream"));
    assert_eq!(raw_pixel(&raw.body, 16, 16), [1.0, 0.0, 0.0]);
    assert_eq!(
        rondo.get("/image.png?t=7").body,
        png.body,
        "queries are ignored"
    );
    assert_eq!(
        rondo.get("/previous.f32").status,
        503,
        "no image before a save yet"
    );

    for target in [
        "/nope",
        "/../image.png",
        "/./image.png",
        "/%2e%2e/image.png",
        "/..%2fimage.png",
        "//image.png",
        "/image.png/",
        "/events/../image.png",
        "/../../../../etc/passwd",
        "/src/serve/page.html",
        "/page.html",
    ] {
        let reply = rondo.get(target);
        assert_eq!(reply.status, 404, "{target}");
        assert!(reply.body.len() < 100, "{target}: no file content");
    }
    assert_eq!(request(rondo.addr, "POST", "/image.png").status, 405);
    // DNS rebinding: a page of another site that resolves to 127.0.0.1 sends its own Host.
    let port = rondo.addr.port();
    for (host, status) in [
        (format!("evil.example:{port}"), 403),
        (format!("localhost:{port}"), 200),
        ("localhost:9000".into(), 200),
        (format!("[::1]:{port}"), 200),
        ("10.1.2.3".into(), 200),
    ] {
        let reply = request_as(rondo.addr, "GET", "/image.png", &host);
        assert_eq!(reply.status, status, "Host: {host}");
    }
    let head = request(rondo.addr, "HEAD", "/image.png");
    assert_eq!((head.status, head.body.len()), (200, 0));
    assert_eq!(
        head.header("Content-Length"),
        Some(png.body.len().to_string().as_str()),
        "HEAD has GET's headers"
    );

    // A new client gets the present at once: the latest pass (full spp) and its done.
    let late = rondo.events();
    let (pass, _) = late.wait("the current pass", |e| e["kind"] == "pass");
    assert_eq!(
        (pass["reload"].as_u64(), pass["spp"].as_u64()),
        (Some(0), Some(4))
    );
    late.done(0);
}

#[test]
fn a_save_streams_a_pass_and_a_broken_save_an_error_while_the_image_stays() {
    let rondo = Rondo::start("events", &scene(RED, 32, 4), &[]);
    let events = rondo.events();
    events.done(0);

    rondo.save(&scene(BLUE, 32, 4));
    let (reload, _) = events.wait("a reload", |e| e["kind"] == "reload");
    assert_eq!(reload["reload"], 1);
    assert_eq!(reload["trigger"][0], "scene.ron");
    let (pass, _) = events.wait("a pass of reload 1", |e| {
        e["kind"] == "pass" && e["reload"] == 1
    });
    assert_eq!(pass["changed"], "materials");
    assert_eq!(pass["target_spp"], 4);
    events.done(1);
    let before = rondo.get("/image.png").body;
    assert_eq!(
        raw_pixel(&rondo.get("/image.f32").body, 16, 16),
        [0.0, 0.0, 1.0]
    );

    let broken = scene(BLUE, 32, 4).replace("intensity: 1.0", "intensity: 1.0 1.0");
    rondo.save(&broken);
    let (error, seen) = events.wait("an error", |e| e["kind"] == "error");
    assert!(
        seen.iter().all(|e| e["kind"] != "pass"),
        "a broken save renders nothing: {seen:?}"
    );
    let message = error["message"].as_str().expect("a message");
    let file = error["file"].as_str().expect("a file");
    assert!(file.ends_with("scene.ron"), "{file}");
    assert!(
        !message.contains("scene.ron"),
        "the place is in fields, not the message: {message}"
    );
    assert_eq!(error["line"], 5);
    let col = error["column"].as_u64().expect("a column") as usize;
    assert_eq!(
        error["col"].as_u64(),
        Some(col as u64),
        "older scripts read `col`"
    );
    let line5 = broken.lines().nth(4).expect("line 5");
    // The watch loop may quote a window of a long line, starting with "…".
    let quoted = error["source_line"].as_str().expect("a source line");
    assert!(
        line5.ends_with(quoted.trim_start_matches('…')) && quoted.contains("1.0 1.0"),
        "{quoted:?} is the end of {line5:?}, the stray value included"
    );
    assert!(
        line5[col - 1..].starts_with("1.0"),
        "column {col} points at the stray value in {line5:?}"
    );
    assert_eq!(error["reload"], 1, "the image shown is still reload 1's");
    assert!(
        rondo.get("/image.png").body == before,
        "/image.png stays byte-identical"
    );

    // The next good save clears the error and renders; A/B's previous image is reload 1's.
    rondo.save(&scene(GREEN, 32, 4));
    events.wait("reload 2", |e| e["kind"] == "reload" && e["reload"] == 2);
    events.done(2);
    assert_eq!(
        raw_pixel(&rondo.get("/image.f32").body, 16, 16),
        [0.0, 1.0, 0.0]
    );
    assert_eq!(
        raw_pixel(&rondo.get("/previous.f32").body, 16, 16),
        [0.0, 0.0, 1.0]
    );
    let late = rondo.events();
    let (_, first) = late.done(2);
    assert!(
        first.iter().all(|e| e["kind"] != "error"),
        "a good save clears the error for new clients too: {first:?}"
    );
}

#[test]
fn idle_and_stalled_clients_do_not_hold_up_the_render() {
    // Eight passes (preview, 1, 2, …, 64 spp) of a 256² image: 768 KiB per /image.f32. The
    // image is large enough that each reload renders for several of the feed's 50 ms progress
    // ticks (at 128² a fast machine finished a reload between two ticks).
    let rondo = Rondo::start("stalled", &scene(RED, 256, 64), &[]);
    let events = rondo.events();
    events.done(0);
    // Twenty event streams that never read a byte.
    let idle: Vec<TcpStream> = (0..20)
        .map(|_| {
            let mut s = TcpStream::connect(rondo.addr).expect("connect");
            write!(s, "GET /events HTTP/1.1\r\nHost: localhost\r\n\r\n").expect("send");
            s
        })
        .collect();
    // And one client that asks for 100 images (79 MB, far more than loopback buffers hold) and
    // never reads: its connection's writer blocks for good.
    let mut stalled = TcpStream::connect(rondo.addr).expect("connect");
    let pipelined = "GET /image.f32 HTTP/1.1\r\nHost: localhost\r\n\r\n".repeat(100);
    stalled.write_all(pipelined.as_bytes()).expect("send");
    let mut stalled_events = TcpStream::connect(rondo.addr).expect("connect");
    write!(
        stalled_events,
        "GET /events HTTP/1.1\r\nHost: localhost\r\n\r\n"
    )
    .expect("send");

    for (reload, wall) in [(1, BLUE), (2, GREEN), (3, RED)] {
        rondo.save(&scene(wall, 256, 64));
        let (_, seen) = events.done(reload);
        let spp: Vec<u64> = seen
            .iter()
            .filter(|e| e["kind"] == "pass" && e["reload"] == reload)
            .filter_map(|e| e["spp"].as_u64())
            .collect();
        // The pass plan: a preview (1 sample per 2×2 pixels), then doubling to 64.
        assert!(
            spp.first() == Some(&1)
                && spp.windows(2).all(|w| w[0] <= w[1])
                && [2, 4, 8, 16, 32, 64].iter().all(|n| spp.contains(n)),
            "every pass of reload {reload} reached the reading client: {spp:?}"
        );
        assert!(
            seen.iter()
                .any(|e| e["kind"] == "progress" && e["reload"] == reload),
            "progress events flow during the passes"
        );
        rondo.line(&format!("reload {reload}'s line"), |l| {
            l.starts_with(&format!("reload {reload}: ")) && l.contains("full")
        });
    }
    assert_eq!(
        raw_pixel(&rondo.get("/image.f32").body, 64, 64),
        [1.0, 0.0, 0.0]
    );
    drop((idle, stalled, stalled_events));
}

#[test]
fn sigint_stops_the_server() {
    let mut rondo = Rondo::start("sigint", &scene(RED, 32, 4), &[]);
    rondo.events().done(0);
    let pid = rondo.child.id().to_string();
    let kill = Command::new("kill")
        .args(["-INT", &pid])
        .status()
        .expect("run kill");
    assert!(kill.success());
    let status =
        common::wait_or_kill(&mut rondo.child, WAIT).expect("rondo did not stop on SIGINT");
    assert!(status.success(), "{status}");
    assert!(
        TcpStream::connect(rondo.addr).is_err(),
        "nothing listens after the stop"
    );
}

#[test]
fn serve_without_output_and_a_bad_address_are_handled() {
    let bad = Command::new(env!("CARGO_BIN_EXE_rondo"))
        .args(["watch", "x.ron", "--serve", "nonsense"])
        .output()
        .expect("run rondo");
    assert!(!bad.status.success());
    let text = String::from_utf8_lossy(&bad.stderr);
    assert!(text.contains("--serve \"nonsense\""), "{text}");
    let neither = Command::new(env!("CARGO_BIN_EXE_rondo"))
        .args(["watch", "x.ron"])
        .output()
        .expect("run rondo");
    assert!(!neither.status.success(), "watch needs -o or --serve");
    let rondo = Rondo::start("no-output", &scene(RED, 32, 4), &[]);
    rondo.events().done(0);
    let files: Vec<PathBuf> = std::fs::read_dir(&rondo.dir)
        .expect("list dir")
        .map(|e| e.expect("entry").path())
        .collect();
    assert_eq!(
        files,
        std::slice::from_ref(&rondo.scene),
        "no image written without -o"
    );
}

/// The library's server on a free loopback port with `limits`; no image is ever fed to it.
fn library_server(limits: Limits) -> (Viewer, rondo::serve::Feed) {
    let options = Options {
        limits,
        ..Options::default()
    };
    let addr = SocketAddr::from(([127, 0, 0, 1], 0));
    Viewer::start(addr, false, options).expect("start the viewer")
}

/// Peak resident memory of process `pid` in KiB (Linux's `VmHWM`).
#[cfg(target_os = "linux")]
fn peak_rss_kib(pid: u32) -> u64 {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).expect("/proc status");
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
        .expect("VmHWM in /proc/PID/status")
}

#[cfg(target_os = "linux")]
#[test]
fn an_oversized_request_head_is_refused_without_being_kept() {
    // A header line is bounded: a 200 MB one must not be kept in memory.
    let rondo = Rondo::start("big-head", &scene(RED, 32, 4), &[]);
    rondo.events().done(0);
    let pid = rondo.child.id();
    let before = peak_rss_kib(pid);
    let mut s = TcpStream::connect(rondo.addr).expect("connect");
    let writer = {
        let mut s = s.try_clone().expect("clone the socket");
        std::thread::spawn(move || {
            // 64 MiB of one header line; the server stops reading long before the end, so the
            // writes fail once it has closed (that is the point).
            let _ = write!(s, "GET / HTTP/1.1\r\nHost: localhost\r\nX-Big: ");
            let block = vec![b'a'; 1 << 20];
            for _ in 0..64 {
                if s.write_all(&block).is_err() {
                    return;
                }
            }
            let _ = s.write_all(b"\r\n\r\n");
        })
    };
    s.set_read_timeout(Some(WAIT)).expect("timeout");
    let mut head = Vec::new();
    let mut byte = [0];
    while !head.ends_with(b"\r\n") && s.read(&mut byte).expect("a reply") == 1 {
        head.push(byte[0]);
    }
    let status_line = String::from_utf8_lossy(&head);
    assert!(
        status_line.starts_with("HTTP/1.1 431 "),
        "an oversized head is refused: {status_line:?}"
    );
    drop(s);
    writer.join().expect("writer");
    let grown = peak_rss_kib(pid).saturating_sub(before);
    assert!(
        grown < 16 * 1024,
        "the head was not kept: peak memory grew by {grown} KiB"
    );
    assert_eq!(rondo.get("/").status, 200, "the server goes on");
    let heads = [
        "GET / HTTP/2.0\r\nHost: localhost\r\n\r\n",
        "GET / HTTP/1.1\r\nHost: localhost\r\n folded\r\n\r\n",
        "GET / HTTP/1.1\r\n\r\n",
    ];
    for (head, status) in heads.iter().zip([505, 400, 400]) {
        let mut s = TcpStream::connect(rondo.addr).expect("connect");
        s.write_all(head.as_bytes()).expect("send");
        assert_eq!(reply(s).status, status, "{head:?}");
    }
}

#[test]
fn connections_over_the_limit_are_refused_and_idle_ones_do_not_block_a_request() {
    // Connections are capped: a thread per connection without a limit exhausts the process.
    let limits = Limits {
        max_connections: 8,
        head_timeout: WAIT,
        ..Limits::default()
    };
    // Seven connections that send nothing: the eighth, a real request, is answered.
    let (viewer, _feed) = library_server(limits.clone());
    let idle: Vec<TcpStream> = (0..7)
        .map(|_| TcpStream::connect(viewer.addr()).expect("connect"))
        .collect();
    let page = request(viewer.addr(), "GET", "/");
    assert_eq!(page.status, 200);
    assert!(String::from_utf8_lossy(&page.body).contains("<canvas"));
    drop((idle, viewer));

    // Eight hold every place: more connections are answered 503 and closed at once, not held.
    let (viewer, _feed) = library_server(limits);
    let idle: Vec<TcpStream> = (0..8)
        .map(|_| TcpStream::connect(viewer.addr()).expect("connect"))
        .collect();
    for _ in 0..20 {
        let refused = request(viewer.addr(), "GET", "/");
        assert_eq!(refused.status, 503, "{}", refused.head);
    }
    // Once the idle ones are gone, requests are answered again (each closed connection gives
    // its place back as soon as its thread sees the close).
    drop(idle);
    let deadline = Instant::now() + WAIT;
    while request(viewer.addr(), "GET", "/").status != 200 {
        assert!(Instant::now() < deadline, "no place came back");
    }
}

#[test]
fn a_client_that_does_not_finish_its_head_in_time_is_disconnected() {
    // Reads time out: without, an idle connection would hold its thread
    // forever.
    let (viewer, _feed) = library_server(Limits {
        head_timeout: Duration::from_millis(200),
        ..Limits::default()
    });
    // Sends nothing: closed without an answer.
    let mut silent = TcpStream::connect(viewer.addr()).expect("connect");
    silent.set_read_timeout(Some(WAIT)).expect("timeout");
    let mut buf = Vec::new();
    let read = silent.read_to_end(&mut buf);
    assert!(
        matches!(read, Ok(0)),
        "an idle connection is closed: {read:?}, {buf:?}"
    );
    // Sends part of a head: 408.
    let mut partial = TcpStream::connect(viewer.addr()).expect("connect");
    partial
        .write_all(b"GET / HTTP/1.1\r\nHost: localhost\r\n")
        .expect("send");
    assert_eq!(reply(partial).status, 408);
}

#[test]
fn any_bind_answers_only_ip_addresses_localhost_and_allowed_names() {
    // The Host check holds on 0.0.0.0 too, or DNS rebinding would reach the viewer.
    let rondo = Rondo::start_on("any-bind", &scene(RED, 32, 4), "0.0.0.0:0", &[]);
    rondo.events().done(0);
    let port = rondo.addr.port();
    let get = |host: &str| request_as(rondo.addr, "GET", "/image.png", host).status;
    for host in [
        format!("127.0.0.1:{port}"),
        format!("192.168.7.20:{port}"),
        "[::1]".into(),
        format!("[fe80::1]:{port}"),
        format!("localhost:{port}"),
    ] {
        assert_eq!(get(&host), 200, "Host: {host}");
    }
    for host in [
        format!("evil.com:{port}"),
        "evil.com".into(),
        "localhost.evil.com".into(),
        "127.0.0.1.evil.com".into(),
    ] {
        assert_eq!(get(&host), 403, "Host: {host}");
    }
    drop(rondo);

    let allowed = Rondo::start_on(
        "allow-host",
        &scene(RED, 32, 4),
        "0.0.0.0:0",
        &["--allow-host", "evil.com", "--allow-host", "viewer.lan"],
    );
    allowed.events().done(0);
    let get = |host: &str| request_as(allowed.addr, "GET", "/image.png", host).status;
    for host in ["evil.com", "EVIL.com:8730", "viewer.lan", "127.0.0.1"] {
        assert_eq!(get(host), 200, "allowed Host: {host}");
    }
    assert_eq!(get("other.com"), 403);

    for bad in [
        &["watch", "x.ron", "--serve", "--allow-host", "evil.com:80"][..],
        &["watch", "x.ron", "-o", "x.png", "--allow-host", "evil.com"],
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_rondo"))
            .args(bad)
            .output()
            .expect("run rondo");
        assert_eq!(out.status.code(), Some(2), "{bad:?} is a usage error");
        let text = String::from_utf8_lossy(&out.stderr);
        assert!(text.contains("--allow-host"), "{text}");
    }
}

#[test]
fn head_requests_get_headers_and_no_body() {
    // HEAD /events sends the head only, never the stream.
    let (viewer, _feed) = library_server(Limits::default());
    let events = request(viewer.addr(), "HEAD", "/events");
    assert_eq!(events.status, 200);
    assert_eq!(events.header("Content-Type"), Some("text/event-stream"));
    assert!(events.body.is_empty(), "{:?}", events.body);
    for (target, status) in [("/", 200), ("/image.png", 503), ("/nope", 404)] {
        let get = request(viewer.addr(), "GET", target);
        let head = request(viewer.addr(), "HEAD", target);
        assert_eq!((get.status, head.status), (status, status), "{target}");
        assert!(head.body.is_empty(), "HEAD {target}: {:?}", head.body);
        assert_eq!(
            head.header("Content-Length"),
            Some(get.body.len().to_string().as_str()),
            "HEAD {target} says GET's length"
        );
    }
}

#[test]
fn a_huge_error_is_cut_in_the_event_stream() {
    // Events are kept and replayed to every new client, so a huge bad save must not make a huge
    // event. The watch loop bounds its messages too; the server does not count on it.
    let (viewer, feed) = library_server(Limits::default());
    let error = rondo::SceneError {
        path: "scene.ron".into(),
        location: Some(rondo::scene::error::Location { line: 2, col: 7 }),
        field: Some(format!("materials.{}", "f".repeat(1 << 20))),
        message: format!("bad \x1b]0;title\x07\n{}", "x".repeat(8 << 20)),
        source_line: Some(format!("\x1b[31m\r{}", "é".repeat(512 * 1024))),
    };
    feed.observe(&rondo::watch::Report::Failed(Box::new(error)), None);

    let events = Events::open(viewer.addr());
    let (error, _) = events.wait("the error", |e| e["kind"] == "error");
    let message = error["message"].as_str().expect("a message");
    assert!(
        message.len() <= MAX_MESSAGE + CUT.len() && message.ends_with(CUT),
        "the message is cut: {} bytes",
        message.len()
    );
    assert!(
        message.starts_with("bad \x1b]0;title\x07\nxxx"),
        "control characters travel escaped in one JSON line"
    );
    assert_eq!(
        (
            error["file"].as_str(),
            error["line"].as_u64(),
            error["column"].as_u64()
        ),
        (Some("scene.ron"), Some(2), Some(7))
    );
    let field = error["field"].as_str().expect("a field");
    assert!(
        field.len() <= MAX_MESSAGE + CUT.len() && field.starts_with("materials.ff"),
        "the field is cut: {} bytes",
        field.len()
    );
    let source = error["source_line"].as_str().expect("a source line");
    assert!(source.starts_with("\x1b[31m\ré"), "{:?}", &source[..20]);
    assert_eq!(
        source.chars().count(),
        MAX_SOURCE_LINE + CUT.chars().count(),
        "the source line is cut"
    );
    assert!(source.ends_with(CUT));
}

/// The header `[width, height, reload, samples]` and the floats of a raw float image.
fn raw_floats(body: &[u8]) -> ([u32; 4], Vec<f32>) {
    assert_eq!(&body[..8], b"RONDOF32");
    let u = |i: usize| u32::from_le_bytes(body[8 + 4 * i..12 + 4 * i].try_into().expect("u32"));
    let floats = body[24..]
        .chunks(4)
        .map(|b| f32::from_le_bytes(b.try_into().expect("f32")))
        .collect();
    ([u(0), u(1), u(2), u(3)], floats)
}

/// A first image of `reload`, 2×1 pixels, for the library's server.
fn wrote(feed: &rondo::serve::Feed, reload: u64) {
    let report = rondo::watch::Report::Wrote {
        reload,
        samples: 1,
        preview: false,
        spp: 8,
        changes: rondo::ecs::resources::ChangeSummary::default(),
        new_scene: true,
        at: Instant::now(),
    };
    feed.observe(&report, Some(&rondo::Film::new(2, 1)));
}

const DENOISED_ROUTES: [&str; 3] = ["/denoised.f32", "/albedo.f32", "/normal.f32"];

#[test]
fn the_newest_denoised_pass_is_served_with_its_albedo_and_normal() {
    use glam::Vec3;
    let (viewer, feed) = library_server(Limits::default());
    let addr = viewer.addr();
    wrote(&feed, 4);
    for target in DENOISED_ROUTES {
        let get = request(addr, "GET", target);
        assert_eq!(get.status, 404, "{target} before a denoised pass");
        assert_eq!(request(addr, "HEAD", target).status, 404, "HEAD {target}");
    }
    let events = Events::open(addr);
    events.wait("the pass", |e| e["kind"] == "pass");

    let sink = feed.denoise_sink();
    sink(&rondo::denoise::DenoisedFrame {
        reload: 4,
        samples: 8,
        images: rondo::denoise::FilmImages {
            width: 2,
            height: 1,
            colour: vec![Vec3::new(9.0, 9.0, 9.0); 2],
            albedo: Some(vec![Vec3::new(0.25, 0.5, 0.75), Vec3::ONE]),
            normal: Some(vec![Vec3::Z, Vec3::NEG_X]),
        },
        denoised: vec![Vec3::new(1.0, 2.0, 3.0), Vec3::new(4.0, 5.0, 6.0)],
        quality: rondo::denoise::Quality::Balanced,
        took: Duration::from_millis(21),
        saved: Instant::now(),
    });
    let (event, _) = events.wait("the denoised pass", |e| e["kind"] == "denoised");
    assert_eq!(
        (&event["reload"], &event["spp"], &event["quality"]),
        (&4.into(), &8.into(), &"balanced".into())
    );
    assert_eq!(event["took_ms"].as_f64(), Some(21.0));
    assert!(event["since_save_ms"].as_f64().is_some_and(|t| t >= 0.0));

    let expected: [Vec<f32>; 3] = [
        vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0],
        vec![0.25, 0.5, 0.75, 1.0, 1.0, 1.0],
        vec![0.0, 0.0, 1.0, -1.0, 0.0, 0.0],
    ];
    for (target, floats) in DENOISED_ROUTES.into_iter().zip(expected) {
        let get = request(addr, "GET", target);
        assert_eq!(get.status, 200, "{target}");
        assert_eq!(get.header("Content-Type"), Some("application/octet-stream"));
        assert_eq!(
            (get.header("X-Rondo-Reload"), get.header("X-Rondo-Samples")),
            (Some("4"), Some("8")),
            "{target} names its pass"
        );
        assert_eq!(raw_floats(&get.body), ([2, 1, 4, 8], floats), "{target}");
        let head = request(addr, "HEAD", target);
        assert_eq!((head.status, head.body.len()), (200, 0));
        // Exact paths only, and the Host check, as for every route.
        for bad in [
            format!("{target}/"),
            format!("/{target}"),
            format!("/..{target}"),
            target.to_uppercase(),
        ] {
            assert_eq!(request(addr, "GET", &bad).status, 404, "{bad}");
        }
        assert_eq!(request_as(addr, "GET", target, "evil.example").status, 403);
        assert_eq!(request(addr, "POST", target).status, 405);
    }
    // A client that comes later is told about it at once.
    let late = Events::open(addr);
    late.wait("the denoised pass, replayed", |e| {
        e["kind"] == "denoised" && e["spp"] == 8
    });

    // The next render's first image: the denoised pass is of another image now.
    wrote(&feed, 5);
    for target in DENOISED_ROUTES {
        assert_eq!(request(addr, "GET", target).status, 404, "{target}");
    }
}

#[test]
fn watch_serve_denoises_each_pass_for_the_viewer() {
    if common::denoiser().is_none() {
        return;
    }
    let rondo = Rondo::start("denoised", &scene(RED, 32, 4), &["--denoise"]);
    let events = rondo.events();
    let (event, _) = events.wait("the last pass denoised", |e| {
        e["kind"] == "denoised" && e["reload"] == 0 && e["spp"] == 4
    });
    assert!(
        ["fast", "balanced", "high"].contains(&event["quality"].as_str().unwrap_or("")),
        "{event}"
    );
    assert!(event["took_ms"].as_f64().is_some() && event["since_save_ms"].as_f64().is_some());
    let get = |target: &str| {
        let reply = rondo.get(target);
        assert_eq!(reply.status, 200, "{target}");
        assert_eq!(
            (
                reply.header("X-Rondo-Reload"),
                reply.header("X-Rondo-Samples")
            ),
            (Some("0"), Some("4")),
            "{target} is of the last pass"
        );
        raw_pixel(&reply.body, 16, 16)
    };
    // The centre pixel sees only the emitter, facing the camera: its albedo is its emission,
    // its normal points back at the camera; denoised, it stays close to the emission.
    assert_eq!(get("/albedo.f32"), [1.0, 0.0, 0.0]);
    assert_eq!(get("/normal.f32"), [0.0, 0.0, -1.0]);
    let denoised = get("/denoised.f32");
    assert!(
        (denoised[0] - 1.0).abs() < 0.02 && denoised[1].abs() < 0.02 && denoised[2].abs() < 0.02,
        "{denoised:?}"
    );
    assert_eq!(
        get("/image.f32"),
        [1.0, 0.0, 0.0],
        "the raw image is not replaced"
    );
}

#[test]
fn watch_denoise_writes_the_denoised_output_and_the_viewer_shows_it() {
    if common::denoiser().is_none() {
        return;
    }
    let rondo = Rondo::start(
        "denoise-output",
        &scene(RED, 32, 4),
        &["--denoise", "-o", "{dir}/out.exr"],
    );
    let line = rondo.line("a denoised pass", |l| l.starts_with("reload 0: denoised"));
    assert!(
        line.ends_with(", wrote out.exr"),
        "--denoise reaches the loop: {line}"
    );
    rondo
        .events()
        .wait("a denoised pass", |e| e["kind"] == "denoised");
}

#[test]
fn without_the_denoiser_denoise_is_refused_and_the_viewer_stays_raw() {
    let empty = common::temp_dir("serve-no-oidn");
    let good = empty.join("scene.ron");
    std::fs::write(&good, scene(RED, 32, 4)).expect("write scene");
    let mut refused = Command::new(env!("CARGO_BIN_EXE_rondo"))
        .env("RONDO_OIDN_DIR", empty.path())
        .arg("watch")
        .arg(&good)
        .args(["--serve", "127.0.0.1:0", "--denoise"])
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start rondo");
    let status =
        common::wait_or_kill(&mut refused, WAIT).expect("--denoise without a denoiser ends");
    let mut text = String::new();
    refused
        .stderr
        .take()
        .expect("piped stderr")
        .read_to_string(&mut text)
        .expect("stderr");
    assert!(!status.success(), "{text}");
    assert!(
        text.contains("Open Image Denoise") && text.contains("not available"),
        "{text}"
    );
    assert!(!text.contains("viewer:"), "refused before serving: {text}");

    // Without the flag the library is not even looked for: a folder holding something that
    // would fail loudly if loaded gives no warning, and the viewer shows the raw images.
    let bogus = common::temp_dir("serve-bogus-oidn");
    std::fs::write(bogus.join("libOpenImageDenoise.so.2"), "not a library").expect("write");
    let env = [("RONDO_OIDN_DIR", bogus.path())];
    let rondo = Rondo::start_with("no-oidn", &scene(RED, 32, 4), "127.0.0.1:0", &env, &[]);
    rondo.events().done(0);
    // A second render: news of a denoise of the first would have been reported by its end.
    rondo.save(&scene(GREEN, 32, 4));
    rondo.events().done(1);
    let said: Vec<String> = rondo.stderr.try_iter().collect();
    assert!(
        !said.iter().any(|l| l.contains("denoise")),
        "no denoiser without --denoise: {said:?}"
    );
    assert_eq!(
        raw_pixel(&rondo.get("/image.f32").body, 16, 16),
        [0.0, 1.0, 0.0]
    );
    for target in DENOISED_ROUTES {
        assert_eq!(rondo.get(target).status, 404, "{target}");
    }
}
