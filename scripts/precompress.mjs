// Writes FILE.br (brotli) and FILE.gz (gzip -9) next to each file given, when missing or older
// than the file: scripts/serve.mjs sends them to browsers that accept them.
// Usage: node scripts/precompress.mjs FILE...
import { brotliCompressSync, constants, gzipSync } from "node:zlib";
import { readFileSync, statSync, writeFileSync } from "node:fs";

const newer = (a, b) => {
  try {
    return statSync(a).mtimeMs > statSync(b).mtimeMs;
  } catch {
    return true;
  }
};

for (const file of process.argv.slice(2)) {
  if (!newer(file, `${file}.br`) && !newer(file, `${file}.gz`)) continue;
  const bytes = readFileSync(file);
  // Brotli quality 9: within 15 % of quality 11's size, about 13 times faster to write.
  writeFileSync(`${file}.br`, brotliCompressSync(bytes, {
    params: {
      [constants.BROTLI_PARAM_QUALITY]: 9,
      [constants.BROTLI_PARAM_SIZE_HINT]: bytes.length,
    },
  }));
  writeFileSync(`${file}.gz`, gzipSync(bytes, { level: 9 }));
}
