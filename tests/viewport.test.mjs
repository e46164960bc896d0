// End to end: the built site in real headless Chromium, once per graphics configuration.
import { after, before, describe, test } from "node:test";
import assert from "node:assert/strict";
import {
  CONFIGURATIONS, DESKTOP_VIEWPORT, assertDrawnAtJoints, assertNotDrawnAt, decodePng, isFigureColour, launch,
  openEditor, pointsAwayFromFigure, saveArtifact, serve, viewportRect, waitForSettled,
} from "./browser.mjs";

let site;
before(async () => { site = await serve(); });
after(() => site.server.close());

function bodyPixelsIn(image, region) {
  let count = 0;
  for (let y = region.y; y < region.y + region.height; y += 2) {
    for (let x = region.x; x < region.x + region.width; x += 2) {
      if (isFigureColour(image.at(x, y))) count += 1;
    }
  }
  return count;
}

for (const [name, configuration] of Object.entries(CONFIGURATIONS)) {
  describe(`editor on ${configuration.backend}`, () => {
    let context;
    let editor;
    before(async () => {
      // The figure's pixel counts below are for a laptop's window.
      context = await launch({ ...configuration, viewport: DESKTOP_VIEWPORT });
      editor = await openEditor(context, site.url);
    });
    after(async () => { await context?.close(); });

    test("loads without console errors and reports its backend", async () => {
      const { page, errors } = editor;
      const backend = await page.evaluate(() => document.body.dataset.backend);
      const adapter = await page.evaluate(() => document.body.dataset.adapter);
      const firstFrameMs = Number(await page.evaluate(() => document.body.dataset.firstFrameMs));
      console.log(`[${name}] backend ${backend}, adapter "${adapter}", first frame ${firstFrameMs} ms after navigation`);
      assert.equal(backend, configuration.backend);
      assert.ok(adapter.length > 0);
      assert.ok(await page.locator("#loading").isHidden(), "the loading indicator is gone");
      assert.deepEqual(errors, []);
    });

    test("the viewport shows the standing body as a skinned figure, and an orbit drag turns the view", async () => {
      const { page } = editor;
      const state = await waitForSettled(page, { still: true });
      const before = await page.screenshot();
      saveArtifact(`viewport-${name}.png`, before);
      const image = decodePng(before);
      // The viewport's rectangle, as the editor reports it (between the panels and bars):
      // every pixel check below looks inside it.
      const viewport = viewportRect(state);
      assert.equal(state.figure, true, "the mannequin is drawn as its skinned figure");
      // Catches a figure drawn elsewhere than its posture puts it (a wrong camera or
      // skinning palette), or not at all: the figure's colours at each projected joint.
      assertDrawnAtJoints(image, state, { label: `${name}: ` });
      // Catches a figure drawn everywhere (or a colour test that passes the floor): none of
      // its colours beside the body.
      assertNotDrawnAt(image, pointsAwayFromFigure(state), { label: `${name}: ` });
      // The test of the test: no pixel of the panels, the menu and the status bar passes as
      // the figure's colour.
      let outside = 0;
      for (let y = 0; y < image.height; y += 1) {
        for (let x = 0; x < image.width; x += 1) {
          const inViewport = x >= viewport.x && x < viewport.x + viewport.width
            && y >= viewport.y && y < viewport.y + viewport.height;
          if (!inViewport && isFigureColour(image.at(x, y))) outside += 1;
        }
      }
      assert.equal(outside, 0, "panel pixels pass as the figure's colour");
      const bodyBefore = bodyPixelsIn(image, viewport);
      // About 9,400 counted (every second row and column) front on, 5,200 from the side.
      assert.ok(bodyBefore > 6000, `only ${bodyBefore} figure pixels in the viewport`);

      // Start the drag on the background (not on the body, which would pull it).
      const startX = viewport.x + viewport.width * 0.9;
      const startY = viewport.y + viewport.height * 0.15;
      await page.mouse.move(startX, startY);
      await page.mouse.down();
      for (let step = 1; step <= 10; step += 1) {
        await page.mouse.move(startX - step * 15, startY + step * 4);
      }
      await page.mouse.up();
      const orbited = await waitForSettled(page, { still: true });
      const turned = await page.screenshot();
      saveArtifact(`viewport-${name}-orbited.png`, turned);
      const after = decodePng(turned);
      // Catches an orbit that does not turn the view: the hands, far from the axis the view
      // turns about, moved on screen.
      for (const hand of ["l_radiocarpal", "r_radiocarpal"]) {
        const moved = Math.hypot(orbited.screen[hand][0] - state.screen[hand][0],
          orbited.screen[hand][1] - state.screen[hand][1]);
        assert.ok(moved > 10, `${hand} moved ${moved.toFixed(1)} px on screen`);
      }
      // Catches a picture that does not follow the camera: the figure is drawn where the
      // turned view projects the joints, and the viewport's pixels changed.
      assertDrawnAtJoints(after, orbited, { label: `${name}, orbited: ` });
      assertNotDrawnAt(after, pointsAwayFromFigure(orbited), { label: `${name}, orbited: ` });
      let differing = 0;
      for (let y = viewport.y; y < viewport.y + viewport.height; y += 1) {
        for (let x = viewport.x; x < viewport.x + viewport.width; x += 1) {
          const [r0, g0] = image.at(x, y);
          const [r1, g1] = after.at(x, y);
          if (Math.abs(r1 - r0) > 8 || Math.abs(g1 - g0) > 8) differing += 1;
        }
      }
      assert.ok(differing > 5000, `only ${differing} pixels of the viewport changed after the drag`);
      const bodyAfter = bodyPixelsIn(after, viewport);
      console.log(`[${name}] figure pixels in the viewport (every second row and column): ${bodyBefore}, orbited ${bodyAfter}`);
      assert.ok(bodyAfter > 3500, `the body is still in view: ${bodyAfter} figure pixels`);
    });
  });
}

describe("the site as served", () => {
  test("the wasm comes precompressed (brotli, gzip), 2.7 MiB or less gzipped", async () => {
    const wasm = `${site.url}pkg/stance_web_bg.wasm`;
    const size = async (encoding) => {
      const response = await fetch(wasm, { headers: { "Accept-Encoding": encoding } });
      const body = new Uint8Array(await response.arrayBuffer());
      return { encoding: response.headers.get("content-encoding"), bytes: body.length };
    };
    // Node's fetch decodes what it asked for: the length on the wire is the file's.
    const plain = await size("identity");
    const br = await fetch(wasm, { headers: { "Accept-Encoding": "br" } });
    const gz = await fetch(wasm, { headers: { "Accept-Encoding": "gzip" } });
    assert.equal(plain.encoding, null);
    assert.equal(br.headers.get("content-encoding"), "br");
    assert.equal(gz.headers.get("content-encoding"), "gzip");
    const { statSync } = await import("node:fs");
    const dist = new URL("../dist/pkg/", import.meta.url);
    const gzBytes = statSync(new URL("stance_web_bg.wasm.gz", dist)).size;
    const brBytes = statSync(new URL("stance_web_bg.wasm.br", dist)).size;
    console.log(`[site] wasm ${(plain.bytes / 1024).toFixed(0)} KiB, ${(gzBytes / 1024).toFixed(0)} KiB gzipped, `
      + `${(brBytes / 1024).toFixed(0)} KiB brotli`);
    assert.equal((await br.arrayBuffer()).byteLength, plain.bytes, "the brotli copy decodes to the wasm");
    // 2.6 MiB until the keypoint lift (File > Open keypoints, in the loading worker) came
    // into the page's module: 2,638 -> 2,674 KiB with the lift's crate at opt-level z. 2.65
    // MiB until mesh props (their reader, drawing and export), collision's active set and
    // the lift's staged solves came in: 2,706 -> 2,728 KiB (2026-11-28; brotli, what
    // browsers take, 2,261 KiB).
    assert.ok(gzBytes <= 2.7 * 1024 * 1024, `${gzBytes} bytes gzipped`);
  });
});

describe("editor without any graphics backend", () => {
  test("shows a readable error screen, not a blank page", async () => {
    // WebGL off and WebGPU without an adapter: neither backend can start.
    const context = await launch({
      backend: "none",
      args: ["--disable-3d-apis", "--disable-webgl", "--disable-features=WebGPU,Vulkan"],
    });
    try {
      const page = context.pages()[0] ?? (await context.newPage());
      await page.goto(site.url);
      await page.waitForFunction(() => document.body.dataset.error, null, { timeout: 90_000 });
      assert.ok(await page.locator("#error").isVisible(), "the error screen is shown");
      assert.ok(await page.locator("#loading").isHidden(), "the spinner is gone");
      const message = await page.locator("#error-message").textContent();
      assert.match(message, /WebGPU|WebGL/i, `the message names the missing backends: ${message}`);
      const screenshot = await page.screenshot();
      saveArtifact("error-screen.png", screenshot);
      // Readable: light text on the dark page, i.e. a real share of bright pixels.
      const image = decodePng(screenshot);
      let bright = 0;
      for (let i = 0; i < image.data.length; i += 4) {
        if (image.data[i] > 180 && image.data[i + 1] > 180 && image.data[i + 2] > 180) bright += 1;
      }
      assert.ok(bright > 500, `only ${bright} bright (text) pixels on the error screen`);
    } finally {
      await context.close();
    }
  });
});
