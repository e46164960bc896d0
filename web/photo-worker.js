// The page's pose detector (File > Open photo…), a classic Web Worker started by photo.js
// the first time a photo is opened, never on page load. It runs MediaPipe Pose (the npm
// package @mediapipe/pose 0.5.1675469404, Apache-2.0, copied into dist/vendor/mediapipe-pose/
// by scripts/build-web.sh: nothing is fetched from elsewhere) on the decoded photo and
// returns the 33 landmarks of the person it finds.
//
// In:  { type: "detect", id, bitmap: ImageBitmap }
// Out: { id, landmarks: Float32Array (33 x: x, y, z, visibility) | null (no person),
//        ms, startMs } or { id, error }
//
// MediaPipe's legacy "solutions" API was written for a page; in a worker three things need
// help (measured in headless Chromium, docs/control-maps.md "Photos"):
// - its worker branch passes every file of the solution to importScripts, the .tflite model
//   too (which the browser refuses as a script): only the scripts go through, the model is
//   fetched by the solution itself (its modelComplexity option loads it);
// - the packed assets' loader reads its `locateFile` from the global
//   `createMediapipeSolutionsPackedAssets`, which the page branch sets and the worker branch
//   does not;
// - the worker branch creates its WebGL context on an OffscreenCanvas but never keeps the
//   context its image input is uploaded with (the page branch does): it is taken back from
//   the canvas after `initialize`. These names are those of the pinned version, checked.
// Inference runs on the CPU (XNNPACK in WebAssembly, `useCpuInference`): on software GL it
// is several times faster than the GPU path (0.3-0.7 s against 7-12 s for a first photo).

// Inside a function: the package's scripts share this worker's global scope (importScripts),
// so nothing of this file is declared there.
(() => {
  const BASE = "vendor/mediapipe-pose/";
  const VERSION = "0.5.1675469404";
  // BlazePose GHUM 3D "full": the middle of the package's three models (lite, full, heavy).
  const MODEL_COMPLEXITY = 1;

  const locateFile = (file) => `${BASE}${file}`;

  const importScriptsAsGiven = self.importScripts.bind(self);
  let pose = null;
  let starting = null;
  let resolveResults = null;

  function start() {
    if (!starting) {
      starting = (async () => {
        self.createMediapipeSolutionsPackedAssets = { locateFile };
        self.importScripts = (...urls) => importScriptsAsGiven(...urls.filter((url) => /\.js$/.test(url)));
        importScriptsAsGiven(locateFile("pose.js"));
        if (typeof self.Pose !== "function") throw new Error("pose.js did not define Pose");
        if (self.VERSION !== undefined && self.VERSION !== VERSION) {
          throw new Error(`@mediapipe/pose ${self.VERSION} is not the version this page was written for (${VERSION})`);
        }
        const solution = new self.Pose({ locateFile });
        solution.setOptions({
          modelComplexity: MODEL_COMPLEXITY,
          smoothLandmarks: false,
          enableSegmentation: false,
          minDetectionConfidence: 0.5,
          minTrackingConfidence: 0.5,
          useCpuInference: true,
        });
        solution.onResults((results) => {
          resolveResults?.(results);
          resolveResults = null;
        });
        await solution.initialize();
        const inner = solution.h;
        if (!inner || typeof OffscreenCanvas !== "function" || !(inner.m instanceof OffscreenCanvas)) {
          throw new Error("MediaPipe's worker set-up is not the one this page knows");
        }
        if (!inner.K) inner.K = inner.m.getContext("webgl2") || inner.m.getContext("webgl");
        if (!inner.K) throw new Error("no WebGL context in the worker for the detector's input");
        pose = solution;
      })();
      // A start that failed is tried again by the next photo (and says why again).
      starting.catch(() => {
        starting = null;
      });
    }
    return starting;
  }

  // One pass of the detector over `bitmap`: its landmarks, or null where it found nobody.
  async function pass(bitmap) {
    const results = new Promise((resolve) => {
      resolveResults = resolve;
    });
    await pose.send({ image: bitmap });
    const { poseLandmarks } = await results;
    return poseLandmarks?.length ? poseLandmarks : null;
  }

  self.onmessage = async ({ data }) => {
    const { id, bitmap } = data;
    const started = performance.now();
    try {
      await start();
      const ready = performance.now();
      // A photo is not a video: nothing is tracked from the previous one. The first pass finds
      // the person and its region; the second, tracking that region on the same picture,
      // refines the landmarks (a region from the landmarks rather than from the detector's box).
      await pose.reset();
      const first = await pass(bitmap);
      const landmarks = first && ((await pass(bitmap)) ?? first);
      bitmap.close?.();
      const flat = landmarks
        ? Float32Array.from(landmarks.flatMap((l) => [l.x, l.y, l.z ?? 0, l.visibility ?? 0]))
        : null;
      self.postMessage(
        { id, landmarks: flat, ms: performance.now() - started, startMs: ready - started },
        flat ? [flat.buffer] : [],
      );
    } catch (error) {
      self.postMessage({ id, error: String(error?.message ?? error) });
    }
  };
})();
