// A small static server for dist/ (no dependencies): `node scripts/serve.mjs [port]`.
// Also imported by the end-to-end tests, which start it on a free port.
import { createServer } from "node:http";
import { readFile, stat } from "node:fs/promises";
import { extname, join, normalize, resolve } from "node:path";
import { fileURLToPath } from "node:url";

const root = resolve(fileURLToPath(new URL("../dist", import.meta.url)));
const types = {
  ".html": "text/html; charset=utf-8", ".js": "text/javascript; charset=utf-8",
  ".mjs": "text/javascript; charset=utf-8", ".css": "text/css; charset=utf-8",
  ".wasm": "application/wasm", ".json": "application/json", ".svg": "image/svg+xml",
  ".png": "image/png", ".jpg": "image/jpeg", ".glb": "model/gltf-binary",
  ".gltf": "model/gltf+json", ".vrm": "model/gltf-binary", ".txt": "text/plain; charset=utf-8",
};

export function startServer(port = 0, host = "127.0.0.1") {
  const server = createServer(async (request, response) => {
    try {
      const url = new URL(request.url, "http://localhost");
      let path = normalize(decodeURIComponent(url.pathname)).replace(/^([/\\])+/, "");
      if (path === "" || path.endsWith("/")) path += "index.html";
      const file = join(root, path);
      if (!file.startsWith(root)) throw Object.assign(new Error("outside"), { code: "ENOENT" });
      const info = await stat(file);
      if (!info.isFile()) throw Object.assign(new Error("not a file"), { code: "ENOENT" });
      // A precompressed copy (written by scripts/precompress.mjs) where the browser takes it.
      const accepted = String(request.headers["accept-encoding"] ?? "");
      let encoding = null;
      for (const [name, suffix] of [["br", ".br"], ["gzip", ".gz"]]) {
        if (encoding || !new RegExp(`\\b${name}\\b`).test(accepted)) continue;
        const copy = await stat(file + suffix).catch(() => null);
        if (copy?.isFile() && copy.mtimeMs >= info.mtimeMs) encoding = [name, suffix];
      }
      const body = await readFile(encoding ? file + encoding[1] : file);
      response.writeHead(200, {
        "Content-Type": types[extname(file)] ?? "application/octet-stream",
        "Cache-Control": "no-cache",
        "Vary": "Accept-Encoding",
        ...(encoding ? { "Content-Encoding": encoding[0] } : {}),
      });
      response.end(body);
    } catch (error) {
      response.writeHead(error.code === "ENOENT" ? 404 : 500, { "Content-Type": "text/plain" });
      response.end(error.code === "ENOENT" ? "not found" : "server error");
    }
  });
  return new Promise((resolvePromise) => {
    server.listen(port, host, () => resolvePromise(server));
  });
}

if (process.argv[1] && resolve(process.argv[1]) === fileURLToPath(import.meta.url)) {
  const port = Number(process.argv[2] ?? process.env.PORT ?? 8080);
  const server = await startServer(port);
  const { port: actual } = server.address();
  console.log(`Stance is running at http://localhost:${actual}/  (Ctrl+C to stop)`);
}
