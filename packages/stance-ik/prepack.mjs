// `npm pack` and `npm publish` run this first (the package's prepack). Inside the Stance
// repository it builds the WebAssembly (scripts/build-package.sh: quick when nothing
// changed), so that a tarball always carries the pkg/ its index.js imports. A copy of this
// folder outside the repository cannot build: there it refuses to pack, naming what is
// missing, instead of making a tarball that installs and fails only at import.
import { execFileSync } from "node:child_process";
import { existsSync, readFileSync } from "node:fs";
import { dirname, join } from "node:path";
import { fileURLToPath } from "node:url";

const here = dirname(fileURLToPath(import.meta.url));
const root = join(here, "..", "..");
const build = join(root, "scripts", "build-package.sh");
if (existsSync(build) && existsSync(join(root, "crates", "stance_js"))) {
  execFileSync("bash", [build], { cwd: root, stdio: "inherit" });
}
const { files } = JSON.parse(readFileSync(join(here, "package.json"), "utf8"));
const missing = files.filter((file) => !existsSync(join(here, file)));
if (missing.length > 0) {
  console.error(
    `stance-ik cannot be packed: ${missing.join(", ")} missing. Build the WebAssembly first `
      + "with scripts/build-package.sh in the Stance repository.",
  );
  process.exit(1);
}
