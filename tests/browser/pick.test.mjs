// Picking in the live viewer, in a real browser: headless Debian chromium (/usr/bin/chromium)
// driven by playwright-core against `rondo watch --serve --editor-url …`.
//
//   node pick.test.mjs                      # the checks, then the hover latency on the Cornell box
//   node pick.test.mjs --screenshot out.png # also a screenshot of a picked entity
//
// RONDO_BIN names the binary (default: ../../target/release/rondo), RONDO_PICK_HOVERS the
// number of timed hovers (default 40). Every wait is bounded; any failure exits non-zero. The
// last line is "N passed, N failed". Times are reported, never asserted.

import fs from "node:fs";
import os from "node:os";
import path from "node:path";
import { WAIT, check, root, runSteps, startRondo, stopRondo } from "./harness.mjs";

const screenshot = (() => {
  const i = process.argv.indexOf("--screenshot");
  return i > 0 ? path.resolve(process.argv[i + 1]) : null;
})();
const HOVERS = Number(process.env.RONDO_PICK_HOVERS) || 40;
const EDITOR = "vscode://file/{path}:{line}:{col}";
const SKY = 4294967295;

// 64×64, camera at (0, 0, −5) looking at the origin (+z), up +y, fov 40°: image x grows along
// forward × up = −x, 17.6 pixels per unit at z = 0. Pixel (49, 32) sees only the ball (x = −1),
// (14, 32) only the crate's box, (32, 32) only the wall (z = 5, ±2), (2, 2) the sky. The crate's
// box spans pixel columns 3..23 and rows 22..41 (its front face at z = −0.5, x from 0.5 to 1.5;
// its side at x = 0.5 reaching back to z = 0.5).
const SCENE = `Scene(
    camera: Camera(position: (0, 0, -5), look_at: (0, 0, 0), fov: 40.0),
    settings: Settings(width: 64, height: 64, spp: 4, max_depth: 3),
    materials: {
        "wall": Light(emit: Constant((1.0, 1.0, 1.0)), intensity: 1.0, two_sided: true),
        "clay": Diffuse(albedo: Constant((0.5, 0.5, 0.5))),
    },
    entities: [
        Entity(name: "wall", material: "wall", shape: Quad(a: (-2, -2, 5), b: (2, -2, 5), c: (2, 2, 5), d: (-2, 2, 5))),
        Entity(name: "ball", material: "clay", shape: Sphere(center: (-1, 0, 0), radius: 0.5)),
        Entity(name: "crate", prefab: "prefabs/crate.ron", transform: Transform(translate: (1, -0.5, 0))),
    ],
)
`;
const CRATE = `Prefab(
    materials: { "wood": Diffuse(albedo: Constant((0.6, 0.4, 0.2))) },
    entities: [
        Entity(name: "box", material: "wood", shape: Box(min: (-0.5, 0, -0.5), max: (0.5, 1, 0.5))),
    ],
)
`;

// "path:line:col" of the first `needle` after the first `after` in `file`, counted here.
function locate(file, after, needle) {
  const text = fs.readFileSync(file, "utf8");
  const at = text.indexOf(needle, text.indexOf(after));
  const before = text.slice(0, at);
  const line = before.split("\n").length;
  const col = [...before.slice(before.lastIndexOf("\n") + 1)].length + 1;
  return `${file}:${line}:${col}`;
}

// The ids the server hands out, read here: { width, height, ids }.
async function fetchIds(url) {
  const buffer = await (await fetch(new URL("/pick/ids.u32", url))).arrayBuffer();
  const head = new DataView(buffer, 8, 12);
  const width = head.getUint32(0, true), height = head.getUint32(4, true);
  return { width, height, ids: new Uint32Array(buffer, 20, width * height) };
}

// Moves the mouse over pixel (x, y) of the image (its centre) and waits for the panel of `id`.
async function hover(page, x, y, id) {
  const box = await page.locator("#canvas").boundingBox();
  const width = await page.evaluate(() => document.getElementById("canvas").width);
  const scale = box.width / width;
  await page.mouse.move(box.x + (x + 0.5) * scale, box.y + (y + 0.5) * scale);
  try {
    await page.waitForFunction((id) => document.getElementById("pick").dataset.id === id, id, { timeout: WAIT });
  } catch (e) {
    const seen = await page.evaluate(() => document.getElementById("pick").dataset.id).catch(() => "?");
    throw new Error(`hover over (${x}, ${y}) never showed id ${id}: the panel shows ${seen}\n${e.stack}`);
  }
}

// Waits until the page has an image and its ids; on timeout, the error says what it has.
async function waitPicks(page) {
  try {
    await page.waitForFunction(() => document.body.dataset.pickReload !== undefined
      && !document.getElementById("canvas").hidden, null, { timeout: WAIT });
  } catch (e) {
    const seen = await page.evaluate(() => JSON.stringify(document.body.dataset)).catch(() => "?");
    throw new Error(`the page never had an image and its ids: ${seen}\n${e.stack}`);
  }
}

const text = (page, selector) => page.textContent(selector);

async function behaviour(context) {
  const dir = fs.realpathSync(fs.mkdtempSync(path.join(os.tmpdir(), "rondo-pick-")));
  fs.mkdirSync(path.join(dir, "prefabs"));
  const file = path.join(dir, "scene.ron"), crate = path.join(dir, "prefabs/crate.ron");
  fs.writeFileSync(file, SCENE);
  fs.writeFileSync(crate, CRATE);
  const rondo = startRondo(file, ["--threads", "2", "--editor-url", EDITOR]);
  try {
    const url = await rondo.url;
    await context.grantPermissions(["clipboard-read", "clipboard-write"], { origin: new URL(url).origin });
    const page = await context.newPage();
    page.on("pageerror", (e) => console.log(`page error: ${e.message}`));
    await page.goto(url);
    await waitPicks(page);
    const { width, ids } = await fetchIds(url);
    const table = await (await fetch(new URL("/pick/table.json", url))).json();
    const idOf = (name) => table.entities.find((e) => e.name === name).id;
    check("the ids name the ball, the crate's box, the wall and the sky at known pixels",
      ids[32 * width + 49] === idOf("ball") && ids[32 * width + 14] === idOf("crate/box")
        && ids[32 * width + 32] === idOf("wall") && ids[2 * width + 2] === SKY,
      `${ids[32 * width + 49]} ${ids[32 * width + 14]} ${ids[32 * width + 32]} ${ids[2 * width + 2]}`);

    await hover(page, 49, 32, String(idOf("ball")));
    check("hover: the ball's name", (await text(page, "#pick .name")) === "ball", await text(page, "#pick .name"));
    check("... its place", (await text(page, "#pick .entity")) === locate(file, 'Entity(name: "ball"', '"ball"'),
      await text(page, "#pick .entity"));
    check("... its material and where it is defined",
      (await text(page, "#pick .material")) === "clay"
        && (await text(page, "#pick .material-at")) === locate(file, "materials", '"clay"'),
      `${await text(page, "#pick .material")} ${await text(page, "#pick .material-at")}`);
    check("... and no placement", (await page.locator("#pick .chain").count()) === 0);

    await hover(page, 14, 32, String(idOf("crate/box")));
    const boxAt = locate(crate, "entities", '"box"');
    check("hover: the prefab's box by its full name", (await text(page, "#pick .name")) === "crate/box",
      await text(page, "#pick .name"));
    check("... at its line in the prefab", (await text(page, "#pick .entity")) === boxAt, await text(page, "#pick .entity"));
    check("... its material in the prefab", (await text(page, "#pick .material")) === "wood"
      && (await text(page, "#pick .material-at")) === locate(crate, "materials", '"wood"'),
      `${await text(page, "#pick .material")} ${await text(page, "#pick .material-at")}`);
    check("... placed by \"crate\" at its line in the scene",
      (await text(page, "#pick .chain .placement")) === "crate"
        && (await text(page, "#pick .chain .placement-at")) === locate(file, 'Entity(name: "crate"', '"crate"'),
      await text(page, "#pick .chain"));
    const [l, c] = boxAt.slice(crate.length + 1).split(":");
    const href = await page.getAttribute("#pick a.entity", "href");
    check("--editor-url makes the place a link", href === `vscode://file/${crate}:${l}:${c}`, href);

    await hover(page, 2, 2, "sky");
    check("hover over the sky says so", (await text(page, "#pick .name")) === "sky (no entity)");

    // Click: pinned, outlined, copied.
    await hover(page, 14, 32, String(idOf("crate/box")));
    const canvasBox = await page.locator("#canvas").boundingBox();
    const scale = canvasBox.width / width;
    await page.mouse.click(canvasBox.x + 14.5 * scale, canvasBox.y + 32.5 * scale);
    await page.waitForFunction(() => document.getElementById("pick").dataset.pinned === "true"
      && !document.getElementById("pick-outline").hidden, null, { timeout: WAIT });
    await hover(page, 49, 32, String(idOf("crate/box")));
    check("a click pins the entity: hovering elsewhere keeps it", (await text(page, "#pick .name")) === "crate/box");
    const copied = await page.getAttribute("#pick", "data-copied");
    const clipboard = await page.evaluate(() => navigator.clipboard.readText()).catch((e) => `unreadable: ${e}`);
    check("... copies its place", copied === boxAt && clipboard === boxAt, `${copied} / ${clipboard}`);

    // The outline: exactly the box's pixels with a neighbour of another id (from the ids read
    // here), within the box's projection.
    const id = idOf("crate/box");
    const want = [];
    for (let y = 0; y < 64; y++) {
      for (let x = 0; x < 64; x++) {
        const i = y * 64 + x;
        if (ids[i] !== id) continue;
        const inner = x > 0 && y > 0 && x < 63 && y < 63
          && ids[i - 1] === id && ids[i + 1] === id && ids[i - 64] === id && ids[i + 64] === id;
        if (!inner) want.push(i);
      }
    }
    const got = await page.evaluate(() => {
      const o = document.getElementById("pick-outline");
      const d = o.getContext("2d").getImageData(0, 0, o.width, o.height).data;
      const out = [];
      for (let i = 0; i < o.width * o.height; i++) if (d[4 * i + 3] > 0) out.push(i);
      return out;
    });
    check("the outline is the entity's boundary pixels", JSON.stringify(got) === JSON.stringify(want),
      `${got.length} outlined, ${want.length} expected`);
    const xs = got.map((i) => i % 64), ys = got.map((i) => Math.floor(i / 64));
    const bounds = [Math.min(...xs), Math.max(...xs), Math.min(...ys), Math.max(...ys)];
    check("... around the box's projection (columns 3..23, rows 22..41)",
      Math.abs(bounds[0] - 3) <= 1 && Math.abs(bounds[1] - 23) <= 1 && Math.abs(bounds[2] - 22) <= 1
        && Math.abs(bounds[3] - 41) <= 1, String(bounds));
    const overlay = await page.locator("#pick-outline").boundingBox();
    const background = await page.evaluate(() => getComputedStyle(document.getElementById("pick-outline")).backgroundColor);
    check("... laid over the image, which shows through", Math.abs(overlay.x - canvasBox.x) < 1
      && Math.abs(overlay.width - canvasBox.width) < 1 && background === "rgba(0, 0, 0, 0)",
      JSON.stringify([overlay, canvasBox, background]));
    if (screenshot) { await page.screenshot({ path: screenshot }); console.log(`wrote ${screenshot}`); }

    await page.keyboard.press("Escape");
    await page.waitForFunction(() => document.getElementById("pick-outline").hidden, null, { timeout: WAIT });
    check("Escape unpins", true);
    await page.close();
  } catch (e) {
    throw new Error(`${e.message}\nrondo's log:\n${rondo.log.join("")}`);
  } finally {
    await stopRondo(rondo.child);
    fs.rmSync(dir, { recursive: true, force: true });
  }
}

// Hover → panel on the Cornell box at 512×512: the time from the mouse event to the panel
// updated, measured by the page (performance.now()), over HOVERS moves between pixels of
// different entities; the first hover of an entity fetches its entry, later ones are cached.
async function latency(context) {
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), "rondo-pick-latency-"));
  const file = path.join(dir, "cornell.ron");
  fs.writeFileSync(file, fs.readFileSync(path.join(root, "scenes/cornell.ron"), "utf8"));
  const rondo = startRondo(file, ["--spp", "16"]);
  const fetched = [], cached = [], frames = [];
  try {
    const url = await rondo.url;
    const page = await context.newPage();
    await page.goto(url);
    await waitPicks(page);
    const { width, height, ids } = await fetchIds(url);
    // One pixel of each id seen, in a fixed order, inside its entity (its 5×5 neighbourhood
    // of the same id), so that a mouse position rounded to a screen pixel stays on it.
    const inside = (i) => {
      const x = i % width, y = Math.floor(i / width);
      if (x < 2 || y < 2 || x >= width - 2 || y >= height - 2) return false;
      for (let dy = -2; dy <= 2; dy++) {
        for (let dx = -2; dx <= 2; dx++) if (ids[i + dy * width + dx] !== ids[i]) return false;
      }
      return true;
    };
    const first = new Map();
    for (let i = 0; i < ids.length; i += 7) if (!first.has(ids[i]) && inside(i)) first.set(ids[i], i);
    const spots = [...first.values()];
    let previous = null;
    for (let k = 0; k < HOVERS; k++) {
      const i = spots[k % spots.length];
      if (ids[i] === previous) continue;
      previous = ids[i];
      const before = Number(await page.evaluate(() => document.body.dataset.picks || 0));
      await hover(page, i % width, Math.floor(i / width), ids[i] === SKY ? "sky" : String(ids[i]));
      await page.waitForFunction((n) => Number(document.body.dataset.picks) > n, before, { timeout: WAIT })
        .catch((e) => { throw new Error(`no frame after the hover over id ${ids[i]} (${before} before)\n${e.stack}`); });
      const [ms, frameMs, wasCached] = await page.evaluate(() => [Number(document.body.dataset.pickMs),
        Number(document.body.dataset.pickFrameMs), document.body.dataset.pickCached === "true"]);
      (wasCached ? cached : fetched).push(ms);
      frames.push(frameMs);
    }
    await page.close();
    check(`hovered ${fetched.length + cached.length} times over ${spots.length} ids (${width}x${height})`,
      fetched.length + cached.length > 0);
  } finally {
    await stopRondo(rondo.child);
    fs.rmSync(dir, { recursive: true, force: true });
  }
  const stats = (v) => {
    if (!v.length) return "none";
    v.sort((a, b) => a - b);
    return `median ${v[v.length >> 1].toFixed(2)} ms (min ${v[0].toFixed(2)}, max ${v[v.length - 1].toFixed(2)}, n ${v.length})`;
  };
  console.log("latency, mouse move -> pick panel updated, Cornell box 512x512:");
  console.log(`  entry fetched  ${stats(fetched)}`);
  console.log(`  entry cached   ${stats(cached)}`);
  console.log(`  to the frame that paints it (all)  ${stats(frames)}`);
}

await runSteps("the picking test ran to the end", [behaviour, latency]);
