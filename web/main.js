// Starts the Stance editor (Rust compiled to WebAssembly) on the page's canvas, and shows a
// readable error screen instead of a blank page when it cannot start.
import init, { WebHandle } from "./pkg/stance_web.js";
import { connectSensor, disconnectSensor } from "./sensors.js";
import {
  cancelJob, fetchWithProgress, importAvatar, runJob, openFiles, startImporter, uploadAvatar,
} from "./loading.js";
import { createAccessibilityMirror } from "./accessibility.js";
import { pickPhoto } from "./photo.js";
import { describe } from "./common.js";

const loading = document.getElementById("loading");
const errorScreen = document.getElementById("error");
const errorMessage = document.getElementById("error-message");

// Graphics failures come from wgpu in its own words; say first what they mean to a user.
const GRAPHICS_FAILURE = /surface|adapter|webgl|webgpu|getContext|wgpu/i;

function showError(message) {
  loading.hidden = true;
  if (GRAPHICS_FAILURE.test(message)) {
    message = `Neither WebGPU nor WebGL2 could start in this browser. (Details: ${message})`;
  }
  errorMessage.textContent = message;
  errorScreen.hidden = false;
  document.body.dataset.error = message;
  console.warn("Stance could not start:", message);
}

// The browser services the editor asks for (see crates/stance_web/src/web.rs).
const fileInput = document.createElement("input");
fileInput.type = "file";
fileInput.accept = ".json,application/json,.glb,.gltf,.vrm,.bvh,.bin,.fob,.txt,.log";
fileInput.hidden = true;
// A .gltf is picked together with its .bin and images.
fileInput.multiple = true;
document.body.append(fileInput);

// egui's widgets as DOM elements for screen readers and keyboards (web/accessibility.js).
const accessibility = createAccessibilityMirror(
  document.getElementById("stance-canvas"),
  (id, action, value) => window.stance?.accessibility_action(id, action, value ?? undefined),
);

window.stanceHost = {
  loadText(key) {
    try {
      return window.localStorage.getItem(key);
    } catch {
      return null;
    }
  },
  saveText(key, text) {
    window.localStorage.setItem(key, text);
  },
  // Puts the posture link in the address bar without reloading; returns the whole link.
  shareLink(fragment) {
    const url = new URL(window.location.href);
    url.hash = fragment;
    ignoreNextHashChange = url.hash;
    window.history.replaceState(null, "", url);
    return url.href;
  },
  download(fileName, text) {
    offerDownload(fileName, new Blob([text], { type: "application/json" }));
  },
  // Binary files (sensor recordings, posed avatars).
  downloadBytes(fileName, bytes) {
    offerDownload(fileName, new Blob([bytes], { type: "application/octet-stream" }));
  },
  // Motion-capture sensors over WebSerial / WebHID (web/sensors.js).
  connectSensor(requestJson) {
    if (!window.stance) throw new Error("the editor is not running");
    connectSensor(window.stance, requestJson);
  },
  disconnectSensor() {
    disconnectSensor();
  },
  // The editor's accessibility tree changed (JSON, see web/accessibility.js).
  accessibility(treeJson) {
    accessibility.update(treeJson);
  },
  pickFile() {
    fileInput.value = "";
    fileInput.click();
  },
  // File > Open photo…: the picker, then the page's pose detector (see photo.js).
  pickPhoto() {
    if (!window.stance) throw new Error("the editor is not running");
    pickPhoto(window.stance);
  },
  // Fetches an avatar with a progress bar; its textures are decoded off the main thread and
  // the bytes go to the editor.
  fetchFile(url) {
    if (!window.stance) throw new Error("the editor is not running");
    fetchWithProgress(window.stance, url);
  },
  // Steps an avatar's upload to the GPU in tasks of the page's own (see loading.js).
  uploadAvatar() {
    if (!window.stance) return false;
    return uploadAvatar(window.stance);
  },
  // Imports an avatar file in the loading worker; false when it cannot (see loading.js).
  importAvatar(name, names, lengths, bytes) {
    if (!window.stance) return false;
    return importAvatar(window.stance, name, names, lengths, bytes);
  },
  // Runs a job (a clip read and retargeted, keypoints lifted) in a loading worker; false
  // when it cannot (see loading.js).
  runJob(kind, id, job) {
    if (!window.stance) return false;
    return runJob(window.stance, kind, id, job);
  },
  cancelJob(id) {
    cancelJob(id);
  },
};

// The editor's WebAssembly, compiled once: the page runs it, and the loading worker runs the
// same module to import avatars.
async function compileEditor() {
  const url = new URL("./pkg/stance_web_bg.wasm", import.meta.url);
  try {
    return await WebAssembly.compileStreaming(fetch(url));
  } catch {
    // A server that does not say application/wasm.
    const response = await fetch(url);
    if (!response.ok) throw new Error(`${url.pathname}: the server answered ${response.status}`);
    return WebAssembly.compile(await response.arrayBuffer());
  }
}

function offerDownload(fileName, blob) {
  const anchor = document.createElement("a");
  anchor.href = URL.createObjectURL(blob);
  anchor.download = fileName;
  document.body.append(anchor);
  anchor.click();
  anchor.remove();
  setTimeout(() => URL.revokeObjectURL(anchor.href), 10000);
}

let ignoreNextHashChange = null;

// The files of a drop, folders walked (their files named with their path in the folder).
async function droppedFiles(dataTransfer) {
  const entries = [...(dataTransfer.items || [])]
    .map((item) => item.webkitGetAsEntry?.())
    .filter(Boolean);
  if (!entries.some((entry) => entry.isDirectory)) {
    return [...dataTransfer.files].map((file) => ({ file, path: null }));
  }
  const out = [];
  const walk = async (entry) => {
    if (entry.isFile) {
      const file = await new Promise((resolve, reject) => entry.file(resolve, reject));
      out.push({ file, path: entry.fullPath.replace(/^\//, "") });
    } else if (entry.isDirectory) {
      const reader = entry.createReader();
      for (;;) {
        const batch = await new Promise((resolve, reject) => reader.readEntries(resolve, reject));
        if (!batch.length) break;
        for (const child of batch) await walk(child);
      }
    }
  };
  for (const entry of entries) await walk(entry);
  return out;
}

function connectPage(handle) {
  fileInput.addEventListener("change", () =>
    openFiles(handle, [...fileInput.files].map((file) => ({ file, path: null }))));
  window.addEventListener("dragover", (event) => event.preventDefault());
  window.addEventListener("drop", (event) => {
    event.preventDefault();
    if (!event.dataTransfer?.files?.length) return;
    // The entries must be taken before the event returns.
    droppedFiles(event.dataTransfer).then(
      (files) => openFiles(handle, files),
      (error) => handle.report_failure(`the dropped files could not be read: ${describe(error)}`),
    );
  });
  // A posture link pasted into the address bar of an open editor.
  window.addEventListener("hashchange", () => {
    if (window.location.hash === ignoreNextHashChange) return;
    handle.open_link(window.location.hash.slice(1));
  });
}


async function main() {
  if (typeof WebAssembly !== "object") {
    showError("This browser has no WebAssembly.");
    return;
  }
  let module;
  try {
    module = await compileEditor();
    await init({ module_or_path: module });
  } catch (error) {
    showError(`The editor's code could not load: ${describe(error)}`);
    return;
  }
  const handle = new WebHandle();
  window.stance = handle;
  // The loading workers start with the editor: the autosave's clip, asked for as the editor
  // starts, is read and retargeted in one of them.
  startImporter(module);
  try {
    await handle.start(
      document.getElementById("stance-canvas"),
      window.location.hash.slice(1),
    );
  } catch (error) {
    showError(describe(error));
    return;
  }
  connectPage(handle);
  // ?avatar=URL opens that avatar.
  const avatarUrl = new URLSearchParams(window.location.search).get("avatar");
  if (avatarUrl) window.stanceHost.fetchFile(avatarUrl);
  // A crash after start: show it rather than a frozen canvas.
  const watchdog = setInterval(() => {
    const panic = handle.panic_message();
    if (panic) {
      clearInterval(watchdog);
      showError(`The editor stopped: ${panic}`);
    }
  }, 1000);
}

main();
