// stance-ik: Stance's prioritized IK solver, one ES module for browsers and Node 20+.
// Importing it instantiates the WebAssembly module once (top-level await): in Node from the
// file next to this one, in a browser with fetch.
import init, { initSync, solve as solveProblem, retargetBvh, Skeleton, Solver } from './pkg/stance_ik.js';

const wasmUrl = new URL('./pkg/stance_ik_bg.wasm', import.meta.url);
if (typeof process !== 'undefined' && process.versions && process.versions.node) {
  const { readFile } = await import('node:fs/promises');
  initSync({ module: await readFile(wasmUrl) });
} else {
  await init({ module_or_path: wasmUrl });
}

/**
 * Solves a problem (`docs/problem-format.md`: a skeleton, tasks by level, settings, a start
 * posture), as an object or JSON text. Returns what `stance solve` prints: `joints` (world
 * positions), `posture` (DOF values by joint), `report` (status, iterations, per-level
 * residuals, the level that gave way) and, with limb tasks, `limbs`. Throws an `Error` whose
 * message names the offending field (`tasks[2].joint: unknown joint ...`).
 */
export function solve(problem) {
  return solveProblem(problem);
}

/**
 * Retargets a BVH clip (its text) onto an H-Anim `skeleton` (`Skeleton.hanim(loa)` or
 * `Skeleton.fromSkin(...)`): any naming (CMU, MotionBuilder, Mixamo, Daz, Biped...) and
 * proportions, foot contacts detected and held unless `options.contacts === false`. Returns
 * `{frameTime, frameCount, values, contacts, iterations, notes}`: `values` holds one posture
 * (`skeleton.dofCount` DOF values, `skeleton.dofNames` order) per frame of the source.
 */
export function retarget(skeleton, bvh, options = {}) {
  return retargetBvh(skeleton, bvh, options.contacts !== false);
}

export { Skeleton, Solver };
