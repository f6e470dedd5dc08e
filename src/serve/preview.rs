//! The framing routes: while the user orbits, pans or dollies in the viewer, the page asks for
//! quick images of the scene through the camera it is framing, without touching any file.
//!
//! | route | content |
//! |---|---|
//! | `POST /preview.f32` | the preview as raw floats (see [`super::RAW_MAGIC`]), for the page |
//! | `POST /preview.png` | the same preview as 8-bit sRGB PNG, the bytes `rondo render -o x.png` writes |
//! | `GET /frame.js` | the page's side: mouse and key framing, "Save camera", "Undo" |
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

use super::camera::{CameraFields, MAX_BODY};
use super::http::{self, Request};
use super::images::Frame;
use super::secret::Secret;
use crate::scene::camera_edit::check_camera;
use crate::watch::{
    MAX_PREVIEW_DIVISOR, MAX_PREVIEW_SPP, PreviewOutcome, PreviewRequest, Previews,
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
    /// `GET /frame.js`.
    Script,
}

impl Route {
    /// The route of a path (query removed), matched exactly.
    pub fn of(path: &str) -> Option<Self> {
        Some(match path {
            "/preview.f32" => Self::Raw,
            "/preview.png" => Self::Png,
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
struct Body {
    camera: CameraFields,
    spp: u32,
    #[serde(default = "half")]
    divisor: u32,
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
    let (status, text) = match preview(stream, request, previews, secret, host, timeout) {
        Ok(Some((frame, took))) => {
            let bytes = match route {
                Route::Png => frame.png(),
                _ => Ok(frame.raw()),
            };
            return match bytes {
                Ok(bytes) => {
                    let content_type = match route {
                        Route::Png => "image/png",
                        _ => "application/octet-stream",
                    };
                    let headers = [
                        ("Content-Type", content_type),
                        ("X-Rondo-Reload", &frame.reload().to_string()),
                        ("X-Rondo-Samples", &frame.samples().to_string()),
                        (
                            "X-Rondo-Took-Ms",
                            &format!("{:.1}", took.as_secs_f64() * 1e3),
                        ),
                    ];
                    http::respond(stream, 200, &headers, bytes, true)
                }
                Err(e) => http::respond_text(stream, 500, &format!("{e}\n"), true),
            };
        }
        // The client is gone.
        Ok(None) => return Ok(()),
        Err(refusal) => refusal,
    };
    http::respond_text(stream, status, &format!("{text}\n"), true)
}

/// Checks a preview request and has it rendered: the image and the time from the request to
/// the image, `None` if the client left while its body was read, or the refusal.
fn preview(
    stream: &mut TcpStream,
    request: &Request,
    previews: Option<&Previews>,
    secret: &Secret,
    host: &str,
    timeout: Duration,
) -> Result<Option<(Frame, Duration)>, (u16, String)> {
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
    let body: Body =
        serde_json::from_slice(&body).map_err(|e| (400, format!("not a preview request: {e}")))?;
    if !(1..=MAX_PREVIEW_SPP).contains(&body.spp) {
        return refuse(400, &format!("spp must be 1 to {MAX_PREVIEW_SPP}"));
    }
    if !(1..=MAX_PREVIEW_DIVISOR).contains(&body.divisor) {
        return refuse(400, &format!("divisor must be 1 to {MAX_PREVIEW_DIVISOR}"));
    }
    let camera = check_camera(&body.camera.values()).map_err(|e| (400, e.to_string()))?;
    let request = PreviewRequest {
        camera,
        spp: body.spp,
        divisor: body.divisor,
    };
    let start = Instant::now();
    match previews.request(request, WAIT) {
        PreviewOutcome::Image(image) => {
            let frame = Frame::new(image.reload, image.film);
            Ok(Some((frame, start.elapsed())))
        }
        PreviewOutcome::Superseded => refuse(409, "a newer preview replaced this one"),
        PreviewOutcome::NotReady => refuse(503, "no scene has loaded yet"),
        PreviewOutcome::TimedOut => refuse(503, "the render loop did not answer in time"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn routes_match_whole_paths_only() {
        assert_eq!(Route::of("/preview.f32"), Some(Route::Raw));
        assert_eq!(Route::of("/preview.png"), Some(Route::Png));
        assert_eq!(Route::of("/frame.js"), Some(Route::Script));
        for bad in ["/preview", "/preview.f32/", "//frame.js", "/PREVIEW.PNG"] {
            assert_eq!(Route::of(bad), None, "{bad}");
        }
    }
}
