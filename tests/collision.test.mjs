// End to end: collision avoidance in the built site (WebGL2). The tasks panel's toggle turns
// the body's collision task on; a pull of the right forearm across the body (front view) then
// keeps the forearm outside the torso's capsules in every frame sampled and the hand slides
// round the front of the belly to the body's left side, where without it the forearm goes
// through the torso. The capsules come from the page's state (`collision.capsules`: each one's joint,
// ends and radius as posed); their overlap is measured here by sampling, apart from the
// solver's closest points.
import { after, before, describe, test } from "node:test";
import assert from "node:assert/strict";
import {
  CONFIGURATIONS, clickButton, freshStoragePerTab, launch, openEditor, pressKeys, saveArtifact,
  serve, waitForSettled,
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

const sub = (a, b) => a.map((x, i) => x - b[i]);
const dot = (a, b) => a.reduce((s, x, i) => s + x * b[i], 0);
const lerp = (a, b, t) => a.map((x, i) => x + (b[i] - x) * t);

/** The distance from `p` to the segment `a b` (its clamped projection). */
function toSegment(p, a, b) {
  const ab = sub(b, a);
  const len2 = dot(ab, ab);
  const t = len2 > 0 ? Math.min(1, Math.max(0, dot(sub(p, a), ab) / len2)) : 0;
  const d = sub(p, lerp(a, b, t));
  return Math.sqrt(dot(d, d));
}

/** How deep (m) the right forearm's capsule goes into the torso's (spine and chest) at `s`. */
function forearmInTorso(s) {
  const capsules = s.collision.capsules;
  const forearm = capsules.find((c) => c.joint === "r_elbow");
  const torso = capsules.filter((c) => c.joint.startsWith("vl") || c.joint.startsWith("vt"));
  let deepest = -Infinity;
  for (const t of torso) {
    let nearest = Infinity;
    for (let k = 0; k <= 400; k += 1) {
      nearest = Math.min(nearest, toSegment(lerp(forearm.a, forearm.b, k / 400), t.a, t.b));
    }
    deepest = Math.max(deepest, forearm.radius + t.radius - nearest);
  }
  return deepest;
}

/**
 * In the front view, grabs the right forearm and drags the pointer across the body to the
 * torso's left side,
 * sampling the state after each move and while held: the deepest the forearm went into the
 * torso, the solver's times (ms) and the last state.
 */
async function pullAcrossTheChest(page) {
  // The front view (key 1): the pull's plane, facing the camera through the grabbed point,
  // is then the body's frontal plane at the forearm's depth, through the torso.
  const before = await state(page);
  await pressKeys(page, "1", {
    until: (s) => Math.abs(s.screen.r_radiocarpal[0] - before.screen.r_radiocarpal[0]) > 1,
  });
  const start = await waitForSettled(page, { still: true, what: "the front view" });
  const [wx, wy] = start.screen.r_radiocarpal;
  const [ex, ey] = start.screen.r_elbow;
  const [px] = start.screen.sacroiliac;
  const grabX = ex + (wx - ex) * 0.6 + Math.sign(wx - px) * 3;
  const grabY = ey + (wy - ey) * 0.6;
  // Across the belly at the height of the lowest lumbar vertebra, to twice the hips' width
  // left of the left hip (the body faces the camera: its left is the screen's right).
  const goalX = start.screen.l_hip[0] + 2 * (start.screen.l_hip[0] - start.screen.r_hip[0]);
  const goalY = start.screen.vl5[1];
  let deepest = -Infinity;
  const solverMs = [];
  await page.mouse.move(grabX, grabY);
  await page.mouse.down();
  // 12 pointer moves and 4 held samples (each waits for a frame of software GL).
  for (let step = 1; step <= 12; step += 1) {
    await page.mouse.move(grabX + (goalX - grabX) * step / 12, grabY + (goalY - grabY) * step / 12);
    const sample = await state(page);
    deepest = Math.max(deepest, forearmInTorso(sample));
    solverMs.push(sample.solver_ms);
  }
  const during = await state(page);
  for (let i = 0; i < 4; i += 1) {
    await page.waitForTimeout(50);
    const sample = await state(page);
    deepest = Math.max(deepest, forearmInTorso(sample));
    solverMs.push(sample.solver_ms);
  }
  const held = await state(page);
  await page.mouse.up();
  return { start, during, held, deepest, solverMs, goal: [goalX, goalY] };
}

describe("collision avoidance in the browser", () => {
  test("a pull across the body keeps the forearm outside the torso with collision on", async () => {
    const { page, errors } = await openEditor(context, site.url, await context.newPage());
    await waitForSettled(page);
    const on = await clickButton(page, "collision", { until: (s) => s.collision?.on === true });
    assert.equal(on.collision.on, true, "the toggle turned collision on");
    assert.ok(on.tasks.some((t) => t.level === 2 && /collision/.test(t.description)),
      `a collision task at level 2: ${on.tasks.map((t) => t.description).join("; ")}`);
    await waitForSettled(page);
    const withTask = await pullAcrossTheChest(page);
    saveArtifact("collision-pull-webgl2.png", await page.screenshot());
    assert.equal(withTask.during.pulling, true, "the drag grabbed the body");
    // Round the front of the torso to the body's left side (+X in its frame), not stopped at
    // its right.
    const [wx, , wz] = withTask.held.joints.r_radiocarpal;
    assert.ok(wx > 0.15, `the wrist slid round to the body's left: x ${wx.toFixed(3)} m`);
    assert.ok(wz > withTask.held.joints.vl5[2], `in front of the belly: z ${wz.toFixed(3)} m`);
    await page.close();

    const { page: free } = await openEditor(context, site.url, await context.newPage());
    await waitForSettled(free);
    const without = await pullAcrossTheChest(free);
    saveArtifact("collision-pull-off-webgl2.png", await free.screenshot());
    await free.close();
    const at = (s, j) => s.joints[j].map((v) => v.toFixed(3)).join(", ");
    console.log(`[collision] the wrist ended at (${at(withTask.held, "r_radiocarpal")}) m with collision on, `
      + `(${at(without.held, "r_radiocarpal")}) without (started at (${at(withTask.start, "r_radiocarpal")}))`);

    const sorted = [...withTask.solverMs].sort((a, b) => a - b);
    const freeSorted = [...without.solverMs].sort((a, b) => a - b);
    console.log(`[collision] forearm into the torso at most ${(withTask.deepest * 1e3).toFixed(2)} mm with `
      + `collision on, ${(without.deepest * 1e3).toFixed(1)} mm without; solver per frame while pulling `
      + `median ${sorted[sorted.length >> 1].toFixed(2)} ms, max ${sorted[sorted.length - 1].toFixed(2)} ms `
      + `(without: median ${freeSorted[freeSorted.length >> 1].toFixed(2)}, max `
      + `${freeSorted[freeSorted.length - 1].toFixed(2)} ms); ${withTask.held.collision.contacts.length} `
      + "contacts held at the end");
    assert.ok(without.deepest > 0.01, `without collision the forearm goes in: ${without.deepest} m`);
    assert.ok(withTask.deepest < 0.001, `the forearm ${withTask.deepest} m into the torso`);
    assert.deepEqual(errors, [], `console errors: ${errors.join(" / ")}`);
  });
});
