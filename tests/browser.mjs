// Shared helpers of the end-to-end tests: the two Chromium configurations (WebGL2 and
// WebGPU), the static server, PNG pixels, the `stance` CLI.
import { chromium } from "playwright-core";
import assert from "node:assert/strict";
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

/** A laptop's window: what `tests/viewport.test.mjs` measures the figure in. */
export const DESKTOP_VIEWPORT = { width: 1280, height: 720 };

/** The window of the other tests: software GL draws each frame in proportion to its pixels
 * (the frame interval while pulling: 350 ms at 1280x720, 250 ms at 1000x600, one run each),
 * and what they check does not depend on the window's size. */
export async function launch(configuration) {
  const userDataDir = mkdtempSync(join(tmpdir(), "stance-chromium-"));
  return chromium.launchPersistentContext(userDataDir, {
    executablePath: CHROMIUM,
    headless: true,
    args: [...BASE_ARGS, ...configuration.args],
    viewport: configuration.viewport ?? { width: 1000, height: 600 },
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

/** The page's state (its test hook `window.stance.state_json()`), parsed. */
export async function pageState(page) {
  return JSON.parse(await page.evaluate(() => window.stance.state_json()));
}

/** A line on a state for a failure message: what waits on the solver, the view, the avatar. */
export function describeState(state) {
  if (!state) return "no state was read";
  const tasks = (state.tasks ?? []).map((t) => `${t.description} (level ${t.level}) residual `
    + `${Number(t.residual).toExponential(1)}${t.gave_way != null ? `, gave way ${t.gave_way}` : ""}`);
  return [`revision ${state.revision}`, `settled ${state.settled}`, `pulling ${state.pulling}`,
    `gave_way ${state.gave_way}`, `importing ${state.importing}`,
    `avatar ${state.avatar ? `${state.avatar.name} uploaded ${state.avatar.uploaded}` : "none"}`,
    `notice ${JSON.stringify(state.notice?.text ?? null)}`, `tasks: ${tasks.join("; ")}`].join(", ");
}

/**
 * Polls the page's state until `predicate(state, previous)` holds (`previous`: the state read
 * before it) and returns that state; after `timeout` ms, fails naming `what` and the last
 * state read. Nothing passes on a timeout.
 */
export async function waitForState(page, predicate, { timeout = 20_000, what = "the awaited state",
  interval = 50 } = {}) {
  const started = Date.now();
  let previous = null;
  let state = null;
  for (;;) {
    state = await pageState(page);
    if (predicate(state, previous)) return state;
    if (Date.now() - started > timeout) break;
    previous = state;
    await page.waitForTimeout(interval);
  }
  throw new Error(`${what}: not within ${timeout} ms. Last state: ${describeState(state)}`);
}

/**
 * Clicks the button the editor published under `name` (the state's `buttons`), waiting for it
 * to be published: a menu or window opened by the click before shows a frame later, and later
 * still when another test file shares the CPU. With `until` (a predicate on the state), waits
 * for the click's effect and returns that state. egui counts a press and a release as a click
 * only when the frames that read them are under 0.8 s apart; on this shared CPU a frame can
 * be longer, so a click that had no effect at all (`until` and `started` both false after
 * 5 s) is made once more, and said so.
 */
export async function clickButton(page, name, { until = null, started = until,
  timeout = 20_000 } = {}) {
  const { buttons } = await waitForState(page, (s) => Boolean(s.buttons?.[name]),
    { timeout: 10_000, what: `the ${name} button on screen` });
  const [x, y, width, height] = buttons[name];
  await page.mouse.click(x + width / 2, y + height / 2);
  if (!until) return null;
  const what = `the effect of a click on ${name}: ${until.toString()}`;
  try {
    const state = await waitForState(page, (s) => until(s) || started(s), { timeout: 5_000, what });
    if (until(state)) return state;
  } catch {
    console.log(`[click] ${name}: no effect within 5 s, clicked again`);
    await page.mouse.click(x + width / 2, y + height / 2);
  }
  return waitForState(page, until, { timeout, what });
}

/**
 * Presses `keys` (Playwright's notation, e.g. "Control+z") and waits for `until`. A press
 * with no effect at all within 5 s (`started` false; egui can drop input that arrives during
 * a long frame, as with clicks) is made once more, and logged; a press that had an effect is
 * never repeated, so a test still sees each effective press's outcome.
 */
export async function pressKeys(page, keys, { until, started = until, timeout = 20_000,
  what = `the effect of ${keys}` } = {}) {
  await page.keyboard.press(keys);
  try {
    const state = await waitForState(page, (s) => until(s) || started(s), { timeout: 5_000, what });
    if (until(state)) return state;
  } catch {
    console.log(`[keys] ${keys}: no effect within 5 s, pressed again (${what})`);
    await page.keyboard.press(keys);
  }
  return waitForState(page, until, { timeout, what });
}

const sameScreen = (a, b) => Object.entries(a.screen).every(([joint, [x, y]]) => b.screen[joint]
  && Math.abs(b.screen[joint][0] - x) < 0.01 && Math.abs(b.screen[joint][1] - y) < 0.01);

/** How long the joints must stay where they are on screen for the view to count as still:
 * longer than two frames of software GL in headless Chromium on a loaded 2-core machine
 * (550-650 ms a frame), so that a view still moving (egui's smooth zoom, a camera easing
 * toward the selected character) is not taken for a still one between two of its frames. */
const STILL_MS = 1_500;

/**
 * Waits until the solver has settled (the state's `settled`) and, with `still`, the view
 * too (the joints on screen where they were for `STILL_MS`); fails with a message naming
 * what did not settle otherwise.
 */
export function waitForSettled(page, { timeout = 20_000, still = false, what = "the posture settles" } = {}) {
  let since = 0;
  let first = null;
  return waitForState(page, (state) => {
    if (!state.settled) {
      first = null;
      return false;
    }
    if (!still) return true;
    if (!first || !sameScreen(first, state)) {
      first = state;
      since = Date.now();
      return false;
    }
    return Date.now() - since >= STILL_MS;
  }, { timeout, what: still ? `${what} and the view stops moving` : what });
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

const LINEAR = Array.from({ length: 256 }, (_, c) => {
  const v = c / 255;
  return v <= 0.04045 ? v / 12.92 : ((v + 0.055) / 1.055) ** 2.4;
});
/** An sRGB byte (0-255, not rounded) from a linear value, as the shaders' linear_to_srgb. */
function srgbByte(linear) {
  const c = Math.min(1, Math.max(0, linear));
  return 255 * (c <= 0.0031308 ? c * 12.92 : 1.055 * c ** (1 / 2.4) - 0.055);
}

/**
 * The mannequin's two materials (public/default-avatar.glb, written by `stance make-avatar`:
 * "skin" and "clothes"), linear base colours. tests/pixels.test.mjs checks them against the
 * file.
 */
export const FIGURE_MATERIALS = { skin: [0.78, 0.6, 0.49], clothes: [0.22, 0.3, 0.42] };

/**
 * Of a pixel, the mannequin's material and light that come closest to it under the skinned
 * shader's lighting (skinned.wgsl: linear = base * light + specular, light = sky 0.22-0.4 +
 * diffuse 0-0.75, specular 0-0.04): `{ material, light, specular, error }`, the error the
 * largest difference of a channel in sRGB levels.
 */
export function figureFit([r, g, b]) {
  const p = [LINEAR[r], LINEAR[g], LINEAR[b]];
  let best = null;
  for (const [material, base] of Object.entries(FIGURE_MATERIALS)) {
    const norm = base[0] ** 2 + base[1] ** 2 + base[2] ** 2;
    for (let specular = 0; specular <= 0.04 + 1e-9; specular += 0.005) {
      const light = base.reduce((sum, c, i) => sum + (p[i] - specular) * c, 0) / norm;
      const error = Math.max(...base.map((c, i) => Math.abs(srgbByte(c * light + specular) - [r, g, b][i])));
      if (!best || error < best.error) best = { material, light, specular, error };
    }
  }
  return best;
}

/**
 * A pixel of the mannequin's figure (the default avatar the editor draws, its saved image,
 * ?avatar=default-avatar.glb): its skin or its clothes lit as the shader lights them, the
 * light from 0.2 to 1.2 (measured on the editor's screenshot: 0.25 in the figure's shadows
 * to 1.1 where the light faces it), within 4 sRGB levels. Not the background, the floor and
 * its axes, the panels, the overlays (tests/pixels.test.mjs); not a textured avatar's pixel
 * either (`isAvatarPixel`). Edge pixels, blended with what is behind, do not pass.
 */
export function isFigureColour(rgb) {
  const key = (rgb[0] << 16) | (rgb[1] << 8) | rgb[2];
  let known = FIGURE_CACHE.get(key);
  if (known === undefined) {
    const fit = figureFit(rgb);
    known = fit.error <= 4 && fit.light >= 0.2 && fit.light <= 1.2;
    FIGURE_CACHE.set(key, known);
  }
  return known;
}
const FIGURE_CACHE = new Map();

// The floor's colours (floor.wgsl): its base, its lines (minor ones at 0.35), the red and
// blue axes, each faded into the background with distance, in sRGB levels. Not under a contact
// shadow (which darkens the base and lines near the feet): a darkened grey is also a textured
// avatar's grey in shade, and the checks that use this look away from the feet.
const FLOOR = {
  base: [0.055, 0.06, 0.07].map(srgbByte),
  line: [0.2, 0.21, 0.23].map(srgbByte),
  red: [0.55, 0.12, 0.12].map(srgbByte),
  blue: [0.12, 0.2, 0.6].map(srgbByte),
};
const BACKGROUND_LEVELS = [0.13, 0.145, 0.17].map((c) => c * 255);
const mix = (a, b, t) => a.map((v, i) => v + (b[i] - v) * t);
const FLOOR_SEGMENTS = [["base", "line"], ["base", "red"], ["base", "blue"]]
  .map(([a, b]) => [FLOOR[a], FLOOR[b]]);

/**
 * A pixel of the viewport's backdrop: the background, or the floor (its colours blended as
 * the edges of its lines and axes blend them with its base, faded into the background), within
 * 4 sRGB levels.
 */
export function isBackdrop(rgb) {
  const key = (rgb[0] << 16) | (rgb[1] << 8) | rgb[2];
  let known = BACKDROP_CACHE.get(key);
  if (known === undefined) {
    known = onTheBackdrop(rgb);
    BACKDROP_CACHE.set(key, known);
  }
  return known;
}
const BACKDROP_CACHE = new Map();

function onTheBackdrop(rgb) {
  for (const [a, b] of FLOOR_SEGMENTS) {
    for (let t = 0; t <= 1 + 1e-9; t += 0.05) {
      const near = mix(a, b, t);
      // The fade into the background that comes closest, 0 to 1.
      const away = near.map((v, i) => BACKGROUND_LEVELS[i] - v);
      const length = away.reduce((sum, v) => sum + v * v, 0);
      const fade = Math.min(1, Math.max(0, length > 0
        ? away.reduce((sum, v, i) => sum + v * (rgb[i] - near[i]), 0) / length : 0));
      const colour = mix(near, BACKGROUND_LEVELS, fade);
      if (Math.max(...colour.map((v, i) => Math.abs(v - rgb[i]))) <= 4) return true;
    }
  }
  return false;
}

/**
 * A textured avatar's pixel, inside the viewport: not its backdrop. Its textures have any
 * colours, so this passes the overlays too, and the panels: only ever ask inside the
 * viewport's rectangle, away from the overlays, and for a share of a patch (`shareNear`).
 */
export function isAvatarPixel(rgb) {
  return !isBackdrop(rgb);
}

/**
 * The joints of the body the pixel checks look at: head, trunk, limbs and feet (not the
 * fingers, a few pixels wide; the feet by their middle, the ankles being under the pins'
 * markers).
 */
export const BODY_JOINTS = ["skullbase", "vt1", "vl1", "sacroiliac", "l_shoulder", "r_shoulder",
  "l_elbow", "r_elbow", "l_radiocarpal", "r_radiocarpal", "l_hip", "r_hip", "l_knee",
  "r_knee", "l_tarsometatarsal_2", "r_tarsometatarsal_2"];

/**
 * The viewport's rectangle in whole pixels (the state's `viewport`, points = CSS pixels),
 * `inset` pixels in from each edge. With an avatar loaded the editor's rectangle runs about
 * 10 px under the tasks panel (702 px wide where 693 show): checks that must see only the
 * viewport's own pixels take it 16 px in.
 */
export function viewportRect(state, inset = 0) {
  const [x, y, width, height] = state.viewport;
  return { x: Math.ceil(x) + inset, y: Math.ceil(y) + inset, width: Math.floor(width) - 2 * inset,
    height: Math.floor(height) - 2 * inset };
}

const inside = (rect, x, y) => x >= rect.x && y >= rect.y && x < rect.x + rect.width
  && y < rect.y + rect.height;

/** The share of the pixels within `radius` (a square) of `point` that pass `test`. */
export function shareNear(image, [px, py], test, radius = 4) {
  let passed = 0;
  let all = 0;
  for (let y = Math.round(py) - radius; y <= Math.round(py) + radius; y += 1) {
    for (let x = Math.round(px) - radius; x <= Math.round(px) + radius; x += 1) {
      if (x < 0 || y < 0 || x >= image.width || y >= image.height) continue;
      all += 1;
      if (test(image.at(x, y))) passed += 1;
    }
  }
  return all ? passed / all : 0;
}

/**
 * Asserts that the figure is drawn at each of `joints` that the state's skeleton has, as the
 * state projects it: at least `share` of the pixels around each projected joint pass `test`.
 * Returns the shares (STANCE_PIXEL_LOG=1 prints them).
 */
export function assertDrawnAtJoints(image, state, { test = isFigureColour, joints = BODY_JOINTS,
  share = 0.5, radius = 4, label = "" } = {}) {
  const rect = viewportRect(state);
  const shares = {};
  const missing = [];
  // A skeleton mapped from an avatar may lack some (a shorter spine).
  const present = joints.filter((joint) => !state.joints || joint in state.joints);
  assert.ok(present.length >= 12, `${label}only ${present.join(", ")} of the joints checked`);
  for (const joint of present) {
    const point = state.screen[joint];
    assert.ok(point, `${label}the state projects ${joint} onto the screen`);
    assert.ok(inside(rect, point[0], point[1]), `${label}${joint} at ${point} is inside the viewport`);
    shares[joint] = shareNear(image, point, test, radius);
    if (process.env.STANCE_PIXEL_LOG) console.log(`[pixels] ${label}${joint} ${shares[joint].toFixed(2)}`);
    if (shares[joint] < share) missing.push(`${joint} at (${point.map(Math.round)}): ${shares[joint].toFixed(2)}`);
  }
  assert.deepEqual(missing, [], `${label}the figure is not drawn where these joints project `
    + `(share of figure pixels around each, ${share} wanted): ${missing.join("; ")}`);
  return shares;
}

/**
 * Points of the viewport away from the figure: left and right of the projected joints' box
 * by `margin` pixels, at the height of the head, the hips and the knees, where inside the
 * viewport (16 px in: `viewportRect`); and the viewport's two top corners.
 */
export function pointsAwayFromFigure(state, margin = 70) {
  const rect = viewportRect(state, 16);
  const points = Object.values(state.screen);
  const left = Math.min(...points.map((p) => p[0])) - margin;
  const right = Math.max(...points.map((p) => p[0])) + margin;
  const heights = ["skullbase", "sacroiliac", "l_knee"].map((joint) => state.screen[joint][1]);
  const away = [[rect.x + 6, rect.y + 6], [rect.x + rect.width - 6, rect.y + 6]];
  for (const y of heights) away.push([left, y], [right, y]);
  return away.filter(([x, y]) => inside(rect, x - 5, y - 5) && inside(rect, x + 5, y + 5));
}

/** Asserts that no more than a few pixels around each point pass `test` (the figure's colours). */
export function assertNotDrawnAt(image, points, {
  test = isFigureColour, radius = 4, label = "", minShare = 0.1,
} = {}) {
  // A tenth of the square: a body part drawn there covers far more; a pixel or two where the
  // floor's lines and an axis blend into a colour of the figure's do not count.
  const drawn = points.filter((point) => shareNear(image, point, test, radius) >= minShare);
  assert.deepEqual(drawn.map((p) => p.map(Math.round)), [],
    `${label}figure pixels where only the backdrop should be (around each point, ${radius} px)`);
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
