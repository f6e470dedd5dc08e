// The page's side of "Save camera" (served at /camera_write.js, see src/serve/camera.rs).
//
//   const cam = await rondoCamera.load();  // the scene file's camera; remembers its version
//   await rondoCamera.save({...cam, position: [0, 2, -6]});  // writes it into the scene file
//   await rondoCamera.undo();  // writes back the camera's text before the last save, as it was
//
// A camera is {position: [x, y, z], look_at: [x, y, z], up: [x, y, z], fov, aperture,
// focus_distance}. Each call resolves to the camera now in the file, or rejects with an Error
// whose `status` is the server's (409: the file changed since load(): load again; 422: the
// scene's camera is a glTF camera; 400: a camera the scene format refuses). The write needs the
// session's token, which the server puts in this page's <meta name="rondo-token">.
"use strict";

window.rondoCamera = (() => {
  const meta = document.querySelector('meta[name="rondo-token"]');
  const token = meta ? meta.content : "";
  // The version of the scene file last read or written, the camera in it and its text, and the
  // texts before each save (for undo).
  let base = null;
  let current = null;
  let text = null;
  const history = [];

  async function reply(response) {
    const text = await response.text();
    if (!response.ok) {
      const error = new Error(text.trim() || response.statusText);
      error.status = response.status;
      throw error;
    }
    return JSON.parse(text);
  }

  async function load() {
    const answer = await reply(await fetch("/camera.json", { cache: "no-store" }));
    base = answer.base;
    current = answer.camera;
    text = answer.text;
    if (current === null) {
      const error = new Error(answer.error);
      error.status = 422;
      throw error;
    }
    return current;
  }

  // Writes `fields` (the camera's numbers, or {text} of an earlier value) with the base.
  async function write(fields) {
    if (base === null) {
      await load();
    }
    const body = JSON.stringify({ base, ...fields });
    const answer = await reply(
      await fetch("/camera", {
        method: "POST",
        headers: { "Content-Type": "application/json", "X-Rondo-Token": token },
        body,
      }),
    );
    base = answer.base;
    current = answer.camera;
    text = answer.text;
    return current;
  }

  async function save(cam) {
    if (current === null) {
      await load();
    }
    const before = text;
    const written = await write({
      position: cam.position,
      look_at: cam.look_at,
      up: cam.up,
      fov: cam.fov,
      aperture: cam.aperture,
      focus_distance: cam.focus_distance,
    });
    history.push(before);
    return written;
  }

  async function undo() {
    if (history.length === 0) {
      return current;
    }
    const written = await write({ text: history[history.length - 1] });
    history.pop();
    return written;
  }

  return { load, save, undo };
})();
