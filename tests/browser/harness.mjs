// What the browser tests share: the rondo binary and a real headless chromium (Debian's
// /usr/bin/chromium driven by playwright-core), checks that count, and bounded waits.
//
// RONDO_BIN names the binary (default: ../../target/release/rondo), CHROMIUM the browser.

import { spawn } from "node:child_process";
import fs from "node:fs";
import os from "node:os";
import path from "node:path";
import { fileURLToPath } from "node:url";
import { chromium } from "playwright-core";

const here = path.dirname(fileURLToPath(import.meta.url));
/** The repository's root. */
export const root = path.resolve(here, "../..");
const bin = process.env.RONDO_BIN || path.join(root, "target/release/rondo");
const browserPath = process.env.CHROMIUM || "/usr/bin/chromium";
/** The bound of every wait, in ms. */
export const WAIT = 30_000;

/** Counts of the checks so far. */
export const results = { passed: 0, failed: 0 };

/** Records one check, printed as "ok   name" or "FAIL name: detail". */
export function check(name, ok, detail = "") {
  if (ok) { results.passed++; console.log(`ok   ${name}`); }
  else { results.failed++; console.log(`FAIL ${name}${detail ? `: ${detail}` : ""}`); }
}

/** `rondo watch SCENE --serve 127.0.0.1:0 ARGS`: the child, its viewer URL (a promise) and its stderr. */
export function startRondo(scenePath, args = []) {
  const child = spawn(bin, ["watch", scenePath, "--serve", "127.0.0.1:0", ...args], {
    stdio: ["ignore", "ignore", "pipe"],
  });
  const log = [];
  const url = new Promise((resolve, reject) => {
    const timer = setTimeout(() => reject(new Error(`no viewer line: ${log.join("")}`)), WAIT);
    child.stderr.setEncoding("utf8");
    child.stderr.on("data", (text) => {
      log.push(text);
      const m = /viewer: (http:\/\/\S+)/.exec(log.join(""));
      if (m) { clearTimeout(timer); resolve(m[1]); }
    });
    child.on("exit", (code) => reject(new Error(`rondo exited (${code}): ${log.join("")}`)));
    child.on("error", reject);
  });
  return { child, url, log };
}

/** `rondo render ARGS`, resolving to its exit code. */
export function render(args) {
  const child = spawn(bin, ["render", ...args], { stdio: ["ignore", "ignore", "inherit"] });
  return new Promise((resolve, reject) => {
    child.on("exit", (code) => resolve(code));
    child.on("error", reject);
  });
}

/** Stops a `rondo watch` (SIGINT, SIGKILL after WAIT); resolves to its exit code or signal. */
export async function stopRondo(child) {
  if (child.exitCode !== null) return child.exitCode;
  const exited = new Promise((resolve) => child.on("exit", (code, signal) => resolve(code ?? signal)));
  child.kill("SIGINT");
  const timer = setTimeout(() => child.kill("SIGKILL"), WAIT);
  const code = await exited;
  clearTimeout(timer);
  return code;
}

/** A headless chromium with a fresh profile: { context, profile }. */
export async function launch() {
  if (!fs.existsSync(browserPath)) throw new Error(`${browserPath} missing: apt-get install chromium`);
  const profile = fs.mkdtempSync(path.join(os.tmpdir(), "rondo-chromium-"));
  const context = await chromium.launchPersistentContext(profile, {
    executablePath: browserPath,
    headless: true,
    viewport: { width: 1000, height: 760 },
    args: ["--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
           "--disable-background-networking", "--disable-component-update", "--disable-sync"],
  });
  return { context, profile };
}

/** Median, min, max and count of `values` in ms, as one line. */
export function stats(values) {
  if (!values.length) return "none";
  const v = [...values].sort((a, b) => a - b);
  const at = (q) => v[Math.min(v.length - 1, Math.floor(q * v.length))];
  return `median ${at(0.5).toFixed(1)} ms (p90 ${at(0.9).toFixed(1)}, min ${v[0].toFixed(1)}, max ${v[v.length - 1].toFixed(1)}, n ${v.length})`;
}

/** Runs each step with one browser, then prints "N passed, N failed" and exits (non-zero on a
 * failure, or if nothing passed). A step that throws fails the check `ranToTheEnd`. */
export async function runSteps(ranToTheEnd, steps) {
  let context, profile;
  try {
    ({ context, profile } = await launch());
    for (const step of steps) await step(context);
  } catch (e) {
    check(ranToTheEnd, false, e.stack || String(e));
  } finally {
    if (context) await context.close();
    if (profile) fs.rmSync(profile, { recursive: true, force: true });
  }
  console.log(`${results.passed} passed, ${results.failed} failed`);
  process.exit(results.failed === 0 && results.passed > 0 ? 0 : 1);
}
