// File > Open photo…: the page decodes the picture the user picks (the browser's own
// decoders), a Web Worker (photo-worker.js, MediaPipe Pose served from this site) finds the
// person in it, and the editor gets MediaPipe's landmarks with the photo to show behind the
// viewport (WebHandle.photo_detected), or why not (WebHandle.photo_failed). The editor turns
// the landmarks into OpenPose keypoints and lifts them as File > Open keypoints does.
//
// Nothing of the detector loads with the page: its worker starts the first time a photo is
// opened (its scripts, WebAssembly and model, about 16 MB, then come from the browser's cache).

import { describe } from "./common.js";
import { showProgress, hideProgress, warmJobs } from "./loading.js";

// The photo behind the viewport is scaled down to fit a texture the viewport can take
// (WebGL2's smallest guaranteed limit).
const MAX_REFERENCE_SIDE = 2048;

// The photo picker, made the first time it is asked for (the page's other file input stays
// the only one until then).
let input = null;

let worker = null;
let nextRequest = 0;
const pending = new Map();

function detector() {
  if (worker) return worker;
  worker = new Worker(new URL("./photo-worker.js", import.meta.url));
  worker.onmessage = ({ data }) => {
    pending.get(data.id)?.(data);
    pending.delete(data.id);
  };
  worker.onerror = (event) => {
    event.preventDefault?.();
    const error = event.message || "the detector's worker failed";
    for (const resolve of pending.values()) resolve({ error });
    pending.clear();
    worker = null;
  };
  return worker;
}

function detect(bitmap) {
  const id = nextRequest++;
  return new Promise((resolve) => {
    pending.set(id, resolve);
    detector().postMessage({ type: "detect", id, bitmap }, [bitmap]);
  });
}

// The photo as RGBA8 pixels, scaled to fit MAX_REFERENCE_SIDE.
function referencePixels(bitmap) {
  const scale = Math.min(1, MAX_REFERENCE_SIDE / Math.max(bitmap.width, bitmap.height));
  const width = Math.max(1, Math.round(bitmap.width * scale));
  const height = Math.max(1, Math.round(bitmap.height * scale));
  const canvas = new OffscreenCanvas(width, height);
  const context = canvas.getContext("2d", { willReadFrequently: true });
  context.drawImage(bitmap, 0, 0, width, height);
  const { data } = context.getImageData(0, 0, width, height);
  return { width, height, rgba: new Uint8Array(data.buffer, data.byteOffset, data.byteLength) };
}

// Opens `file` as a photo for the editor `handle`.
export async function openPhoto(handle, file) {
  const name = file.name;
  const started = performance.now();
  performance.mark("stance:photo-picked");
  showProgress(`Finding the person in ${name}…`);
  // The lift's worker starts meanwhile: the first photo's lift does not wait for it.
  warmJobs("lift");
  try {
    let bitmap;
    try {
      bitmap = await createImageBitmap(file);
    } catch (error) {
      handle.photo_failed(name, `it is not an image this browser can decode (${describe(error)})`);
      return;
    }
    const { width, height } = bitmap;
    const reference = referencePixels(bitmap);
    // The detector sees the photo at the reference's size too (its landmarks are fractions of
    // the picture; its own input is 256 px): a large photo would not fit the worker's WebGL
    // texture. The bitmap goes to the worker (transferred, not copied).
    let seen = bitmap;
    if (reference.width !== width || reference.height !== height) {
      seen = await createImageBitmap(bitmap, {
        resizeWidth: reference.width, resizeHeight: reference.height, resizeQuality: "high",
      });
      bitmap.close();
    }
    const decodedMs = performance.now() - started;
    const reply = await detect(seen);
    if (reply.error) {
      handle.photo_failed(name, `the pose detector could not run: ${reply.error}`);
      return;
    }
    if (!reply.landmarks) {
      handle.photo_failed(name, "no person was found in it");
      return;
    }
    const detectMs = performance.now() - started;
    console.log(`photo ${name} (${width}x${height}): decoded in ${decodedMs.toFixed(0)} ms, `
      + `the person found in ${reply.ms.toFixed(0)} ms in the worker (its start ${reply.startMs.toFixed(0)} ms)`);
    performance.mark("stance:photo-detected");
    handle.photo_detected(name, width, height, reply.landmarks, reference.rgba, reference.width,
      reference.height, detectMs);
  } catch (error) {
    handle.photo_failed(name, describe(error));
  } finally {
    hideProgress();
  }
}

// stanceHost.pickPhoto: the picker for File > Open photo….
export function pickPhoto(handle) {
  if (!input) {
    input = document.createElement("input");
    input.type = "file";
    input.accept = "image/*";
    input.hidden = true;
    input.id = "photo-input";
    document.body.append(input);
  }
  input.value = "";
  input.onchange = () => {
    const [file] = input.files;
    if (file) openPhoto(handle, file);
  };
  input.click();
}
