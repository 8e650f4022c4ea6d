// The browser lab's worker: loads vlab compiled to WebAssembly and runs one
// lab per message, passing on what the lab tells (docs/browser-lab.md).
// The exports: lab_alloc(len) -> ptr, lab_run(ptr, len) -> 0 | 1 and the
// module's memory; the import env.lab_message(kind, ptr, len) carries JSON:
// kind 0 an event (setup, progress, frame), 1 the result, 2 an error (text).
"use strict";

let lab = null;
const decoder = new TextDecoder();
const kinds = ["event", "result", "error"];

function labMessage(kind, ptr, len) {
  const bytes = new Uint8Array(lab.exports.memory.buffer, ptr, len);
  // decode copies, so the module may reuse its memory at once
  postMessage({ kind: kinds[kind] || "error", text: decoder.decode(bytes) });
}

async function load() {
  const response = await fetch("vlab_web.wasm");
  if (!response.ok) {
    throw new Error(`vlab_web.wasm: HTTP ${response.status} (build it with web/build.sh)`);
  }
  const bytes = await response.arrayBuffer();
  const { instance } = await WebAssembly.instantiate(bytes, {
    env: { lab_message: labMessage },
  });
  return instance;
}

onmessage = async (message) => {
  try {
    if (lab === null) {
      lab = await load();
    }
    const request = new TextEncoder().encode(JSON.stringify(message.data));
    const ptr = lab.exports.lab_alloc(request.length);
    new Uint8Array(lab.exports.memory.buffer, ptr, request.length).set(request);
    const started = performance.now();
    lab.exports.lab_run(ptr, request.length);
    postMessage({ kind: "done", wall_s: (performance.now() - started) / 1000 });
  } catch (e) {
    // a trap (the module then cannot be reused) or a failed load
    lab = null;
    postMessage({ kind: "error", text: String(e) });
    postMessage({ kind: "done", wall_s: NaN });
  }
};
