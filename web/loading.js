// Opening files and fetched avatars without blocking the page: files are read and fetched
// with a progress bar, and a worker (load-worker.js) decodes the textures of a glTF, GLB or
// VRM with the browser's decoders. Once it holds the editor's WebAssembly module it also
// imports the avatars the editor asks for (stanceHost.importAvatar), so that the main thread
// only receives the imported avatar; before that (or where no worker can run) the editor
// receives the file with its decoded pixels and imports it itself.

import { isModel } from "./model-files.js";
import { concat, describe } from "./common.js";

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

// Imports under way in the worker: the bar stays until they are back.
let importing = 0;

// Hidden once the editor has taken the files (its own import runs in its next frame) and the
// worker's imports are back.
function done() {
  requestAnimationFrame(() => requestAnimationFrame(() => {
    if (importing === 0) bar.hidden = true;
  }));
}

let worker = null;
let workerImports = false;
let nextRequest = 0;
const pending = new Map();

function loader() {
  if (worker === null) {
    try {
      worker = new Worker(new URL("./load-worker.js", import.meta.url), { type: "module" });
      worker.onmessage = ({ data }) => {
        if (data.type === "ready") {
          workerImports = data.ok;
          if (!data.ok) console.warn("the loading worker cannot import avatars:", data.error);
          return;
        }
        pending.get(data.id)?.(data);
        pending.delete(data.id);
      };
      worker.onerror = (event) => {
        console.warn("the loading worker failed:", event.message);
        workerImports = false;
        for (const resolve of pending.values()) resolve(null);
        pending.clear();
      };
    } catch {
      worker = undefined;
    }
  }
  return worker || null;
}

function request(message, transfer = []) {
  const id = nextRequest++;
  return new Promise((resolve) => {
    pending.set(id, resolve);
    worker.postMessage({ ...message, id }, transfer);
  });
}

// The textures of the model file last handed to the editor, decoding in the worker while the
// editor looks at the file: its import request (if it comes) takes them.
let prefetched = null;

// Gives the loading worker the editor's compiled module: from then on it imports avatars.
export function startImporter(module) {
  loader()?.postMessage({ type: "init", module });
}

// stanceHost.importAvatar: the editor asks for `name` (with its resources, `lengths[i]`
// bytes each, one after the other in `bytes`) to be imported off the main thread. False when
// the worker cannot: the editor imports it itself.
export function importAvatar(handle, name, names, lengths, bytes) {
  if (!workerImports || !loader()) return false;
  const files = [];
  let offset = 0;
  names.forEach((fileName, i) => {
    // A copy: `bytes` is a view of the editor's memory, which posting would copy whole.
    files.push({ name: fileName, bytes: bytes.slice(offset, offset + lengths[i]) });
    offset += lengths[i];
  });
  importing += 1;
  progress(`Importing ${name.split("/").pop()}…`);
  const decoding = prefetched?.name === name ? prefetched.decoding : Promise.resolve(null);
  prefetched = null;
  decoding.then((decoded) => {
    const images = decoded?.file === name ? decoded.images : null;
    return request({ type: "import", files, images }, (images ?? []).map((i) => i.rgba.buffer));
  }).then((reply) => {
    performance.mark("stance:avatar-imported");
    // One reply at a time reaches the editor, each texture in a task of its own: a 2048x2048
    // texture is 16 MB to copy into the editor's memory.
    delivery = delivery.then(async () => {
      try {
        if (reply?.avatar) {
          for (const pixels of reply.pixels) {
            handle.avatar_texture(pixels);
            await nextTask();
          }
          handle.avatar_imported(name, reply.avatar, reply.importMs, reply.imagesFromHost);
        } else {
          handle.avatar_import_failed(name, reply?.error ?? "the loading worker stopped");
        }
      } catch (error) {
        handle.avatar_import_failed(name, describe(error));
      } finally {
        importing -= 1;
        done();
      }
    });
  });
  return true;
}

let delivery = Promise.resolve();

// stanceHost.uploadAvatar: the editor began putting an avatar on the GPU. The page steps the
// upload (a few MB of texture per task, WebHandle.upload_avatar_step) in tasks back to back
// instead of the editor's frames: a frame that repaints the canvas can take a few hundred ms
// to come where the canvas is composited in software, and the upload would wait for each.
export function uploadAvatar(handle) {
  const channel = new MessageChannel();
  channel.port1.onmessage = () => {
    let more = false;
    try {
      more = handle.upload_avatar_step();
    } catch (error) {
      console.warn(`the avatar's upload: ${describe(error)}`);
    }
    if (more) channel.port2.postMessage(null);
    else channel.port1.close();
  };
  channel.port2.postMessage(null);
  return true;
}

function nextTask() {
  return new Promise((resolve) => setTimeout(resolve, 0));
}

// The texture images of the model among `files`, decoded off the main thread; null where no
// worker could do it (the editor then decodes them itself).
function decodeTextures(files) {
  if (!loader() || !files.some((f) => isModel(f.name))) {
    return Promise.resolve(null);
  }
  return request({ type: "decode", files }).then((decoded) => {
    performance.mark("stance:textures-decoded");
    return decoded;
  });
}

// Hands the decoded pixels to the editor (for the file they belong to), then the files.
// With an importing worker the editor asks for the import, which takes the textures the
// worker started decoding at once.
async function deliver(handle, files) {
  const model = files.find((f) => isModel(f.name));
  if (workerImports && model) {
    prefetched = { name: model.name, decoding: decodeTextures(files) };
  } else if (model) {
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
