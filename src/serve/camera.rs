//! The camera routes: the page reads the scene's camera and writes a camera the user framed
//! back into the scene file ("Save camera").
//!
//! | route | content |
//! |---|---|
//! | `GET /camera.json` | the camera of the scene file as it is on disk, with its version `base` |
//! | `POST /camera` | writes a camera into the scene file; answers the new `base` |
//! | `GET /camera_write.js` | the page's side: `window.rondoCamera = {load(), save(cam), undo()}` |
//!
//! `GET /camera.json` answers
//! `{"base":"<32 hex>","camera":{"position":[x,y,z],"look_at":[…],"up":[…],"fov":40,"aperture":0,"focus_distance":5},"text":"Camera(…)","error":null}`:
//! `base` names the bytes of the file read (a hash keyed by random keys of the session), `text`
//! is the camera's value as written, `look_at` the point at the focus distance along the view
//! (the file may have given a `direction`). Where the file's camera cannot be written (a
//! `Gltf(…)` camera, none, one that does not parse), `camera` and `text` are `null` and `error`
//! says why. A file that cannot be read answers `503`.
//!
//! `POST /camera` takes the same camera fields and the `base` the page read, as a JSON object
//! of at most [`MAX_BODY`] bytes, and replaces the text of the scene file's `camera:` value
//! (and nothing else: [`crate::scene::camera_edit`]) through
//! [`crate::output_file::write_bytes`]; it answers the new `base`, `camera` and `text`. Instead
//! of the fields, `{"base":…,"text":"Camera(…)"}` writes that text as it is (an undo puts an
//! earlier value back byte for byte; it must read as a `Camera(…)` and end where the value
//! ends, [`crate::scene::camera_edit::restore_camera`]). The watch loop then sees the file
//! change and reloads it as after any save. Refused, the file untouched:
//!
//! - `403`: an `Origin` header other than `http://<Host>`, or no `X-Rondo-Token` header holding
//!   the session's secret (`secret.rs`: only the served page knows it);
//! - `411`/`413`/`400`/`408`: a body without `Content-Length`, over [`MAX_BODY`], not the JSON
//!   object expected, or not sent in time;
//! - `400`: a camera the scene format refuses (a non-finite number, fov outside (0, 180), a
//!   negative aperture, a focus distance ≤ 0, `up` parallel to the view, `look_at` = `position`);
//! - `409`: the file no longer has the version `base` (changed since the page read it), cannot
//!   be read, or is a symbolic link (the atomic write would replace the link by a file);
//! - `422`: the file's camera is not a `Camera(…)` of its own (a `Gltf(…)`, none).
//!
//! An undo is a write of the camera's text before (the page keeps it): the server keeps no
//! history.
//! Writes are one at a time; the check of `base` and the rename are not atomic together, so an
//! editor's save in between them is overwritten (the rename never writes into another file).

use std::hash::{BuildHasher, RandomState};
use std::io::Write;
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, PoisonError};
use std::time::Duration;

use glam::Vec3;
use serde::Deserialize;
use serde_json::{Value, json};

use super::http::{self, Request};
use super::secret::Secret;
use crate::scene::bounded_read::read_text;
use crate::scene::camera_edit::{
    CameraEditError, CameraValues, camera_span, check_camera, replace_camera, restore_camera,
};
use crate::scene::format::{SceneCamera, parse};

/// Longest body `POST /camera` reads, in bytes.
pub const MAX_BODY: usize = 4096;

/// The page's side of the camera routes.
const SCRIPT: &str = include_str!("camera_write.js");

/// The camera routes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Route {
    /// `GET /camera.json`.
    Read,
    /// `POST /camera`.
    Write,
    /// `GET /camera_write.js`.
    Script,
}

impl Route {
    /// The route of a path (query removed), matched exactly.
    pub fn of(path: &str) -> Option<Self> {
        Some(match path {
            "/camera.json" => Self::Read,
            "/camera" => Self::Write,
            "/camera_write.js" => Self::Script,
            _ => return None,
        })
    }
}

/// The scene file the camera routes read and write, and what they share.
pub struct SceneFile {
    /// The watched scene file (`None`: the camera routes answer `404`).
    path: Option<PathBuf>,
    /// Two keyed hashers, whose 64-bit hashes together name a version of the file.
    keys: [RandomState; 2],
    /// Held through each write.
    writing: Mutex<()>,
}

impl SceneFile {
    /// The camera routes of the scene file `path`.
    pub fn new(path: Option<PathBuf>) -> Self {
        Self {
            path,
            keys: [RandomState::new(), RandomState::new()],
            writing: Mutex::new(()),
        }
    }

    /// The version of the file whose bytes are `bytes`: 128 bits of hash, keyed by random keys
    /// of this session (so a version cannot be forged without the file's bytes), in hex.
    fn version(&self, bytes: &[u8]) -> String {
        let [a, b] = &self.keys;
        format!("{:016x}{:016x}", a.hash_one(bytes), b.hash_one(bytes))
    }
}

/// A camera as the page sends it: the body of `POST /camera` (with its `base`), the `camera`
/// of a preview request.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraFields {
    position: [f64; 3],
    look_at: [f64; 3],
    up: [f64; 3],
    fov: f64,
    aperture: f64,
    focus_distance: f64,
}

impl CameraFields {
    /// The camera in `f32`, as the scene holds it (a number out of range becomes infinite, and
    /// is refused by [`check_camera`]).
    pub fn values(&self) -> CameraValues {
        let v = |[x, y, z]: [f64; 3]| Vec3::new(x as f32, y as f32, z as f32);
        CameraValues {
            position: v(self.position),
            look_at: v(self.look_at),
            up: v(self.up),
            fov: self.fov as f32,
            aperture: self.aperture as f32,
            focus_distance: self.focus_distance as f32,
        }
    }
}

/// What `POST /camera` writes.
enum NewCamera {
    /// A camera of these numbers, written one field per line.
    Values(CameraValues),
    /// This text of a `Camera(…)`, as it is (an undo).
    Text(String),
}

/// The body of `POST /camera`: the `base` the page read and either the camera's fields or
/// (an undo) the `text` of an earlier value, in one object.
fn write_body(body: &[u8]) -> Result<(String, NewCamera), Refusal> {
    let not = |e: serde_json::Error| (400, format!("not a camera: {e}"));
    let mut fields: serde_json::Map<String, Value> = serde_json::from_slice(body).map_err(not)?;
    let Some(Value::String(base)) = fields.remove("base") else {
        return Err((400, "not a camera: no \"base\" string".into()));
    };
    if fields.len() == 1
        && let Some(Value::String(text)) = fields.remove("text")
    {
        return Ok((base, NewCamera::Text(text)));
    }
    let camera: CameraFields = serde_json::from_value(Value::Object(fields)).map_err(not)?;
    let camera = camera.values();
    check_camera(&camera).map_err(|e| (400, e.to_string()))?;
    Ok((base, NewCamera::Values(camera)))
}

/// A camera as JSON, each number the shortest decimal that reads back as its `f32` (`33.3`, not
/// the `33.29999923706055` of its `f64`).
fn camera_json(c: &CameraValues) -> Value {
    let n = |v: f32| v.to_string().parse::<f64>().unwrap_or(f64::from(v));
    let v = |v: Vec3| v.to_array().map(n);
    json!({
        "position": v(c.position),
        "look_at": v(c.look_at),
        "up": v(c.up),
        "fov": n(c.fov),
        "aperture": n(c.aperture),
        "focus_distance": n(c.focus_distance),
    })
}

fn respond_json(stream: &mut impl Write, value: &Value, with_body: bool) -> std::io::Result<()> {
    http::respond(
        stream,
        200,
        &[("Content-Type", "application/json")],
        value.to_string().as_bytes(),
        with_body,
    )
}

/// Answers a camera route (the method is checked by the caller: `POST` for [`Route::Write`],
/// `GET` or `HEAD` for the others). `host` is the request's `Host`, already checked;
/// `timeout` bounds the reading of a body.
pub fn answer(
    stream: &mut TcpStream,
    route: Route,
    request: &Request,
    (scene, secret): (&SceneFile, &Secret),
    host: &str,
    timeout: Duration,
) -> std::io::Result<()> {
    let with_body = request.method != "HEAD";
    match route {
        Route::Script => http::respond(
            stream,
            200,
            &[("Content-Type", "text/javascript; charset=utf-8")],
            SCRIPT.as_bytes(),
            with_body,
        ),
        Route::Read => {
            let (status, text) = match read(scene) {
                Ok(value) => return respond_json(stream, &value, with_body),
                Err(refusal) => refusal,
            };
            http::respond_text(stream, status, &format!("{text}\n"), with_body)
        }
        Route::Write => {
            let (status, text) = match write(stream, request, scene, secret, host, timeout) {
                Ok(Some(value)) => return respond_json(stream, &value, true),
                // The client is gone.
                Ok(None) => return Ok(()),
                Err(refusal) => refusal,
            };
            http::respond_text(stream, status, &format!("{text}\n"), true)
        }
    }
}

/// A refusal: its status and why.
type Refusal = (u16, String);

/// The body of `GET /camera.json`.
fn read(scene: &SceneFile) -> Result<Value, Refusal> {
    let path = scene
        .path
        .as_deref()
        .ok_or((404, "no scene file".to_string()))?;
    let text = read_text(path).map_err(|e| (503, format!("{}: {e}", path.display())))?;
    let base = scene.version(text.as_bytes());
    Ok(match own_camera(path, &text) {
        Ok((camera, value)) => {
            json!({ "base": base, "camera": camera_json(&camera), "text": value, "error": null })
        }
        Err(error) => json!({ "base": base, "camera": null, "text": null, "error": error }),
    })
}

/// The scene text's own camera and the text of its value, or why there is none to write.
fn own_camera<'a>(path: &Path, text: &'a str) -> Result<(CameraValues, &'a str), String> {
    let span = camera_span(text).map_err(|e| e.to_string())?;
    let value = &text[span.value];
    let desc = match parse::<SceneCamera>(path, value) {
        Ok(SceneCamera::Camera(desc)) => desc,
        Ok(SceneCamera::Gltf(_)) => {
            return Err(CameraEditError::NotOwn(Some("Gltf".into())).to_string());
        }
        Err(e) => return Err(format!("the camera does not parse: {}", e.message)),
    };
    let camera = CameraValues {
        position: desc.position,
        look_at: desc.position + desc.direction.normalize() * desc.focus_distance,
        up: desc.up,
        fov: desc.fov,
        aperture: desc.aperture,
        focus_distance: desc.focus_distance,
    };
    Ok((camera, value))
}

/// Checks and carries out `POST /camera`: the answer's JSON, `None` if the client left while
/// its body was read, or the refusal.
fn write(
    stream: &mut TcpStream,
    request: &Request,
    scene: &SceneFile,
    secret: &Secret,
    host: &str,
    timeout: Duration,
) -> Result<Option<Value>, Refusal> {
    let refuse = |status: u16, text: &str| Err((status, text.to_string()));
    if let Err(why) = secret.admits(request, host) {
        return refuse(403, &format!("no write: {why}"));
    }
    let Some(path) = scene.path.as_deref() else {
        return refuse(404, "no scene file");
    };
    let body = match http::read_body(stream, request, MAX_BODY, timeout) {
        Ok(body) => body,
        Err(e) => return e.refusal(MAX_BODY).map_or(Ok(None), Err),
    };
    let (base, camera) = write_body(&body)?;
    let _writing = scene.writing.lock().unwrap_or_else(PoisonError::into_inner);
    let new_text = edit(path, scene, &base, &camera)?;
    crate::output_file::write_bytes(path, new_text.as_bytes())
        .map_err(|e| (500, format!("cannot write {}: {e}", path.display())))?;
    let (read, value) = own_camera(path, &new_text).map_err(|e| (500, e))?;
    let camera = match camera {
        NewCamera::Values(camera) => camera,
        NewCamera::Text(_) => read,
    };
    Ok(Some(json!({
        "base": scene.version(new_text.as_bytes()),
        "camera": camera_json(&camera),
        "text": value,
    })))
}

/// The text of the scene file at `path` with `camera` written in, if the file is a regular file
/// (not a symbolic link) whose version is still `base` and whose camera is its own.
fn edit(path: &Path, scene: &SceneFile, base: &str, camera: &NewCamera) -> Result<String, Refusal> {
    let link = std::fs::symlink_metadata(path)
        .map_err(|e| (409, format!("cannot read {}: {e}", path.display())))?
        .file_type()
        .is_symlink();
    if link {
        return Err((
            409,
            format!(
                "{} is a symbolic link: writing would replace the link by a file",
                path.display()
            ),
        ));
    }
    let text = read_text(path).map_err(|e| (409, format!("{}: {e}", path.display())))?;
    if scene.version(text.as_bytes()) != base {
        return Err((
            409,
            "the scene file changed since its camera was read: read it again".to_string(),
        ));
    }
    match camera {
        NewCamera::Values(camera) => replace_camera(&text, camera),
        NewCamera::Text(value) => restore_camera(&text, value),
    }
    .map_err(|e| match e {
        CameraEditError::Invalid(_) => (400, e.to_string()),
        _ => (422, e.to_string()),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn routes_match_whole_paths_only() {
        assert_eq!(Route::of("/camera"), Some(Route::Write));
        assert_eq!(Route::of("/camera.json"), Some(Route::Read));
        assert_eq!(Route::of("/camera_write.js"), Some(Route::Script));
        for bad in [
            "/camera/",
            "//camera",
            "/CAMERA",
            "/camera.json/x",
            "camera",
        ] {
            assert_eq!(Route::of(bad), None, "{bad}");
        }
    }

    #[test]
    fn versions_differ_with_any_byte_and_between_sessions() {
        let (a, b) = (SceneFile::new(None), SceneFile::new(None));
        let v = a.version(b"Scene()");
        assert_eq!(v.len(), 32);
        assert_eq!(v, a.version(b"Scene()"));
        assert_ne!(v, a.version(b"Scene( )"));
        assert_ne!(v, b.version(b"Scene()"));
    }
}
