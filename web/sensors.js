// The byte transport of motion-capture sensors: WebSerial and WebHID. Only bytes move here;
// decoding, calibration and everything else happen in Rust (stance_mocap through the editor).
// The editor asks through window.stanceHost.connectSensor(requestJson) and hears back through
// the WebHandle: sensor_connected(name), sensor_bytes(bytes), sensor_report(id, data),
// sensor_lost(reason).

import { describe } from "./common.js";

let current = null; // { close(): Promise<void> } of the open device

function hex4(value) {
  return Number(value).toString(16).padStart(4, "0");
}

// How long closing waits for the stop bytes to go out (a stalled port must not block it).
const STOP_WRITE_TIMEOUT_MS = 500;

async function writeBytes(port, bytes) {
  if (!bytes?.length || !port.writable) return;
  const writer = port.writable.getWriter();
  try {
    await writer.write(new Uint8Array(bytes));
  } finally {
    writer.releaseLock();
  }
}

async function openSerial(handle, request) {
  if (!("serial" in navigator)) {
    throw new Error(
      "this browser has no Web Serial API (use Chrome or Edge, on https or localhost)",
    );
  }
  const port = await navigator.serial.requestPort();
  await port.open({ baudRate: request.baud_rate });
  const info = port.getInfo ? port.getInfo() : {};
  const name = info.usbVendorId
    ? `serial port ${hex4(info.usbVendorId)}:${hex4(info.usbProductId)} at ${request.baud_rate} baud`
    : `serial port at ${request.baud_rate} baud`;
  let closing = false;
  let reader = null;
  const onDisconnect = (event) => {
    if (event.target === port || event.port === port) {
      if (!closing) handle.sensor_lost("The serial device was unplugged.");
      closing = true;
    }
  };
  navigator.serial.addEventListener("disconnect", onDisconnect);
  await writeBytes(port, request.setup);
  handle.sensor_connected(name);
  (async () => {
    try {
      while (port.readable && !closing) {
        reader = port.readable.getReader();
        try {
          for (;;) {
            const { value, done } = await reader.read();
            if (done) break;
            if (value?.length) handle.sensor_bytes(value);
          }
        } finally {
          reader.releaseLock();
          reader = null;
        }
      }
      if (!closing) handle.sensor_lost("The serial device stopped sending.");
    } catch (error) {
      if (!closing) handle.sensor_lost(`The serial device failed: ${describe(error)}.`);
    } finally {
      closing = true;
      navigator.serial.removeEventListener("disconnect", onDisconnect);
    }
  })();
  return {
    async close() {
      closing = true;
      // The device's stop command (request.stop), so that it does not keep streaming.
      try {
        await Promise.race([
          writeBytes(port, request.stop),
          new Promise((resolve) => setTimeout(resolve, STOP_WRITE_TIMEOUT_MS)),
        ]);
      } catch {}
      try {
        await reader?.cancel();
      } catch {}
      try {
        await port.close();
      } catch {}
    },
  };
}

async function openHid(handle, request) {
  if (!("hid" in navigator)) {
    throw new Error("this browser has no WebHID API (use Chrome or Edge, on https or localhost)");
  }
  const devices = await navigator.hid.requestDevice({ filters: request.filters });
  const device = devices?.[0];
  if (!device) throw new Error("no device was chosen");
  if (!device.opened) await device.open();
  let closing = false;
  const onReport = (event) => {
    const view = event.data;
    handle.sensor_report(
      event.reportId,
      new Uint8Array(view.buffer, view.byteOffset, view.byteLength),
    );
  };
  const onDisconnect = (event) => {
    if (event.device === device && !closing) {
      closing = true;
      handle.sensor_lost("The HID device was unplugged.");
    }
  };
  device.addEventListener("inputreport", onReport);
  navigator.hid.addEventListener("disconnect", onDisconnect);
  handle.sensor_connected(device.productName || "HID device");
  return {
    async close() {
      closing = true;
      device.removeEventListener("inputreport", onReport);
      navigator.hid.removeEventListener("disconnect", onDisconnect);
      try {
        await device.close();
      } catch {}
    },
  };
}

// Opens the device the editor asked for; failures reach the editor as sensor_lost.
export function connectSensor(handle, requestJson) {
  const request = JSON.parse(requestJson);
  const open = request.kind === "hid" ? openHid : openSerial;
  const previous = current;
  current = null;
  (async () => {
    try {
      await previous?.close();
      current = await open(handle, request);
    } catch (error) {
      const reason =
        error?.name === "NotFoundError"
          ? "no device was chosen."
          : error?.name === "SecurityError"
            ? "the browser refused access to the device."
            : `${describe(error)}.`;
      handle.sensor_lost(`Could not open the device: ${reason}`);
    }
  })();
}

export function disconnectSensor() {
  const device = current;
  current = null;
  device?.close();
}
