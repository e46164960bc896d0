// The three.js example of the stance-ik package (examples/three, served at
// /examples/three/): the avatar loads with three.js's GLTFLoader and meshopt decoder, its
// skin is mapped onto H-Anim, and pulling the right hand with the mouse moves the hand while
// the pinned feet stay within 1 mm. Prints the frame time while pulling next to three.js's
// own frame time without IK (`?ik=0`), in the same browser (software GL).
import { after, before, describe, test } from "node:test";
import assert from "node:assert/strict";
import { ARTIFACTS, CONFIGURATIONS, launch, serve } from "./browser.mjs";
import { mkdirSync } from "node:fs";

let served;
let context;

before(async () => {
  served = await serve();
  context = await launch(CONFIGURATIONS.webgl2);
});

after(async () => {
  await context?.close();
  served?.server.close();
});

async function open(query = "") {
  const page = await context.newPage();
  const errors = [];
  page.on("console", (m) => m.type() === "error" && errors.push(m.text()));
  page.on("pageerror", (e) => errors.push(String(e)));
  await page.goto(`${served.url}examples/three/${query}`);
  await page.waitForFunction(() => window.stanceExample?.error || window.stanceExample?.frames > 3, null, {
    timeout: 90_000,
  });
  const error = await page.evaluate(() => window.stanceExample.error);
  assert.equal(error, null, `the example failed: ${error}`);
  return { page, errors };
}

const distance = (a, b) => Math.hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);

/** Median of the last `n` samples of a per-frame series. */
async function median(page, series, n = 60) {
  return page.evaluate(
    ([series, n]) => {
      const s = window.stanceExample[series].slice(-n).sort((a, b) => a - b);
      return s[Math.floor(s.length / 2)];
    },
    [series, n],
  );
}

describe("three.js example", () => {
  test("pulling the hand moves it while the feet stay within 1 mm", async () => {
    const { page, errors } = await open();
    const before = await page.evaluate(() => structuredClone(window.stanceExample));
    assert.ok(before.joints >= 18, `${before.joints} H-Anim joints mapped`);
    const box = await page.locator("#view").boundingBox();
    const [sx, sy] = before.handScreen;
    const x = box.x + ((sx + 1) / 2) * box.width;
    const y = box.y + ((1 - sy) / 2) * box.height;
    await page.mouse.move(x, y);
    await page.mouse.down();
    const firstFrame = await page.evaluate(() => window.stanceExample.frames);
    for (let i = 1; i <= 30; i++) {
      await page.mouse.move(x + 3 * i, y - 4 * i);
      await page.waitForTimeout(30);
    }
    // The frames of the drag itself are timed.
    const dragFrames = (await page.evaluate(() => window.stanceExample.frames)) - firstFrame;
    const withIk = {
      solve: await median(page, "solveMs", dragFrames),
      render: await median(page, "renderMs", dragFrames),
    };
    // Hold still while the solver settles.
    await page.waitForTimeout(1000);
    const pulled = await page.evaluate(() => structuredClone(window.stanceExample));
    await page.mouse.up();
    mkdirSync(ARTIFACTS, { recursive: true });
    await page.screenshot({ path: `${ARTIFACTS}three-example-pulled.png` });
    const moved = distance(pulled.hand, before.hand);
    assert.ok(moved > 0.1, `the hand moved ${moved} m`);
    assert.ok(pulled.hand[1] > before.hand[1] + 0.05, "up, with the pointer");
    pulled.feet.forEach((foot, i) => {
      const drift = distance(foot, before.feet[i]);
      assert.ok(drift < 1e-3, `foot ${i} moved ${drift} m`);
    });
    assert.deepEqual(errors, []);
    await page.close();

    const plain = await open("?ik=0");
    await plain.page.waitForTimeout(1500);
    const render = await median(plain.page, "renderMs");
    await plain.page.close();
    const line =
      `three.js example (software GL): IK ${withIk.solve.toFixed(2)} ms + render ` +
      `${withIk.render.toFixed(2)} ms per frame while pulling (median of ${dragFrames} frames); ` +
      `three.js alone ${render.toFixed(2)} ms`;
    console.log(line);
  });
});
