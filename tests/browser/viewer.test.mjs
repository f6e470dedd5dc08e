// The live viewer in a real browser: headless Debian chromium (/usr/bin/chromium, never a
// downloaded build) driven by playwright-core against `rondo watch --serve`.
//
//   node viewer.test.mjs                      # the checks, then the latency on the Cornell box
//   node viewer.test.mjs --screenshot out.png # also a screenshot of the page (docs/viewer.png)
//
// RONDO_BIN names the binary (default: ../../target/release/rondo), RONDO_LATENCY_EDITS the
// number of timed edits (default 5). Every wait is bounded; any failure, including a missing
// chromium, exits non-zero. The last line is "N passed, N failed". The denoised view needs Open
// Image Denoise (scripts/fetch-oidn.sh): without it its checks are skipped, unless
// RONDO_REQUIRE_OIDN=1 (as in CI), when they fail.

import fs from "node:fs";
import os from "node:os";
import path from "node:path";
import { WAIT, check, root, runSteps, startRondo, stopRondo } from "./harness.mjs";

const screenshot = (() => {
  const i = process.argv.indexOf("--screenshot");
  return i > 0 ? path.resolve(process.argv[i + 1]) : null;
})();
const LATENCY_EDITS = Number(process.env.RONDO_LATENCY_EDITS) || 5;

// A scene whose centre pixel sees only the `wall` emitter, so its colour is exactly the wall's
// emission (any sample count, preview included). Line 5 holds the wall's material. Pixel
// (32, 7) sees only the ball (albedo 0.5, unlit from the front: black). `settings` are extra
// settings.
function scene(wall, settings = "") {
  return `Scene(
    camera: Camera(position: (0, 0, -5), look_at: (0, 0, 0), fov: 40.0),
    settings: Settings(width: 64, height: 64, spp: 4, max_depth: 3${settings}),
    materials: {
        "wall": Light(emit: Constant(${wall}), intensity: 1.0, two_sided: true),
        "ball": Diffuse(albedo: Constant((0.5, 0.5, 0.5))),
    },
    entities: [
        Entity(name: "wall", material: "wall", shape: Quad(a: (-10, -10, 5), b: (10, -10, 5), c: (10, 10, 5), d: (-10, 10, 5))),
        Entity(name: "ball", material: "ball", shape: Sphere(center: (0, 1.4, 0), radius: 0.3)),
    ],
)
`;
}

// Saves like an editor that writes a temporary file and renames it over the original; resolves
// with the wall-clock time (ms since the epoch) at which the save completed.
function save(file, text) {
  const tmp = `${file}.tmp~`;
  fs.writeFileSync(tmp, text);
  fs.renameSync(tmp, file);
  return performance.timeOrigin + performance.now();
}

const pixelAt = (page, x, y) => page.evaluate(([x, y]) => {
  const c = document.getElementById("canvas");
  return Array.from(c.getContext("2d").getImageData(x, y, 1, 1).data.slice(0, 3));
}, [x, y]);

// Waits until pixel (x, y) of the canvas is `rgb`; on timeout, the error says what the page
// showed instead (pixel, reload drawn, A/B button, status line).
async function waitPixel(page, x, y, rgb) {
  try {
    await page.waitForFunction(([x, y, rgb]) => {
      const c = document.getElementById("canvas");
      if (c.hidden) return false;
      const d = c.getContext("2d").getImageData(x, y, 1, 1).data;
      return d[0] === rgb[0] && d[1] === rgb[1] && d[2] === rgb[2];
    }, [x, y, rgb], { timeout: WAIT, polling: 10 });
  } catch (e) {
    const seen = await page.evaluate(() => {
      const $ = (id) => document.getElementById(id);
      return `reload drawn ${$("canvas").dataset.reload}, A/B "${$("ab").textContent}", status "${$("status").textContent}"`;
    }).catch(() => "page state unknown");
    throw new Error(`pixel (${x}, ${y}) never became ${rgb}: it is ${await pixelAt(page, x, y).catch(() => "?")}; ${seen}\n${e.stack}`);
  }
}

// Picks an image in the raw / denoised / albedo / normal switch, as a click on its label.
async function choose(page, mode) {
  await page.click(`#modes label:has(input[value="${mode}"])`);
}

// What the footer says is shown ("denoised · 4 spp · high · 20 ms").
const shownText = (page) => page.textContent("#shown");

// Waits until the footer's "shown" text matches `pattern` (and the canvas draws that kind).
async function waitShown(page, pattern, kind) {
  try {
    await page.waitForFunction(([source, kind]) => new RegExp(source).test(document.getElementById("shown").textContent)
      && document.getElementById("canvas").dataset.kind === kind, [pattern.source, kind], { timeout: WAIT, polling: 10 });
  } catch (e) {
    throw new Error(`the page never said ${pattern} (canvas ${kind}): it says "${await shownText(page).catch(() => "?")}"\n${e.stack}`);
  }
}

// Waits until rondo's log matches `pattern`.
async function waitLog(rondo, pattern) {
  const end = Date.now() + WAIT;
  while (!pattern.test(rondo.log.join(""))) {
    if (Date.now() > end) throw new Error(`rondo never printed ${pattern}`);
    await new Promise((r) => setTimeout(r, 20));
  }
}

// A digest of the canvas's pixels, to tell images apart.
const canvasDigest = (page) => page.evaluate(() => {
  const c = document.getElementById("canvas");
  const d = c.getContext("2d").getImageData(0, 0, c.width, c.height).data;
  let h = 2166136261;
  for (let i = 0; i < d.length; i++) h = Math.imul(h ^ d[i], 16777619);
  return `${c.width}x${c.height}:${h >>> 0}`;
});

async function behaviour(context) {
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), "rondo-viewer-"));
  const file = path.join(dir, "scene.ron");
  fs.writeFileSync(file, scene("(1.0, 0.0, 0.0)"));
  const rondo = startRondo(file, ["--threads", "2"]);
  try {
    const url = await rondo.url;
    const page = await context.newPage();
    const loads = [];
    page.on("load", () => loads.push(Date.now()));
    await page.goto(url);
    // The raw image: these checks are of exact emitted values, which the denoiser only nears.
    await choose(page, "raw");
    await waitPixel(page, 32, 32, [255, 0, 0]);
    check("the first image appears (centre pixel red)", true);
    await page.evaluate(() => { window.__marker = "same page"; });

    save(file, scene("(0.0, 0.0, 1.0)"));
    await waitPixel(page, 32, 32, [0, 0, 255]);
    const marker = await page.evaluate(() => window.__marker);
    check("a save changes the image without reloading the page", marker === "same page" && loads.length === 1,
      `marker ${marker}, ${loads.length} loads`);

    const broken = scene("(0.0, 0.0, 1.0)").replace("intensity: 1.0", "intensity: 1.0 1.0");
    save(file, broken);
    await page.waitForSelector("#error", { state: "visible", timeout: WAIT });
    const where = await page.textContent("#error .where");
    const message = await page.textContent("#error .message");
    const source = await page.textContent("#error .source");
    // The place comes from the event's fields (file, line, column, field), not from the message:
    // the column is that of the stray value, counted here from the text saved.
    const line5 = broken.split("\n")[4];
    const column = line5.indexOf("1.0 1.0") + "1.0 ".length + 1;
    check("a broken save shows file:line:column and the field", where.startsWith(`${file}:5:${column} (materials.wall`), where);
    check("... and what is wrong, without the place", message.length > 0 && !message.includes("scene.ron"), message);
    const caret = source.split("\n")[1] ?? "";
    check("... with a caret under the column", caret.indexOf("^") - "     | ".length === column - 1, JSON.stringify(source));
    check("... and the offending source line", source.includes('"wall": Light(emit: Constant((0.0, 0.0, 1.0)), intensity: 1.0 1.0'), source);
    check("... over the last good image", String(await pixelAt(page, 32, 32)) === "0,0,255");

    save(file, scene("(0.0, 1.0, 0.0)"));
    await waitPixel(page, 32, 32, [0, 255, 0]);
    await page.waitForSelector("#error", { state: "hidden", timeout: WAIT });
    check("the next good save clears the error and shows its image", true);

    await page.waitForFunction(() => !document.getElementById("ab").disabled, null, { timeout: WAIT });
    await page.click("#ab");
    await waitPixel(page, 32, 32, [0, 0, 255]);
    check("A/B shows the image from before the last save", true);
    await page.click("#ab");
    await waitPixel(page, 32, 32, [0, 255, 0]);

    // Closed forms: 1.0 at -1 stop is 0.5 linear; sRGB(0.5) = 0.7354 -> 188; linear -> 128.
    await page.fill("#exposure", "-1");
    await page.dispatchEvent("#exposure", "input");
    check("exposure -1 stop in sRGB gives 188", String(await pixelAt(page, 32, 32)) === "0,188,0",
      String(await pixelAt(page, 32, 32)));
    await page.click("#srgb");
    check("... and 128 when displayed linear", String(await pixelAt(page, 32, 32)) === "0,128,0",
      String(await pixelAt(page, 32, 32)));

    const box = await page.locator("#canvas").boundingBox();
    await page.mouse.move(box.x + box.width * 32.5 / 64, box.y + box.height * 32.5 / 64);
    const inspected = await page.textContent("#pixel");
    check("the pixel inspector shows x, y and linear RGB", inspected.includes("x 32 y 32") && inspected.includes("0.0000 1.0000 0.0000"), inspected);

    await page.click("#zoom");
    const width = await page.evaluate(() => parseFloat(document.getElementById("canvas").style.width));
    check("1:1 zoom shows one screen pixel per pixel", Math.abs(width - 64) < 0.01, String(width));
    await page.close();
  } catch (e) {
    // What rondo printed says which reloads ran and what each changed.
    throw new Error(`${e.message}\nrondo's log:\n${rondo.log.join("")}`);
  } finally {
    const code = await stopRondo(rondo.child);
    check("rondo stops on SIGINT", code === 0, String(code));
    fs.rmSync(dir, { recursive: true, force: true });
  }
}

// The switch raw / denoised / albedo / normal on the scene of `behaviour`: denoised by default
// once the render has a denoised image, each image drawn (closed forms where there are some),
// a choice that sticks over saves, and raw with a word when the chosen image does not exist.
async function denoising(context) {
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), "rondo-viewer-denoise-"));
  const file = path.join(dir, "scene.ron");
  // Denoised passes are asked for by the scene, not by `--denoise`, which would outrank the
  // save below that turns the denoiser off.
  fs.writeFileSync(file, scene("(1.0, 0.0, 0.0)", ", denoise: true"));
  const rondo = startRondo(file, ["--threads", "2"]);
  try {
    const page = await context.newPage();
    await page.goto(await rondo.url);
    // The last pass (4 spp) denoised, or rondo's warning that there is no denoiser.
    const missing = waitLog(rondo, /denoiser \(Open Image Denoise\) is not available/).then(() => "missing");
    const denoised = waitShown(page, /^denoised · 4 spp · \w+ · /, "denoised").then(() => "denoised");
    missing.catch(() => {});
    denoised.catch(() => {});
    if (await Promise.race([missing, denoised]) === "missing") {
      if (process.env.RONDO_REQUIRE_OIDN === "1") {
        check("the viewer shows denoised images", false, "RONDO_REQUIRE_OIDN=1 but the denoiser is missing");
      } else {
        console.log("skip the denoised view: no Open Image Denoise (scripts/fetch-oidn.sh)");
      }
      await page.close();
      return;
    }
    check("a denoised pass is shown by default, and the footer says so", true, await shownText(page));
    const digests = { denoised: await canvasDigest(page) };

    // Albedo: the emitter's is its emission (1, 0, 0), the ball's 0.5 (sRGB 188).
    await choose(page, "albedo");
    await waitShown(page, /^albedo · 4 spp$/, "albedo");
    digests.albedo = await canvasDigest(page);
    const albedo = [await pixelAt(page, 32, 32), await pixelAt(page, 32, 7)];
    check("albedo: the wall's emission and the ball's 0.5", String(albedo) === "255,0,0,188,188,188", String(albedo));

    // The switch is a radio group: an arrow key moves to the next image. The wall faces the
    // camera: normal (0, 0, -1), drawn as n * 0.5 + 0.5 = (128, 128, 0).
    await page.focus('#modes input[value="albedo"]');
    await page.keyboard.press("ArrowRight");
    await waitShown(page, /^normal · 4 spp$/, "normal");
    digests.normal = await canvasDigest(page);
    check("normal (chosen with the keyboard): the wall's, as n * 0.5 + 0.5", String(await pixelAt(page, 32, 32)) === "128,128,0",
      String(await pixelAt(page, 32, 32)));

    await choose(page, "raw");
    await waitShown(page, /^raw · 4 spp$/, "raw");
    digests.raw = await canvasDigest(page);
    check("raw: the emission itself", String(await pixelAt(page, 32, 32)) === "255,0,0", String(await pixelAt(page, 32, 32)));
    check("the four images differ", new Set(Object.values(digests)).size === 4, JSON.stringify(digests));

    // The choice sticks: the next render is denoised, raw stays. (A save may start two
    // reloads, so their numbers are read from the page.)
    save(file, scene("(0.0, 0.0, 1.0)", ", denoise: true"));
    await waitPixel(page, 32, 32, [0, 0, 255]);
    await page.waitForFunction(() => images.denoised && images.current.samples === 4
      && images.denoised.reload === images.current.reload && images.denoised.samples === 4, null, { timeout: WAIT });
    check("a chosen raw image stays raw over a save", /^raw · 4 spp$/.test(await shownText(page)), await shownText(page));

    // Denoised chosen, then a save that turns the denoiser off: raw, and the footer says why.
    await choose(page, "denoised");
    await waitShown(page, /^denoised · 4 spp/, "denoised");
    save(file, scene("(0.0, 1.0, 0.0)", ", denoise: false"));
    await waitPixel(page, 32, 32, [0, 255, 0]);
    await waitShown(page, /^raw · 4 spp \(no denoised image of reload \d+ yet\)$/, "raw");
    const reload = await page.evaluate(() => document.getElementById("canvas").dataset.reload);
    check("with no denoised image of the render, raw is shown and the footer says so",
      (await shownText(page)).endsWith(`of reload ${reload} yet)`), `${await shownText(page)}, reload ${reload} drawn`);
    await page.close();
  } catch (e) {
    throw new Error(`${e.message}\nrondo's log:\n${rondo.log.join("")}`);
  } finally {
    await stopRondo(rondo.child);
    fs.rmSync(dir, { recursive: true, force: true });
  }
}

// Save -> first image of the edit, for material edits of the Cornell box at 512x512: on disk
// (rondo's own "first image … since save", with -o), on the event stream (the `pass` event
// reaching the page) and on the page (the canvas drawn).
async function latency(context) {
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), "rondo-viewer-latency-"));
  const file = path.join(dir, "scene.ron");
  const original = fs.readFileSync(path.join(root, "scenes/cornell.ron"), "utf8");
  const [red, blue] = ["(0.65, 0.05, 0.05)", "(0.05, 0.05, 0.65)"];
  if (!original.includes(red)) throw new Error("scenes/cornell.ron: no red material to edit");
  fs.writeFileSync(file, original);
  const rondo = startRondo(file, ["-o", path.join(dir, "out.png")]);
  const rows = [], stream = [], fetches = [], draws = [];
  try {
    const page = await context.newPage();
    await page.goto(await rondo.url);
    await page.waitForFunction(() => document.getElementById("canvas").dataset.reload === "0", null, { timeout: WAIT });
    await page.evaluate(() => {
      window.__seen = [];
      window.__events = [];
      const handle = window.onEvent;
      window.onEvent = (e) => {
        if (e.kind === "pass") window.__events.push({ reload: e.reload, at: performance.timeOrigin + performance.now() });
        handle(e);
      };
      const c = document.getElementById("canvas");
      new MutationObserver(() => window.__seen.push({ reload: Number(c.dataset.reload), at: performance.timeOrigin + performance.now() }))
        .observe(c, { attributes: true, attributeFilter: ["data-samples", "data-reload"] });
    });
    let text = original;
    for (let i = 1; i <= LATENCY_EDITS; i++) {
      text = text.includes(red) ? text.replace(red, blue) : text.replace(blue, red);
      // Let the previous render settle a moment so each edit starts from the same state.
      await new Promise((r) => setTimeout(r, 300));
      const saved = save(file, text);
      await page.waitForFunction((n) => window.__seen.some((s) => s.reload === n), i, { timeout: WAIT, polling: 5 });
      const [drawn, event] = await page.evaluate((n) => [window.__seen.find((s) => s.reload === n).at,
        window.__events.find((s) => s.reload === n).at], i);
      rows.push(drawn - saved);
      stream.push(event - saved);
      const [fetchMs, drawMs] = await page.evaluate(() => [document.body.dataset.fetchMs, document.body.dataset.drawMs]);
      fetches.push(Number(fetchMs));
      draws.push(Number(drawMs));
    }
    await page.close();
  } finally {
    await stopRondo(rondo.child);
    fs.rmSync(dir, { recursive: true, force: true });
  }
  const stats = (v) => {
    v.sort((a, b) => a - b);
    return `median ${v[v.length >> 1].toFixed(1)} ms (min ${v[0].toFixed(1)}, max ${v[v.length - 1].toFixed(1)})`;
  };
  const disk = rondo.log.join("").split("\n").filter((l) => l.startsWith("reload "))
    .map((l) => /first image ([\d.]+) (m?s)/.exec(l)).filter(Boolean)
    .map((m) => Number(m[1]) * (m[2] === "s" ? 1000 : 1));
  console.log(`latency, save -> first image, Cornell box 512x512, material edit, ${rows.length} edits:`);
  if (disk.length) console.log(`  on disk (rondo's log)     ${stats(disk)}`);
  console.log(`  on the stream (page)      ${stats(stream)}`);
  console.log(`  drawn on the page         ${stats(rows)}`);
  console.log(`    of which: fetch of /image.f32 ${stats(fetches)}, tone-map and draw ${stats(draws)}`);
  check("the page shows each edit", rows.length === LATENCY_EDITS);
}

async function takeScreenshot(context, out) {
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), "rondo-viewer-shot-"));
  const file = path.join(dir, "cornell.ron");
  fs.writeFileSync(file, fs.readFileSync(path.join(root, "scenes/cornell.ron"), "utf8"));
  const rondo = startRondo(file, ["--spp", "64"]);
  try {
    const page = await context.newPage();
    await page.goto(await rondo.url);
    await page.waitForFunction(() => /64\/64 spp · done/.test(document.getElementById("status").textContent), null, { timeout: 10 * WAIT });
    const box = await page.locator("#canvas").boundingBox();
    await page.mouse.move(box.x + box.width * 0.3, box.y + box.height * 0.6);
    await page.screenshot({ path: out });
    console.log(`wrote ${out}`);
    await page.close();
  } finally {
    await stopRondo(rondo.child);
    fs.rmSync(dir, { recursive: true, force: true });
  }
}

await runSteps("the browser test ran to the end", [
  behaviour, denoising, latency,
  ...(screenshot ? [(context) => takeScreenshot(context, screenshot)] : []),
]);
