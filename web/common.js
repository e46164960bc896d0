// What the page's modules and its loading worker share.

// The byte arrays one after the other in one array.
export function concat(arrays) {
  const all = new Uint8Array(arrays.reduce((sum, bytes) => sum + bytes.length, 0));
  let offset = 0;
  for (const bytes of arrays) {
    all.set(bytes, offset);
    offset += bytes.length;
  }
  return all;
}

// An error (or a rejection's reason) in words.
export function describe(error) {
  if (error === undefined || error === null) return "unknown error";
  if (typeof error === "string") return error;
  return error.message || String(error);
}
