//! The framing routes: while the user orbits, pans or dollies in the viewer, the page asks for
//! quick images of the scene through the camera it is framing, and for the focus distance of
//! a point it clicks, without touching any file.
//!
//! | route | content |
//! |---|---|
//! | `POST /preview.f32` | the preview as raw floats (see [`super::RAW_MAGIC`]), for the page |
//! | `POST /preview.png` | the same preview as 8-bit sRGB PNG, the bytes `rondo render -o x.png` writes |
//! | `POST /focus` | `{"focus_distance":d,"reload":n}`: the depth of the point at a place of the image |
//! | `GET /frame.js` | the page's side: mouse and key framing, focus on click, "Save camera", "Undo" |
//!
//! The body is a JSON object of at most [`super::MAX_BODY`] bytes,
//! `{"camera":{"position":[x,y,z],"look_at":[…],"up":[…],"fov":40,"aperture":0,"focus_distance":5},"spp":1,"divisor":2}`,
//! the camera as `POST /camera` takes it (checked the same way: it is the camera a save would
//! write), `spp` in 1..=[`MAX_PREVIEW_SPP`] and `divisor` in 1..=[`MAX_PREVIEW_DIVISOR`]
//! (default 2). The image is the last scene that loaded, seen through that camera at the
//! scene's width and height divided by `divisor` with samples `0..spp`: the image
//! `rondo render` makes of the scene file with that camera, size and `--spp` (see
//! [`crate::watch::Previews`] for how requests meet the render loop: the newest wins, and the
//! progressive render pauses while the user frames).
//!
//! `POST /focus` takes `{"camera":{…},"x":0.5,"y":0.5}`, `x` and `y` in [0, 1] the place in the
//! image as fractions of its width and height from the top-left corner, and answers with the
//! depth along that camera's view of the first surface its central ray through that place hits
//! (as picking sees it: masked-out surfaces are passed through), the `focus_distance` that
//! makes that point sharp; `null` for the sky or background.
//!
//! Answers: `200` with the image (headers `X-Rondo-Reload`, `X-Rondo-Samples`, and
//! `X-Rondo-Took-Ms`: from the request's arrival to its image rendered); `409` when a
//! newer request replaced this one before it was rendered; `503` before the first frame or if
//! the render loop did not answer in [`WAIT`]; `404` when the server has no render loop to ask
//! (the previews were not set up); refusals as for `POST /camera`: `403` without the session's
//! token or from another `Origin`, `411`/`413`/`400`/`408` for the body, `400` for a camera the
//! scene format refuses or an `spp` out of range.

use std::net::TcpStream;
use std::time::{Duration, Instant};

use serde::Deserialize;
use serde_json::json;

use super::camera::{CameraFields, MAX_BODY};
use super::http::{self, Request};
use super::images::Frame;
use super::secret::Secret;
use crate::scene::camera_edit::check_camera;
use crate::watch::{
    MAX_PREVIEW_DIVISOR, MAX_PREVIEW_SPP, PreviewAsk, PreviewOutcome, PreviewRequest, Previews,
};

/// How long a request waits for the render loop.
pub const WAIT: Duration = Duration::from_secs(10);

/// The page's side of framing.
const SCRIPT: &str = include_str!("frame.js");

/// The framing routes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Route {
    /// `POST /preview.f32`.
    Raw,
    /// `POST /preview.png`.
    Png,
    /// `POST /focus`.
    Focus,
    /// `GET /frame.js`.
    Script,
}

impl Route {
    /// The route of a path (query removed), matched exactly.
    pub fn of(path: &str) -> Option<Self> {
        Some(match path {
            "/preview.f32" => Self::Raw,
            "/preview.png" => Self::Png,
            "/focus" => Self::Focus,
            "/frame.js" => Self::Script,
            _ => return None,
        })
    }

    /// Whether the route takes `POST` (the others take `GET` and `HEAD`).
    pub fn posts(self) -> bool {
        self != Self::Script
    }
}

/// The body of a preview request.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ImageBody {
    camera: CameraFields,
    spp: u32,
    #[serde(default = "half")]
    divisor: u32,
}

/// The body of a focus request.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FocusBody {
    camera: CameraFields,
    x: f32,
    y: f32,
}

/// The default divisor of the scene's size: half its width and height.
fn half() -> u32 {
    2
}

/// Answers a framing route (the method is checked by the caller). `host` is the request's
/// `Host`, already checked; `timeout` bounds the reading of a body.
pub fn answer(
    stream: &mut TcpStream,
    route: Route,
    request: &Request,
    (previews, secret): (Option<&Previews>, &Secret),
    host: &str,
    timeout: Duration,
) -> std::io::Result<()> {
    if route == Route::Script {
        let with_body = request.method != "HEAD";
        let content_type = "text/javascript; charset=utf-8";
        let headers = [("Content-Type", content_type)];
        return http::respond(stream, 200, &headers, SCRIPT.as_bytes(), with_body);
    }
    let (status, text) = match ask(stream, route, request, (previews, secret), host, timeout) {
        Ok(Some((outcome, took))) => return send(stream, route, outcome, took),
        // The client is gone.
        Ok(None) => return Ok(()),
        Err(refusal) => refusal,
    };
    http::respond_text(stream, status, &format!("{text}\n"), true)
}

/// Sends the answer to a request of `route` that the render loop answered with `outcome`
/// after `took`.
fn send(
    stream: &mut TcpStream,
    route: Route,
    outcome: PreviewOutcome,
    took: Duration,
) -> std::io::Result<()> {
    let took = format!("{:.1}", took.as_secs_f64() * 1e3);
    let (status, text) = match outcome {
        PreviewOutcome::Image(image) => {
            let frame = Frame::new(image.reload, image.film);
            let (bytes, content_type) = match route {
                Route::Png => (frame.png(), "image/png"),
                _ => (Ok(frame.raw()), "application/octet-stream"),
            };
            return match bytes {
                Ok(bytes) => {
                    let headers = [
                        ("Content-Type", content_type),
                        ("X-Rondo-Reload", &frame.reload().to_string()),
                        ("X-Rondo-Samples", &frame.samples().to_string()),
                        ("X-Rondo-Took-Ms", &took),
                    ];
                    http::respond(stream, 200, &headers, bytes, true)
                }
                Err(e) => http::respond_text(stream, 500, &format!("{e}\n"), true),
            };
        }
        PreviewOutcome::Focus(depth, reload) => {
            let body = json!({ "focus_distance": depth, "reload": reload }).to_string();
            let headers = [
                ("Content-Type", "application/json"),
                ("Cache-Control", "no-store"),
                ("X-Rondo-Took-Ms", &took),
            ];
            return http::respond(stream, 200, &headers, body.as_bytes(), true);
        }
        PreviewOutcome::Superseded => (409, "a newer preview replaced this one"),
        PreviewOutcome::NotReady => (503, "no scene has loaded yet"),
        PreviewOutcome::TimedOut => (503, "the render loop did not answer in time"),
    };
    http::respond_text(stream, status, &format!("{text}\n"), true)
}

/// Checks a request of `route` and has the render loop answer it: its outcome and the time
/// from the request to the answer, `None` if the client left while its body was read, or the
/// refusal.
fn ask(
    stream: &mut TcpStream,
    route: Route,
    request: &Request,
    (previews, secret): (Option<&Previews>, &Secret),
    host: &str,
    timeout: Duration,
) -> Result<Option<(PreviewOutcome, Duration)>, (u16, String)> {
    let refuse = |status: u16, text: &str| Err((status, text.to_string()));
    if let Err(why) = secret.admits(request, host) {
        return refuse(403, &format!("no preview: {why}"));
    }
    let Some(previews) = previews else {
        return refuse(404, "this server renders no previews");
    };
    let body = match http::read_body(stream, request, MAX_BODY, timeout) {
        Ok(body) => body,
        Err(e) => return e.refusal(MAX_BODY).map_or(Ok(None), Err),
    };
    let (camera, ask) = if route == Route::Focus {
        let body: FocusBody = serde_json::from_slice(&body)
            .map_err(|e| (400, format!("not a focus request: {e}")))?;
        if !((0.0..=1.0).contains(&body.x) && (0.0..=1.0).contains(&body.y)) {
            return refuse(400, "x and y must be fractions of the image, 0 to 1");
        }
        let ask = PreviewAsk::Focus {
            x: body.x,
            y: body.y,
        };
        (body.camera, ask)
    } else {
        let body: ImageBody = serde_json::from_slice(&body)
            .map_err(|e| (400, format!("not a preview request: {e}")))?;
        if !(1..=MAX_PREVIEW_SPP).contains(&body.spp) {
            return refuse(400, &format!("spp must be 1 to {MAX_PREVIEW_SPP}"));
        }
        if !(1..=MAX_PREVIEW_DIVISOR).contains(&body.divisor) {
            return refuse(400, &format!("divisor must be 1 to {MAX_PREVIEW_DIVISOR}"));
        }
        let ask = PreviewAsk::Image {
            spp: body.spp,
            divisor: body.divisor,
        };
        (body.camera, ask)
    };
    let camera = check_camera(&camera.values()).map_err(|e| (400, e.to_string()))?;
    let start = Instant::now();
    let outcome = previews.request(PreviewRequest { camera, ask }, WAIT);
    Ok(Some((outcome, start.elapsed())))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn routes_match_whole_paths_only() {
        assert_eq!(Route::of("/preview.f32"), Some(Route::Raw));
        assert_eq!(Route::of("/preview.png"), Some(Route::Png));
        assert_eq!(Route::of("/focus"), Some(Route::Focus));
        assert_eq!(Route::of("/frame.js"), Some(Route::Script));
        for bad in ["/preview", "/preview.f32/", "//frame.js", "/PREVIEW.PNG"] {
            assert_eq!(Route::of(bad), None, "{bad}");
        }
    }
}
