// Framing with the mouse in the live viewer, in a real browser (see harness.mjs): a drag shows
// previews of a new camera without touching the file, "Save camera" changes only the camera's
// bytes and the reload that follows equals a fresh render, Undo puts the file back, Escape
// drops the framing, and a page of another origin cannot write. Then the time from a mouse move
// to its preview drawn, on the Cornell box at 512×512.
//
//   node frame.test.mjs
//
// RONDO_FRAME_MOVES sets the number of timed moves (default 30). Every wait is bounded; any
// failure exits non-zero. The last line is "N passed, N failed". Times are reported, never
// asserted.

import fs from "node:fs";
import os from "node:os";
import path from "node:path";
import { WAIT, check, render, root, runSteps, startRondo, stats, stopRondo } from "./harness.mjs";

const MOVES = Number(process.env.RONDO_FRAME_MOVES) || 30;

// 64×64 at 4 spp: a lit wall behind a ball and a box, seen from (0, 0, −5).
const CAMERA = "Camera(position: (0, 0, -5), look_at: (0, 0, 0), fov: 40.0)";
const SCENE = `// framing test
Scene(
    settings: Settings(width: 64, height: 64, spp: 4, max_depth: 3),
    camera: ${CAMERA}, // the camera
    materials: {
        "wall": Light(emit: Constant((1.0, 0.9, 0.8)), intensity: 1.0, two_sided: true),
        "clay": Diffuse(albedo: Constant((0.5, 0.5, 0.5))),
        "wood": Diffuse(albedo: Constant((0.6, 0.4, 0.2))),
    },
    entities: [
        Entity(name: "wall", material: "wall", shape: Quad(a: (-3, -3, 5), b: (3, -3, 5), c: (3, 3, 5), d: (-3, 3, 5))),
        Entity(name: "ball", material: "clay", shape: Sphere(center: (-1, 0, 0), radius: 0.5)),
        Entity(name: "box", material: "wood", shape: Box(min: (0.5, -0.5, -0.5), max: (1.5, 0.5, 0.5))),
    ],
)
`;

const waitFor = (page, fn, arg) => page.waitForFunction(fn, arg, { timeout: WAIT });
const kind = (page) => page.evaluate(() => document.getElementById("canvas").dataset.kind);
const framed = (page) => page.evaluate(() => window.rondoFraming.camera());
const previews = (page) => page.evaluate(() => Number(document.body.dataset.previews || 0));
const digest = (page) => page.evaluate(() => {
  const c = document.getElementById("canvas");
  const d = c.getContext("2d").getImageData(0, 0, c.width, c.height).data;
  let h = 0;
  for (let i = 0; i < d.length; i++) h = (h * 31 + d[i]) | 0;
  return `${c.width}x${c.height}:${h}`;
});

// Holds the left button at the canvas's centre and moves `steps` times by (dx, dy).
async function drag(page, dx, dy, steps = 5, button = "left") {
  const box = await page.locator("#canvas").boundingBox();
  let x = box.x + box.width / 2, y = box.y + box.height / 2;
  await page.mouse.move(x, y);
  await page.mouse.down({ button });
  for (let i = 0; i < steps; i++) {
    x += dx; y += dy;
    await page.mouse.move(x, y);
  }
  await page.mouse.up({ button });
}

// The first and last byte offsets where `a` and `b` differ, in `a`: [start, endA, endB).
function diffSpan(a, b) {
  let start = 0;
  while (start < a.length && start < b.length && a[start] === b[start]) start++;
  let end = 0;
  while (end < a.length - start && end < b.length - start
         && a[a.length - 1 - end] === b[b.length - 1 - end]) end++;
  return [start, a.length - end, b.length - end];
}

// Polls `GET route` until `ok(response)`; resolves to the response's bytes.
async function pollImage(url, ok) {
  const deadline = Date.now() + WAIT;
  while (Date.now() < deadline) {
    const r = await fetch(new URL("/image.png", url));
    if (r.ok && ok(r)) return Buffer.from(await r.arrayBuffer());
    await new Promise((f) => setTimeout(f, 50));
  }
  throw new Error("no such image in time");
}

async function behaviour(context) {
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), "rondo-frame-"));
  const file = path.join(dir, "scene.ron");
  fs.writeFileSync(file, SCENE);
  const rondo = startRondo(file, ["--threads", "2"]);
  try {
    const url = await rondo.url;
    const page = await context.newPage();
    await page.goto(url);
    await waitFor(page, () => document.getElementById("canvas").dataset.samples === "4");
    const original = fs.readFileSync(file, "utf8");
    const before = await digest(page);

    // A drag orbits: previews of the new camera, the file untouched, no pick pinned.
    await drag(page, 12, 3);
    await waitFor(page, () => Number(document.body.dataset.previews) >= 1
      && document.getElementById("canvas").dataset.kind === "preview");
    const cam = await framed(page);
    check("a drag frames a new camera", cam && cam.position.join() !== "0,0,-5", JSON.stringify(cam));
    check("its preview is drawn, coarse then at half size", (await digest(page)).startsWith("16x16:")
      || (await digest(page)).startsWith("32x32:"), await digest(page));
    await waitFor(page, () => document.getElementById("canvas").width === 32
      && document.getElementById("canvas").dataset.samples === "16");
    check("once the camera rests the preview refines to half size at 16 spp", true);
    check("the preview shows another view", (await digest(page)) !== before);
    check("a drag writes no file", fs.readFileSync(file, "utf8") === original);
    const pinned = await page.evaluate(() => document.getElementById("pick")?.dataset.pinned);
    check("a drag does not pin a pick", pinned !== "true", String(pinned));

    // The wheel dollies away from the point looked at.
    const d0 = Math.hypot(...cam.position);
    const box = await page.locator("#canvas").boundingBox();
    await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
    await page.mouse.wheel(0, 200);
    await waitFor(page, (d) => {
      const c = window.rondoFraming.camera();
      return c && Math.hypot(...c.position) > d * 1.1;
    }, d0);
    check("the wheel dollies out", true);

    // Save camera: only the camera's bytes change; the reload equals a fresh render.
    const saved = await framed(page);
    const shownBefore = await previews(page);
    await page.click("text=Save camera");
    const deadline = Date.now() + WAIT;
    while (fs.readFileSync(file, "utf8") === original && Date.now() < deadline) {
      await new Promise((f) => setTimeout(f, 20));
    }
    const written = fs.readFileSync(file, "utf8");
    const [start, endOld] = diffSpan(original, written);
    const valueStart = original.indexOf(CAMERA), valueEnd = valueStart + CAMERA.length;
    check("Save camera changes only the camera's value", written !== original
      && start >= valueStart && endOld <= valueEnd, `changed [${start}, ${endOld}) of [${valueStart}, ${valueEnd})`);
    const read = await (await fetch(new URL("/camera.json", url))).json();
    const close = (a, b) => a.every((v, i) => Math.abs(v - b[i]) <= 1e-5 * Math.max(1, Math.abs(b[i])));
    check("the file holds the framed camera", close(read.camera.position, saved.position)
      && close(read.camera.look_at, saved.look_at), JSON.stringify([read.camera, saved]));
    await waitFor(page, () => document.getElementById("canvas").dataset.kind === "raw"
      && Number(document.getElementById("canvas").dataset.reload) >= 1);
    check("the reload's image replaces the preview", await previews(page) >= shownBefore);
    const shown = await pollImage(url, (r) => Number(r.headers.get("x-rondo-reload")) >= 1
      && r.headers.get("x-rondo-samples") === "4");
    const fresh = path.join(dir, "fresh.png");
    check("rondo render of the saved file ran", await render([file, "-o", fresh]) === 0);
    check("the image after the save is a fresh render of the file", shown.equals(fs.readFileSync(fresh)));

    // Undo writes the camera before the save back.
    await page.click("text=Undo");
    await waitFor(page, () => document.getElementById("framing").textContent.startsWith("undone"));
    const undone = await (await fetch(new URL("/camera.json", url))).json();
    check("Undo writes the camera back", close(undone.camera.position, [0, 0, -5])
      && close(undone.camera.look_at, [0, 0, 0]), JSON.stringify(undone.camera));
    const afterUndo = fs.readFileSync(file, "utf8");
    check("Undo puts the camera's text back: the file as it was, byte for byte", afterUndo === original);

    // Escape drops the framing and shows the render again; the file stays.
    await waitFor(page, () => document.getElementById("canvas").dataset.kind === "raw");
    await drag(page, -10, 0);
    await waitFor(page, () => document.getElementById("canvas").dataset.kind === "preview");
    await page.keyboard.press("Escape");
    await waitFor(page, () => document.getElementById("canvas").dataset.kind === "raw");
    check("Escape ends the framing", (await framed(page)) === null);
    check("and writes nothing", fs.readFileSync(file, "utf8") === afterUndo);

    // A page of another origin cannot write: the token header makes a preflight the server
    // never grants, and a plain POST lacks the token.
    const other = await context.newPage();
    await other.goto("data:text/html,<title>elsewhere</title>");
    const token = await page.evaluate(() => document.querySelector('meta[name="rondo-token"]').content);
    const attempts = await other.evaluate(async ([url, token, body]) => {
      const out = [];
      try {
        const r = await fetch(new URL("/camera", url), { method: "POST", body,
          headers: { "Content-Type": "application/json", "X-Rondo-Token": token } });
        out.push(`answered ${r.status}`);
      } catch (e) { out.push("blocked"); }
      try {
        await fetch(new URL("/camera", url), { method: "POST", mode: "no-cors", body });
        out.push("sent");
      } catch (e) { out.push("blocked"); }
      return out;
    }, [url, token, JSON.stringify({ base: undone.base, ...undone.camera, fov: 20 })]);
    check("a cross-origin write with the token is blocked by the browser", attempts[0] === "blocked", attempts.join());
    check("no cross-origin write reaches the file", fs.readFileSync(file, "utf8") === afterUndo);
    await other.close();
    await page.close();
  } finally {
    await stopRondo(rondo.child);
    fs.rmSync(dir, { recursive: true, force: true });
  }
}

// Mouse move → preview drawn, on the Cornell box at 512×512 (previews 128×128 at 1 spp), as the
// page measures it (performance.now()): MOVES moves of a held drag, each waiting for its
// preview; then a continuous drag of a move every 16 ms for 2 s, counting previews drawn.
async function latency(context) {
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), "rondo-frame-latency-"));
  const file = path.join(dir, "cornell.ron");
  fs.writeFileSync(file, fs.readFileSync(path.join(root, "scenes/cornell.ron"), "utf8"));
  const rondo = startRondo(file, ["--spp", "16"]);
  try {
    const url = await rondo.url;
    const page = await context.newPage();
    await page.goto(url);
    await waitFor(page, () => document.getElementById("canvas").dataset.samples === "16");
    const box = await page.locator("#canvas").boundingBox();
    let x = box.x + box.width / 2, y = box.y + box.height / 2;
    await page.mouse.move(x, y);
    await page.mouse.down();
    for (let k = 0; k < MOVES; k++) {
      const n = await page.evaluate(() => window.rondoFraming.latencies.length);
      x += k % 2 ? -6 : 6;
      await page.mouse.move(x, y);
      await waitFor(page, (n) => window.rondoFraming.latencies.length > n, n);
    }
    const [timed, server] = await page.evaluate(() => [[...window.rondoFraming.latencies],
      [...window.rondoFraming.rendering]]);
    const drawnBefore = await previews(page);
    const start = Date.now();
    for (let k = 0; Date.now() - start < 2000; k++) {
      x += k % 2 ? -4 : 4;
      await page.mouse.move(x, y);
      await new Promise((f) => setTimeout(f, 16));
    }
    const drawn = (await previews(page)) - drawnBefore;
    await page.mouse.up();
    check(`timed ${timed.length} moves`, timed.length === MOVES);
    console.log("latency, mouse move -> preview drawn, Cornell box 512x512 (preview 128x128, 1 spp):");
    console.log(`  first move (may wait for the pass in flight)  ${timed[0].toFixed(1)} ms`);
    console.log(`  later moves  ${stats(timed.slice(1))}`);
    console.log(`    of which the server's render (request in to image out)  ${stats(server.slice(1))}`);
    console.log(`  continuous drag, a move every 16 ms for 2 s: ${drawn} previews drawn (${(drawn / 2).toFixed(1)}/s)`);
    await page.close();
  } finally {
    await stopRondo(rondo.child);
    fs.rmSync(dir, { recursive: true, force: true });
  }
}

await runSteps("the framing test ran to the end", [behaviour, latency]);
