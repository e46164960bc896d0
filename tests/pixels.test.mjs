// The pixel tests of the end-to-end tests, tested (no browser): `isFigureColour` passes the
// mannequin's two materials as the skinned shader lights them and nothing else the editor
// draws (the background, the floor and its axes, the overlays, the panels: colours measured
// on the editor's screenshots); `isBackdrop` passes the background and the floor.
import { describe, test } from "node:test";
import assert from "node:assert/strict";
import { readFileSync } from "node:fs";
import { FIGURE_MATERIALS, isBackdrop, isFigureColour } from "./browser.mjs";

const srgb = (linear) => {
  const c = Math.min(1, Math.max(0, linear));
  return Math.round(255 * (c <= 0.0031308 ? c * 12.92 : 1.055 * c ** (1 / 2.4) - 0.055));
};

// Pixels of the editor's screenshots (WebGL2, SwiftShader) that are not the figure.
const NOT_FIGURE = {
  background: [33, 37, 43],
  "floor, far": [32, 36, 42],
  "floor base": [66, 69, 75],
  "floor line": [124, 127, 132],
  "floor line, faded": [80, 83, 90],
  "red axis": [196, 97, 97],
  "blue axis": [97, 124, 203],
  "panel fill": [248, 248, 248],
  "panel frame": [230, 230, 230],
  "panel text": [60, 60, 60],
  "panel text, grey": [124, 124, 124],
  "selected button": [144, 209, 255],
  "green status text": [90, 210, 120],
  "skeleton overlay": [255, 255, 255],
  "support polygon": [120, 200, 255],
  "selected joint": [240, 200, 60],
  "pull line": [207, 128, 255],
  "pin marker": [84, 183, 85],
  "ring": [215, 76, 76],
  "mid grey": [128, 128, 128],
  black: [0, 0, 0],
};

describe("the pixel tests", () => {
  test("FIGURE_MATERIALS are the default avatar's materials", () => {
    const glb = readFileSync(new URL("../public/default-avatar.glb", import.meta.url));
    const json = JSON.parse(glb.subarray(20, 20 + glb.readUInt32LE(12)).toString("utf8"));
    const materials = Object.fromEntries(json.materials.map((m) => [m.name,
      m.pbrMetallicRoughness.baseColorFactor.slice(0, 3)]));
    assert.deepEqual(Object.keys(materials).sort(), Object.keys(FIGURE_MATERIALS).sort());
    for (const [name, colour] of Object.entries(FIGURE_MATERIALS)) {
      colour.forEach((c, i) => assert.ok(Math.abs(c - materials[name][i]) < 1e-6,
        `${name}: ${colour} in the test, ${materials[name]} in the file`));
    }
  });

  test("isFigureColour passes the figure's materials lit from shadow to full light", () => {
    for (const [name, base] of Object.entries(FIGURE_MATERIALS)) {
      for (const light of [0.25, 0.4, 0.65, 0.9, 1.1]) {
        for (const specular of [0, 0.02, 0.04]) {
          const pixel = base.map((c) => srgb(c * light + specular));
          assert.ok(isFigureColour(pixel), `${name} at light ${light}, specular ${specular}: ${pixel}`);
        }
      }
    }
  });

  // Catches a check that counts any pixel (the old one passed every non-grey colour: the
  // axes, the overlays, the selected button of the panels).
  test("isFigureColour fails the background, the floor, the overlays and the panels", () => {
    for (const [what, pixel] of Object.entries(NOT_FIGURE)) {
      assert.ok(!isFigureColour(pixel), `${what} ${pixel} passed as the figure's colour`);
    }
    // The figure's colours, too dark (the figure is never lit below 0.2) or too far off.
    assert.ok(!isFigureColour(FIGURE_MATERIALS.clothes.map((c) => srgb(c * 0.08))));
    assert.ok(!isFigureColour(FIGURE_MATERIALS.skin.map((c, i) => srgb(c * 0.65) + (i === 1 ? 12 : 0))));
  });

  test("isBackdrop passes the background and the floor, not the figure", () => {
    for (const what of ["background", "floor, far", "floor base", "floor line", "floor line, faded",
      "red axis", "blue axis"]) {
      assert.ok(isBackdrop(NOT_FIGURE[what]), `${what} ${NOT_FIGURE[what]}`);
    }
    for (const what of ["panel fill", "skeleton overlay", "selected joint", "pull line"]) {
      assert.ok(!isBackdrop(NOT_FIGURE[what]), `${what} ${NOT_FIGURE[what]}`);
    }
    for (const [name, base] of Object.entries(FIGURE_MATERIALS)) {
      const pixel = base.map((c) => srgb(c * 0.65));
      assert.ok(!isBackdrop(pixel), `${name} ${pixel}`);
    }
  });
});
