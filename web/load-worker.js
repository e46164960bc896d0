// The page's loading worker, off the main thread:
// - decodes the texture images of a glTF, GLB or VRM with the browser's own decoders
//   (createImageBitmap), so that the importer takes the RGBA pixels as they are instead of
//   decoding PNG, JPEG or WebP in WebAssembly;
// - and, once the page has given it the editor's compiled WebAssembly module, imports the
//   whole avatar (glTF parsing, meshopt, skins, the H-Anim mapping) with the editor's own
//   importer and returns it split for the trip: the avatar's bytes and each texture's pixels
//   (WebHandle.avatar_texture, then WebHandle.avatar_imported);
// - and runs the editor's jobs (stanceHost.runJob) with the editor's own code: reads and
//   retargets a clip file in steps, reporting its progress between them, and returns the
//   clip and its retargeting in parts of frames; or lifts keypoints, returned in one part
//   (WebHandle.job_head, job_part, job_done).
//
// In:  { type: "init", module }                      -> { type: "ready", ok, error }
//      { type: "decode", id, files: [{ name, bytes }] } -> { id, file, images, skipped }
//      { type: "import", id, files, images?, follow? }  -> { id, avatar, textures, pixels:
//                          [Uint8Array], importMs, imagesFromHost } or { id, error }
//      { type: "job", id, job: Uint8Array }            -> { type: "progress", id, fraction }...
//                          then { id, parts: [Uint8Array] (head, frames...), ms } or { id, error }
//      (images: those a "decode" request returned; follow: the page decodes them meanwhile
//      and fills the textures' empty pixels, textures giving image, width and height of
//      each; else they are decoded here first)
// Images: [{ index, width, height, rgba: Uint8Array }]. Whatever cannot be decoded here (no
// OffscreenCanvas, an unknown format, a missing file) is left out: the importer decodes it
// itself and names the problem.

import init, { import_avatar_file, run_job } from "./pkg/stance_web.js";
import { isModel } from "./model-files.js";
import { concat, describe } from "./common.js";

const GLB_MAGIC = 0x46546c67; // "glTF"
const JSON_CHUNK = 0x4e4f534a;
const BIN_CHUNK = 0x004e4942;
// Larger images are left to the importer, which refuses them by name.
const MAX_SIDE = 8192;

// The editor's module instantiated (a promise), once "init" came.
let initialized = null;

self.onmessage = async ({ data }) => {
  if (data.type === "init") {
    try {
      initialized = init({ module_or_path: data.module });
      await initialized;
      self.postMessage({ type: "ready", ok: true });
    } catch (error) {
      self.postMessage({ type: "ready", ok: false, error: describe(error) });
    }
    return;
  }
  const { id, files } = data;
  if (data.type === "job") {
    const reply = await runJob(id, data.job);
    self.postMessage(reply, reply.parts ? reply.parts.map((part) => part.buffer) : []);
    return;
  }
  if (data.type === "import") {
    // The images decoded before come with the import; with `follow`, the page is decoding
    // them meanwhile and the import leaves their pixels out; else they are decoded here.
    let images = data.images ?? [];
    let toFollow = [];
    try {
      if (data.follow) toFollow = textureImages(files).map((source) => source.index);
      else if (!data.images) images = (await decodeImages(files)).images;
    } catch {
      images = [];
      toFollow = [];
    }
    const reply = importAvatar(id, files, images, toFollow);
    const buffers = reply.avatar ? [reply.avatar, reply.textures, ...reply.pixels].map((part) => part.buffer) : [];
    self.postMessage(reply, buffers);
    return;
  }
  let decoded;
  try {
    decoded = await decodeImages(files);
  } catch (error) {
    decoded = { file: null, images: [], skipped: [describe(error)] };
  }
  const { file, images, skipped } = decoded;
  self.postMessage({ id, file, images, skipped }, images.map((image) => image.rgba.buffer));
};

// The avatar among `files` (the first) imported with the others as its resources, the
// images decoded and those whose pixels follow (`toFollow`, image indices); its transfer
// bytes, its textures (image, width, height each) and their pixels (empty where they follow),
// or the importer's words for what is wrong.
function importAvatar(id, files, images, toFollow) {
  const started = performance.now();
  try {
    const [avatar, textures, ...pixels] = import_avatar_file(
      files.map((f) => f.name),
      new Uint32Array(files.map((f) => f.bytes.length)),
      concat(files.map((f) => f.bytes)),
      new Uint32Array(images.map((i) => i.index)),
      new Uint32Array(images.map((i) => i.width)),
      new Uint32Array(images.map((i) => i.height)),
      concat(images.map((i) => i.rgba)),
      new Uint32Array(toFollow),
    );
    return {
      id, avatar, textures, pixels,
      importMs: performance.now() - started,
      // Those that follow count once the page has filled them.
      imagesFromHost: images.length,
    };
  } catch (error) {
    return { id, error: describe(error) };
  }
}

// The job `job` run (a clip read and retargeted, keypoints lifted), its progress posted as it
// goes (each whole per cent); the parts to hand over, or what is wrong.
async function runJob(id, job) {
  const started = performance.now();
  try {
    if (!initialized) throw new Error("the loading worker has no module");
    await initialized;
    let shown = -1;
    const parts = run_job(job, (fraction) => {
      const percent = Math.floor(fraction * 100);
      if (percent > shown) {
        shown = percent;
        self.postMessage({ type: "progress", id, fraction });
      }
    });
    return { id, parts, ms: performance.now() - started };
  } catch (error) {
    return { id, error: describe(error) };
  }
}

// The main file's JSON and binary chunk (GLB, VRM) or its JSON (.gltf).
function container(bytes) {
  const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  if (bytes.byteLength >= 20 && view.getUint32(0, true) === GLB_MAGIC) {
    let at = 12;
    let json = null;
    let bin = null;
    while (at + 8 <= bytes.byteLength) {
      const length = view.getUint32(at, true);
      const type = view.getUint32(at + 4, true);
      const chunk = bytes.subarray(at + 8, Math.min(at + 8 + length, bytes.byteLength));
      if (type === JSON_CHUNK && !json) json = JSON.parse(new TextDecoder().decode(chunk));
      else if (type === BIN_CHUNK && !bin) bin = chunk;
      at += 8 + length + ((4 - (length % 4)) % 4);
    }
    if (!json) throw new Error("no JSON chunk");
    return { json, bin };
  }
  return { json: JSON.parse(new TextDecoder().decode(bytes)), bin: null };
}

function dataUri(uri) {
  const match = /^data:([^;,]*)(;base64)?,(.*)$/s.exec(uri);
  if (!match) return null;
  if (!match[2]) return new TextEncoder().encode(decodeURIComponent(match[3]));
  const text = atob(match[3]);
  const out = new Uint8Array(text.length);
  for (let i = 0; i < text.length; i += 1) out[i] = text.charCodeAt(i);
  return out;
}

// A file of the set named by a relative URI (percent-encoded, maybe "./"), matched on its
// path's end as the importer does.
function resource(files, uri) {
  let path;
  try {
    path = decodeURIComponent(uri).replace(/^\.\//, "");
  } catch {
    return null;
  }
  const found = files.find((f) => f.name === path || f.name.endsWith(`/${path}`));
  return found ? found.bytes : null;
}

function bufferBytes(json, bin, files, index) {
  const buffer = json.buffers?.[index];
  if (!buffer) return null;
  if (buffer.uri === undefined) return bin;
  return dataUri(buffer.uri) ?? resource(files, buffer.uri);
}

function imageBytes(json, bin, files, image) {
  if (image.bufferView !== undefined) {
    const view = json.bufferViews?.[image.bufferView];
    if (!view || view.extensions?.EXT_meshopt_compression) return null;
    const bytes = bufferBytes(json, bin, files, view.buffer);
    const start = view.byteOffset || 0;
    if (!bytes || start + view.byteLength > bytes.byteLength) return null;
    return bytes.subarray(start, start + view.byteLength);
  }
  if (typeof image.uri === "string") return dataUri(image.uri) ?? resource(files, image.uri);
  return null;
}

function mimeOf(image, bytes) {
  if (image.mimeType) return image.mimeType;
  if (bytes[0] === 0x89 && bytes[1] === 0x50) return "image/png";
  if (bytes[0] === 0xff && bytes[1] === 0xd8) return "image/jpeg";
  if (bytes[8] === 0x57 && bytes[9] === 0x45 && bytes[10] === 0x42 && bytes[11] === 0x50) return "image/webp";
  return "";
}

async function decode(bytes, mime) {
  const bitmap = await createImageBitmap(new Blob([bytes], { type: mime }), {
    premultiplyAlpha: "none",
    colorSpaceConversion: "none",
  });
  try {
    const { width, height } = bitmap;
    if (width === 0 || height === 0 || width > MAX_SIDE || height > MAX_SIDE) return null;
    const canvas = new OffscreenCanvas(width, height);
    const context = canvas.getContext("2d", { willReadFrequently: true });
    context.drawImage(bitmap, 0, 0);
    const pixels = context.getImageData(0, 0, width, height).data;
    return { width, height, rgba: new Uint8Array(pixels.buffer, pixels.byteOffset, pixels.byteLength) };
  } finally {
    bitmap.close();
  }
}

// The images the base-colour textures of the model among `files` show (as the importer
// chooses them: a material's baseColorTexture, a VRM 0.x MToon's _MainTex; a WebP source of
// EXT_texture_webp in place of the fallback) whose bytes are at hand, as this worker can
// decode them: [{ index, image, bytes }]; none where it cannot decode. (The importer draws
// nothing else: normal or roughness maps are not worth decoding.)
function textureImages(files) {
  const main = files.find((f) => isModel(f.name));
  if (!main || typeof OffscreenCanvas !== "function" || typeof createImageBitmap !== "function") {
    return [];
  }
  const { json, bin } = container(main.bytes);
  const baseColour = new Set();
  for (const material of json.materials || []) {
    baseColour.add(material?.pbrMetallicRoughness?.baseColorTexture?.index);
  }
  for (const properties of json.extensions?.VRM?.materialProperties || []) {
    baseColour.add(properties?.textureProperties?._MainTex);
  }
  const used = new Set();
  for (const index of baseColour) {
    const texture = Number.isInteger(index) ? json.textures?.[index] : undefined;
    const webp = texture?.extensions?.EXT_texture_webp?.source;
    const source = Number.isInteger(webp) ? webp : texture?.source;
    if (Number.isInteger(source)) used.add(source);
  }
  return [...used].flatMap((index) => {
    const image = json.images?.[index];
    const bytes = image && imageBytes(json, bin, files, image);
    return bytes ? [{ index, image, bytes }] : [];
  });
}

async function decodeImages(files) {
  const main = files.find((f) => isModel(f.name));
  const skipped = [];
  const decoded = await Promise.all(textureImages(files).map(async ({ index, image, bytes }) => {
    try {
      const pixels = await decode(bytes, mimeOf(image, bytes));
      return pixels && { index, ...pixels };
    } catch (error) {
      skipped.push(`image ${index}: ${error?.message || error}`);
      return null;
    }
  }));
  return { file: main?.name ?? null, images: decoded.filter(Boolean), skipped };
}
