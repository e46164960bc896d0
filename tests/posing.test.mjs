// End to end: posing in the built site, as a user does it with the mouse (WebGL2).
// The page's test hook `window.stance.state_json()` exposes the document, the joint positions
// (world and screen) and the rectangles of the main buttons.
import { after, before, describe, test } from "node:test";
import assert from "node:assert/strict";
import { readFileSync } from "node:fs";
import {
  CONFIGURATIONS, assertDrawnAtJoints, clickButton, assertNotDrawnAt, decodePng, isFigureColour, launch,
  openEditor, pointsAwayFromFigure, saveArtifact, freshStoragePerTab, serve,
  waitForSettled, waitForState,
} from "./browser.mjs";

let site;
let context;
before(async () => {
  site = await serve();
  context = await launch(CONFIGURATIONS.webgl2);
  await freshStoragePerTab(context);
});
after(async () => {
  await context?.close();
  site.server.close();
});

async function state(page) {
  return JSON.parse(await page.evaluate(() => window.stance.state_json()));
}

// Catches a page that never settles: it fails naming the state it was left in (a
// waitForFunction's timeout said only "Timeout exceeded"), and never returns unsettled.
function settled(page, timeout = 20_000) {
  return waitForSettled(page, { timeout });
}

// The Table 1 example's click has taken effect: its seven tasks are in the document.
const TABLE1_SET_UP = { until: (s) => s.tasks.length === 7 };

const distance = (a, b) => Math.hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
const percentile = (values, p) => {
  const sorted = [...values].sort((a, b) => a - b);
  return sorted[Math.min(sorted.length - 1, Math.floor(p * sorted.length))];
};

async function freshEditor(url = site.url) {
  const page = await context.newPage();
  const opened = await openEditor(context, url, page);
  await settled(page);
  return opened;
}

describe("posing in the browser", () => {
  test("dragging the right forearm pulls the hand toward the pointer while the pinned feet hold", async () => {
    const { page, errors } = await freshEditor();
    const start = await state(page);
    const startImage = decodePng(await page.screenshot());
    const footBefore = start.joints.l_talocrural;
    const otherFootBefore = start.joints.r_talocrural;
    const handBefore = start.joints.r_radiocarpal;
    const [wx, wy] = start.screen.r_radiocarpal;
    const [ex, ey] = start.screen.r_elbow;
    const [px] = start.screen.sacroiliac;
    const grabX = ex + (wx - ex) * 0.6 + Math.sign(wx - px) * 3;
    const grabY = ey + (wy - ey) * 0.6;
    const goalX = grabX - 60;
    const goalY = grabY - 140;

    const frameMs = [];
    const solverMs = [];
    await page.mouse.move(grabX, grabY);
    await page.mouse.down();
    // 15 pointer moves and 10 held samples (each waits for a frame of software GL): enough
    // frames for the medians, half the time of 30 and 20.
    for (let step = 1; step <= 15; step += 1) {
      await page.mouse.move(grabX + (goalX - grabX) * step / 15, grabY + (goalY - grabY) * step / 15);
      const sample = await state(page);
      frameMs.push(sample.frame_ms);
      solverMs.push(sample.solver_ms);
    }
    const during = await state(page);
    assert.equal(during.pulling, true, "the drag grabbed the body");
    assert.equal(during.selected, "r_elbow", "the forearm was grabbed");
    // Hold still while the solver catches up, then let go.
    for (let i = 0; i < 10; i += 1) {
      await page.waitForTimeout(50);
      const sample = await state(page);
      frameMs.push(sample.frame_ms);
      solverMs.push(sample.solver_ms);
    }
    const held = await state(page);
    await page.mouse.up();
    await settled(page);
    saveArtifact("pull-webgl2.png", await page.screenshot());
    // Deselected (Escape), the skeleton and the elbow's rings over the figure are gone.
    await page.keyboard.press("Escape");
    const end = await waitForState(page, (s, previous) => s.settled && s.selected === null
      && previous?.selected === null, { what: "the forearm is deselected" });
    const endShot = await page.screenshot();
    saveArtifact("pull-deselected-webgl2.png", endShot);

    const [hx, hy] = held.screen.r_radiocarpal;
    const before = Math.hypot(wx - goalX, wy - goalY);
    const afterPull = Math.hypot(hx - goalX, hy - goalY);
    assert.ok(afterPull < before * 0.5,
      `the hand moved toward the pointer on screen: ${before.toFixed(0)} px -> ${afterPull.toFixed(0)} px`);
    assert.ok(end.joints.r_radiocarpal[1] > handBefore[1] + 0.1, "the hand rose");
    assert.ok(distance(end.joints.l_talocrural, footBefore) < 1e-3,
      `the pinned left foot moved ${distance(end.joints.l_talocrural, footBefore)} m`);
    assert.ok(distance(end.joints.r_talocrural, otherFootBefore) < 1e-3, "the right foot held");
    // Catches a drawn body that does not follow the solved posture: the hand's pixels moved
    // where its joint moved. Before the pull the figure is drawn at the hand and nothing
    // where the hand ends; after it, the figure is drawn at every joint as now projected,
    // the hand's new place included, and nowhere beside the body.
    const endImage = decodePng(endShot);
    const [hx1, hy1] = end.screen.r_radiocarpal;
    assert.ok(Math.hypot(hx1 - wx, hy1 - wy) > 60, "the hand moved well away on screen");
    assertDrawnAtJoints(startImage, start, { label: "before the pull: " });
    assertNotDrawnAt(startImage, [[hx1, hy1]], { label: "before the pull, where the hand ends: " });
    assertDrawnAtJoints(endImage, end, { label: "after the pull: " });
    assertNotDrawnAt(endImage, pointsAwayFromFigure(end), { label: "after the pull: " });
    console.log(`[pull] frame time while dragging (egui CPU): median ${percentile(frameMs, 0.5).toFixed(1)} ms, `
      + `p95 ${percentile(frameMs, 0.95).toFixed(1)} ms; solver median ${percentile(solverMs, 0.5).toFixed(2)} ms, `
      + `p95 ${percentile(solverMs, 0.95).toFixed(2)} ms`);
    assert.deepEqual(errors, [], `console errors: ${errors.join(" / ")}`);
    await page.close();
  });

  test("the Table 1 example set up from the tasks panel reaches its level-1 goals", async () => {
    const { page, errors } = await freshEditor();
    await clickButton(page, "table1", TABLE1_SET_UP);
    const result = await settled(page);
    const levelOne = result.tasks.filter((task) => task.level === 1);
    assert.equal(levelOne.length, 4, "left foot position and orientation, gaze, right hand");
    for (const task of levelOne) {
      assert.ok(task.residual < 1e-4, `${task.description}: residual ${task.residual}`);
      assert.equal(task.gave_way, null);
    }
    saveArtifact("table1-webgl2.png", await page.screenshot());
    assert.deepEqual(errors, [], `console errors: ${errors.join(" / ")}`);
    await page.close();
  });

  test("frame time while pulling the body with the Table 1 tasks active, one character and three (measured, not asserted)", async () => {
    const { page, errors } = await freshEditor();
    await clickButton(page, "table1", TABLE1_SET_UP);
    const one = await pullSampled(page);
    const levelOne = one.during.tasks.filter((task) => task.level === 1);
    for (const task of levelOne) {
      assert.ok(task.residual < 1e-3, `level 1 holds while pulling: ${task.description} ${task.residual}`);
    }
    const median = (values) => percentile(values, 0.5);
    const { intervals, cpuMs, solverMs } = one;
    console.log(`[frame] Table 1 + pull, headless Chromium WebGL2 (software GL): frame interval `
      + `median ${median(intervals).toFixed(1)} ms, p95 ${percentile(intervals, 0.95).toFixed(1)} ms `
      + `over ${intervals.length} frames; editor CPU per frame median ${median(cpuMs).toFixed(1)} ms, `
      + `p95 ${percentile(cpuMs, 0.95).toFixed(1)} ms; solver median ${median(solverMs).toFixed(2)} ms, `
      + `p95 ${percentile(solverMs, 0.95).toFixed(2)} ms (${(100 * median(solverMs) / median(intervals)).toFixed(0)}% of the frame interval)`);
    // Issue 31's target: two more LOA 2 characters beside it (Table 1 stays on the first),
    // the pull on the second; the same page, the same run.
    await clickButton(page, "scene_panel", { until: (s) => Boolean(s.buttons?.scene_add) });
    await clickButton(page, "scene_add", { until: (s) => s.characters?.length === 2 });
    await clickButton(page, "scene_add", { until: (s) => s.characters?.length === 3 });
    await clickButton(page, "character_1", { until: (s) => s.characters?.[1]?.selected === true });
    // The panel closed and the view zoomed out: the second character stands 0.8 m to the
    // right of the first, past the view's edge in this window.
    await clickButton(page, "scene_panel", { until: (s) => !s.buttons?.scene_add });
    const { viewport: [vx, vy, vw, vh] } = await state(page);
    await page.mouse.move(vx + vw / 2, vy + vh / 2);
    // Notches until the selected character's leg is in the view, the view still after each
    // (egui eases a wheel's scroll over frames that take up to a second on a loaded machine:
    // CI, 2026-11-29, two notches once left the knee past the edge).
    for (let notch = 0; notch < 6; notch += 1) {
      await page.mouse.wheel(0, 120);
      const view = await waitForSettled(page, { timeout: 30_000, still: true });
      if (inView(view, view.screen.l_knee) && inView(view, view.screen.l_talocrural)) break;
    }
    const three = await pullSampled(page);
    console.log(`[frame] three LOA 2 characters (Table 1 on the first, the pull on the second), headless `
      + `Chromium WebGL2: editor CPU per frame median ${median(three.cpuMs).toFixed(1)} ms against `
      + `${median(cpuMs).toFixed(1)} ms for one (${(median(three.cpuMs) / median(cpuMs)).toFixed(2)}x); `
      + `frame interval median ${median(three.intervals).toFixed(1)} ms against ${median(intervals).toFixed(1)} ms; `
      + `solver median ${median(three.solverMs).toFixed(2)} ms`);
    assert.deepEqual(errors, [], `console errors: ${errors.join(" / ")}`);
    await page.close();
  });

  test("a copied posture link opens the same posture and tasks; a tampered link says so", async () => {
    const { page } = await freshEditor();
    await clickButton(page, "table1", TABLE1_SET_UP);
    const original = await settled(page);
    await clickButton(page, "copy_link");
    await page.waitForFunction(() => window.location.hash.length > 1);
    const link = page.url();
    const fragment = link.slice(link.indexOf("#") + 1);
    console.log(`[link] Table 1 (the document, its sphere and bar): ${fragment.length} characters after '#', ${link.length} in all`);
    // Backs README.md's "about 400 characters for Table 1" (416 in all when written: the
    // document and its sphere and bar, a scene): a link that grows or shrinks by a fifth fails.
    assert.ok(link.length >= 330 && link.length <= 500, `${link.length} characters in all`);
    await page.close();

    const { page: opened, errors } = await freshEditor(link);
    const restored = await state(opened);
    assert.equal(restored.tasks.length, original.tasks.length);
    assert.deepEqual(restored.tasks.map((t) => [t.level, t.description]),
      original.tasks.map((t) => [t.level, t.description]));
    let worst = 0;
    for (const [joint, position] of Object.entries(original.joints)) {
      worst = Math.max(worst, distance(position, restored.joints[joint]));
    }
    // 0.005-degree steps over a chain of ~10 joints of ~1.7 m: well under a millimetre.
    assert.ok(worst < 5e-4, `a joint is ${worst} m from where the link's author had it`);
    assert.deepEqual(errors, [], `console errors: ${errors.join(" / ")}`);
    await opened.close();

    const middle = Math.floor(fragment.length / 2);
    const swapped = fragment[middle] === "A" ? "B" : "A";
    const tampered = `${site.url}#${fragment.slice(0, middle)}${swapped}${fragment.slice(middle + 1)}`;
    const { page: damaged } = await freshEditor(tampered);
    const shown = await state(damaged);
    assert.ok(shown.notice?.error, "a message says the link is damaged");
    assert.match(shown.notice.text, /could not be opened/);
    assert.equal(shown.tasks.length, 4, "the editor opened normally with its default tasks");
    // Still usable: the Table 1 button works.
    await clickButton(damaged, "table1", TABLE1_SET_UP);
    assert.equal((await settled(damaged)).tasks.length, 7);
    saveArtifact("tampered-link-webgl2.png", await damaged.screenshot());
    await damaged.close();
  });

  test("work survives a page reload (autosave)", async () => {
    const { page } = await freshEditor();
    await clickButton(page, "table1", TABLE1_SET_UP);
    const edited = await settled(page);
    await page.waitForTimeout(1500);
    await page.reload();
    await page.waitForFunction(() => document.body.dataset.firstFrameMs);
    const reloaded = await settled(page);
    assert.deepEqual(reloaded.document, edited.document);
    await page.close();
  });

  test("File > Save image downloads a PNG of the posture drawn by the page's GPU", async () => {
    const { page, errors } = await freshEditor();
    await clickButton(page, "file_menu", { until: (s) => Boolean(s.buttons.save_image_menu) });
    await clickButton(page, "save_image_menu", { until: (s) => Boolean(s.buttons.save_image) });
    const download = page.waitForEvent("download", { timeout: 30_000 });
    await clickButton(page, "save_image");
    // A click egui dropped (see clickButton) starts no download: made once more after 10 s.
    let file = await Promise.race([download, page.waitForTimeout(10_000).then(() => null)]);
    if (!file) {
      console.log("[click] save_image: no download within 10 s, clicked again");
      await clickButton(page, "save_image");
      file = await download;
    }
    assert.equal(file.suggestedFilename(), "stance-posture.png");
    const bytes = readFileSync(await file.path());
    saveArtifact("saved-image-webgl2.png", bytes);
    const image = decodePng(bytes);
    assert.deepEqual([image.width, image.height], [1280, 960], "the default size");
    // Catches an image that shows no figure or another view than the viewport's: the image
    // is seen through the viewport's camera (vertical field of view kept, width by aspect),
    // so each joint projected in the viewport lands at a known pixel of the image, where the
    // figure's colours must be; none beside the body, none in the top corners.
    const shown = await state(page);
    const [, , vw, vh] = shown.viewport;
    const toImage = ([sx, sy]) => {
      const ndcX = ((sx - shown.viewport[0]) / vw) * 2 - 1;
      const ndcY = ((sy - shown.viewport[1]) / vh) * 2 - 1;
      const scale = (vw / vh) / (image.width / image.height);
      return [((ndcX * scale + 1) / 2) * image.width, ((ndcY + 1) / 2) * image.height];
    };
    const inImage = {
      viewport: [0, 0, image.width, image.height],
      screen: Object.fromEntries(Object.entries(shown.screen).map(([j, p]) => [j, toImage(p)])),
    };
    assertDrawnAtJoints(image, inImage, { label: "in the saved image: " });
    assertNotDrawnAt(image, pointsAwayFromFigure(inImage, 100), { label: "in the saved image: " });
    let corners = 0;
    for (let y = 0; y < 80; y += 2) {
      for (let x = 0; x < image.width; x += 2) {
        if ((x < 80 || x > image.width - 80) && isFigureColour(image.at(x, y))) corners += 1;
      }
    }
    assert.equal(corners, 0, "the top corners show the background");
    assert.deepEqual(errors, [], `console errors: ${errors.join(" / ")}`);
    await page.close();
  });
});

/**
 * Pulls the selected character's left shin forward and up for 15 pointer moves (each waits
 * for a frame of software GL: enough frames for the figures, half the CI time of 30),
 * sampling the editor's CPU and the solver's time per frame and the frame intervals; the
 * state during the drag.
 */
/** Whether the screen point `[x, y]` lies inside the state's viewport. */
function inView(state, [x, y]) {
  const [vx, vy, vw, vh] = state.viewport;
  return x > vx && x < vx + vw && y > vy && y < vy + vh;
}

async function pullSampled(page) {
  // The view too: after a wheel zoom egui eases the scroll over several frames of software
  // GL, and a knee read before the zoom ends can lie outside the view (CI, 2026-11-28).
  const start = await waitForSettled(page, { timeout: 30_000, still: true });
  const [kx, ky] = start.screen.l_knee;
  assert.ok(inView(start, start.screen.l_knee), `the knee in the view: ${kx}, ${ky} (viewport ${start.viewport})`);
  const [ax, ay] = start.screen.l_talocrural;
  const grabX = kx + (ax - kx) * 0.3;
  const grabY = ky + (ay - ky) * 0.3;
  await page.evaluate(() => {
    window.__frameTimes = [];
    window.__sampling = true;
    const tick = (time) => {
      window.__frameTimes.push(time);
      if (window.__sampling) requestAnimationFrame(tick);
    };
    requestAnimationFrame(tick);
  });
  const cpuMs = [];
  const solverMs = [];
  await page.mouse.move(grabX, grabY);
  await page.mouse.down();
  for (let step = 1; step <= 15; step += 1) {
    await page.mouse.move(grabX + 40 * Math.sin(step / 2.5), grabY - 4 * step);
    const sample = await state(page);
    cpuMs.push(sample.frame_ms);
    solverMs.push(sample.solver_ms);
  }
  const during = await state(page);
  await page.mouse.up();
  const intervals = await page.evaluate(() => {
    window.__sampling = false;
    const t = window.__frameTimes;
    return t.slice(1).map((time, i) => time - t[i]);
  });
  assert.equal(during.pulling, true, "the drag grabbed the body");
  assert.ok(intervals.length > 10, `frames were drawn while dragging: ${intervals.length}`);
  return { during, intervals, cpuMs, solverMs };
}
