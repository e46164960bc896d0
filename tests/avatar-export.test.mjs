// Avatar files through the `stance` CLI, no browser: the generated default avatar and a
// posed export of the shared real avatar pass the Khronos glTF-Validator with zero errors;
// `stance inspect` prints its JSON summary, and fails with a reason on a bad file.
import { before, describe, test } from "node:test";
import assert from "node:assert/strict";
import { spawnSync } from "node:child_process";
import { mkdtempSync, readFileSync, writeFileSync } from "node:fs";
import { tmpdir } from "node:os";
import { dirname, join } from "node:path";
import { fileURLToPath } from "node:url";
import validator from "gltf-validator";
import { stanceBinary } from "./browser.mjs";

const root = join(dirname(fileURLToPath(import.meta.url)), "..");
const sharedAvatar = join(root, "tests", "fixtures", "avatars", "Black_F_2_Casual.glb");
let stance;
let work;

before(() => {
  stance = stanceBinary();
  work = mkdtempSync(join(tmpdir(), "stance-avatar-"));
});

function run(...args) {
  return spawnSync(stance, args, { cwd: root, encoding: "utf8" });
}

async function validate(file) {
  const report = await validator.validateBytes(new Uint8Array(readFileSync(file)), {
    maxIssues: 50,
    externalResourceFunction: () => Promise.reject(new Error("no external resources")),
  });
  const errors = report.issues.messages.filter((m) => m.severity === 0);
  assert.equal(report.issues.numErrors, 0, `${file}: ${JSON.stringify(errors, null, 1)}`);
  return report;
}

describe("avatar files", () => {
  test("make-avatar writes a valid GLB, identical to public/default-avatar.glb", async () => {
    const out = join(work, "default.glb");
    const r = run("make-avatar", out);
    assert.equal(r.status, 0, r.stderr);
    await validate(out);
    assert.ok(readFileSync(out).equals(readFileSync(join(root, "public", "default-avatar.glb"))),
      "public/default-avatar.glb is stale: regenerate it with `stance make-avatar`");
    const info = JSON.parse(run("inspect", out).stdout);
    assert.equal(info.joints, 71);
    assert.equal(info.unmapped.length, 0);
    assert.equal(info.mapping.l_elbow, "l_elbow");
  });

  test("export-posed of the shared avatar passes the validator", async () => {
    const posture = join(work, "posture.json");
    writeFileSync(posture, JSON.stringify({
      loa: 2,
      posture: {
        humanoid_root: { ty: -0.05, ry: 0.3 },
        vl5: { rx: 0.2 },
        skullbase: { ry: 0.4 },
        l_hip: { rx: -0.6 },
        r_knee: { rx: 0.7 },
      },
    }));
    const out = join(work, "posed.glb");
    const r = run("export-posed", sharedAvatar, posture, out);
    assert.equal(r.status, 0, r.stderr);
    await validate(out);
    const info = JSON.parse(run("inspect", out).stdout);
    assert.equal(info.mapping.LeftArm, "l_shoulder");
    assert.ok(info.vertices > 40000);
  });

  test("inspect of the shared avatar", () => {
    const r = run("inspect", sharedAvatar);
    assert.equal(r.status, 0, r.stderr);
    const info = JSON.parse(r.stdout);
    for (const key of ["joints", "mapping", "unmapped", "meshes", "vertices", "extensions", "warnings"]) {
      assert.ok(key in info, key);
    }
    assert.ok(info.extensions.includes("EXT_meshopt_compression"));
    assert.ok(Object.keys(info.mapping).length >= 18);
  });

  test("inspect of a bad file fails with a reason", () => {
    const bad = join(work, "bad.glb");
    writeFileSync(bad, Buffer.from("glTF\u0002\u0000\u0000\u0000\u00ff\u00ff\u0000\u0000", "latin1"));
    const r = run("inspect", bad);
    assert.notEqual(r.status, 0);
    assert.match(r.stderr, /truncated|bad GLB/);
  });
});
