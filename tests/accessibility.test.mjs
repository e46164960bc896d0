// End to end: the editor's widgets in Chromium's accessibility tree (web/accessibility.js mirrors
// egui's AccessKit tree as DOM elements), and the tasks panel operated from the keyboard alone.
import { after, before, describe, test } from "node:test";
import assert from "node:assert/strict";
import {
  CONFIGURATIONS, decodePng, launch, openEditor, saveArtifact, serve,
} from "./browser.mjs";

let site;
before(async () => { site = await serve(); });
after(() => site.server.close());

const state = async (page) => JSON.parse(await page.evaluate(() => window.stance.state_json()));

/** Chromium's own accessibility tree (what a screen reader reads), as [role, name] pairs. */
async function chromiumTree(page) {
  const cdp = await page.context().newCDPSession(page);
  await cdp.send("Accessibility.enable");
  const { nodes } = await cdp.send("Accessibility.getFullAXTree");
  await cdp.detach();
  return nodes
    .filter((node) => !node.ignored)
    .map((node) => [node.role?.value, node.name?.value ?? ""]);
}

/** Presses Tab until the focused element matches `accepts` (at most `limit` times). */
async function tabTo(page, accepts, limit = 250) {
  for (let i = 0; i < limit; i += 1) {
    await page.keyboard.press("Tab");
    const focused = await page.evaluate(() => {
      const element = document.activeElement;
      if (!element?.closest("#a11y")) return null;
      const labels = (element.getAttribute("aria-labelledby") ?? "").split(" ")
        .map((id) => document.getElementById(id)?.textContent ?? "").join(" ");
      return {
        tag: element.tagName, role: element.getAttribute("role") ?? element.tagName.toLowerCase(),
        name: element.getAttribute("aria-label") ?? labels, id: element.id,
      };
    });
    if (focused && accepts(focused)) return { ...focused, presses: i + 1 };
  }
  throw new Error("the Tab key never reached the wanted control");
}

describe("accessibility on WebGL2", () => {
  let context;
  let page;
  before(async () => {
    // A smaller window: the keyboard's way through the panels is the same, and each Tab's
    // frame draws a smaller 3D view (software GL).
    context = await launch({ ...CONFIGURATIONS.webgl2, viewport: { width: 1000, height: 640 } });
    ({ page } = await openEditor(context, site.url));
    await page.waitForFunction(() => document.querySelectorAll("#a11y button").length > 5,
      null, { timeout: 30_000 });
  });
  after(async () => { await context?.close(); });

  test("the tasks panel's buttons are in Chromium's accessibility tree with names", async () => {
    const tree = await chromiumTree(page);
    const has = (role, name) => tree.some(([r, n]) => r === role && n === name);
    const named = (role) => tree.filter(([r, n]) => r === role && n).map(([, n]) => n);
    const updateMs = await page.evaluate(() => document.getElementById("a11y").dataset.updateMs);
    console.log(`[a11y] ${tree.length} nodes; buttons: ${named("button").join(", ")}; `
      + `last mirror update ${updateMs} ms (after the frame, when the browser is idle)`);
    assert.ok(has("region", "Stance editor"), "the mirror is a named region");
    assert.ok(has("button", "Add task"), "the Add task menu");
    assert.ok(has("button", "Table 1 example"), "the tasks panel's example button");
    // Every task's header (its description and status) is a button that opens its fields.
    const tasks = (await state(page)).tasks;
    for (const task of tasks) {
      assert.ok(named("button").some((n) => n.startsWith(task.description)),
        `no button for the task "${task.description}"`);
    }
    const collapsed = await page.evaluate(() =>
      document.querySelectorAll('#a11y button[aria-expanded="false"]').length);
    assert.ok(collapsed >= tasks.length, `${collapsed} closed headers for ${tasks.length} tasks`);
  });

  test("a task is opened, edited and removed from the keyboard alone, with a visible focus", async () => {
    const before = await state(page);
    const first = before.tasks[0].description;
    const header = await tabTo(page, (f) => f.role === "button" && f.name.startsWith(first));
    console.log(`[a11y] the first task's header reached after ${header.presses} Tab presses`);
    // The focus ring shows, and egui's own focus followed the page's.
    const ring = await page.evaluate(() => {
      const style = getComputedStyle(document.activeElement);
      return { style: style.outlineStyle, width: parseFloat(style.outlineWidth) };
    });
    assert.notEqual(ring.style, "none");
    assert.ok(ring.width >= 2, `focus outline ${ring.width}px`);
    await page.waitForFunction((id) => document.getElementById("a11y").dataset.focus === id,
      header.id, { timeout: 5000 });
    const shot = await page.screenshot();
    saveArtifact("a11y-focus.png", shot);
    // The ring is on screen around the header: the mirror's outline colour (#ffbf47).
    const box = await page.evaluate(() => {
      const r = document.activeElement.getBoundingClientRect();
      return { x: Math.floor(r.x) - 4, y: Math.floor(r.y) - 4, w: Math.ceil(r.width) + 8, h: Math.ceil(r.height) + 8 };
    });
    const image = decodePng(shot);
    let ringPixels = 0;
    for (let y = box.y; y < box.y + box.h; y += 1) {
      for (let x = box.x; x < box.x + box.w; x += 1) {
        const [r, g, b] = image.at(x, y);
        if (Math.abs(r - 255) < 30 && Math.abs(g - 191) < 40 && Math.abs(b - 71) < 50) ringPixels += 1;
      }
    }
    assert.ok(ringPixels > box.w, `${ringPixels} focus-ring pixels around the focused header`);

    // Enter opens the task: its fields appear in the accessibility tree, named by their labels.
    await page.keyboard.press("Enter");
    await page.waitForFunction((id) =>
      document.getElementById(id)?.getAttribute("aria-expanded") === "true", header.id,
    { timeout: 5000 });
    await page.waitForTimeout(300);
    const tree = await chromiumTree(page);
    for (const [role, name] of [["spinbutton", "level"], ["spinbutton", "weight"],
      ["checkbox", "active"], ["button", "Remove"]]) {
      assert.ok(tree.some(([r, n]) => r === role && n === name), `no ${role} named ${name}`);
    }

    // The weight: arrow up is one step of the field (its drag speed, 0.01).
    const weight = before.document.tasks[0].weight;
    await tabTo(page, (f) => f.role === "spinbutton" && f.name === "weight");
    await page.keyboard.press("ArrowUp");
    await page.waitForFunction((w) =>
      Math.abs(JSON.parse(window.stance.state_json()).document.tasks[0].weight - w) > 1e-9,
    weight, { timeout: 5000 });
    const stepped = (await state(page)).document.tasks[0].weight;
    assert.ok(Math.abs(stepped - weight - 0.01) < 1e-9, `weight ${weight} -> ${stepped}`);

    // A typed value, confirmed with Enter.
    await page.keyboard.press("Control+A");
    await page.keyboard.type("2.5");
    await page.keyboard.press("Enter");
    await page.waitForFunction(() =>
      JSON.parse(window.stance.state_json()).document.tasks[0].weight === 2.5,
    null, { timeout: 5000 });

    // On to the task's Remove button, pressed with Enter: one task fewer.
    await tabTo(page, (f) => f.role === "button" && f.name === "Remove");
    await page.keyboard.press("Enter");
    await page.waitForFunction((n) =>
      JSON.parse(window.stance.state_json()).document.tasks.length === n - 1,
    before.document.tasks.length, { timeout: 5000 });
  });

  test("the mirror leaves the mouse to the canvas", async () => {
    const hit = await page.evaluate(() => {
      const button = [...document.querySelectorAll("#a11y button")]
        .find((b) => b.getAttribute("aria-label") === "Table 1 example");
      const rect = button.getBoundingClientRect();
      return document.elementFromPoint(rect.x + rect.width / 2, rect.y + rect.height / 2)?.id;
    });
    assert.equal(hit, "stance-canvas");
  });
});
