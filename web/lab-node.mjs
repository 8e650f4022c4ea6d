// Runs the browser lab's WebAssembly in Node, without a browser: for timing
// it against the native CLI (docs/browser-lab.md) and for a quick check of
// a build. Node's engine, V8, is Chromium's.
//   node web/lab-node.mjs [freq_hz gamma seed cycles steady_cycles]
import { readFileSync } from "node:fs";

const [freq, gamma, seed, cycles, steady] = process.argv.slice(2).map(Number);
const request = {
  freq_hz: freq || 40, gamma: gamma || 20, orientation: "vertical", seed: seed || 1,
  cycles: cycles || 8, steady_cycles: steady || 5, rig: "thesis-shaker",
};
const wasm = new URL("site/vlab_web.wasm", import.meta.url);
let lab = null;
let result = null;
const { instance } = await WebAssembly.instantiate(readFileSync(wasm), {
  env: {
    lab_message(kind, ptr, len) {
      const text = new TextDecoder().decode(new Uint8Array(lab.exports.memory.buffer, ptr, len));
      if (kind === 1) result = JSON.parse(text);
      if (kind === 2) console.error(text);
    },
  },
});
lab = instance;
const bytes = new TextEncoder().encode(JSON.stringify(request));
const ptr = lab.exports.lab_alloc(bytes.length);
new Uint8Array(lab.exports.memory.buffer, ptr, bytes.length).set(bytes);
const started = performance.now();
const failed = lab.exports.lab_run(ptr, bytes.length);
const wall = (performance.now() - started) / 1000;
if (failed || result === null) process.exit(1);
const s = result.summary;
console.log(`${s.n_particles} spheres, ${s.steps} drive steps: DEM efficiency ${s.dem.efficiency.toFixed(4)}, measured ${s.measured.efficiency.toFixed(4)}; ${wall.toFixed(2)} s`);
