// Framing in the viewer (served at /frame.js, see src/serve/preview.rs): the mouse and the keys
// move a camera of the page's own, previews of it come from POST /preview.f32, and "Save
// camera" writes it into the scene file through window.rondoCamera (/camera_write.js).
//
//   drag            orbit around the point looked at
//   right/shift-drag pan
//   wheel           dolly (towards or away from the point looked at)
//   W A S D Q E     fly: forward, left, back, right, down, up (with the pointer on the image)
//   Escape          back to the scene's camera (the preview is dropped; the file is untouched)
//
// While framing, the page shows the preview (a quarter of the scene's width and height at 1
// sample per pixel while the camera moves; once it rests, half of them at 4, then 16) and the
// render loop pauses. One request is in
// flight at a time: moves made meanwhile are sent as one request when it returns, so the image
// of an old position never delays the next. window.rondoFraming exposes the state for the page
// (image(), active()) and for tests (camera(), latencies, rendering).
"use strict";

window.rondoFraming = (() => {
  const canvas = document.getElementById("canvas");
  const meta = document.querySelector('meta[name="rondo-token"]');
  const token = meta ? meta.content : "";
  // The previews of a camera, coarse to fine: the first while it moves, the others once it rests.
  const LEVELS = [{ spp: 1, divisor: 4 }, { spp: 4, divisor: 2 }, { spp: 16, divisor: 2 }];
  const REST_MS = 150, DRAG_PX = 3;

  // `file`: the camera of the scene file as last read or written; `cam`: the framed camera
  // (null: not framing); `image`: the newest preview; `movedAt`: time of the newest move not
  // yet shown; `level`: the index in LEVELS of the preview wanted next (-1: none).
  const state = { file: null, cam: null, image: null, movedAt: 0, level: -1, inFlight: false,
                  refineTimer: 0, endAfter: null, reload: -1, passReload: -1 };
  // Of each coarse preview: ms from the move to its preview drawn, and of those the server's
  // (from the request's arrival to its image rendered).
  const latencies = [], rendering = [];

  const bar = document.querySelector("header");
  function button(label, title) {
    const b = document.createElement("button");
    b.textContent = label; b.title = title; b.disabled = true;
    bar.appendChild(b);
    return b;
  }
  const saveButton = button("Save camera", "write the framed camera into the scene file");
  const undoButton = button("Undo", "write back the camera before the last save");
  const resetButton = button("Reset", "back to the scene's camera (Escape)");
  const note = document.createElement("span");
  note.id = "framing";
  bar.appendChild(note);

  const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
  const add = (a, b) => [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
  const mul = (a, s) => [a[0] * s, a[1] * s, a[2] * s];
  const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
  const len = (a) => Math.sqrt(dot(a, a));
  const unit = (a) => mul(a, 1 / len(a));
  // `v` turned by `angle` around the unit axis `k` (Rodrigues).
  function rotate(v, k, angle) {
    const c = Math.cos(angle), s = Math.sin(angle);
    return add(add(mul(v, c), mul(cross(k, v), s)), mul(k, dot(k, v) * (1 - c)));
  }

  function redraw() {
    document.dispatchEvent(new CustomEvent("rondo:redraw"));
  }

  function show(message) {
    note.textContent = message;
  }

  function update() {
    const framing = state.cam !== null;
    saveButton.disabled = !framing || state.file === null;
    resetButton.disabled = !framing;
    document.body.dataset.framing = framing ? "1" : "";
  }

  async function fileCamera() {
    if (state.file === null) state.file = await window.rondoCamera.load();
    return state.file;
  }

  // Starts framing from the file's camera (on the first move; moves meanwhile wait for the
  // same read). Null if it cannot be framed.
  let starting = null;
  function begin() {
    if (state.cam) return Promise.resolve(state.cam);
    if (!starting) {
      starting = (async () => {
        try {
          const file = await fileCamera();
          state.cam = state.cam || structuredClone(file);
          update();
          return state.cam;
        } catch (e) {
          show(`framing needs the scene's own Camera(…): ${e.message}`);
          return null;
        }
      })().finally(() => { starting = null; });
    }
    return starting;
  }

  function end() {
    state.cam = null; state.image = null; state.level = -1; state.endAfter = null;
    clearTimeout(state.refineTimer);
    update();
    redraw();
  }

  // The camera changed: ask for a coarse preview now and finer ones once it rests.
  function moved() {
    state.movedAt = performance.now();
    state.level = 0;
    clearTimeout(state.refineTimer);
    pump();
  }

  function refineLater(after) {
    clearTimeout(state.refineTimer);
    if (after + 1 < LEVELS.length) {
      state.refineTimer = setTimeout(() => { state.level = after + 1; pump(); }, REST_MS);
    }
  }

  async function pump() {
    if (state.inFlight || !state.cam || state.level < 0) return;
    const level = state.level, cam = structuredClone(state.cam), movedAt = state.movedAt;
    const { spp, divisor } = LEVELS[level];
    state.level = -1;
    state.inFlight = true;
    try {
      const response = await fetch("/preview.f32", {
        method: "POST",
        headers: { "Content-Type": "application/json", "X-Rondo-Token": token },
        body: JSON.stringify({ camera: cam, spp, divisor }),
      });
      if (response.ok && state.cam) {
        const image = window.rondoParseRaw(await response.arrayBuffer());
        image.divisor = divisor;
        state.image = image;
        redraw();
        if (level === 0) {
          latencies.push(performance.now() - movedAt);
          rendering.push(Number(response.headers.get("x-rondo-took-ms")));
        }
        document.body.dataset.previews = String(Number(document.body.dataset.previews || 0) + 1);
        show(`framing · preview ${image.width}×${image.height} · ${spp} spp`);
        if (state.level < 0) refineLater(level);
      } else if (!response.ok && response.status !== 409) {
        show(`no preview: ${(await response.text()).trim()}`);
      }
    } catch (e) {
      show(`no preview: ${e.message}`);
    } finally {
      state.inFlight = false;
    }
    pump();
  }

  // Orbit, pan and dolly of the framed camera; distances scale with the distance looked at.
  function orbit(dx, dy) {
    const c = state.cam, up = unit(c.up);
    let offset = sub(c.position, c.look_at);
    offset = rotate(offset, up, -dx * 0.01);
    const right = unit(cross(up, offset));
    const turned = rotate(offset, right, dy * 0.01);
    // Never over the pole: the view stays off the up axis.
    if (Math.abs(dot(unit(turned), up)) < 0.995) offset = turned;
    c.position = add(c.look_at, offset);
  }

  function frameAxes() {
    const c = state.cam;
    const forward = unit(sub(c.look_at, c.position));
    const right = unit(cross(forward, c.up));
    return { forward, right, up: cross(right, forward), distance: len(sub(c.look_at, c.position)) };
  }

  function pan(dx, dy) {
    const c = state.cam, { right, up, distance } = frameAxes();
    const perPixel = 2 * distance * Math.tan((c.fov * Math.PI) / 360) / canvas.clientHeight;
    const move = add(mul(right, -dx * perPixel), mul(up, dy * perPixel));
    c.position = add(c.position, move);
    c.look_at = add(c.look_at, move);
  }

  function dolly(deltaY) {
    const c = state.cam;
    const offset = sub(c.position, c.look_at);
    const scaled = mul(offset, Math.exp(deltaY * 0.001));
    if (len(scaled) > 1e-3) {
      c.position = add(c.look_at, scaled);
      c.focus_distance = len(scaled);
    }
  }

  function fly(key) {
    const { forward, right, up, distance } = frameAxes();
    const step = 0.05 * distance;
    const along = { w: forward, s: mul(forward, -1), d: right, a: mul(right, -1),
                    e: up, q: mul(up, -1) }[key];
    const c = state.cam;
    c.position = add(c.position, mul(along, step));
    c.look_at = add(c.look_at, mul(along, step));
  }

  let drag = null, dragged = false, hovering = false;
  canvas.addEventListener("contextmenu", (ev) => ev.preventDefault());
  canvas.addEventListener("mousedown", (ev) => {
    drag = { x: ev.clientX, y: ev.clientY, pan: ev.button === 2 || ev.shiftKey, moved: false };
  });
  window.addEventListener("mousemove", async (ev) => {
    if (!drag) return;
    const dx = ev.clientX - drag.x, dy = ev.clientY - drag.y;
    if (!drag.moved && Math.hypot(dx, dy) < DRAG_PX) return;
    drag.moved = true;
    const mode = drag.pan;
    drag.x = ev.clientX; drag.y = ev.clientY;
    if (!(await begin())) return;
    if (mode) pan(dx, dy); else orbit(dx, dy);
    moved();
  });
  window.addEventListener("mouseup", () => {
    dragged = drag !== null && drag.moved;
    drag = null;
  });
  // A drag is not a click: picking (pick.js) does not pin on the release of a drag.
  window.addEventListener("click", (ev) => {
    if (dragged && ev.target === canvas) ev.stopImmediatePropagation();
    dragged = false;
  }, true);
  canvas.addEventListener("wheel", async (ev) => {
    ev.preventDefault();
    if (!(await begin())) return;
    dolly(ev.deltaY);
    moved();
  }, { passive: false });
  canvas.addEventListener("mouseenter", () => { hovering = true; });
  canvas.addEventListener("mouseleave", () => { hovering = false; });
  document.addEventListener("keydown", async (ev) => {
    if (ev.key === "Escape" && state.cam) { end(); show(""); return; }
    const key = ev.key.toLowerCase();
    if (!hovering || !"wasdqe".includes(key) || key.length !== 1 || ev.ctrlKey || ev.metaKey) return;
    if (!(await begin())) return;
    fly(key);
    moved();
  });

  saveButton.addEventListener("click", async () => {
    if (!state.cam) return;
    // The reload of the saved file shows the saved camera: the preview stays until its first
    // pass (which may arrive before the write's answer).
    const reload = state.reload;
    try {
      state.file = await window.rondoCamera.save(state.cam);
      undoButton.disabled = false;
      show("saved: the scene reloads");
      if (state.passReload > reload) end();
      else state.endAfter = reload;
    } catch (e) {
      show(`not saved (${e.status ?? "?"}): ${e.message}`);
      if (e.status === 409) {
        // Read the file's version again: a second click writes over the change on disk.
        state.file = await window.rondoCamera.load().catch(() => null);
        show("the scene file changed on disk since it was read: Save again to write over its camera");
      }
    }
  });
  undoButton.addEventListener("click", async () => {
    try {
      state.file = await window.rondoCamera.undo();
      end();
      show("undone: the scene reloads");
    } catch (e) {
      show(`not undone (${e.status ?? "?"}): ${e.message}`);
      if (e.status === 409) state.file = await window.rondoCamera.load().catch(() => null);
    }
  });
  resetButton.addEventListener("click", () => { end(); show(""); });

  // A reload may change the file's camera: it is read again when framing starts. After a save,
  // the first pass of a later reload ends the framing (its image is the saved view).
  document.addEventListener("rondo:event", (ev) => {
    const e = ev.detail;
    if (e.kind === "reload") {
      state.file = null;
      state.reload = Math.max(state.reload, e.reload);
    } else if (e.kind === "pass") {
      state.passReload = Math.max(state.passReload, e.reload);
      if (state.endAfter !== null && e.reload > state.endAfter) {
        end();
        show("");
      }
    }
  });

  return {
    active: () => state.cam !== null && state.image !== null,
    image: () => state.image,
    camera: () => (state.cam ? structuredClone(state.cam) : null),
    latencies,
    rendering,
  };
})();
