"use strict";
// Picking in the viewer of `rondo watch --serve`: for the pixel under the mouse, a panel with the
// entity's full name, its material, the prefab and glTF placements that put it there and where
// each is written (file:line:col; links with `watch --editor-url`). A click pins the entity,
// outlines its pixels and copies its location; a second click on it, a click on the sky or
// Escape unpins. While the user frames a camera (frame.js), the ids describe the scene's own
// camera, not the preview shown: picking is off and nothing stays pinned.
//
// Data: `pick` events (relayed by the page as "rondo:event") say new ids exist; the ids come
// from /pick/ids.u32 ("RONDOIDS", u32 width, height, reload, then width*height u32 ids,
// little-endian; 4294967295 for the sky), one entry at a time from /pick/entity.json?id=N,
// kept until the next `pick` event. Text from files goes in with textContent only.
(() => {
  const SKY = 4294967295;
  const canvas = document.getElementById("canvas");
  const view = document.getElementById("view");

  const style = document.createElement("style");
  style.textContent = `
    #pick { position: fixed; right: 12px; bottom: 40px; max-width: min(70ch, 60vw);
            background: rgba(30, 30, 30, 0.94); border: 1px solid #555; border-radius: 4px;
            padding: 8px 10px; z-index: 2; }
    #pick[data-pinned="true"] { border-color: #ffcc00; }
    #pick .name { font-weight: bold; }
    #pick .dim { color: var(--dim); }
    #pick a { color: #8fb8ff; }
    #pick ol { margin: 2px 0 0; padding-left: 2.5ch; }
    #pick-outline { position: absolute; pointer-events: none; image-rendering: pixelated;
                    background: transparent; margin: 0; }`;
  document.head.append(style);

  const panel = document.createElement("aside");
  panel.id = "pick";
  panel.hidden = true;
  panel.setAttribute("aria-live", "polite");
  document.body.append(panel);

  const overlay = document.createElement("canvas");
  overlay.id = "pick-outline";
  overlay.hidden = true;
  view.append(overlay);

  // `ids`: the latest id buffer; `entries`: entry (or a pending fetch) per id of those ids.
  const state = { ids: null, entries: new Map(), hover: null, pinned: null, pinnedName: null,
                  seq: 0, fetching: false, wanted: false };

  async function fetchIds() {
    state.wanted = true;
    if (state.fetching) return;
    state.fetching = true;
    try {
      while (state.wanted) {
        state.wanted = false;
        const response = await fetch("/pick/ids.u32", { cache: "no-store" });
        if (!response.ok) continue;
        const buffer = await response.arrayBuffer();
        const magic = new TextDecoder().decode(new Uint8Array(buffer, 0, 8));
        if (magic !== "RONDOIDS") continue;
        const head = new DataView(buffer, 8, 12);
        const width = head.getUint32(0, true), height = head.getUint32(4, true);
        const reload = head.getUint32(8, true);
        // Entries hold for a reload's scene: only a new reload's ids make them stale.
        if (!state.ids || state.ids.reload !== reload) state.entries = new Map();
        state.ids = { width, height, reload, data: new Uint32Array(buffer, 20, width * height) };
        state.hover = null;
        document.body.dataset.pickReload = String(state.ids.reload);
        await repin();
      }
    } catch (e) {
      setTimeout(fetchIds, 200);
    } finally {
      state.fetching = false;
    }
  }

  // The entry of `id`, fetched once per id buffer.
  function entry(id) {
    let e = state.entries.get(id);
    if (!e) {
      e = fetch(`/pick/entity.json?id=${id}`, { cache: "no-store" })
        .then((r) => (r.ok ? r.json() : null))
        .catch(() => null);
      state.entries.set(id, e);
    }
    return e;
  }

  function framing() {
    return document.body.dataset.framing === "1";
  }

  // The id under a mouse event, or undefined off the image (or while framing).
  function idAt(ev) {
    const ids = state.ids;
    if (!ids || canvas.hidden || framing()) return undefined;
    const r = canvas.getBoundingClientRect();
    const x = Math.floor((ev.clientX - r.left) * ids.width / r.width);
    const y = Math.floor((ev.clientY - r.top) * ids.height / r.height);
    if (x < 0 || y < 0 || x >= ids.width || y >= ids.height) return undefined;
    return ids.data[y * ids.width + x];
  }

  // "path:line:col" of a place (the path alone where the line is unknown).
  function where(place) {
    return place.line == null ? place.path : `${place.path}:${place.line}:${place.column}`;
  }

  // A place as a link (with --editor-url) or as text.
  function placeNode(place, cls) {
    const node = document.createElement(place.url ? "a" : "span");
    node.className = cls;
    node.textContent = where(place);
    if (place.url) node.href = place.url;
    return node;
  }

  function line(label, ...nodes) {
    const div = document.createElement("div");
    const span = document.createElement("span");
    span.className = "dim";
    span.textContent = label;
    div.append(span, ...nodes);
    return div;
  }

  // What a click copies: the entity's own place if it has a line, else the innermost placement's.
  function copyText(e) {
    if (e.entity.line != null || e.chain.length === 0) return where(e.entity);
    return where(e.chain[e.chain.length - 1].at);
  }

  function render(id, e) {
    panel.replaceChildren();
    panel.hidden = false;
    panel.dataset.id = id === SKY ? "sky" : String(id);
    panel.dataset.pinned = String(state.pinned !== null);
    if (id === SKY || !e) {
      const name = document.createElement("div");
      name.className = "name";
      name.textContent = id === SKY ? "sky (no entity)" : `entity ${id} (unknown)`;
      panel.append(name);
      return;
    }
    const name = document.createElement("div");
    name.className = "name";
    name.textContent = e.name;
    panel.append(name, line("at ", placeNode(e.entity, "entity")));
    const material = document.createElement("span");
    material.className = "material";
    material.textContent = e.material;
    panel.append(line("material ", material, " at ", placeNode(e.material_at, "material-at")));
    if (e.chain.length) {
      const list = document.createElement("ol");
      list.className = "chain";
      for (const link of e.chain) {
        const item = document.createElement("li");
        const what = document.createElement("span");
        what.className = "placement";
        what.textContent = link.name;
        item.append(what, ` (${link.kind} ${link.file}) at `, placeNode(link.at, "placement-at"));
        list.append(item);
      }
      panel.append(line("placed by"), list);
    }
    if (state.pinned === id) {
      const note = document.createElement("div");
      note.className = "dim";
      note.textContent = `pinned · copied ${panel.dataset.copied ?? ""}`;
      panel.append(note);
    }
  }

  // Shows entity `id`; `start` is when the mouse moved (performance.now()), for the latency.
  async function show(id, start) {
    const seq = ++state.seq;
    const cached = state.entries.has(id);
    const e = id === SKY ? null : await entry(id);
    if (seq !== state.seq) return;
    render(id, e);
    // To the panel's DOM updated, and to the frame that paints it.
    const body = document.body.dataset;
    body.pickMs = (performance.now() - start).toFixed(2);
    body.pickCached = String(cached);
    requestAnimationFrame(() => {
      if (seq !== state.seq) return;
      body.pickFrameMs = (performance.now() - start).toFixed(2);
      body.picks = String((Number(body.picks) || 0) + 1);
    });
  }

  // The outline of the pinned entity's pixels: those with a 4-neighbour of another id or off
  // the image.
  function outline() {
    const ids = state.ids;
    if (!ids || state.pinned === null) { overlay.hidden = true; return; }
    const { width, height, data } = ids, id = state.pinned;
    overlay.width = width; overlay.height = height;
    const ctx = overlay.getContext("2d");
    const image = ctx.createImageData(width, height), px = image.data;
    let count = 0;
    for (let y = 0; y < height; y++) {
      for (let x = 0; x < width; x++) {
        const i = y * width + x;
        if (data[i] !== id) continue;
        const edge = x === 0 || y === 0 || x === width - 1 || y === height - 1
          || data[i - 1] !== id || data[i + 1] !== id || data[i - width] !== id || data[i + width] !== id;
        if (!edge) continue;
        px.set([255, 204, 0, 255], 4 * i);
        count++;
      }
    }
    ctx.putImageData(image, 0, 0);
    overlay.dataset.pixels = String(count);
    overlay.hidden = false;
    place();
  }

  // Lays the overlay over the image, however the page scales it.
  function place() {
    if (overlay.hidden) return;
    overlay.style.left = `${canvas.offsetLeft}px`;
    overlay.style.top = `${canvas.offsetTop}px`;
    overlay.style.width = canvas.style.width || `${canvas.width}px`;
    overlay.style.height = canvas.style.height || `${canvas.height}px`;
  }

  async function pin(id) {
    if (id === SKY || id === state.pinned) {
      unpin();
      return;
    }
    state.pinned = id;
    const e = await entry(id);
    if (state.pinned !== id) return;
    state.pinnedName = e ? e.name : null;
    if (e) {
      const text = copyText(e);
      panel.dataset.copied = text;
      if (navigator.clipboard) navigator.clipboard.writeText(text).catch(() => {});
    }
    render(id, e);
    outline();
  }

  function unpin() {
    state.pinned = null;
    state.hover = null;
    state.pinnedName = null;
    delete panel.dataset.copied;
    panel.dataset.pinned = "false";
    overlay.hidden = true;
  }

  // New ids: the pinned entity stays pinned if its id still names it.
  async function repin() {
    if (state.pinned === null) return;
    const id = state.pinned, e = await entry(id);
    if (!e || e.name !== state.pinnedName) { unpin(); return; }
    render(id, e);
    outline();
  }

  canvas.addEventListener("mousemove", (ev) => {
    // The event's own time: from the input, not from when the handler ran.
    const start = Math.min(ev.timeStamp, performance.now());
    const id = idAt(ev);
    if (id === undefined || state.pinned !== null || id === state.hover) return;
    state.hover = id;
    show(id, start);
  });
  canvas.addEventListener("mouseleave", () => {
    state.hover = null;
    if (state.pinned === null) panel.hidden = true;
  });
  canvas.addEventListener("click", (ev) => {
    const id = idAt(ev);
    if (id !== undefined) pin(id);
  });
  document.addEventListener("keydown", (ev) => {
    if (ev.key === "Escape" && state.pinned !== null) { unpin(); panel.hidden = true; }
  });
  document.addEventListener("rondo:event", (ev) => {
    if (ev.detail.kind === "pick") fetchIds();
  });
  new MutationObserver(() => {
    if (!framing()) return;
    unpin();
    panel.hidden = true;
  }).observe(document.body, { attributes: true, attributeFilter: ["data-framing"] });
  new MutationObserver(place).observe(canvas, { attributes: true, attributeFilter: ["style", "width", "height"] });
  window.addEventListener("resize", place);
  window.rondoPick = state;
  // The `pick` event may have come while this script loaded.
  fetchIds();
})();
