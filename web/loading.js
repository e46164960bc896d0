// Opening files and fetched avatars without blocking the page: files are read and fetched
// with a progress bar, the textures of a glTF, GLB or VRM are decoded by the browser in a
// worker (decode-worker.js), and the editor receives the bytes with the decoded pixels.

import { isModel } from "./model-files.js";

const bar = document.createElement("div");
bar.id = "progress";
bar.hidden = true;
bar.setAttribute("role", "status");
bar.setAttribute("aria-live", "polite");
const meter = document.createElement("progress");
meter.max = 1;
const label = document.createElement("span");
bar.append(meter, label);
document.body.append(bar);

// One load at a time shows its progress; `value` undefined shows a busy bar.
function progress(text, value) {
  bar.hidden = false;
  label.textContent = text;
  if (value === undefined) meter.removeAttribute("value");
  else meter.value = value;
}

// Hidden once the editor has taken the files: its import runs in its next frame.
function done() {
  requestAnimationFrame(() => requestAnimationFrame(() => { bar.hidden = true; }));
}

// The byte arrays one after the other in one array.
function concat(arrays) {
  const all = new Uint8Array(arrays.reduce((sum, bytes) => sum + bytes.length, 0));
  let offset = 0;
  for (const bytes of arrays) {
    all.set(bytes, offset);
    offset += bytes.length;
  }
  return all;
}

function describe(error) {
  if (error === undefined || error === null) return "unknown error";
  if (typeof error === "string") return error;
  return error.message || String(error);
}

let worker = null;
let nextRequest = 0;
const pending = new Map();

function decoder() {
  if (worker === null) {
    try {
      worker = new Worker(new URL("./decode-worker.js", import.meta.url), { type: "module" });
      worker.onmessage = ({ data }) => {
        pending.get(data.id)?.(data);
        pending.delete(data.id);
      };
      worker.onerror = () => {
        for (const resolve of pending.values()) resolve(null);
        pending.clear();
      };
    } catch {
      worker = undefined;
    }
  }
  return worker || null;
}

// The texture images of the model among `files`, decoded off the main thread; null where no
// worker could do it (the editor then decodes them itself).
function decodeTextures(files) {
  const decoderWorker = decoder();
  if (!decoderWorker || !files.some((f) => isModel(f.name))) {
    return Promise.resolve(null);
  }
  const id = nextRequest++;
  return new Promise((resolve) => {
    pending.set(id, resolve);
    decoderWorker.postMessage({ id, files });
  });
}

// Hands the decoded pixels to the editor (for the file they belong to), then the files.
async function deliver(handle, files) {
  if (files.some((f) => isModel(f.name))) {
    progress("Decoding textures…");
    const decoded = await decodeTextures(files);
    if (decoded?.file && decoded.images.length) {
      const { images } = decoded;
      handle.decoded_images(
        decoded.file,
        new Uint32Array(images.map((i) => i.index)),
        new Uint32Array(images.map((i) => i.width)),
        new Uint32Array(images.map((i) => i.height)),
        concat(images.map((i) => i.rgba)),
      );
    }
    progress("Building the avatar…");
  }
  if (files.length === 1) {
    handle.open_file(files[0].name, files[0].bytes);
  } else if (files.length > 1) {
    const lengths = new Uint32Array(files.map((f) => f.bytes.length));
    handle.open_files(files.map((f) => f.name), lengths, concat(files.map((f) => f.bytes)));
  }
}

// Files picked or dropped: one opens as it is; several together (a .gltf with its .bin and
// images, a folder) go to the editor as one set, so that the .gltf finds its resources.
export async function openFiles(handle, files) {
  const read = [];
  const size = files.reduce((sum, { file }) => sum + file.size, 0) || 1;
  let loaded = 0;
  try {
    for (const { file, path } of files) {
      progress(`Reading ${file.name}…`, loaded / size);
      try {
        read.push({ name: path || file.name, bytes: new Uint8Array(await file.arrayBuffer()) });
      } catch (error) {
        handle.report_failure(`${file.name} could not be read: ${describe(error)}`);
      }
      loaded += file.size;
    }
    await deliver(handle, read);
  } finally {
    done();
  }
}

// Fetches an avatar with its progress; the bytes go to the editor.
export async function fetchWithProgress(handle, url) {
  try {
    progress("Loading avatar…");
    const response = await fetch(url);
    if (!response.ok) throw new Error(`the server answered ${response.status} ${response.statusText}`);
    const total = Number(response.headers.get("content-length")) || 0;
    const reader = response.body.getReader();
    const chunks = [];
    let received = 0;
    for (;;) {
      const { done: finished, value } = await reader.read();
      if (finished) break;
      chunks.push(value);
      received += value.length;
      if (total) progress(`Loading avatar… ${Math.round((100 * received) / total)} %`, received / total);
      else progress(`Loading avatar… ${(received / 1048576).toFixed(1)} MB`);
    }
    await deliver(handle, [{ name: url, bytes: concat(chunks) }]);
  } catch (error) {
    handle.report_failure(`The avatar at ${url} could not be loaded: ${describe(error)}`);
  } finally {
    done();
  }
}
