// End-to-end test of `deltagi serve` in Debian's chromium, driven headless by playwright-core (which downloads
// no browser): the page shows frames; dragging the object by a known number of pixels moves its mask's
// centroid by as much and changes the delta; every view shows a picture; a light dims the picture; a second
// tab sees the first one's changes and may leave mid-frame; bad messages get errors; the saved scene renders
// with `deltagi render` to the saved image; an idle session uses no CPU. Prints the frame rate and the
// input-to-frame latency of the drag (figures, not asserted).
//
//   node tests/web/live_session.mjs --deltagi build/deltagi --scene examples/cornell-box.json \
//        [--set KEY=VALUE ...] [--out DIR] [--screenshot FILE.png] [--drag-seconds S]
// Exit status: 0 passed, 1 failed, 77 skipped (no playwright-core or no chromium: scripts/install-deps.sh).
import { execFileSync } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';

import { browserOrSkip, finish, logger, startServer } from './harness.mjs';

const args = { sets: [], out: null, screenshot: null, dragSeconds: 1.5 };
for (let i = 2; i < process.argv.length; i++) {
  const a = process.argv[i];
  const next = () => process.argv[++i];
  if (a === '--deltagi') args.deltagi = next();
  else if (a === '--scene') args.scene = next();
  else if (a === '--set') args.sets.push(next());
  else if (a === '--out') args.out = next();
  else if (a === '--screenshot') args.screenshot = next();
  else if (a === '--drag-seconds') args.dragSeconds = Number(next());
  else if (a === '--interactive-scale') args.interactiveScale = next();
  else throw new Error(`unknown argument ${a}`);
}
if (!args.deltagi || !args.scene) throw new Error('usage: live_session.mjs --deltagi PATH --scene SCENE.json');

const { launch } = await browserOrSkip();
const out = args.out || fs.mkdtempSync(path.join(os.tmpdir(), 'deltagi-live-'));
fs.mkdirSync(out, { recursive: true });
const { log, check } = logger();

// ---- the server ------------------------------------------------------------------------------------------
const serve = await startServer(args.deltagi, ['serve', args.scene, ...args.sets.flatMap((s) => ['--set', s]),
  ...(args.interactiveScale ? ['--interactive-scale', args.interactiveScale] : [])], log);
const { server, url } = serve;

function cpuSeconds(pid) {  // user + system time of the process, from /proc
  const fields = fs.readFileSync(`/proc/${pid}/stat`, 'utf8').split(') ')[1].split(' ');
  return (Number(fields[11]) + Number(fields[12])) / 100;  // clock ticks, 100 per second on Linux
}
// The same summed over the descendants alive now of process `root`, but not over `skip`'s subtrees nor
// `root` itself: the browser's processes (renderer, GPU, utilities) are this test's, as the server is.
function descendantsCpuSeconds(root, skip) {
  const parent = new Map();
  for (const name of fs.readdirSync('/proc')) {
    if (!/^\d+$/.test(name)) continue;
    try {
      parent.set(Number(name), Number(fs.readFileSync(`/proc/${name}/stat`, 'utf8').split(') ')[1].split(' ')[1]));
    } catch { /* gone meanwhile */ }
  }
  let total = 0;
  for (const pid of parent.keys()) {
    let p = pid;
    while (p > 1 && p !== root && !skip.includes(p)) p = parent.get(p) || 0;
    if (p !== root || pid === root) continue;
    try { total += cpuSeconds(pid); } catch { /* gone meanwhile */ }
  }
  return total;
}

const browser = await launch();
let failed = null;
try {
  const page = await browser.newPage({ viewport: { width: 1280, height: 1000 }, acceptDownloads: true });
  page.on('pageerror', (e) => { failed = failed || new Error(`page error: ${e.message}`); });
  await page.goto(url);
  await page.waitForFunction(() => window.deltagi && window.deltagi.frames > 0 && window.deltagi.state, null,
    { timeout: 120000 });
  const first = await page.evaluate(() => ({ info: window.deltagi.lastInfo, state: window.deltagi.state }));
  check(first.info.timings.stages.length > 5, `first frame: ${first.state.width}x${first.state.height}, ` +
    `${first.info.timings.total_ms} ms, ${first.info.bytes} bytes of JPEG`);

  const versionOf = (p) => p.evaluate(() => window.deltagi.state.version);
  // Waits for the state after a change, then for the refined frame of that state in `view`.
  async function settled(p, view, since) {
    await p.waitForFunction((v) => window.deltagi.state.version > v, since, { timeout: 60000 });
    await p.waitForFunction((wanted) => {
      const { lastInfo, state } = window.deltagi;
      return lastInfo && lastInfo.refined && lastInfo.view === wanted && lastInfo.version >= state.version;
    }, view, { timeout: 120000 });
  }
  async function change(p, action, view) {
    const since = await versionOf(p);
    await action();
    await settled(p, view, since);
  }
  const setView = async (p, view) => {
    if (await p.evaluate((v) => window.deltagi.state.view === v, view)) return;  // no change, no new frame
    await change(p, () => p.click(`input[name=view][value=${view}]`), view);
  };
  // The canvas's pixels, kept in the page under `name`; statistics computed there.
  const keep = (p, name) => p.evaluate((n) => {
    const c = document.getElementById('frame');
    window[n] = c.getContext('2d').getImageData(0, 0, c.width, c.height);
  }, name);
  const meanAbsDifference = (p, a, b) => p.evaluate(([x, y]) => {
    const d1 = window[x].data, d2 = window[y].data;
    let sum = 0;
    for (let i = 0; i < d1.length; i += 4) sum += Math.abs(d1[i] - d2[i]) + Math.abs(d1[i + 1] - d2[i + 1]) +
      Math.abs(d1[i + 2] - d2[i + 2]);
    return sum / (d1.length / 4 * 3);
  }, [a, b]);
  const imageStats = (p) => p.evaluate(() => {
    const c = document.getElementById('frame');
    const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
    let sum = 0, sum2 = 0;
    for (let i = 0; i < d.length; i += 4) { const v = (d[i] + d[i + 1] + d[i + 2]) / 3; sum += v; sum2 += v * v; }
    const n = d.length / 4;
    return { mean: sum / n, sd: Math.sqrt(Math.max(0, sum2 / n - (sum / n) ** 2)) };
  });
  // The centroid of the object mask's region that holds `seed` (image pixels), by a flood fill.
  const maskCentroid = (p, seed) => p.evaluate(([sx, sy]) => {
    const c = document.getElementById('frame');
    const { width: w, height: h } = c;
    const d = c.getContext('2d').getImageData(0, 0, w, h).data;
    const inside = (x, y) => d[(y * w + x) * 4] > 127;
    // the mask pixel nearest to the seed
    let start = null, best = Infinity;
    for (let y = 0; y < h; y++) for (let x = 0; x < w; x++)
      if (inside(x, y)) { const e = (x - sx) ** 2 + (y - sy) ** 2; if (e < best) { best = e; start = [x, y]; } }
    if (!start) return null;
    const seen = new Uint8Array(w * h);
    const stack = [start];
    seen[start[1] * w + start[0]] = 1;
    let n = 0, cx = 0, cy = 0;
    while (stack.length) {
      const [x, y] = stack.pop();
      n += 1; cx += x + 0.5; cy += y + 0.5;
      for (const [nx, ny] of [[x + 1, y], [x - 1, y], [x, y + 1], [x, y - 1]])
        if (nx >= 0 && ny >= 0 && nx < w && ny < h && !seen[ny * w + nx] && inside(nx, ny)) {
          seen[ny * w + nx] = 1;
          stack.push([nx, ny]);
        }
    }
    return { x: cx / n, y: cy / n, pixels: n, distance: Math.sqrt(best) };
  }, seed);
  const pagePoint = (p, [x, y]) => p.evaluate(([ix, iy]) => {
    const c = document.getElementById('frame');
    const r = c.getBoundingClientRect();
    return [r.left + ix * r.width / c.width, r.top + iy * r.height / c.height];
  }, [x, y]);

  // ---- drag the selected object by a known number of pixels ----------------------------------------------
  const state0 = await page.evaluate(() => window.deltagi.state);
  const object0 = state0.objects[state0.selected];
  check(object0 && object0.anchor, `object "${object0.name}" rests at pixel (${object0.anchor.map((v) => v.toFixed(1))})`);
  await setView(page, 'delta');
  await keep(page, 'deltaBefore');
  await setView(page, 'mask');
  const anchor0 = state0.objects[state0.selected].anchor;
  const seedOffset = Math.max(3, state0.height / 48);
  const before = await maskCentroid(page, [anchor0[0], anchor0[1] - seedOffset]);
  check(before && before.pixels > 20, `mask of the object before the drag: ${before && before.pixels} pixels`);
  await setView(page, 'composite');

  const move = [Math.round(state0.width / 8), Math.round(state0.height / 24)];
  const scale = (await pagePoint(page, [1, 0]))[0] - (await pagePoint(page, [0, 0]))[0];
  const [startX, startY] = await pagePoint(page, anchor0);
  const countsBefore = await page.evaluate(() => ({ frames: window.deltagi.frames,
    latencies: window.deltagi.latencies.length, t: performance.now() }));
  const since = await versionOf(page);
  const loadBefore = fs.readFileSync('/proc/loadavg', 'utf8').split(' ')[0];
  const browserCpu = () => descendantsCpuSeconds(process.pid, [server.pid]);
  const cpuBefore = { server: cpuSeconds(server.pid), browser: browserCpu(), driver: process.cpuUsage() };
  await page.mouse.move(startX, startY);
  await page.mouse.down();
  // A path that wanders (so that the whole drag renders) and ends at the move.
  const steps = Math.max(10, Math.round(args.dragSeconds * 60));
  const dragStart = Date.now();
  for (let i = 1; i <= steps; i++) {
    const t = i / steps;
    const wander = Math.sin(2 * Math.PI * t) * state0.width / 16;
    await page.mouse.move(startX + (move[0] * t + wander) * scale, startY + move[1] * t * scale);
    const due = dragStart + t * args.dragSeconds * 1000;
    const wait = due - Date.now();
    if (wait > 0) await new Promise((r) => setTimeout(r, wait));
  }
  await page.mouse.up();
  const dragWall = (Date.now() - dragStart) / 1000;
  const driverCpu = process.cpuUsage(cpuBefore.driver);
  const cpuDuring = { server: cpuSeconds(server.pid) - cpuBefore.server,
    browser: browserCpu() - cpuBefore.browser,
    driver: (driverCpu.user + driverCpu.system) / 1e6 };
  const drag = await page.evaluate((c) => {
    const { drawn, latencies, frames } = window.deltagi;
    return { frames: frames - c.frames, seconds: (performance.now() - c.t) / 1000, upAt: performance.now(),
      latencies: latencies.slice(c.latencies), frameMs: drawn.filter(([t]) => t > c.t).map(([, ms]) => ms),
      stages: drawn.filter(([t]) => t > c.t).map(([, , , stages, jpeg]) => [...stages, ['jpeg', jpeg]]) };
  }, countsBefore);
  await settled(page, 'composite', since);
  const sorted = [...drag.latencies].sort((a, b) => a - b);
  const quantile = (q) => (sorted.length ? sorted[Math.min(sorted.length - 1, Math.floor(q * sorted.length))] : NaN);
  const fps = drag.frames / drag.seconds;
  log(`FIGURES: drag of ${drag.seconds.toFixed(2)} s: ${drag.frames} frames displayed = ${fps.toFixed(1)} per ` +
    `second; input-to-frame latency median ${quantile(0.5).toFixed(0)} ms, p90 ${quantile(0.9).toFixed(0)} ms, ` +
    `max ${sorted.length ? sorted[sorted.length - 1].toFixed(0) : NaN} ms (${sorted.length} mouse events); ` +
    `render time per frame median ${[...drag.frameMs].sort((a, b) => a - b)[drag.frameMs.length >> 1]} ms; ` +
    `load average (1 min) ${loadBefore} before the drag, ${fs.readFileSync('/proc/loadavg', 'utf8').split(' ')[0]} ` +
    `after, on ${os.cpus().length} cores`);
  log(`FIGURES: CPU during the drag (cores busy on average over ${dragWall.toFixed(2)} s): deltagi serve ` +
    `${(cpuDuring.server / dragWall).toFixed(2)}, the browser ${(cpuDuring.browser / dragWall).toFixed(2)}, ` +
    `this test's driver ${(cpuDuring.driver / dragWall).toFixed(2)}`);
  const stageMedians = {};
  for (const stages of drag.stages) for (const [name, ms] of stages) (stageMedians[name] ||= []).push(ms);
  log(`FIGURES: median ms per stage of the frames shown during the drag: ${Object.entries(stageMedians)
    .map(([name, v]) => `${name} ${v.sort((a, b) => a - b)[v.length >> 1].toFixed(1)}`).join(', ')}`);
  check(drag.frames >= 3 && sorted.length >= 3, 'frames were shown during the drag');
  const refinedAfter = await page.evaluate((upAt) => window.deltagi.drawn.find(([t, , refined]) => t > upAt &&
    refined), drag.upAt);
  if (refinedAfter)
    log(`FIGURES: the refined frame after the drag: rendered in ${refinedAfter[1].toFixed(1)} ms, shown ` +
      `${((refinedAfter[0] - drag.upAt) / 1000).toFixed(2)} s after the mouse was released`);

  const state1 = await page.evaluate(() => window.deltagi.state);
  const anchor1 = state1.objects[state1.selected].anchor;
  check(Math.abs(anchor1[0] - anchor0[0] - move[0]) < 1 && Math.abs(anchor1[1] - anchor0[1] - move[1]) < 1,
    `the object rests under the cursor: anchor moved by (${(anchor1[0] - anchor0[0]).toFixed(2)}, ` +
    `${(anchor1[1] - anchor0[1]).toFixed(2)}) for a drag of (${move})`);
  if (args.screenshot) {
    await page.screenshot({ path: args.screenshot, fullPage: true });
    log(`screenshot: ${args.screenshot}`);
  }
  await setView(page, 'mask');
  const after = await maskCentroid(page, [anchor1[0], anchor1[1] - seedOffset]);
  const moved = [after.x - before.x, after.y - before.y];
  const tolerance = 0.15 * Math.hypot(...move) + 2;
  check(Math.hypot(moved[0] - move[0], moved[1] - move[1]) < tolerance,
    `the mask's centroid moved by (${moved.map((v) => v.toFixed(1))}) for a drag of (${move}) (within ` +
    `${tolerance.toFixed(1)} pixels)`);
  await setView(page, 'delta');
  await keep(page, 'deltaAfter');
  const deltaChange = await meanAbsDifference(page, 'deltaBefore', 'deltaAfter');
  check(deltaChange > 0.2, `the delta changed: mean |difference| ${deltaChange.toFixed(2)} of 255`);

  // ---- every view shows a picture --------------------------------------------------------------------------
  for (const view of ['composite', 'background', 'delta', 'mask', 'object', 'shadow', 'indirect', 'depth']) {
    await setView(page, view);
    const s = await imageStats(page);
    const legend = await page.evaluate(() => !document.getElementById('scale').hidden);
    check(s.sd > 1 && legend === ['delta', 'shadow', 'indirect'].includes(view),
      `view ${view}: mean ${s.mean.toFixed(1)}, spread ${s.sd.toFixed(1)}, colour scale ${legend ? 'shown' : 'hidden'}`);
  }
  await setView(page, 'composite');

  // ---- a second tab sees the changes, and may leave mid-frame ----------------------------------------------
  const second = await browser.newPage();
  await second.goto(url);
  await second.waitForFunction(() => window.deltagi && window.deltagi.frames > 0, null, { timeout: 60000 });
  const v0 = await versionOf(page);
  await second.click('#rotate-right');
  await page.waitForFunction((v) => window.deltagi.state.version > v &&
    window.deltagi.lastInfo.version > v, v0, { timeout: 60000 });
  check(true, 'a rotation in a second tab reached the first tab (state and frame)');
  await second.click('#rotate-left');
  await second.close();  // while the frame of that rotation renders or streams
  await settled(page, 'composite', v0 + 1);
  check(true, 'the first tab gets frames after the second left mid-frame');

  // ---- the object list chooses the object the mouse moves ---------------------------------------------------
  if (state0.objects.length > 1) {
    const v = await versionOf(page);
    await page.selectOption('#object', '1');
    await page.waitForFunction((w) => window.deltagi.state.version > w, v, { timeout: 60000 });
    const selected = await page.evaluate(() => window.deltagi.state.selected);
    await page.selectOption('#object', '0');
    check(selected === 1, `object "${state0.objects[1].name}" chosen from the list`);
  }

  // ---- bad messages get errors, and the session goes on ----------------------------------------------------
  const replies = await page.evaluate(() => new Promise((resolve) => {
    const ws = new WebSocket(`ws://${location.host}/ws`);
    const errors = [];
    ws.onmessage = (e) => {
      if (typeof e.data !== 'string') return;
      const m = JSON.parse(e.data);
      if (m.type === 'error') errors.push(m.message);
      if (errors.length === 4) { ws.close(); resolve(errors); }
    };
    ws.onopen = () => {
      ws.send('{"type": "drag", ');
      ws.send(JSON.stringify({ type: 'drag', object: 99, x: 1, y: 1 }));
      ws.send(JSON.stringify({ type: 'options', values: { 'volume.resolution': 1024 } }));
      ws.send('x'.repeat(100000));
    };
    setTimeout(() => resolve(errors), 10000);
  }));
  check(replies.length === 4, `four bad messages, four errors: ${replies.map((r) => JSON.stringify(r)).join('; ')}`);

  // ---- a light, dimmed from its slider -----------------------------------------------------------------------
  const bright = await imageStats(page);
  await change(page, () => page.evaluate(() => {
    const input = document.getElementById('light-intensity');
    input.value = String(Number(input.value) * 0.25);
    input.dispatchEvent(new Event('change'));
  }), 'composite');
  const dim = await imageStats(page);
  check(dim.mean < bright.mean - 1, `light dimmed to a quarter: mean ${bright.mean.toFixed(1)} -> ${dim.mean.toFixed(1)}`);
  // The page redraws a part of its controls only when the state changed it: the light's did change.
  const shownIntensity = await page.evaluate(() => [document.getElementById('light-intensity-value').textContent,
    window.deltagi.state.lights[Number(document.getElementById('light').value)].intensity.toFixed(3)]);
  check(shownIntensity[0] === shownIntensity[1], `the intensity shown is the state's: ${shownIntensity.join(' = ')}`);

  // ---- an idle session uses no CPU ----------------------------------------------------------------------------
  const cpu0 = cpuSeconds(server.pid);
  await new Promise((r) => setTimeout(r, 2000));
  const idle = cpuSeconds(server.pid) - cpu0;
  check(idle < 0.2, `idle after refining: ${idle.toFixed(2)} s of CPU in 2 s`);

  // ---- save scene + save image = deltagi render of the saved scene -------------------------------------------
  const saveAs = async (button, name) => {
    const [download] = await Promise.all([page.waitForEvent('download'), page.click(button)]);
    const file = path.join(out, name);
    await download.saveAs(file);
    return file;
  };
  const sceneFile = await saveAs('#save-scene', 'saved-scene.json');
  const imageFile = await saveAs('#save-image', 'saved-image.png');
  const cliFile = path.join(out, 'cli-render.png');
  execFileSync(args.deltagi, ['render', sceneFile, '-o', cliFile, '--quiet'], { stdio: 'inherit' });
  const comparison = JSON.parse(execFileSync(args.deltagi, ['compare', imageFile, cliFile, '--json']).toString());
  check(comparison.rmse <= 1e-4, `saved image vs deltagi render of the saved scene: RMSE ${comparison.rmse}`);
} catch (e) {
  failed = e;
}
await finish(browser, serve, failed, log);
