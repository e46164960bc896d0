// Starts the Stance editor (Rust compiled to WebAssembly) on the page's canvas, and shows a
// readable error screen instead of a blank page when it cannot start.
import init, { WebHandle } from "./pkg/stance_web.js";

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

function describe(error) {
  if (error === undefined || error === null) return "unknown error";
  if (typeof error === "string") return error;
  return error.message || String(error);
}

async function main() {
  if (typeof WebAssembly !== "object") {
    showError("This browser has no WebAssembly.");
    return;
  }
  try {
    await init();
  } catch (error) {
    showError(`The editor's code could not load: ${describe(error)}`);
    return;
  }
  const handle = new WebHandle();
  window.stance = handle;
  try {
    await handle.start(document.getElementById("stance-canvas"));
  } catch (error) {
    showError(describe(error));
    return;
  }
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
