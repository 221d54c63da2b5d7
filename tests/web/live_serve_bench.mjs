// The figures of `deltagi live --serve` (docs/live.md): the server reads a capture's camera frames itself,
// registers and renders each, and a page (Debian's chromium, headless, on the same machine) shows them.
// Prints the frames shown per second over the measured seconds, the median from a frame's arrival in the
// server to its JPEG, the median render time and the share of the source's frames dropped. The capture's
// frames are played there and back three times (a 60-frame capture: 12 s at 30 frames per second). A
// measurement, not a test: nothing is asserted.
//
//   node tests/web/live_serve_bench.mjs --deltagi build/deltagi --capture out/bench-capture [--seconds 6]
//        [--fps 30] [--json FILE]
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';

import { browserOrSkip, finish, logger, startServer } from './harness.mjs';

const args = { seconds: 6, fps: 30 };
for (let i = 2; i < process.argv.length; i++) {
  const a = process.argv[i];
  const next = () => process.argv[++i];
  if (a === '--deltagi') args.deltagi = path.resolve(next());
  else if (a === '--capture') args.capture = path.resolve(next());
  else if (a === '--seconds') args.seconds = Number(next());
  else if (a === '--fps') args.fps = Number(next());
  else if (a === '--json') args.json = next();
  else throw new Error(`unknown argument ${a}`);
}
if (!args.deltagi || !args.capture) throw new Error('usage: live_serve_bench.mjs --deltagi PATH --capture DIR');

// The capture there and back, three times, as links in a folder of its own.
const frames = fs.readdirSync(path.join(args.capture, 'camera')).filter((f) => /^frame_\d{4}\.png$/.test(f)).sort();
const played = fs.mkdtempSync(path.join(os.tmpdir(), 'deltagi-serve-bench-'));
const order = [...frames, ...[...frames].reverse()];
for (let i = 0; i < 3 * order.length; i++)
  fs.symlinkSync(path.join(args.capture, 'camera', order[i % order.length]),
    path.join(played, `frame_${String(i).padStart(4, '0')}.png`));

const { log } = logger();
const { launch } = await browserOrSkip();
const serve = await startServer(args.deltagi, ['live', path.join(args.capture, 'scene.json'), '--camera',
  path.join(played, 'frame_####.png'), '--fps', String(args.fps), '--serve'], log);
const browser = await launch();
let failed = null;
try {
  const page = await browser.newPage({ viewport: { width: 1280, height: 1000 } });
  await page.goto(serve.url);
  // The first frames are the renderer's first touch of its buffers: measured after 2 s.
  await page.waitForTimeout(2000);
  const shown = [];
  const start = Date.now();
  while (Date.now() - start < args.seconds * 1000) {
    await page.waitForTimeout(10);
    const info = await page.evaluate(() => window.deltagi.lastInfo);
    if (info && info.camera && (!shown.length || shown[shown.length - 1].camera.number !== info.camera.number))
      shown.push(info);
  }
  const median = (values) => {
    const s = [...values].sort((a, b) => a - b);
    return s.length ? s[Math.floor(s.length / 2)] : NaN;
  };
  const first = shown[0], last = shown[shown.length - 1];
  const figures = {
    frames_shown_per_second: Number((shown.length / args.seconds).toFixed(2)),
    arrival_to_jpeg_ms_median: median(shown.map((i) => i.camera.latency_ms)),
    render_ms_median: median(shown.map((i) => i.timings.total_ms)),
    dropped_share: shown.length > 1
      ? Number(((last.camera.dropped - first.camera.dropped) / (last.camera.number - first.camera.number)).toFixed(2))
      : NaN,
  };
  log(`figures: ${JSON.stringify(figures)}`);
  if (args.json) fs.writeFileSync(args.json, `${JSON.stringify(figures, null, 2)}\n`);
} catch (e) {
  failed = e;
}
fs.rmSync(played, { recursive: true, force: true });
await finish(browser, serve, failed, log);
