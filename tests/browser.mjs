// Shared helpers of the end-to-end tests: the two Chromium configurations (WebGL2 and
// WebGPU), the static server, PNG pixels, the `stance` CLI.
import { chromium } from "playwright-core";
import { execFileSync } from "node:child_process";
import { mkdtempSync, mkdirSync, writeFileSync } from "node:fs";
import { tmpdir } from "node:os";
import { join } from "node:path";
import { PNG } from "pngjs";
import { startServer } from "../scripts/serve.mjs";

const ROOT = new URL("..", import.meta.url).pathname;

/** The `stance` CLI: `$STANCE_BIN`, else the debug build, built when it is missing or old. */
export function stanceBinary() {
  if (process.env.STANCE_BIN) return process.env.STANCE_BIN;
  execFileSync("cargo", ["build", "--quiet", "-p", "stance_cli", "--bin", "stance"], {
    cwd: ROOT,
    stdio: "inherit",
  });
  return join(process.env.CARGO_TARGET_DIR ?? join(ROOT, "target"), "debug", "stance");
}

export const CHROMIUM = process.env.CHROMIUM_PATH ?? "/usr/bin/chromium";
export const ARTIFACTS = new URL("../artifacts/", import.meta.url).pathname;

const BASE_ARGS = [
  "--no-sandbox", "--disable-background-networking", "--disable-component-update",
  "--disable-sync", "--no-first-run", "--disable-quic", "--disable-dev-shm-usage",
];

/** The browser configurations: WebGL2 (ANGLE/SwiftShader) and WebGPU (SwiftShader Vulkan). */
export const CONFIGURATIONS = {
  webgl2: { backend: "WebGL2", args: [] },
  webgpu: {
    backend: "WebGPU",
    args: ["--enable-unsafe-webgpu", "--use-angle=vulkan", "--enable-features=Vulkan",
      "--use-vulkan=swiftshader"],
  },
};

export async function launch(configuration) {
  const userDataDir = mkdtempSync(join(tmpdir(), "stance-chromium-"));
  return chromium.launchPersistentContext(userDataDir, {
    executablePath: CHROMIUM,
    headless: true,
    args: [...BASE_ARGS, ...configuration.args],
    viewport: { width: 1280, height: 720 },
  });
}

/** Each new tab starts from empty storage (no autosave of another test); a reload in the same
 * tab keeps it. */
export async function freshStoragePerTab(context) {
  await context.addInitScript(() => {
    if (!window.sessionStorage.getItem("stance-test-tab")) {
      window.localStorage.clear();
      window.sessionStorage.setItem("stance-test-tab", "1");
    }
  });
}

export async function serve() {
  const server = await startServer(0);
  const { port } = server.address();
  return { server, url: `http://localhost:${port}/` };
}

/** Opens the editor and waits for its first rendered frame; collects console errors. */
export async function openEditor(context, url, existingPage = undefined) {
  const page = existingPage ?? context.pages()[0] ?? (await context.newPage());
  const errors = [];
  page.on("console", (message) => {
    if (message.type() === "error") errors.push(message.text());
  });
  page.on("pageerror", (error) => errors.push(String(error)));
  await page.goto(url);
  await page.waitForFunction(
    () => document.body.dataset.firstFrameMs || document.body.dataset.error,
    null, { timeout: 90_000 },
  );
  const error = await page.evaluate(() => document.body.dataset.error);
  if (error) throw new Error(`the editor showed its error screen: ${error}`);
  return { page, errors };
}

export function decodePng(buffer) {
  const png = PNG.sync.read(buffer);
  return {
    width: png.width,
    height: png.height,
    at(x, y) {
      const i = (Math.round(y) * png.width + Math.round(x)) * 4;
      return [png.data[i], png.data[i + 1], png.data[i + 2]];
    },
    data: png.data,
  };
}

/** The viewport's background (BACKGROUND_SRGB of stance_render), with a little tolerance. */
export function BACKGROUND(r, g, b) {
  return Math.abs(r - 33) <= 6 && Math.abs(g - 37) <= 6 && Math.abs(b - 43) <= 6;
}

/** A figure's pixel (the mannequin's figure or an avatar: skin, clothes, hair): neither the
 * background nor the grey floor grid. */
export function isFigureColour([r, g, b]) {
  const grey = Math.abs(r - g) < 12 && Math.abs(g - b) < 12;
  return !grey && !BACKGROUND(r, g, b);
}

export function saveArtifact(name, buffer) {
  mkdirSync(ARTIFACTS, { recursive: true });
  writeFileSync(join(ARTIFACTS, name), buffer);
}

/**
 * The page's main-thread tasks over 50 ms while `action` runs, from a Chromium trace: each as
 * `{ ms, commitMs }`, where `commitMs` is the compositor's share (`Commit`: in headless
 * Chromium without a GPU it reads the WebGL canvas back and waits for SwiftShader to finish
 * the frame, which a GPU-composited browser does not). `ms - commitMs` is what the page's own
 * script and layout held the thread.
 */
export async function longTasks(page, action) {
  const cdp = await page.context().newCDPSession(page);
  const events = [];
  cdp.on("Tracing.dataCollected", ({ value }) => events.push(...value));
  const complete = new Promise((resolve) => cdp.on("Tracing.tracingComplete", resolve));
  await cdp.send("Tracing.start", {
    traceConfig: { includedCategories: ["toplevel", "blink", "gpu", "disabled-by-default-devtools.timeline"] },
    transferMode: "ReportEvents",
  });
  let result;
  try {
    result = await action();
  } finally {
    await cdp.send("Tracing.end");
    await complete;
    await cdp.detach();
  }
  const main = new Set(events
    .filter((e) => e.ph === "M" && e.name === "thread_name" && e.args?.name === "CrRendererMain")
    .map((e) => `${e.pid}:${e.tid}`));
  const onMain = events.filter((e) => e.ph === "X" && main.has(`${e.pid}:${e.tid}`));
  const tasks = onMain
    .filter((e) => e.name === "ThreadControllerImpl::RunTask" && e.dur > 50_000)
    .map((task) => {
      const inside = (e) => e.pid === task.pid && e.tid === task.tid && e.ts >= task.ts
        && e.ts + (e.dur ?? 0) <= task.ts + task.dur;
      const commit = onMain.filter((e) => e.name === "Commit" && inside(e))
        .reduce((sum, e) => sum + e.dur, 0);
      return { ms: task.dur / 1000, commitMs: commit / 1000 };
    });
  return { result, tasks };
}

/** A line describing `longTasks`' result. */
export function describeLongTasks(tasks) {
  const own = tasks.map((t) => t.ms - t.commitMs);
  const longest = tasks.reduce((a, t) => (t.ms > (a?.ms ?? 0) ? t : a), null);
  return `${tasks.length} main-thread tasks over 50 ms, longest ${Math.round(longest?.ms ?? 0)} ms `
    + `(${Math.round(longest?.commitMs ?? 0)} ms of it the compositor's canvas readback); `
    + `longest without the readback ${Math.round(Math.max(0, ...own))} ms`;
}
