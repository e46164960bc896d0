// stance-ik: Stance's prioritized IK solver, one ES module for browsers and Node 20+.
// Importing it instantiates the solver's WebAssembly module once (top-level await): in Node
// from the file next to this one, in a browser with fetch. Retargeting is a second module,
// loaded by the first `retarget` call: a page that only poses never downloads it.
import init, { initSync, solve as solveProblem, Skeleton, Solver } from './pkg/stance_ik.js';

const isNode = typeof process !== 'undefined' && process.versions && process.versions.node;

/** Instantiates a wasm-bindgen module's WebAssembly (`init`/`initSync` of its glue). */
async function instantiate(glue, wasmUrl) {
  if (isNode) {
    const { readFile } = await import('node:fs/promises');
    glue.initSync({ module: await readFile(wasmUrl) });
  } else {
    await glue.default({ module_or_path: wasmUrl });
  }
}

await instantiate({ default: init, initSync }, new URL('./pkg/stance_ik_bg.wasm', import.meta.url));

let retargeting = null;

/** The retargeting module, loaded and instantiated once (the first `retarget` call). */
function retargetingModule() {
  if (!retargeting) {
    retargeting = (async () => {
      const glue = await import('./pkg/stance_ik_motion.js');
      await instantiate(glue, new URL('./pkg/stance_ik_motion_bg.wasm', import.meta.url));
      return glue;
    })();
    // A failed load (offline, a file missing) is not kept: the next call tries again.
    retargeting.catch(() => { retargeting = null; });
  }
  return retargeting;
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
 * proportions, foot contacts detected and held unless `options.contacts === false`. Resolves
 * to `{frameTime, frameCount, values, contacts, iterations, notes}`: `values` holds one
 * posture (`skeleton.dofCount` DOF values, `skeleton.dofNames` order) per frame of the source.
 * The first call loads the retargeting module (a second WebAssembly file).
 */
export async function retarget(skeleton, bvh, options = {}) {
  if (!(skeleton instanceof Skeleton)) {
    throw new TypeError('retarget: skeleton must be a Skeleton (Skeleton.hanim or Skeleton.fromSkin)');
  }
  const { retargetBvh } = await retargetingModule();
  return retargetBvh(skeleton.recipe, bvh, options.contacts !== false);
}

export { Skeleton, Solver };
