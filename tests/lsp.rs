//! `rondo lsp` driven as an editor drives it: the real binary, JSON-RPC over its standard input
//! and output, framed here by hand (`Content-Length`), on a scene with a prefab in a temporary
//! directory. Expected places are computed from where the test writes or inserts text.

mod common;

use std::io::{BufRead, BufReader, Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, ExitStatus, Stdio};
use std::sync::mpsc::{Receiver, channel};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use common::gltf_doc::square_panel;
use common::temp_dir;
use serde_json::{Value, json};

/// How long a reply may take before the test gives up (a hang guard, not a measurement).
const PATIENCE: Duration = Duration::from_secs(60);

const SCENE: &str = r#"Scene(
    camera: Camera(position: (0, 1, -5), look_at: (0, 1, 0)),
    settings: Settings(width: 8, height: 8, spp: 1),
    materials: {
        "copper": Metal(albedo: Constant((0.9, 0.6, 0.4)), roughness: 0.2),
        "white": Diffuse(albedo: Constant((0.7, 0.7, 0.7))),
        "lamp": Light(emit: Constant((1, 1, 1)), intensity: 4),
    },
    entities: [
        Entity(name: "floor", material: "white", shape: Quad(a: (-5, 0, -5), b: (-5, 0, 5), c: (5, 0, 5), d: (5, 0, -5))),
        Entity(name: "ball", material: "copper", shape: Sphere(center: (0, 1, 0), radius: 0.5), transform: Transform(translate: (1, 2, 3))),
        Entity(name: "lamp", material: "lamp", shape: Sphere(center: (0, 4, 0), radius: 0.5)),
        Entity(name: "tall", prefab: "prefabs/box.ron", materials: { "surface": "white" }, transform: Transform(translate: (2, 0, 0), scale: (1, 2, 1))),
    ],
)
"#;

const PREFAB: &str = r#"// A unit box.
Prefab(
    materials: { "surface": Diffuse(albedo: Constant((0.73, 0.73, 0.73))) },
    entities: [ Entity(name: "box", material: "surface", shape: Box(min: (0, 0, 0), max: (1, 1, 1))) ],
)
"#;

/// A running `rondo lsp` and what it wrote.
struct Client {
    child: Child,
    stdin: Option<ChildStdin>,
    messages: Receiver<Value>,
    stderr: Arc<Mutex<String>>,
    stderr_reader: Option<std::thread::JoinHandle<()>>,
    /// Notifications read while waiting for something else.
    held: Vec<Value>,
    next_id: i64,
}

impl Client {
    fn start() -> Self {
        let mut child = Command::new(env!("CARGO_BIN_EXE_rondo"))
            .arg("lsp")
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("start rondo lsp");
        let stdout = child.stdout.take().expect("stdout");
        let (tx, messages) = channel();
        std::thread::spawn(move || {
            let mut r = BufReader::new(stdout);
            loop {
                let mut length = None;
                loop {
                    let mut line = String::new();
                    if r.read_line(&mut line).unwrap_or(0) == 0 {
                        return;
                    }
                    let line = line.trim_end();
                    if line.is_empty() {
                        break;
                    }
                    if let Some(v) = line.strip_prefix("Content-Length: ") {
                        length = v.parse::<usize>().ok();
                    }
                }
                let mut body = vec![0; length.expect("Content-Length from the server")];
                if r.read_exact(&mut body).is_err() {
                    return;
                }
                let value: Value = serde_json::from_slice(&body).expect("the server writes JSON");
                if tx.send(value).is_err() {
                    return;
                }
            }
        });
        let stderr = Arc::new(Mutex::new(String::new()));
        let mut err = child.stderr.take().expect("stderr");
        let sink = stderr.clone();
        let stderr_reader = std::thread::spawn(move || {
            let mut r = BufReader::new(&mut err);
            let mut line = String::new();
            while r.read_line(&mut line).unwrap_or(0) > 0 {
                if let Ok(mut s) = sink.lock() {
                    s.push_str(&line);
                }
                line.clear();
            }
        });
        let stdin = child.stdin.take();
        Self {
            child,
            stdin,
            messages,
            stderr,
            stderr_reader: Some(stderr_reader),
            held: Vec::new(),
            next_id: 1,
        }
    }

    fn write_raw(&mut self, bytes: &[u8]) {
        let stdin = self.stdin.as_mut().expect("stdin open");
        stdin.write_all(bytes).expect("write to the server");
        stdin.flush().expect("flush");
    }

    fn send(&mut self, message: &Value) {
        let body = serde_json::to_vec(message).expect("json");
        self.write_raw(format!("Content-Length: {}\r\n\r\n", body.len()).as_bytes());
        self.write_raw(&body);
    }

    fn notify(&mut self, method: &str, params: Value) {
        self.send(&json!({"jsonrpc": "2.0", "method": method, "params": params}));
    }

    /// Sends a request and returns its whole response.
    fn request(&mut self, method: &str, params: Value) -> Value {
        let id = self.next_id;
        self.next_id += 1;
        self.send(&json!({"jsonrpc": "2.0", "id": id, "method": method, "params": params}));
        self.response(&json!(id))
    }

    fn next(&mut self) -> Value {
        self.messages.recv_timeout(PATIENCE).unwrap_or_else(|e| {
            panic!(
                "no message from the server ({e}); stderr: {}",
                self.stderr()
            )
        })
    }

    /// The response with `id`, holding notifications that come first.
    fn response(&mut self, id: &Value) -> Value {
        loop {
            let m = self.next();
            if m.get("id") == Some(id) && m.get("method").is_none() {
                return m;
            }
            self.held.push(m);
        }
    }

    /// The next diagnostics published for `uri`.
    fn diagnostics(&mut self, uri: &str) -> Vec<Value> {
        let is_it = |m: &Value| {
            m["method"] == "textDocument/publishDiagnostics" && m["params"]["uri"] == uri
        };
        if let Some(k) = self.held.iter().position(is_it) {
            let m = self.held.remove(k);
            return m["params"]["diagnostics"]
                .as_array()
                .cloned()
                .unwrap_or_default();
        }
        loop {
            let m = self.next();
            if is_it(&m) {
                return m["params"]["diagnostics"]
                    .as_array()
                    .cloned()
                    .unwrap_or_default();
            }
            self.held.push(m);
        }
    }

    fn initialize(&mut self) -> Value {
        let r = self.request(
            "initialize",
            json!({"processId": null, "rootUri": null, "capabilities": {}}),
        );
        self.notify("initialized", json!({}));
        r
    }

    fn open(&mut self, uri: &str, text: &str) {
        self.notify(
            "textDocument/didOpen",
            json!({"textDocument": {"uri": uri, "languageId": "ron", "version": 1, "text": text}}),
        );
    }

    fn stderr(&self) -> String {
        self.stderr.lock().map(|s| s.clone()).unwrap_or_default()
    }

    /// Closes standard input and waits for the process.
    fn finish(mut self) -> (ExitStatus, String) {
        drop(self.stdin.take());
        let status = self.child.wait().expect("wait");
        // The stderr reader ends with the process.
        if let Some(reader) = self.stderr_reader.take() {
            let _ = reader.join();
        }
        let stderr = self.stderr();
        assert!(
            !stderr.contains("panicked"),
            "the server panicked: {stderr}"
        );
        (status, stderr)
    }
}

impl Drop for Client {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// A scene with a prefab on disk; returns (scene path, its URI).
fn workspace(dir: &Path) -> (PathBuf, String) {
    std::fs::create_dir_all(dir.join("prefabs")).expect("mkdir");
    std::fs::write(dir.join("prefabs/box.ron"), PREFAB).expect("prefab");
    std::fs::write(dir.join("prefabs/notes.txt"), "not a prefab").expect("notes");
    let scene = dir.join("scene.ron");
    std::fs::write(&scene, SCENE).expect("scene");
    let uri = format!("file://{}", scene.display());
    (scene, uri)
}

/// The LSP position (line, UTF-16 column; the text is ASCII) of byte `offset` of `text`.
fn position(text: &str, offset: usize) -> (u64, u64) {
    let before = &text[..offset];
    let line = before.matches('\n').count() as u64;
    let col = before.rsplit('\n').next().map_or(0, str::len) as u64;
    (line, col)
}

/// The byte offset of `needle` within the line of `text` that contains `line_marker`.
fn find_in_line(text: &str, line_marker: &str, needle: &str) -> usize {
    let line_start = text[..text.find(line_marker).expect(line_marker)]
        .rfind('\n')
        .map_or(0, |i| i + 1);
    line_start + text[line_start..].find(needle).expect(needle)
}

fn pos_json((line, col): (u64, u64)) -> Value {
    json!({"line": line, "character": col})
}

fn errors(diagnostics: &[Value]) -> Vec<&Value> {
    diagnostics.iter().filter(|d| d["severity"] == 1).collect()
}

#[test]
fn a_typo_in_the_buffer_is_reported_at_its_exact_range() {
    let dir = temp_dir("lsp-typo");
    let (scene, uri) = workspace(&dir);
    let mut c = Client::start();
    let init = c.initialize();
    assert_eq!(
        init["result"]["capabilities"]["textDocumentSync"]["change"],
        2
    );
    c.open(&uri, SCENE);
    let first = c.diagnostics(&uri);
    assert!(errors(&first).is_empty(), "{first:?}");

    // Incremental sync: the ball's `"copper"` becomes `"coppr"`.
    let at = find_in_line(SCENE, "\"ball\"", "\"copper\"");
    let (line, col) = position(SCENE, at);
    c.notify(
        "textDocument/didChange",
        json!({"textDocument": {"uri": uri, "version": 2}, "contentChanges": [{
            "range": {"start": pos_json((line, col)), "end": pos_json((line, col + 8))},
            "text": "\"coppr\""}]}),
    );
    let d = c.diagnostics(&uri);
    let e = errors(&d);
    assert_eq!(e.len(), 1, "{d:?}");
    assert_eq!(e[0]["range"]["start"], pos_json((line, col)));
    assert_eq!(
        e[0]["range"]["end"],
        pos_json((line, col + "\"coppr\"".len() as u64))
    );
    let message = e[0]["message"].as_str().unwrap_or_default();
    assert!(message.contains("unknown material \"coppr\""), "{message}");
    assert_eq!(
        std::fs::read_to_string(&scene).expect("scene"),
        SCENE,
        "the file on disk is untouched"
    );

    // Full sync: the whole text, with `"whte"` in the floor instead.
    let at = find_in_line(SCENE, "\"floor\"", "\"white\"");
    let text = format!(
        "{}\"whte\"{}",
        &SCENE[..at],
        &SCENE[at + "\"white\"".len()..]
    );
    c.notify(
        "textDocument/didChange",
        json!({"textDocument": {"uri": uri, "version": 3}, "contentChanges": [{"text": text}]}),
    );
    let d = c.diagnostics(&uri);
    let e = errors(&d);
    assert_eq!(e.len(), 1, "{d:?}");
    let (line, col) = position(&text, at);
    assert_eq!(e[0]["range"]["start"], pos_json((line, col)));
    assert_eq!(e[0]["range"]["end"], pos_json((line, col + 6)));

    // A parse error: a closing bracket deleted.
    let broken = SCENE.replacen("radius: 0.5),", "radius: 0.5,", 1);
    c.notify(
        "textDocument/didChange",
        json!({"textDocument": {"uri": uri, "version": 4}, "contentChanges": [{"text": broken}]}),
    );
    let d = c.diagnostics(&uri);
    assert_eq!(errors(&d).len(), 1, "{d:?}");
    let r = c.request("shutdown", Value::Null);
    assert_eq!(r["result"], Value::Null);
    c.notify("exit", Value::Null);
    let (status, _) = c.finish();
    assert_eq!(status.code(), Some(0));
}

#[test]
fn an_unsaved_prefab_buffer_stands_for_its_file_in_the_scenes_that_place_it() {
    let dir = temp_dir("lsp-prefab-buffer");
    let (_, uri) = workspace(&dir);
    let prefab_uri = format!("file://{}", dir.join("prefabs/box.ron").display());
    let mut c = Client::start();
    c.initialize();
    c.open(&uri, SCENE);
    assert_eq!(errors(&c.diagnostics(&uri)).len(), 0);

    // The buffer names a material the prefab does not define; the file on disk is still good.
    let broken = PREFAB.replace("material: \"surface\"", "material: \"surfac\"");
    c.open(&prefab_uri, &broken);
    let scene_d = c.diagnostics(&uri);
    let e = errors(&scene_d);
    assert_eq!(e.len(), 1, "the scene's load reads the buffer: {scene_d:?}");
    assert!(
        e[0]["message"]
            .as_str()
            .is_some_and(|m| m.contains("box.ron")),
        "{scene_d:?}"
    );
    let prefab_d = c.diagnostics(&prefab_uri);
    let e = errors(&prefab_d);
    assert_eq!(e.len(), 1, "shown in the prefab's buffer too: {prefab_d:?}");
    let typo = broken.find("\"surfac\"").expect("typo");
    assert_eq!(e[0]["range"]["start"], pos_json(position(&broken, typo)));
    assert_eq!(
        e[0]["range"]["end"],
        pos_json(position(&broken, typo + "\"surfac\"".len()))
    );

    // Mended in the buffer: both clear.
    c.notify(
        "textDocument/didChange",
        json!({"textDocument": {"uri": prefab_uri, "version": 2},
               "contentChanges": [{"text": PREFAB}]}),
    );
    assert_eq!(errors(&c.diagnostics(&uri)).len(), 0);
    assert_eq!(errors(&c.diagnostics(&prefab_uri)).len(), 0);

    // Broken again, then closed unsaved: the scene reads the file on disk again.
    c.notify(
        "textDocument/didChange",
        json!({"textDocument": {"uri": prefab_uri, "version": 3},
               "contentChanges": [{"text": broken}]}),
    );
    assert_eq!(errors(&c.diagnostics(&uri)).len(), 1);
    c.notify(
        "textDocument/didClose",
        json!({"textDocument": {"uri": prefab_uri}}),
    );
    assert_eq!(errors(&c.diagnostics(&uri)).len(), 0);
    c.request("shutdown", Value::Null);
    c.notify("exit", Value::Null);
    let (status, _) = c.finish();
    assert_eq!(status.code(), Some(0));
}

#[test]
fn definition_goes_to_the_material_the_prefab_and_its_names() {
    let dir = temp_dir("lsp-definition");
    let (_, uri) = workspace(&dir);
    let mut c = Client::start();
    c.initialize();
    c.open(&uri, SCENE);
    let definition = |c: &mut Client, at: usize| {
        c.request(
            "textDocument/definition",
            json!({"textDocument": {"uri": uri}, "position": pos_json(position(SCENE, at))}),
        )["result"]
            .clone()
    };
    let copper = find_in_line(SCENE, "\"ball\"", "\"copper\"") + 3;
    let r = definition(&mut c, copper);
    let defined = SCENE.find("\"copper\":").expect("definition");
    assert_eq!(r["uri"], uri.as_str());
    assert_eq!(r["range"]["start"], pos_json(position(SCENE, defined)));

    let path = find_in_line(SCENE, "\"tall\"", "prefabs/box");
    let r = definition(&mut c, path);
    let prefab_uri = format!("file://{}", dir.join("prefabs/box.ron").display());
    assert_eq!(r["uri"], prefab_uri.as_str());

    let surface = find_in_line(SCENE, "\"tall\"", "\"surface\"") + 1;
    let r = definition(&mut c, surface);
    assert_eq!(r["uri"], prefab_uri.as_str());
    let in_prefab = PREFAB.find("\"surface\":").expect("prefab's surface");
    assert_eq!(r["range"]["start"], pos_json(position(PREFAB, in_prefab)));

    let name = find_in_line(SCENE, "\"ball\"", "ball");
    assert_eq!(definition(&mut c, name), Value::Null);
}

#[test]
fn completion_lists_names_fields_kinds_and_paths() {
    let dir = temp_dir("lsp-completion");
    let (_, uri) = workspace(&dir);
    let empty = SCENE.replacen("material: \"copper\"", "material: \"\"", 1);
    let mut c = Client::start();
    c.initialize();
    c.open(&uri, &empty);
    let labels = |c: &mut Client, text: &str, at: usize| {
        let r = c.request(
            "textDocument/completion",
            json!({"textDocument": {"uri": uri}, "position": pos_json(position(text, at))}),
        );
        let mut labels: Vec<String> = r["result"]
            .as_array()
            .unwrap_or_else(|| panic!("{r}"))
            .iter()
            .map(|i| i["label"].as_str().unwrap_or_default().to_string())
            .collect();
        labels.sort();
        labels
    };
    // The materials written in SCENE's `materials` map.
    let inside = empty.find("material: \"\"").expect("empty") + "material: \"".len();
    assert_eq!(labels(&mut c, &empty, inside), ["copper", "lamp", "white"]);
    let after_open = find_in_line(&empty, "\"ball\"", "Entity(") + "Entity(".len();
    assert_eq!(
        labels(&mut c, &empty, after_open),
        [
            "gltf",
            "material",
            "materials",
            "name",
            "prefab",
            "shape",
            "transform"
        ]
    );
    let shape = find_in_line(&empty, "\"ball\"", "Sphere(");
    assert_eq!(
        labels(&mut c, &empty, shape),
        ["Box", "Mesh", "Plane", "Quad", "Sphere", "Triangle"]
    );
    let in_sphere = find_in_line(&empty, "\"ball\"", "center");
    assert_eq!(labels(&mut c, &empty, in_sphere), ["center", "radius"]);
    let kind = find_in_line(&empty, "\"copper\":", "Metal");
    assert_eq!(
        labels(&mut c, &empty, kind),
        ["Dielectric", "Diffuse", "Glossy", "Light", "Metal", "Pbr"]
    );
    // Files beside the prefab: the .ron one, not notes.txt.
    let folder = find_in_line(&empty, "\"tall\"", "box.ron");
    assert_eq!(labels(&mut c, &empty, folder), ["box.ron"]);
    // The prefab's names, in the placement's map.
    let key = find_in_line(&empty, "\"tall\"", "surface");
    assert_eq!(labels(&mut c, &empty, key), ["surface"]);
}

#[test]
fn symbols_list_materials_then_entities() {
    let dir = temp_dir("lsp-symbols");
    let (_, uri) = workspace(&dir);
    let mut c = Client::start();
    c.initialize();
    c.open(&uri, SCENE);
    let r = c.request(
        "textDocument/documentSymbol",
        json!({"textDocument": {"uri": uri}}),
    );
    let symbols = r["result"].as_array().unwrap_or_else(|| panic!("{r}"));
    let names: Vec<&str> = symbols
        .iter()
        .map(|s| s["name"].as_str().unwrap_or_default())
        .collect();
    assert_eq!(
        names,
        ["copper", "white", "lamp", "floor", "ball", "lamp", "tall"]
    );
    let ball = &symbols[4];
    let line = position(SCENE, SCENE.find("Entity(name: \"ball\"").expect("ball")).0;
    assert_eq!(ball["range"]["start"]["line"], line);
    assert_eq!(
        ball["selectionRange"]["start"],
        pos_json(position(SCENE, SCENE.find("\"ball\"").expect("ball")))
    );
}

#[test]
fn hover_shows_definitions_bounds_and_placements() {
    let dir = temp_dir("lsp-hover");
    let (_, uri) = workspace(&dir);
    let mut c = Client::start();
    c.initialize();
    c.open(&uri, SCENE);
    // The scene has loaded once its diagnostics are out.
    c.diagnostics(&uri);
    let hover = |c: &mut Client, at: usize| {
        let r = c.request(
            "textDocument/hover",
            json!({"textDocument": {"uri": uri}, "position": pos_json(position(SCENE, at))}),
        );
        r["result"]["contents"]["value"]
            .as_str()
            .unwrap_or_else(|| panic!("{r}"))
            .to_string()
    };
    let copper = find_in_line(SCENE, "\"ball\"", "\"copper\"") + 2;
    let shown = hover(&mut c, copper);
    assert!(
        shown.contains("\"copper\": Metal(albedo: Constant((0.9, 0.6, 0.4)), roughness: 0.2)"),
        "{shown}"
    );
    // A sphere of radius 0.5 at (0, 1, 0), moved by (1, 2, 3).
    let ball = find_in_line(SCENE, "\"ball\"", "ball");
    let shown = hover(&mut c, ball);
    assert!(
        shown.contains("min [0.5, 2.5, 2.5] max [1.5, 3.5, 3.5]"),
        "{shown}"
    );
    // The unit box scaled by (1, 2, 1), moved by (2, 0, 0); one entity placed.
    let tall = find_in_line(SCENE, "\"tall\"", "tall");
    let shown = hover(&mut c, tall);
    assert!(shown.contains("min [2, 0, 0] max [3, 2, 1]"), "{shown}");
    assert!(
        shown.contains("places 1 entity") && shown.contains("`tall/box`"),
        "{shown}"
    );
}

#[test]
fn exit_without_shutdown_is_status_1() {
    let mut c = Client::start();
    c.initialize();
    c.notify("exit", Value::Null);
    let (status, _) = c.finish();
    assert_eq!(status.code(), Some(1));
}

#[test]
fn bad_messages_get_errors_and_the_server_goes_on() {
    let mut c = Client::start();
    let early = c.request("textDocument/hover", json!({}));
    assert_eq!(early["error"]["code"], -32002);
    c.initialize();
    c.write_raw(b"Content-Length: 9\r\n\r\n{\"id\": 1,");
    let m = c.next();
    assert_eq!(
        (m["id"].clone(), m["error"]["code"].clone()),
        (Value::Null, json!(-32700))
    );
    c.send(&json!([1, 2]));
    assert_eq!(c.next()["error"]["code"], -32600);
    let r = c.request("rondo/nothing", json!({}));
    assert_eq!(r["error"]["code"], -32601);
    let r = c.request("textDocument/hover", json!({"textDocument": 5}));
    assert_eq!(r["error"]["code"], -32602);
    c.notify("rondo/unknown", json!({}));
    // A body over the limit (64 MiB) is read past, never stored: the next request is answered
    // and the process's peak memory stays far below the body's size.
    let big = (64u64 << 20) + 1;
    c.write_raw(format!("Content-Length: {big}\r\n\r\n").as_bytes());
    let chunk = vec![b' '; 1 << 20];
    let mut left = big as usize;
    while left > 0 {
        let n = left.min(chunk.len());
        c.write_raw(&chunk[..n]);
        left -= n;
    }
    let r = c.request("shutdown", Value::Null);
    assert_eq!(r["result"], Value::Null);
    let status =
        std::fs::read_to_string(format!("/proc/{}/status", c.child.id())).unwrap_or_default();
    let peak_kib: u64 = status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
        .unwrap_or(0);
    assert!(
        peak_kib < 40 << 10,
        "peak memory {peak_kib} KiB for a skipped body of 64 MiB"
    );
    // A length no one could send: the server skips until the input ends, then stops.
    c.write_raw(b"Content-Length: 18446744073709551615\r\n\r\n{}");
    let (status, stderr) = c.finish();
    assert_eq!(status.code(), Some(1));
    assert!(
        stderr.contains("unknown notification \"rondo/unknown\""),
        "{stderr}"
    );
    assert!(stderr.contains("67108865 bytes skipped"), "{stderr}");
}

#[test]
fn a_header_that_does_not_parse_stops_the_server_with_a_message() {
    let mut c = Client::start();
    c.write_raw(b"Content-Length: lots\r\n\r\n{}");
    let (status, stderr) = c.finish();
    assert_eq!(status.code(), Some(1));
    assert!(
        stderr.contains("Content-Length \"lots\" is not a number"),
        "{stderr}"
    );
}

#[test]
fn gltf_placements_are_checked_completed_hovered_and_followed() {
    let dir = temp_dir("lsp-gltf");
    workspace(&dir);
    std::fs::create_dir_all(dir.join("models")).expect("mkdir");
    std::fs::write(dir.join("models/panel.gltf"), square_panel()).expect("gltf");
    std::fs::write(dir.join("models/readme.txt"), "not a model").expect("notes");
    let placement = "        Entity(name: \"panel\", gltf: \"models/panel.gltf\", transform: Transform(translate: (-0.5, 0.6, 2.5))),\n";
    let end = SCENE.rfind("    ],").expect("end of entities");
    let text = format!("{}{placement}{}", &SCENE[..end], &SCENE[end..]);
    let scene = dir.join("gltf.ron");
    std::fs::write(&scene, &text).expect("scene");
    let uri = format!("file://{}", scene.display());
    let mut c = Client::start();
    c.initialize();
    c.open(&uri, &text);
    let first = c.diagnostics(&uri);
    assert!(errors(&first).is_empty(), "{first:?}");
    let at = |c: &mut Client, method: &str, text: &str, offset: usize| {
        c.request(
            method,
            json!({"textDocument": {"uri": uri}, "position": pos_json(position(text, offset))}),
        )["result"]
            .clone()
    };

    // Hover on the placement: the unit square moved by (−0.5, 0.6, 2.5), and its one entity.
    let name = find_in_line(&text, "\"panel\"", "panel");
    let shown = at(&mut c, "textDocument/hover", &text, name);
    let shown = shown["contents"]["value"].as_str().unwrap_or_default();
    assert!(
        shown.contains("min [-0.5, 0.6, 2.5] max [0.5, 1.6, 2.5]"),
        "{shown}"
    );
    assert!(
        shown.contains("places 1 entity") && shown.contains("`panel/sign`"),
        "{shown}"
    );

    // Definition: the path goes to the file.
    let path = find_in_line(&text, "\"panel\"", "panel.gltf");
    let r = at(&mut c, "textDocument/definition", &text, path);
    let gltf_uri = format!("file://{}", dir.join("models/panel.gltf").display());
    assert_eq!(r["uri"], gltf_uri.as_str(), "{r}");

    // Completion in the path: the glTF file beside it, not the text file.
    let r = at(&mut c, "textDocument/completion", &text, path);
    let labels: Vec<&str> = r
        .as_array()
        .unwrap_or_else(|| panic!("{r}"))
        .iter()
        .map(|i| i["label"].as_str().unwrap_or_default())
        .collect();
    assert_eq!(labels, ["panel.gltf"], "{r}");

    // A typo in the path: an error over the path's string, naming it.
    let typo = text.replacen("models/panel.gltf", "models/panell.gltf", 1);
    c.notify(
        "textDocument/didChange",
        json!({"textDocument": {"uri": uri, "version": 2}, "contentChanges": [{"text": typo}]}),
    );
    let d = c.diagnostics(&uri);
    let e = errors(&d);
    assert_eq!(e.len(), 1, "{d:?}");
    let quoted = find_in_line(&typo, "\"panel\"", "\"models/panell.gltf\"");
    assert_eq!(
        e[0]["range"]["start"],
        pos_json(position(&typo, quoted)),
        "{d:?}"
    );
    let message = e[0]["message"].as_str().unwrap_or_default();
    assert!(message.contains("panell.gltf"), "{message}");
}

/// The script headless Neovim runs (Lua, Neovim 0.7 and later): opens `RONDO_SCENE`, starts
/// `RONDO_BIN lsp` as its language client, then as a user would: types a typo into the buffer
/// and waits for the error, takes it back and waits for none, asks for a completion, a
/// definition and a hover at the places the test gives; writes what it saw to `RONDO_OUT`.
const NVIM_SCRIPT: &str = r#"
local out = {}
local function finish()
  local f = io.open(vim.env.RONDO_OUT, "w")
  f:write(vim.fn.json_encode(out))
  f:close()
  vim.cmd("qall!")
end
local ok, err = pcall(function()
  vim.cmd("edit " .. vim.fn.fnameescape(vim.env.RONDO_SCENE))
  local buf = vim.api.nvim_get_current_buf()
  local id = vim.lsp.start_client({ name = "rondo", cmd = { vim.env.RONDO_BIN, "lsp" },
                                    root_dir = vim.fn.fnamemodify(vim.env.RONDO_SCENE, ":h") })
  vim.lsp.buf_attach_client(buf, id)
  out.initialized = vim.wait(30000, function()
    local c = vim.lsp.get_client_by_id(id)
    return c ~= nil and c.initialized
  end, 20)
  local function errors()
    return vim.diagnostic.get(buf, { severity = vim.diagnostic.severity.ERROR })
  end
  local line, col = tonumber(vim.env.RONDO_TYPO_LINE), tonumber(vim.env.RONDO_TYPO_COL)
  vim.api.nvim_buf_set_text(buf, line, col, line, col + 8, { '"coppr"' })
  out.typo_seen = vim.wait(30000, function() return #errors() > 0 end, 20)
  local e = errors()[1]
  if e then
    out.typo = { lnum = e.lnum, col = e.col, end_col = e.end_col, message = e.message }
  end
  vim.api.nvim_buf_set_text(buf, line, col, line, col + 7, { '"copper"' })
  out.fixed = vim.wait(30000, function() return #errors() == 0 end, 20)
  local function ask(method, l, c)
    local params = { textDocument = { uri = vim.uri_from_bufnr(buf) },
                     position = { line = l, character = c } }
    local answers = vim.lsp.buf_request_sync(buf, method, params, 30000) or {}
    local answer = answers[id]
    return answer and answer.result
  end
  local items = ask("textDocument/completion", line, col + 1) or {}
  out.completion = {}
  for _, item in ipairs(items.items or items) do table.insert(out.completion, item.label) end
  table.sort(out.completion)
  local def = ask("textDocument/definition", line, col + 3)
  if def and def[1] then def = def[1] end
  out.definition = def and def.range and def.range.start
  local hover = ask("textDocument/hover", tonumber(vim.env.RONDO_HOVER_LINE),
                    tonumber(vim.env.RONDO_HOVER_COL))
  out.hover = hover and hover.contents and hover.contents.value
end)
if not ok then out.error = tostring(err) end
finish()
"#;

/// Neovim's `nvim`, or `None` (after saying why) when it is missing and `RONDO_REQUIRE_NVIM`
/// is not `1` (CI sets it, after installing Debian's `neovim`).
fn nvim() -> Option<&'static str> {
    let found = Command::new("nvim")
        .arg("--version")
        .stdout(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if found {
        return Some("nvim");
    }
    assert!(
        std::env::var("RONDO_REQUIRE_NVIM").as_deref() != Ok("1"),
        "RONDO_REQUIRE_NVIM=1 but no nvim on the PATH (Debian: apt-get install neovim)"
    );
    eprintln!("skipped: no nvim on the PATH (Debian: apt-get install neovim)");
    None
}

#[test]
fn headless_neovim_shows_diagnostics_completes_follows_and_hovers() {
    let Some(nvim) = nvim() else { return };
    let dir = temp_dir("lsp-nvim");
    let (scene, _) = workspace(&dir);
    let script = dir.join("init.lua");
    std::fs::write(&script, NVIM_SCRIPT).expect("script");
    let out = dir.join("seen.json");
    let typo = find_in_line(SCENE, "\"ball\"", "\"copper\"");
    let (line, col) = position(SCENE, typo);
    let (hover_line, hover_col) = position(SCENE, find_in_line(SCENE, "\"ball\"", "ball"));
    let mut child = Command::new(nvim)
        .args(["--headless", "-n", "-i", "NONE", "--noplugin", "-u"])
        .arg(&script)
        .env("RONDO_BIN", env!("CARGO_BIN_EXE_rondo"))
        .env("RONDO_SCENE", &scene)
        .env("RONDO_OUT", &out)
        .env("RONDO_TYPO_LINE", line.to_string())
        .env("RONDO_TYPO_COL", col.to_string())
        .env("RONDO_HOVER_LINE", hover_line.to_string())
        .env("RONDO_HOVER_COL", hover_col.to_string())
        .env("XDG_STATE_HOME", &*dir)
        .env("XDG_DATA_HOME", &*dir)
        .current_dir(&*dir)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("start nvim");
    let deadline = std::time::Instant::now() + 3 * PATIENCE;
    while child.try_wait().expect("wait").is_none() {
        if std::time::Instant::now() > deadline {
            let _ = child.kill();
            panic!("nvim did not finish");
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let seen: Value =
        serde_json::from_str(&std::fs::read_to_string(&out).expect("nvim wrote what it saw"))
            .expect("JSON");
    assert!(seen["error"].is_null(), "{seen}");
    assert_eq!(seen["initialized"], true, "{seen}");
    assert_eq!(seen["typo_seen"], true, "{seen}");
    let e = &seen["typo"];
    assert_eq!(
        (e["lnum"].as_u64(), e["col"].as_u64()),
        (Some(line), Some(col)),
        "{seen}"
    );
    assert_eq!(
        e["end_col"].as_u64(),
        Some(col + "\"coppr\"".len() as u64),
        "{seen}"
    );
    assert!(
        e["message"]
            .as_str()
            .is_some_and(|m| m.contains("unknown material \"coppr\"")),
        "{seen}"
    );
    assert_eq!(seen["fixed"], true, "{seen}");
    assert_eq!(
        seen["completion"],
        json!(["copper", "lamp", "white"]),
        "{seen}"
    );
    let defined = SCENE.find("\"copper\":").expect("definition");
    assert_eq!(
        seen["definition"],
        pos_json(position(SCENE, defined)),
        "{seen}"
    );
    let hover = seen["hover"].as_str().unwrap_or_default();
    assert!(
        hover.contains("min [0.5, 2.5, 2.5] max [1.5, 3.5, 3.5]"),
        "{seen}"
    );
    assert_eq!(
        std::fs::read_to_string(&scene).expect("scene"),
        SCENE,
        "the file on disk is untouched"
    );
}
