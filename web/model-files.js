// What the page and its decode worker both need to know about file names.

// A glTF, GLB or VRM by its name (a URL's query and fragment left out).
export function isModel(name) {
  return /\.(glb|vrm|gltf)$/i.test(name.split(/[?#]/)[0]);
}
