// The README's screenshot of the live viewer: the Cornell box in `rondo watch --serve`, the tall
// box picked (its panel pinned, its pixels outlined). Uses the browser tests' harness (Debian
// chromium, tests/browser's playwright-core: `npm ci` there once).
//
//   RONDO_BIN=target/release/rondo node scripts/viewer-screenshot.mjs [OUT.png]
//
// OUT defaults to docs/picking.png. The scene is a copy of scenes/cornell.ron in a temporary
// directory, so the panel names that copy.

import fs from "node:fs";
import os from "node:os";
import path from "node:path";
import { WAIT, launch, root, startRondo, stopRondo } from "../tests/browser/harness.mjs";

const out = path.resolve(process.argv[2] || path.join(root, "docs/picking.png"));
const dir = fs.mkdtempSync(path.join(os.tmpdir(), "rondo-screenshot-"));
const scene = path.join(dir, "cornell.ron");
fs.copyFileSync(path.join(root, "scenes/cornell.ron"), scene);
const rondo = startRondo(scene, ["--spp", "64"]);
const { context, profile } = await launch();
try {
  const page = await context.newPage();
  await page.goto(await rondo.url);
  const waitFor = (fn) => page.waitForFunction(fn, undefined, { timeout: 4 * WAIT });
  await waitFor(() => document.getElementById("canvas").dataset.samples === "64");
  await waitFor(() => window.rondoPick && window.rondoPick.ids !== null);
  // The tall box: left of the centre (the image's right is the scene's −x).
  const box = await page.locator("#canvas").boundingBox();
  await page.mouse.move(box.x + 0.36 * box.width, box.y + 0.5 * box.height);
  await page.mouse.down();
  await page.mouse.up();
  await waitFor(() => document.getElementById("pick").dataset.pinned === "true");
  await page.waitForTimeout(200);
  await page.screenshot({ path: out });
  const name = await page.evaluate(() => document.querySelector("#pick .name")?.textContent);
  console.log(`${out}: ${name} pinned`);
} finally {
  await context.close();
  fs.rmSync(profile, { recursive: true, force: true });
  await stopRondo(rondo.child);
  fs.rmSync(dir, { recursive: true, force: true });
}
