// End to end: the built site in real headless Chromium, once per graphics configuration.
import { after, before, describe, test } from "node:test";
import assert from "node:assert/strict";
import {
  CONFIGURATIONS, decodePng, isFigureColour, launch, openEditor, saveArtifact, serve,
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
      context = await launch(configuration);
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
      await page.waitForTimeout(300);
      const before = await page.screenshot();
      saveArtifact(`viewport-${name}.png`, before);
      const image = decodePng(before);
      // The viewport's rectangle, as the editor reports it (between the panels and bars).
      const state = JSON.parse(await page.evaluate(() => window.stance.state_json()));
      const [vx, vy, vw, vh] = state.viewport;
      const viewport = { x: Math.ceil(vx), y: Math.ceil(vy), width: Math.floor(vw), height: Math.floor(vh) };
      assert.equal(state.figure, true, "the mannequin is drawn as its skinned figure");
      const bodyBefore = bodyPixelsIn(image, viewport);
      assert.ok(bodyBefore > 800, `only ${bodyBefore} figure pixels in the viewport`);
      // The corners of the viewport are background or floor, not body.
      assert.ok(!isFigureColour(image.at(viewport.x + 10, viewport.y + 10)));

      // Start the drag on the background (not on the body, which would pull it).
      const startX = viewport.x + viewport.width * 0.9;
      const startY = viewport.y + viewport.height * 0.15;
      await page.mouse.move(startX, startY);
      await page.mouse.down();
      for (let step = 1; step <= 10; step += 1) {
        await page.mouse.move(startX - step * 15, startY + step * 4);
      }
      await page.mouse.up();
      await page.waitForTimeout(500);
      const turned = await page.screenshot();
      saveArtifact(`viewport-${name}-orbited.png`, turned);
      const after = decodePng(turned);
      let differing = 0;
      for (let i = 0; i < after.data.length; i += 4) {
        if (Math.abs(after.data[i] - image.data[i]) > 8
          || Math.abs(after.data[i + 1] - image.data[i + 1]) > 8) differing += 1;
      }
      assert.ok(differing > 5000, `only ${differing} pixels changed after the drag`);
      assert.ok(bodyPixelsIn(after, viewport) > 500, "the body is still in view");
    });
  });
}

describe("the site as served", () => {
  test("the wasm comes precompressed (brotli, gzip), 3 MiB or less gzipped", async () => {
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
    assert.ok(gzBytes <= 3 * 1024 * 1024, `${gzBytes} bytes gzipped`);
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
