// Takes the browser lab's screenshot for docs/browser-lab.md: headless
// Chromium over its DevTools protocol, a run to the end, the whole page.
//   node --experimental-websocket web/screenshot.mjs URL OUT.png [FRAME]
// FRAME: the replay's frame to show, counted back from the last (e.g. 6).
// (Node 22 needs no flag.) Serve web/site first, e.g.
//   python3 -m http.server 8765 -d web/site
import { spawn } from "node:child_process";
import { writeFileSync, mkdtempSync } from "node:fs";
import { tmpdir } from "node:os";
import { join } from "node:path";

const [url, out, frame] = process.argv.slice(2);
const port = 9333;
const browser = spawn("chromium", ["--headless=new", "--no-sandbox", "--disable-gpu",
  `--remote-debugging-port=${port}`, `--user-data-dir=${mkdtempSync(join(tmpdir(), "lab-"))}`,
  "--window-size=1100,1000", "about:blank"], { stdio: "ignore" });
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
let target;
for (let i = 0; i < 50 && !target; i++) {
  await sleep(200);
  // The page's URL goes whole, its own `&` and `?` encoded: unencoded,
  // DevTools would keep only what comes before the first `&`.
  try { target = await (await fetch(`http://127.0.0.1:${port}/json/new?${encodeURIComponent(url)}`, { method: "PUT" })).json(); } catch {}
}
if (!target) {
  browser.kill();
  throw new Error(`Chromium's DevTools did not answer on port ${port} within 10 s`);
}
const ws = new WebSocket(target.webSocketDebuggerUrl);
await new Promise((r) => ws.addEventListener("open", r));
let id = 0;
const waiting = new Map();
ws.addEventListener("message", (m) => {
  const msg = JSON.parse(m.data);
  if (waiting.has(msg.id)) { waiting.get(msg.id)(msg.result); waiting.delete(msg.id); }
});
const call = (method, params = {}) => new Promise((r) => {
  waiting.set(++id, r);
  ws.send(JSON.stringify({ id, method, params }));
});
let finished = false;
for (let i = 0; i < 600 && !finished; i++) {
  const r = await call("Runtime.evaluate", { expression: "window.labWallSeconds !== undefined" });
  finished = r.result.value === true;
  if (!finished) await sleep(500);
}
if (!finished) {
  ws.close();
  browser.kill();
  // A page that never finished is not a screenshot of the lab: say so and
  // write nothing.
  throw new Error(`the lab at ${url} did not finish its run within 300 s; no screenshot written`);
}
if (frame !== undefined) {
  await call("Runtime.evaluate", { expression:
    `$("scrub").value = frames.length - 1 - ${Number(frame)}; $("scrub").dispatchEvent(new Event("input"))` });
}
await sleep(500);
const metrics = await call("Page.getLayoutMetrics");
const size = metrics.cssContentSize || metrics.contentSize;
const shot = await call("Page.captureScreenshot", { format: "png", captureBeyondViewport: true,
  clip: { x: 0, y: 0, width: 1100, height: Math.ceil(size.height), scale: 1 } });
writeFileSync(out, Buffer.from(shot.data, "base64"));
console.log(`wrote ${out}`);
ws.close();
browser.kill();
