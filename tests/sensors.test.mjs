// End to end: motion-capture sensors in the built site (WebGL2). A page init script puts a
// fake navigator.serial and navigator.hid in the page; they stream what `stance
// simulate-sensors` wrote (a right arm reaching and bending), and the test compares the
// avatar's joints with the simulation's ground truth after calibration.
import { after, before, describe, test } from "node:test";
import assert from "node:assert/strict";
import { execFileSync } from "node:child_process";
import { mkdtempSync, readFileSync } from "node:fs";
import { tmpdir } from "node:os";
import { dirname, join } from "node:path";
import { fileURLToPath } from "node:url";
import {
  CONFIGURATIONS, clickButton, freshStoragePerTab, launch, openEditor, serve, stanceBinary, waitForState,
} from "./browser.mjs";

const root = join(dirname(fileURLToPath(import.meta.url)), "..");
const RATE_HZ = 50;
let site;
let context;
let work;
let fob; // { frames: [[byte]], truth: [[sample]] } one entry per frame (4 sensors)
let slime; // { reports: [[id, [byte]]], truth }

function simulate(stance, protocolArgs, name) {
  const out = join(work, `${name}.bin`);
  const truth = join(work, `${name}.json`);
  execFileSync(stance, ["simulate-sensors", ...protocolArgs, "--rate-hz", String(RATE_HZ),
    "--duration-secs", "4", "--out", out, "--truth", truth]);
  return { bytes: [...readFileSync(out)], truth: JSON.parse(readFileSync(truth, "utf8")) };
}

function byFrame(truth) {
  const frames = [];
  for (let i = 0; i < truth.length; i += 4) frames.push(truth.slice(i, i + 4));
  return frames;
}

/** Splits a report log ("HR", id, length, data, check) into reports. */
function reportLog(bytes) {
  const reports = [];
  let i = 0;
  while (i + 5 <= bytes.length && bytes[i] === 0x48 && bytes[i + 1] === 0x52) {
    const length = bytes[i + 3];
    reports.push([bytes[i + 2], bytes.slice(i + 4, i + 4 + length)]);
    i += 5 + length;
  }
  assert.equal(i, bytes.length, "a well-formed report log");
  return reports;
}

// Quaternions [x, y, z, w].
const mul = ([ax, ay, az, aw], [bx, by, bz, bw]) => [
  aw * bx + ax * bw + ay * bz - az * by,
  aw * by - ax * bz + ay * bw + az * bx,
  aw * bz + ax * by - ay * bx + az * bw,
  aw * bw - ax * bx - ay * by - az * bz,
];
const inv = ([x, y, z, w]) => [-x, -y, -z, w];
const angleDeg = (a, b) => {
  const d = mul(inv(a), b);
  const norm = Math.hypot(...d);
  return (2 * Math.acos(Math.min(1, Math.abs(d[3] / norm))) * 180) / Math.PI;
};
/** A rotation from its matrix columns (the images of x, y, z). */
function fromColumns([c0, c1, c2]) {
  const m = [[c0[0], c1[0], c2[0]], [c0[1], c1[1], c2[1]], [c0[2], c1[2], c2[2]]];
  const w = Math.sqrt(Math.max(0, 1 + m[0][0] + m[1][1] + m[2][2])) / 2;
  const x = Math.sqrt(Math.max(0, 1 + m[0][0] - m[1][1] - m[2][2])) / 2;
  const y = Math.sqrt(Math.max(0, 1 - m[0][0] + m[1][1] - m[2][2])) / 2;
  const z = Math.sqrt(Math.max(0, 1 - m[0][0] - m[1][1] + m[2][2])) / 2;
  return [
    Math.sign(m[2][1] - m[1][2]) * x || x,
    Math.sign(m[0][2] - m[2][0]) * y || y,
    Math.sign(m[1][0] - m[0][1]) * z || z,
    w,
  ];
}
// The editor's world (+Y up, +Z front, +X left) from the device frames of the sensors window.
const WORLD_FROM_TRANSMITTER = fromColumns([[0, 0, 1], [-1, 0, 0], [0, -1, 0]]);
const WORLD_FROM_EARTH = fromColumns([[0, 0, 1], [1, 0, 0], [0, 1, 0]]);

// Sensors 1..4 (torso, upper arm, forearm, hand) -> the "Torso + right arm" preset.
const DRIVEN = [["vt1", 1], ["r_shoulder", 2], ["r_elbow", 3], ["r_radiocarpal", 4]];

before(async () => {
  work = mkdtempSync(join(tmpdir(), "stance-sensors-"));
  const stance = stanceBinary();
  const fobStream = simulate(stance, ["--protocol", "fob", "--fob-mode", "pos-quat", "--group"], "fob");
  const recordLength = 15; // POS/QUAT (7 words) + the group-mode address byte
  const frames = [];
  for (let i = 0; i < fobStream.bytes.length; i += 4 * recordLength) {
    frames.push(fobStream.bytes.slice(i, i + 4 * recordLength));
  }
  fob = { bytes: fobStream.bytes, frames, truth: byFrame(fobStream.truth) };
  assert.equal(fob.frames.length, fob.truth.length);
  const slimeStream = simulate(stance, ["--protocol", "slimevr-hid"], "slimevr");
  slime = { reports: reportLog(slimeStream.bytes), truth: byFrame(slimeStream.truth) };
  assert.equal(slime.reports.length, slime.truth.length, "one receiver report per frame");

  site = await serve();
  context = await launch(CONFIGURATIONS.webgl2);
  await freshStoragePerTab(context);
  await context.addInitScript(() => {
    // A serial port whose bytes the test pushes, and which records what the page writes.
    const serialListeners = {};
    const fakeSerial = { opened: null, written: [], controller: null };
    const port = {
      readable: null,
      writable: null,
      getInfo: () => ({ usbVendorId: 0x0403, usbProductId: 0x6001 }),
      async open(options) {
        fakeSerial.opened = options;
        port.readable = new ReadableStream({ start(c) { fakeSerial.controller = c; } });
        port.writable = new WritableStream({ write(chunk) { fakeSerial.written.push(...chunk); } });
      },
      async close() {},
    };
    fakeSerial.push = (frames) => frames.forEach((f) => fakeSerial.controller.enqueue(new Uint8Array(f)));
    fakeSerial.unplug = () => {
      for (const listener of serialListeners.disconnect ?? []) listener({ target: port });
      fakeSerial.controller.error(new DOMException("The device has been lost.", "NetworkError"));
    };
    window.__fakeSerial = fakeSerial;
    Object.defineProperty(navigator, "serial", {
      configurable: true,
      value: {
        async requestPort() { return port; },
        async getPorts() { return [port]; },
        addEventListener(type, f) { (serialListeners[type] ??= []).push(f); },
        removeEventListener(type, f) {
          serialListeners[type] = (serialListeners[type] ?? []).filter((g) => g !== f);
        },
      },
    });
    // A SlimeVR receiver whose input reports the test sends.
    const hidListeners = {};
    const deviceListeners = {};
    const device = {
      productName: "SlimeVR receiver (fake)",
      vendorId: 0x1209,
      productId: 0x7690,
      opened: false,
      async open() { device.opened = true; },
      async close() { device.opened = false; },
      addEventListener(type, f) { (deviceListeners[type] ??= []).push(f); },
      removeEventListener(type, f) {
        deviceListeners[type] = (deviceListeners[type] ?? []).filter((g) => g !== f);
      },
    };
    window.__fakeHid = {
      requested: null,
      send(reports) {
        for (const [reportId, bytes] of reports) {
          const data = new DataView(new Uint8Array(bytes).buffer);
          for (const f of deviceListeners.inputreport ?? []) f({ reportId, data, device });
        }
      },
      unplug() {
        for (const f of hidListeners.disconnect ?? []) f({ device });
      },
    };
    Object.defineProperty(navigator, "hid", {
      configurable: true,
      value: {
        async requestDevice(options) { window.__fakeHid.requested = options; return [device]; },
        async getDevices() { return [device]; },
        addEventListener(type, f) { (hidListeners[type] ??= []).push(f); },
        removeEventListener(type, f) {
          hidListeners[type] = (hidListeners[type] ?? []).filter((g) => g !== f);
        },
      },
    });
  });
});
after(async () => {
  await context?.close();
  site?.server.close();
});

async function state(page) {
  return JSON.parse(await page.evaluate(() => window.stance.state_json()));
}

// Catches a page that never gets there (never settles, never connects): it fails naming
// the predicate and the state the page was left in (a waitForFunction's timeout said only
// "Timeout exceeded"), and returns the state that met the predicate, not a later one.
function waitFor(page, predicate, argument, timeout = 20_000) {
  const what = `the page's state meets ${predicate.toString()}`
    + `${argument == null ? "" : ` with ${JSON.stringify(argument)}`}`;
  return waitForState(page, (s) => predicate(s, argument), { timeout, what });
}

/** Opens the editor with these sensor settings remembered, and the sensors window open. */
async function editorWithSensors(settings) {
  const page = await context.newPage();
  const { errors } = await openEditor(context, site.url, page);
  if (settings) {
    await page.evaluate((text) => window.localStorage.setItem("stance.sensors.settings", text),
      JSON.stringify(settings));
    await page.reload();
    await page.waitForFunction(() => document.body.dataset.firstFrameMs);
  }
  await waitFor(page, (s) => s.settled);
  await clickButton(page, "sensors_open", { until: (s) => Boolean(s.buttons.sensors_connect) });
  return { page, errors };
}

/** Calibrates on the first frame, then checks the driven joints against the truth. */
async function followsTheArm(page, sendFrames, frameCount, truth, worldFromDevice, label) {
  await sendFrames(0, 1);
  await waitFor(page, (s) => s.sensors.samples >= 4);
  await clickButton(page, "sensors_preset_right_arm", { until: (s) => s.sensors.assigned === 4 });
  await clickButton(page, "sensors_calibrate", { until: (s) => s.sensors.calibrated });
  const calibrated = await waitFor(page, (s) => s.sensors.calibrated && s.settled);
  // At the calibration instant the joints keep the calibration posture (Molet et al.).
  const atCalibration = Object.fromEntries(
    DRIVEN.map(([joint]) => [joint, calibrated.sensors.driven[joint].world]),
  );
  const first = Object.fromEntries(truth[0].map((s) => [s.sensor, s.orientation]));
  let worst = 0;
  let sent = 1;
  for (const k of [25, 50, 100, Math.min(150, frameCount - 1)]) {
    await sendFrames(sent, k + 1);
    sent = k + 1;
    const now = await waitFor(page, (s, n) => s.sensors.samples >= n && s.settled, 4 * (k + 1));
    for (const [joint, sensor] of DRIVEN) {
      const measured = truth[k].find((s) => s.sensor === sensor).orientation;
      // J(t) = A S(t) S(0)^-1 A^-1 J_cal
      const expected = mul(
        mul(mul(worldFromDevice, mul(measured, inv(first[sensor]))), inv(worldFromDevice)),
        atCalibration[joint],
      );
      const error = angleDeg(now.sensors.driven[joint].world, expected);
      worst = Math.max(worst, error);
      assert.ok(error < 1, `${label} frame ${k}: ${joint} is ${error.toFixed(3)} degrees off`);
    }
  }
  const final = await state(page);
  console.log(`[sensors] ${label}: worst joint error ${worst.toFixed(3)} degrees; bytes to posture `
    + `${final.sensors.latency_median_ms?.toFixed(1)} ms median, ${final.sensors.latency_max_ms?.toFixed(1)} ms max`);
  return final;
}

/** The largest difference between the numbers of two documents of the same shape. */
function largestDifference(a, b) {
  if (typeof a === "number" && typeof b === "number") return Math.abs(a - b);
  if (a && b && typeof a === "object" && typeof b === "object") {
    const keys = new Set([...Object.keys(a), ...Object.keys(b)]);
    let largest = 0;
    for (const key of keys) {
      if (!(key in a) || !(key in b)) return Infinity;
      largest = Math.max(largest, largestDifference(a[key], b[key]));
    }
    return largest;
  }
  return a === b ? 0 : Infinity;
}

const jointDistance = (a, b) => Math.hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);

describe("motion-capture sensors in the browser", () => {
  test("a Flock of Birds on a (fake) serial port drives the arm; unplugging says so and keeps the posture", async () => {
    const { page, errors } = await editorWithSensors();
    const before = await state(page);
    await clickButton(page, "sensors_connect", {
      until: (s) => s.sensors.link === "connected",
      started: (s) => s.sensors.link !== "idle",
    });
    const port = await page.evaluate(() => ({
      baudRate: window.__fakeSerial.opened?.baudRate,
      written: window.__fakeSerial.written,
    }));
    assert.equal(port.baudRate, 115200);
    assert.equal(port.written.at(-1), "@".charCodeAt(0), "the bridge starts the stream");

    const sendFrames = (from, to) => page.evaluate((frames) => window.__fakeSerial.push(frames),
      fob.frames.slice(from, to));
    await followsTheArm(page, sendFrames, fob.frames.length, fob.truth, WORLD_FROM_TRANSMITTER, "Flock of Birds");
    const held = await state(page);
    for (const foot of ["l_talocrural", "r_talocrural"]) {
      const moved = jointDistance(held.joints[foot], before.joints[foot]);
      assert.ok(moved < 1e-3, `the pinned ${foot} stays (moved ${moved} m)`);
    }
    // The hand moved with the arm (the simulated reach lifts it well forward).
    assert.ok(jointDistance(held.joints.r_radiocarpal, before.joints.r_radiocarpal) > 0.1);

    await page.evaluate(() => window.__fakeSerial.unplug());
    const lost = await waitFor(page, (s) => s.sensors.link === "lost");
    assert.match(lost.notice.text, /unplugged/);
    assert.equal(lost.notice.error, true);
    await page.waitForTimeout(300);
    const after = await state(page);
    const drift = largestDifference(after.document.posture, held.document.posture);
    assert.ok(drift < 1e-4, `the posture stays (moved by ${drift})`);
    assert.deepEqual(errors, []);
    await page.close();
  });

  test("a SlimeVR receiver on (fake) WebHID drives the arm", async () => {
    const { page, errors } = await editorWithSensors({ device: "SlimeVr", frame: "EarthZUp" });
    await clickButton(page, "sensors_connect", {
      until: (s) => s.sensors.link === "connected",
      started: (s) => s.sensors.link !== "idle",
    });
    const requested = await page.evaluate(() => window.__fakeHid.requested);
    assert.deepEqual(requested.filters, [{ vendorId: 0x1209, productId: 0x7690 }]);
    const sendFrames = (from, to) => page.evaluate((reports) => window.__fakeHid.send(reports),
      slime.reports.slice(from, to));
    await followsTheArm(page, sendFrames, slime.reports.length, slime.truth, WORLD_FROM_EARTH, "SlimeVR");
    await page.evaluate(() => window.__fakeHid.unplug());
    const lost = await waitFor(page, (s) => s.sensors.link === "lost");
    assert.match(lost.notice.text, /unplugged/);
    assert.deepEqual(errors, []);
    await page.close();
  });

  test("a recording replays through the same path as the device", async () => {
    const { page, errors } = await editorWithSensors();
    const [chooser] = await Promise.all([
      page.waitForEvent("filechooser"),
      clickButton(page, "sensors_replay"),
    ]);
    await chooser.setFiles(join(work, "fob.bin"));
    await waitFor(page, (s) => s.sensors.link === "replaying");
    const done = await waitFor(page, (s) => s.sensors.link === "idle", null, 30_000);
    assert.equal(done.sensors.samples, fob.truth.length * 4);
    assert.equal(done.sensors.bad_frames, 0);
    assert.match(done.notice.text, /Replay of fob\.bin finished/);
    assert.deepEqual(errors, []);
    await page.close();
  });
});
