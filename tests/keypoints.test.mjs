// File > Open keypoints… in the page: an OpenPose JSON that `stance render` wrote (a stride
// seen from the left, its hidden keypoints missing: tests/fixtures/openpose/stride-768x512.json;
// it carries no camera, so the lift fits one and keeps it as the saved view) is picked from
// the File menu and lifted in the page's loading worker (web/loading.js runJob, the "lift"
// lane). The character becomes "Person 1" in
// another posture; the lifted document, drawn again by the `stance` CLI through the saved view
// it carries, gives back the file's keypoints (body and hands) within 3 px (an oracle outside the page: the
// CLI's renderer, not the page's lift). A JSON that is OpenPose in form but not in content (a
// person with 2 numbers) is refused by a notice that names the problem, the document as it was.
import { after, before, describe, test } from "node:test";
import assert from "node:assert/strict";
import { execFileSync } from "node:child_process";
import { mkdtempSync, readFileSync, writeFileSync } from "node:fs";
import { tmpdir } from "node:os";
import { dirname, join } from "node:path";
import { fileURLToPath } from "node:url";
import {
  CONFIGURATIONS, clickButton, freshStoragePerTab, launch, openEditor, pageState, serve,
  stanceBinary, waitForState,
} from "./browser.mjs";

const root = join(dirname(fileURLToPath(import.meta.url)), "..");
const fixture = join(root, "tests", "fixtures", "openpose", "stride-768x512.json");
let served;
let context;
let dir;

before(async () => {
  dir = mkdtempSync(join(tmpdir(), "stance-keypoints-"));
  served = await serve();
  context = await launch(CONFIGURATIONS.webgl2);
  await freshStoragePerTab(context);
});

after(async () => {
  await context?.close();
  served?.server.close();
});

/** Picks `file` through File > Open keypoints… (the menu entry asks the page for a file). */
async function openKeypoints(page, file) {
  await clickButton(page, "file_menu", { until: (s) => Boolean(s.buttons?.open_keypoints) });
  const chooser = page.waitForEvent("filechooser", { timeout: 20_000 });
  await clickButton(page, "open_keypoints");
  await (await chooser).setFiles(file);
}

/** The first person's OpenPose keypoints (body, then both hands) as [x, y] pixels, null where
 * missing (confidence 0). */
function keypointsOf(json) {
  const person = json.people[0];
  const flat = [...person.pose_keypoints_2d, ...(person.hand_left_keypoints_2d ?? []),
    ...(person.hand_right_keypoints_2d ?? [])];
  const points = [];
  for (let k = 0; k < flat.length; k += 3) {
    points.push(flat[k + 2] > 0 ? [flat[k], flat[k + 1]] : null);
  }
  return points;
}

describe("File > Open keypoints in the page", () => {
  test("a keypoints file is lifted in the worker into a character that gives them back; a bad one is named and changes nothing", async () => {
    const { page, errors } = await openEditor(context, served.url);
    const workerTimes = [];
    page.on("console", (message) => {
      const match = /lift job \S+ done in the worker in (\d+) ms/.exec(message.text());
      if (match) workerTimes.push(Number(match[1]));
    });
    const before = await pageState(page);
    assert.equal(before.characters.length, 1);

    await openKeypoints(page, fixture);
    const lifted = await waitForState(page, (s) => s.notice && /stride-768x512\.json/.test(s.notice.text)
      && s.characters?.[0]?.name === "Person 1", { timeout: 120_000, what: "the lifted character" });
    assert.equal(lifted.notice.error, false, lifted.notice.text);
    console.log(`notice: ${lifted.notice.text}`);
    // Lifted in the page's worker lane: the job was requested and came back there.
    const marks = await page.evaluate(() => ["stance:lift-requested", "stance:lift-done"]
      .map((name) => performance.getEntriesByName(name).length));
    assert.deepEqual(marks, [1, 1], "the lift ran as the page's worker job");
    assert.equal(lifted.characters.length, 1);

    // The posture changed: the stride moves the ankles and wrists by tens of centimetres.
    const moved = ["l_talocrural", "r_talocrural", "l_radiocarpal", "r_radiocarpal"].map((joint) => {
      const [a, b] = [before.joints[joint], lifted.joints[joint]];
      return Math.hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
    });
    console.log(`moved by the lift (m): ${moved.map((m) => m.toFixed(3)).join(", ")}`);
    assert.ok(Math.max(...moved) > 0.1, `the posture hardly changed: ${moved}`);
    assert.ok(lifted.document.camera, "the lifted document keeps the keypoints' camera");

    // The lifted document drawn again by the CLI through its saved view: the file's keypoints.
    const doc = join(dir, "lifted.json");
    writeFileSync(doc, JSON.stringify(lifted.document));
    const again = join(dir, "again.json");
    execFileSync(stanceBinary(), ["render", doc, "--map", "openpose", "--size", "768x512",
      "--out", join(dir, "again.png"), "--keypoints-out", again], { stdio: "inherit" });
    const want = keypointsOf(JSON.parse(readFileSync(fixture, "utf8")));
    const got = keypointsOf(JSON.parse(readFileSync(again, "utf8")));
    let worst = 0;
    let compared = 0;
    want.forEach((p, k) => {
      if (!p || !got[k]) return;
      worst = Math.max(worst, Math.hypot(p[0] - got[k][0], p[1] - got[k][1]));
      compared += 1;
    });
    console.log(`${compared} keypoints (body and hands) back within ${worst.toFixed(2)} px; `
      + `the lift took ${workerTimes.join(", ")} ms in the worker (wasm)`);
    assert.ok(compared >= 50, `only ${compared} keypoints compared`);
    assert.ok(worst <= 3, `a keypoint ${worst.toFixed(2)} px off`);

    // Not OpenPose in content: named, nothing changed.
    const bad = join(dir, "two-numbers.json");
    writeFileSync(bad, JSON.stringify({
      people: [{ pose_keypoints_2d: [1, 2] }], canvas_width: 9, canvas_height: 9,
    }));
    await openKeypoints(page, bad);
    const refused = await waitForState(page, (s) => s.notice?.error
      && /two-numbers\.json/.test(s.notice.text), { timeout: 60_000, what: "the refusal" });
    console.log(`notice: ${refused.notice.text}`);
    assert.match(refused.notice.text, /2 numbers, expected 54/);
    assert.deepEqual(refused.document, lifted.document, "the document is as it was");
    assert.deepEqual(refused.characters.map((c) => c.name), ["Person 1"]);
    assert.deepEqual(errors, []);
  });
});
