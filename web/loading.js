// Opening files and fetched avatars without blocking the page: files are read and fetched
// with a progress bar. Two Web Workers (load-worker.js) take the work off the main thread:
// one decodes the base-colour textures of a glTF, GLB or VRM with the browser's decoders;
// the other, once it holds the editor's WebAssembly module, imports the avatars the editor
// asks for (stanceHost.importAvatar) meanwhile, leaving those textures' pixels to follow, so
// that the main thread only receives the imported avatar and uploads it to the GPU in tasks
// of its own (stanceHost.uploadAvatar). Before that (or where no worker can run) the editor
// receives the file with its decoded pixels and imports it itself. A third one, with the
// same module, runs the editor's jobs (stanceHost.runJob): reads and retargets the clip files
// it asks for, its progress going to the editor as it goes; a fourth lifts keypoints (File >
// Open keypoints, a depth flip): one worker per kind of job, so that one does not cancel the
// other. Cancel (stanceHost.cancelJob) stops a job (its worker is ended; the next job of its
// kind starts another).

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

let workerImports = false;
// A loading worker said it cannot run the editor's code: none will.
let workersFailed = false;

// A loading worker (load-worker.js) and its requests, answered by id; null where none can run.
function startWorker(onReady) {
  let worker;
  try {
    worker = new Worker(new URL("./load-worker.js", import.meta.url), { type: "module" });
  } catch {
    return null;
  }
  const pending = new Map();
  const progress = new Map();
  let nextRequest = 0;
  worker.onmessage = ({ data }) => {
    if (data.type === "ready") {
      onReady?.(data);
      return;
    }
    if (data.type === "progress") {
      progress.get(data.id)?.(data.fraction);
      return;
    }
    progress.delete(data.id);
    pending.get(data.id)?.(data);
    pending.delete(data.id);
  };
  worker.onerror = (event) => {
    console.warn("a loading worker failed:", event.message);
    onReady?.({ ok: false, error: event.message });
    for (const resolve of pending.values()) resolve(null);
    pending.clear();
  };
  return {
    post: (message) => worker.postMessage(message),
    // `onProgress`: called with what the worker reports of this request before its reply.
    request(message, transfer = [], onProgress = null) {
      const id = nextRequest++;
      if (onProgress) progress.set(id, onProgress);
      return new Promise((resolve) => {
        pending.set(id, resolve);
        worker.postMessage({ ...message, id }, transfer);
      });
    },
    // Ends the worker: its requests under way resolve with null.
    stop() {
      worker.terminate();
      for (const resolve of pending.values()) resolve(null);
      pending.clear();
      progress.clear();
    },
  };
}

// Two workers: one imports avatars with the editor's module, the other decodes textures
// meanwhile (undefined: not started yet).
let importer;
let decoder;

function loader() {
  if (importer === undefined) {
    importer = startWorker((ready) => {
      workerImports = ready.ok;
      workersFailed = !ready.ok;
      if (!ready.ok) console.warn("the loading worker cannot import avatars:", ready.error);
    });
  }
  return importer;
}

function textureDecoder() {
  if (decoder === undefined) decoder = startWorker(null);
  return decoder;
}

// The textures of the model file last handed to the editor, decoding in the worker while the
// editor looks at the file: its import request (if it comes) takes them.
let prefetched = null;

// The editor's compiled module, for the workers that run its code.
let editorModule = null;

// Gives the loading worker the editor's compiled module: from then on it imports avatars.
// The texture decoder starts with it, so that the first file does not wait for a worker to
// load (a few hundred ms while the page is busy).
export function startImporter(module) {
  editorModule = module;
  loader()?.post({ type: "init", module });
  textureDecoder();
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
  const decoding = prefetched?.name === name ? prefetched.decoding : null;
  prefetched = null;
  importWith(loader(), files, decoding).then((reply) => {
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

// The import of `files` in the worker. Where the page is decoding their textures
// (`decoding`), the import runs meanwhile without those pixels, and the decoded images fill
// its textures once both are done.
async function importWith(worker, files, decoding) {
  performance.mark("stance:import-requested");
  if (!decoding) return worker.request({ type: "import", files });
  const [reply, decoded] = await Promise.all([
    worker.request({ type: "import", files, follow: true }),
    decoding,
  ]);
  if (!reply?.avatar) return reply;
  const filled = fillTextures(reply, decoded);
  if (filled) return filled;
  // A texture the browser could not decode: the importer decodes it itself and names what is
  // wrong with it.
  const images = decoded?.images ?? null;
  return worker.request({ type: "import", files, images }, (images ?? []).map((i) => i.rgba.buffer));
}

// The worker's reply with the textures whose pixels follow (empty, of a size) filled by the
// decoded images; null where one is missing or of another size.
function fillTextures(reply, decoded) {
  const given = new Set();
  const pixels = reply.pixels.map((own, i) => {
    const [image, width, height] = reply.textures.subarray(3 * i, 3 * i + 3);
    if (own.length > 0) return own;
    const found = decoded?.images.find((d) => d.index === image && d.width === width && d.height === height);
    if (!found) return null;
    // An image shown by two textures travels twice.
    const rgba = given.has(found) ? found.rgba.slice() : found.rgba;
    given.add(found);
    return rgba;
  });
  if (pixels.includes(null)) return null;
  return { ...reply, pixels, imagesFromHost: reply.imagesFromHost + given.size };
}

let delivery = Promise.resolve();

// The progress bar for the page's other work (photo.js: a photo's detection): a busy bar
// saying `text`, then hidden as after a load.
export function showProgress(text) {
  progress(text);
}

export function hideProgress() {
  done();
}

// The workers that run the editor's jobs, one per kind ("clip", "lift"): each with its worker
// (undefined: none started; null: none can run) and the editor's request it works on.
const lanes = new Map();

function lane(kind) {
  if (!lanes.has(kind)) lanes.set(kind, { worker: undefined, request: null });
  const it = lanes.get(kind);
  if (it.worker === undefined) {
    it.worker = startWorker(null);
    it.worker?.post({ type: "init", module: editorModule });
  }
  return it;
}

// Starts the worker of the jobs of `kind` if none is, so that a job asked for later does not
// wait for it to load and instantiate the editor's module (a photo's lift: started while the
// detector looks at the photo).
export function warmJobs(kind) {
  if (editorModule && !workersFailed) lane(kind);
}

// stanceHost.runJob: the editor asks for the job `job` (stance_model::HostJob as bytes: a clip
// file with the body and the settings, or keypoints to lift) of kind `kind` to run off the
// main thread, as its request `id`. The progress goes to the editor as it comes; the result
// in parts, each in a task of its own (the frames of a long clip are tens of megabytes).
// False when no worker can: the editor does it itself. While the first worker is still
// starting (the autosave's clip, asked for as the editor starts) the request goes to the
// kind's worker, which takes it once it has compiled the editor's code.
export function runJob(handle, kind, id, job) {
  if (!editorModule || workersFailed) return false;
  // Another job of this kind asked for: the one under way is not wanted any more.
  const previous = lanes.get(kind)?.request;
  if (previous != null) cancelJob(previous);
  const it = lane(kind);
  if (!it.worker) return false;
  it.request = id;
  performance.mark(`stance:${kind}-requested`);
  // A lift's busy bar is the page's (the editor's strip has no spinner: its animation would
  // keep the editor drawing, and the reply would wait for its frames).
  if (kind === "lift") progress("Lifting the keypoints…");
  // A copy: `job` is a view of the editor's memory.
  const bytes = job.slice();
  it.worker.request({ type: "job", job: bytes }, [bytes.buffer], (fraction) => {
    if (it.request === id) timed(`stance:${kind}-progress`, () => handle.job_progress(id, fraction));
  }).then((reply) => {
    // (The end-to-end tests time the clip's trip by these marks.)
    performance.mark(kind === "clip" ? "stance:clip-retargeted" : `stance:${kind}-done`);
    delivery = delivery.then(async () => {
      if (it.request !== id) {
        // Cancelled, no other lift asked for since: its busy bar goes.
        if (kind === "lift" && it.request === null) done();
        return;
      }
      try {
        if (reply?.parts) {
          const [head, ...parts] = reply.parts;
          timed(`stance:${kind}-head`, () => handle.job_head(id, head));
          // Cancelled meanwhile: the parts taken so far are let go (the editor ignores the
          // reply to a request it cancelled).
          const dropped = () => handle.job_failed(id, "cancelled");
          for (const part of parts) {
            await nextTask();
            if (it.request !== id) return dropped();
            timed(`stance:${kind}-part`, () => handle.job_part(id, part));
          }
          // A result in one part (a lift) is done at once: a task's wait here is an editor's
          // frame (hundreds of ms in software GL).
          if (parts.length > 0) await nextTask();
          if (it.request !== id) return dropped();
          it.request = null;
          timed(`stance:${kind}-opened`, () => handle.job_done(id));
          console.log(`${kind} job ${id} done in the worker in ${reply.ms.toFixed(0)} ms`);
        } else {
          it.request = null;
          handle.job_failed(id, reply?.error ?? "the loading worker stopped");
        }
      } catch (error) {
        it.request = null;
        handle.job_failed(id, describe(error));
      } finally {
        if (kind === "lift") done();
      }
    });
  });
  return true;
}

// Runs `work` (a call into the editor) as a performance measure named `name`: the tests
// tell the page's own tasks from the editor's frames by them.
function timed(name, work) {
  const start = performance.now();
  try {
    work();
  } finally {
    performance.measure(name, { start });
  }
}

// stanceHost.cancelJob: the editor no longer wants its request `id`: the worker working on
// it is ended (its steps run without a break), and the next job of its kind starts another.
export function cancelJob(id) {
  for (const it of lanes.values()) {
    if (it.request !== id) continue;
    it.request = null;
    it.worker?.stop();
    it.worker = undefined;
  }
}

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
    if (more) {
      channel.port2.postMessage(null);
    } else {
      channel.port1.close();
      // The editor's next frame draws the avatar (its repaint is asked): marked once that
      // frame's work is done.
      requestAnimationFrame(() => setTimeout(() => performance.mark("stance:avatar-shown"), 0));
    }
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
  const worker = textureDecoder();
  if (!worker || !files.some((f) => isModel(f.name))) {
    return Promise.resolve(null);
  }
  return worker.request({ type: "decode", files }).then((decoded) => {
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
    timed("stance:open-file", () => handle.open_file(files[0].name, files[0].bytes));
  } else if (files.length > 1) {
    const lengths = new Uint32Array(files.map((f) => f.bytes.length));
    handle.open_files(files.map((f) => f.name), lengths, concat(files.map((f) => f.bytes)));
  }
}

// Files picked or dropped: one opens as it is; several together (a .gltf with its .bin and
// images, a folder) go to the editor as one set, so that the .gltf finds its resources.
export async function openFiles(handle, files) {
  performance.mark("stance:files-picked");
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
