// The live session's page (`deltagi serve`): shows the frames the server streams over a WebSocket and sends
// it the user's changes as JSON messages (src/live/live_session.h lists them). window.deltagi holds what the
// browser test reads: the frames shown, their infos, the input-to-frame latencies.
'use strict';

const $ = (id) => document.getElementById(id);
const canvas = $('frame');
const context = canvas.getContext('2d');
const live = (window.deltagi = {
  client: 0,
  state: null,
  frames: 0,          // frames drawn
  lastInfo: null,     // the info of the last frame drawn
  shownTimes: [],     // performance.now() of each frame drawn
  latencies: [],      // per mouse event of a drag: ms to the first frame drawn that shows it
  drawn: [],          // per frame drawn: [performance.now(), frame ms, refined, stages, JPEG ms]
  errors: [],
  // The user's camera: frames sent, and per picture drawn over one of them the ms from its capture.
  camera: { sent: 0, shown: 0, latencies: [], info: null },
});
let socket = null;
let seq = 0;
let pendingInfo = null;   // the info that came before the next picture
let newestDrawn = 0;      // frame numbers arrive in order; decoding may not finish in order
// Drag messages sent whose frame has not come yet: {seq, inputs, sentAt}, `inputs` the times of the mouse
// events it carries. Each mouse move goes out at once: the server renders the newest position when it starts a
// frame (it never queues frames). Past kMaxInFlight (a server that stopped answering) moves wait, coalesced.
const kMaxInFlight = 30;
let inFlight = [];
let queuedDrag = null;    // the newest cursor position not yet sent: {x, y, inputs}
let awaiting = [];        // drags whose frame info came, whose picture is not yet drawn
let dragging = null;      // {mouse: [x, y], anchor: [x, y]}
const history = [];       // the last frames' timings, for the chart
const stageColours = ['#e6194b', '#3cb44b', '#ffe119', '#4363d8', '#f58231', '#911eb4', '#46f0f0', '#f032e6',
  '#bcf60c', '#fabebe', '#008080', '#e6beff', '#9a6324', '#fffac8', '#800000', '#aaffc3'];

function status(text) { $('status').textContent = text; }
function showError(text) {
  live.errors.push(text);
  $('error').textContent = text;
}
function send(message) {
  if (socket && socket.readyState === WebSocket.OPEN) socket.send(JSON.stringify(message));
}

function connect() {
  socket = new WebSocket(`ws://${location.host}/ws`);
  socket.binaryType = 'blob';
  socket.onopen = () => status('connected');
  socket.onclose = (event) => {
    status('disconnected; trying again');
    // The server closes a socket that sent a message over its bound (a camera frame over 8 MiB).
    if (event.code === 1009) showError('the server refused a message as too large (over 8 MiB)');
    inFlight = [];
    setTimeout(connect, 1000);
  };
  socket.onmessage = (event) => {
    if (typeof event.data !== 'string') {
      const info = pendingInfo;
      pendingInfo = null;
      if (info) draw(event.data, info);
      return;
    }
    const message = JSON.parse(event.data);
    if (message.type === 'hello') {
      live.client = message.client;
      camera.number = 0;  // the server counts a new connection's camera frames from 1
      forgetCameraFrames();
      // The server reads a camera of its own (deltagi live --serve): its frames come, the page sends none.
      live.serverCamera = message.camera || null;
      $('camera-toggle').hidden = Boolean(live.serverCamera);
      if (live.serverCamera) $('camera-status').textContent = `the server's camera: ${live.serverCamera}`;
    }
    else if (message.type === 'state') applyState(message);
    else if (message.type === 'error') {
      showError(message.message);
      const refused = /^camera frame (\d+):/.exec(message.message);
      if (refused) cameraAnswered(Number(refused[1]));
      // A refused change leaves the control the user set showing it: every part is shown again.
      for (const part of Object.keys(shown)) delete shown[part];
      if (live.state) applyState(live.state);
      inFlight = [];  // a refused drag gets no frame
      flushDrag();
    } else if (message.type === 'frame') {
      pendingInfo = message;
      if (message.camera && message.camera.client === live.client) cameraAnswered(message.camera.number, message);
      if (message.client === live.client) {
        for (const drag of inFlight.filter((d) => d.seq <= message.seq)) awaiting.push({ ...drag, number: message.number });
        inFlight = inFlight.filter((d) => d.seq > message.seq);
        flushDrag();  // the next position goes out while this picture decodes
      }
    }
  };
}

async function draw(blob, info) {
  const bitmap = await createImageBitmap(blob);
  if (info.number < newestDrawn) return;
  newestDrawn = info.number;
  // The canvas keeps the camera's size: frames rendered smaller while something moves (info.scale) are
  // drawn stretched over it, so that pixel coordinates (the drag's) stay the camera's.
  const width = bitmap.width * (info.scale || 1), height = bitmap.height * (info.scale || 1);
  if (canvas.width !== width || canvas.height !== height) {
    canvas.width = width;
    canvas.height = height;
  }
  context.imageSmoothingEnabled = true;
  context.drawImage(bitmap, 0, 0, width, height);
  bitmap.close();
  const now = performance.now();
  live.frames += 1;
  live.lastInfo = info;
  live.shownTimes.push(now);
  live.drawn.push([now, info.timings.total_ms, info.refined, info.timings.stages, info.encode_ms]);
  if (live.shownTimes.length > 10000) live.shownTimes.splice(0, 5000);
  if (live.drawn.length > 10000) live.drawn.splice(0, 5000);
  if (info.camera && (info.camera.client === live.client || info.camera.client === 0)) cameraShown(info, now);
  awaiting = awaiting.filter((drag) => {
    if (drag.number > info.number) return true;
    for (const t of drag.inputs) live.latencies.push(now - t);
    return false;
  });
  $('scale').hidden = !['delta', 'shadow', 'indirect'].includes(info.view);
  history.push(info.timings.stages);
  if (history.length > 60) history.shift();
  timingsFor = info;
  if (!timingsTimer)
    timingsTimer = setTimeout(() => {
      timingsTimer = null;
      showTimings(timingsFor, performance.now());
    }, Math.max(0, lastTimingsShown + kTimingsInterval - now));
}

function median(values) {
  if (!values.length) return NaN;
  const sorted = [...values].sort((a, b) => a - b);
  return sorted[Math.floor(sorted.length / 2)];
}

// The frame-time line, the chart and its legend are drawn again at most every kTimingsInterval ms (for the
// newest frame): each redraw lays the controls out again, which at every frame of a drag cost the browser
// CPU that the renderer, on the same machine, lacked.
const kTimingsInterval = 250;
let lastTimingsShown = -Infinity, timingsTimer = null, timingsFor = null;

function showTimings(info, now) {
  lastTimingsShown = now;
  const recent = live.shownTimes.filter((t) => t > now - 1000).length;
  const latency = median(live.latencies.slice(-30));
  $('frame-time').textContent =
    `${info.refined ? 'refined: the deltagi render image' : 'interactive settings'} · ` +
    `frame ${info.timings.total_ms.toFixed(1)} ms + JPEG ${info.encode_ms.toFixed(1)} ms · ` +
    `${recent} frames shown in the last second` +
    (Number.isFinite(latency) ? ` · input to frame ${latency.toFixed(0)} ms (median of the last 30)` : '');
  const chart = $('chart');
  const g = chart.getContext('2d');
  g.clearRect(0, 0, chart.width, chart.height);
  const totals = history.map((stages) => stages.reduce((sum, [, ms]) => sum + ms, 0));
  // Scaled to the slowest frame but the few slowest (a cold frame after a light or an option change is clipped).
  const full = Math.max(50, [...totals].sort((x, y) => x - y)[Math.floor(0.9 * (totals.length - 1))]);
  const scale = (chart.height - 12) / full;
  const names = [];
  for (const stages of history) for (const [name] of stages) if (!names.includes(name)) names.push(name);
  const width = chart.width / 60;
  history.forEach((stages, i) => {
    let y = chart.height;
    for (const [name, ms] of stages) {
      const h = ms * scale;
      g.fillStyle = stageColours[names.indexOf(name) % stageColours.length];
      g.fillRect(i * width, y - h, width - 1, h);
      y -= h;
    }
  });
  g.fillStyle = '#aaa';
  g.font = '10px sans-serif';
  g.fillText(`${full.toFixed(0)} ms`, 2, 10);
  const legend = $('chart-legend');
  legend.replaceChildren(...info.timings.stages.filter(([, ms]) => ms >= 0.05).map(([name, ms]) => {
    const span = document.createElement('span');
    const swatch = document.createElement('i');
    swatch.style.background = stageColours[names.indexOf(name) % stageColours.length];
    span.append(swatch, `${name} ${ms.toFixed(1)}`);
    return span;
  }));
}

function setOptions(select, values, current) {
  const wanted = values.map(String);
  if ([...select.options].map((o) => o.value).join() !== wanted.join())
    select.replaceChildren(...values.map((v, i) => new Option(v, String(i))));
  select.value = String(current);
}

function rangeFor(input, lo, hi) {
  input.min = String(lo);
  input.max = String(hi);
}

// What each part of the controls last showed (JSON): a state that leaves a part as it was does not touch its
// elements. A drag sends a state with every mouse move, and restyling the controls each time cost the
// browser more than drawing the frames.
const shown = {};
function changed(part, value) {
  const text = JSON.stringify(value);
  if (shown[part] === text) return false;
  shown[part] = text;
  return true;
}

function applyState(state) {
  const first = !live.state;
  live.state = state;
  if (changed('objects', [state.scene, state.objects.map((o) => o.name), state.selected])) {
    $('scene-name').textContent = state.scene;
    setOptions($('object'), state.objects.map((o) => o.name), state.selected);
  }
  document.querySelector(`input[name=view][value=${state.view}]`).checked = true;
  const lightSelect = $('light');
  const lightIndex = Math.min(Number(lightSelect.value) || 0, Math.max(0, state.lights.length - 1));
  if (changed('lights', [state.lights, state.bounds, lightIndex])) showLight(state, lightIndex, first);
  if (changed('options', state.options)) showOptions(state.options);
}

function showLight(state, lightIndex, first) {
  const lightSelect = $('light');
  setOptions(lightSelect, state.lights.map((l) => l.name), lightIndex);
  $('light-controls').hidden = state.lights.length === 0;
  const light = state.lights[lightIndex];
  if (light) {
    const [lo, hi] = state.bounds;
    ['x', 'y', 'z'].forEach((axis, a) => {
      const input = $(`light-${axis}`);
      const margin = 0.25 * (hi[a] - lo[a]);
      rangeFor(input, Math.min(lo[a] - margin, light.position[a]), Math.max(hi[a] + margin, light.position[a]));
      input.disabled = light.type === 'directional';
      if (document.activeElement !== input) input.value = String(light.position[a]);
      $(`light-${axis}-value`).textContent = light.position[a].toFixed(3);
    });
    const intensity = $('light-intensity');
    if (first || Number(intensity.max) < light.intensity) intensity.max = String(Math.max(1, 2 * light.intensity));
    if (document.activeElement !== intensity) intensity.value = String(light.intensity);
    $('light-intensity-value').textContent = light.intensity.toFixed(3);
  }
}

function showOptions(options) {
  for (const control of document.querySelectorAll('[data-option]')) {
    const value = options[control.dataset.option];
    const text = value === 0 || value === null ? 'auto' : String(value);
    if (control.tagName === 'SELECT' && ![...control.options].some((o) => o.value === text))
      control.append(new Option(text, text));
    if (document.activeElement !== control) control.value = text;
    const output = control.parentElement.querySelector('output');
    if (output) output.textContent = text;
  }
}

// ---- input -----------------------------------------------------------------------------------------------

function imagePoint(event) {
  const rect = canvas.getBoundingClientRect();
  return [(event.clientX - rect.left) * (canvas.width / rect.width),
    (event.clientY - rect.top) * (canvas.height / rect.height)];
}

function flushDrag() {
  inFlight = inFlight.filter((d) => performance.now() - d.sentAt < 2000);  // lost: do not stall
  if (inFlight.length >= kMaxInFlight || !queuedDrag || !live.state) return;
  seq += 1;
  send({ type: 'drag', object: live.state.selected, x: queuedDrag.x, y: queuedDrag.y, seq });
  inFlight.push({ seq, inputs: queuedDrag.inputs, sentAt: performance.now() });
  queuedDrag = null;
}

canvas.addEventListener('mousedown', (event) => {
  if (!live.state || !live.state.objects.length || event.button !== 0) return;
  const mouse = imagePoint(event);
  const anchor = live.state.objects[live.state.selected].anchor || mouse;
  dragging = { mouse, anchor };
  canvas.classList.add('dragging');
  canvas.focus();
  event.preventDefault();
});
window.addEventListener('mousemove', (event) => {
  if (!dragging || !live.state) return;
  const [mx, my] = imagePoint(event);
  const x = Math.min(Math.max(dragging.anchor[0] + mx - dragging.mouse[0], 0), live.state.width);
  const y = Math.min(Math.max(dragging.anchor[1] + my - dragging.mouse[1], 0), live.state.height);
  queuedDrag = { x, y, inputs: [...(queuedDrag ? queuedDrag.inputs : []), performance.now()] };
  flushDrag();
});
window.addEventListener('mouseup', () => {
  dragging = null;
  canvas.classList.remove('dragging');
});
setInterval(flushDrag, 100);

function rotate(degrees) {
  if (!live.state || !live.state.objects.length) return;
  send({ type: 'rotate', object: live.state.selected, degrees, seq: ++seq });
}
canvas.addEventListener('wheel', (event) => {
  event.preventDefault();
  rotate(event.deltaY > 0 ? 15 : -15);
}, { passive: false });
canvas.addEventListener('keydown', (event) => {
  if (event.key === 'q' || event.key === 'Q') rotate(-15);
  if (event.key === 'e' || event.key === 'E') rotate(15);
});
$('rotate-left').onclick = () => rotate(-15);
$('rotate-right').onclick = () => rotate(15);
$('object').onchange = (event) => send({ type: 'select', object: Number(event.target.value) });
for (const radio of document.querySelectorAll('input[name=view]'))
  radio.onchange = () => send({ type: 'view', view: radio.value });
$('light').onchange = () => live.state && applyState(live.state);
for (const axis of ['x', 'y', 'z']) {
  const input = $(`light-${axis}`);
  input.oninput = () => { $(`light-${axis}-value`).textContent = Number(input.value).toFixed(3); };
  input.onchange = () => {
    const position = ['x', 'y', 'z'].map((a) => Number($(`light-${a}`).value));
    send({ type: 'light', light: Number($('light').value), position, seq: ++seq });
  };
}
$('light-intensity').oninput = () => {
  $('light-intensity-value').textContent = Number($('light-intensity').value).toFixed(3);
};
$('light-intensity').onchange = () =>
  send({ type: 'light', light: Number($('light').value), intensity: Number($('light-intensity').value), seq: ++seq });
for (const control of document.querySelectorAll('[data-option]')) {
  const output = control.parentElement.querySelector('output');
  control.oninput = () => { if (output) output.textContent = control.value; };
  control.onchange = () => {
    const value = control.value === 'auto' ? 'auto' : parseInt(control.value, 10);
    send({ type: 'options', values: { [control.dataset.option]: value }, seq: ++seq });
  };
}

// ---- the user's camera ------------------------------------------------------------------------------------
// Each frame of the camera is drawn at the scene camera's size (its intrinsics are for that size), encoded as
// a JPEG and sent as a binary message; the server numbers them from 1 per connection. At most
// kCameraInFlight frames are unanswered (no frame info or error yet): the server renders one while the page
// takes and encodes the next, and frames never queue up (the server keeps only the newest anyway).
// While one is unanswered, the next is taken only once the server's time per frame (decoding, registering,
// rendering, encoding: the median of the last few) has passed since the one before, lengthened or shortened
// by half of how much longer than kCameraQueued the last frames waited in the server before it took them:
// so a frame arrives about when the server is free, not a whole frame early (a frame that waits there is
// a frame late), and the server does not sit idle either.
const kCameraQuality = 0.85;
const kCameraInFlight = 2;
const kCameraTimeout = 2000;  // ms after which an unanswered frame no longer holds the next back
const kCameraQueued = 10;     // ms a frame may wait in the server for the one before it
const camera = {
  stream: null, video: null, canvas: null, number: 0, inFlight: new Map(), waiting: false,
  serverMs: [],  // per frame the server answered lately: its time for the frame
  queuedMs: [],  // and how long the frame waited there
  lastCaptured: -Infinity,
};

function cameraAnswered(number, message) {
  const sent = camera.inFlight.get(number);
  if (sent) sent.answered = true;
  if (message && message.camera && message.timings) {
    const c = message.camera;
    const ms = (c.decode_ms || 0) + (c.track_ms || 0) + message.timings.total_ms + (message.encode_ms || 0);
    if (Number.isFinite(ms) && Number.isFinite(c.queued_ms)) {
      camera.serverMs.push(ms);
      camera.queuedMs.push(c.queued_ms);
    }
    if (camera.serverMs.length > 8) camera.serverMs.shift();
    if (camera.queuedMs.length > 3) camera.queuedMs.shift();
  }
  if (camera.waiting) sendCameraFrame();
}

// The frames in flight and the server's times for the last ones, forgotten (a new connection, the camera off).
function forgetCameraFrames() {
  camera.inFlight.clear();
  camera.serverMs = [];
  camera.queuedMs = [];
}

// ms from one frame taken to the next while one is unanswered (0 until the server has answered a few)
function cameraPace() {
  if (camera.serverMs.length < 3) return 0;
  return Math.max(0, median(camera.serverMs) + 0.5 * (median(camera.queuedMs) - kCameraQueued));
}

// A frame drawn over a camera frame: the page's own (the latency from its capture) or the server's (from its
// arrival in the server to the JPEG sent, what the server measures).
function cameraShown(info, now) {
  const own = info.camera.client !== 0;
  const sent = own ? camera.inFlight.get(info.camera.number) : null;
  if (sent) live.camera.latencies.push(now - sent.captured);
  if (!own) live.camera.latencies.push(info.camera.latency_ms);
  if (live.camera.latencies.length > 10000) live.camera.latencies.splice(0, 5000);
  if (own) for (const n of camera.inFlight.keys()) if (n <= info.camera.number) camera.inFlight.delete(n);
  live.camera.shown += 1;
  live.camera.info = info.camera;
  const c = info.camera;
  const registration = c.registration === 'markers'
    ? `registered by ${c.markers_seen} marker${c.markers_seen === 1 ? '' : 's'} (${c.reprojection_error_px.toFixed(2)} px)`
    : c.registration === 'held' ? 'no marker: the last pose'
    : c.uncertain ? 'the markers seen fit poses far apart (one small marker alone: show another or come nearer): the camera image as it is'
    : 'no marker: the camera image as it is';
  const latency = median(live.camera.latencies.slice(-30));
  $('camera-status').textContent = `${own ? '' : `${live.serverCamera}: `}${registration} · ` +
    `${latency.toFixed(0)} ms from ${own ? 'capture to picture' : 'arrival to JPEG'} (median of the last 30) · ` +
    `${c.dropped} dropped` + (info.light ? ` · light frame ${info.light.frames}` : '');
}

function sendCameraFrame() {
  if (!camera.stream || !live.state || !socket || socket.readyState !== WebSocket.OPEN) return;
  const now = performance.now();
  for (const [n, sent] of camera.inFlight) if (now - sent.captured > kCameraTimeout) camera.inFlight.delete(n);
  const unanswered = [...camera.inFlight.values()].filter((sent) => !sent.answered).length;
  const early = unanswered > 0 && now - camera.lastCaptured < cameraPace();
  if (unanswered >= kCameraInFlight || early || camera.video.readyState < 2) {
    camera.waiting = true;
    return;
  }
  camera.waiting = false;
  const { width, height } = live.state;
  if (camera.canvas.width !== width || camera.canvas.height !== height) {
    camera.canvas.width = width;
    camera.canvas.height = height;
  }
  const captured = performance.now();
  camera.lastCaptured = captured;
  camera.canvas.getContext('2d').drawImage(camera.video, 0, 0, width, height);
  const number = ++camera.number;
  camera.inFlight.set(number, { captured, answered: false });
  camera.canvas.toBlob((blob) => {
    if (!blob || !socket || socket.readyState !== WebSocket.OPEN) return;
    // "DGIT" and the time the frame was taken (ms, little-endian float64) before the JPEG: the server's pose
    // filter takes it instead of the frame's arrival, which the encoding delays unevenly.
    const header = new DataView(new ArrayBuffer(12));
    for (let i = 0; i < 4; ++i) header.setUint8(i, 'DGIT'.charCodeAt(i));
    header.setFloat64(4, captured, true);
    socket.send(new Blob([header.buffer, blob]));
    live.camera.sent += 1;
  }, 'image/jpeg', kCameraQuality);
}

function onVideoFrame() {
  if (!camera.video) return;
  sendCameraFrame();
  camera.video.requestVideoFrameCallback(onVideoFrame);
}

async function startCamera() {
  if (!live.state) return;
  if (!navigator.mediaDevices || !navigator.mediaDevices.getUserMedia) {
    showError('camera: the browser gives pages a camera only over https or from this machine ' +
      '(http://localhost or http://127.0.0.1)');
    return;
  }
  const { width, height } = live.state;
  try {
    camera.stream = await navigator.mediaDevices.getUserMedia(
      { video: { width: { ideal: width }, height: { ideal: height } }, audio: false });
  } catch (e) {
    showError(`camera: ${e.name}: ${e.message}`);
    return;
  }
  camera.video = document.createElement('video');
  camera.video.muted = true;
  camera.video.playsInline = true;
  camera.video.srcObject = camera.stream;
  await camera.video.play();
  camera.canvas = document.createElement('canvas');
  const vw = camera.video.videoWidth, vh = camera.video.videoHeight;
  // The scene camera's intrinsics hold for its own aspect: another one is stretched, and registers badly.
  if (Math.abs(vw * height - vh * width) > Math.max(vw, width))
    showError(`camera: the camera gives ${vw}x${vh}, the scene camera is ${width}x${height}: ` +
      'the frames are stretched to it, and the markers register badly; calibrate the scene camera at this size');
  $('camera-toggle').textContent = 'stop the camera';
  camera.video.requestVideoFrameCallback(onVideoFrame);
}

function stopCamera() {
  if (camera.stream) for (const track of camera.stream.getTracks()) track.stop();
  camera.stream = null;
  camera.video = null;
  forgetCameraFrames();
  camera.waiting = false;
  $('camera-toggle').textContent = 'use my camera';
}
$('camera-toggle').onclick = () => (camera.stream ? stopCamera() : startCamera());

function download(url, name) {
  const link = document.createElement('a');
  link.href = url;
  link.download = name;
  document.body.append(link);
  link.click();
  link.remove();
}
$('save-scene').onclick = () => download('/scene.json', 'scene.json');
$('save-image').onclick = () => download('/image.png', 'image.png');
setInterval(() => send({ type: 'ping' }), 20000);

connect();
