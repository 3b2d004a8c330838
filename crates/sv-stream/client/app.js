// Spin-Valence deployment page: the client of `spinvalence serve` (protocol v1,
// docs/protocol.md). Shows the frame, the next unit with its target pose as a ghost, live
// checks with the move arrow and the progress; optional simulated tracker (?sim=1) and WebXR.
//
// State for tests is in DOM attributes: body[data-check] ("none" | "ok" | "bad"),
// body[data-progress] ("done/total"), body[data-connection]; the same on #check / #progress.

import { createFrameView } from './viewer.js';

const SUBPROTOCOL = 'spinvalence.v1';
const COLOURS = {
  idle: '#9aa0a6',
  done: '#3d7a57',
  mine: '#4f9cf7',
  claimed: '#e0a526',
  ok: '#1fa34a',
  bad: '#d93025',
};

const $ = (id) => document.getElementById(id);
const params = new URLSearchParams(location.search);
const SIM = params.get('sim') === '1';

// ---- state -------------------------------------------------------------------------------

const state = {
  ws: null,
  token: '',
  clientId: clientId(),
  role: null,
  epoch: null,
  seq: 0,
  tolerance: { position_mm: 5, angle_deg: 1, overlap_mm: 2 },
  units: [], // targets message units
  byId: new Map(),
  completed: new Set(),
  claims: new Map(), // unit -> client id
  done: 0,
  total: 0,
  next: null,
  lastCheck: null,
  checks: [], // ok flags, for tests and the log
  view: null,
  retry: 0,
  stopped: false,
};
window.__sv = state; // for tests and debugging

function clientId() {
  let id = null;
  try {
    id = localStorage.getItem('sv-client-id');
  } catch (_) { /* storage may be disabled */ }
  if (!id || !/^[A-Za-z0-9._:-]{1,128}$/.test(id)) {
    id = 'web-' + randomHex(8);
    try { localStorage.setItem('sv-client-id', id); } catch (_) { /* ignore */ }
  }
  return id;
}

function randomHex(bytes) {
  const a = new Uint8Array(bytes);
  crypto.getRandomValues(a);
  return Array.from(a, (b) => b.toString(16).padStart(2, '0')).join('');
}

function uuid() {
  if (crypto.randomUUID) return crypto.randomUUID();
  const h = randomHex(16);
  return `${h.slice(0, 8)}-${h.slice(8, 12)}-4${h.slice(13, 16)}-a${h.slice(17, 20)}-${h.slice(20)}`;
}

// ---- token: field or #token= fragment (never in the query string) -----------------------

function tokenFromFragment() {
  const frag = new URLSearchParams(location.hash.replace(/^#/, ''));
  const t = frag.get('token');
  if (t !== null) {
    // keep it out of the address bar and history
    history.replaceState(null, '', location.pathname + location.search);
    try { sessionStorage.setItem('sv-token', t); } catch (_) { /* ignore */ }
    return t;
  }
  try { return sessionStorage.getItem('sv-token') || ''; } catch (_) { return ''; }
}

$('login').addEventListener('submit', (e) => {
  e.preventDefault();
  state.token = $('token').value;
  try { sessionStorage.setItem('sv-token', state.token); } catch (_) { /* ignore */ }
  state.epoch = null; // a new login starts from a snapshot
  state.stopped = false;
  reconnect(0);
});

// ---- DOM state ----------------------------------------------------------------------------

function setConnection(text) {
  document.body.dataset.connection = text;
  $('connection').textContent = text;
}

function message(text) {
  $('message').textContent = text;
}

function setCheck(kind, text) {
  document.body.dataset.check = kind;
  $('check').dataset.check = kind;
  $('check').textContent = text;
}

function renderProgress() {
  const p = `${state.done}/${state.total}`;
  document.body.dataset.progress = p;
  $('progress').dataset.progress = p;
  $('progress').textContent = `${state.done} / ${state.total}` +
    (state.total && state.done === state.total ? ' - all units placed' : '');
  $('progress-bar').max = Math.max(1, state.total);
  $('progress-bar').value = state.done;
  const next = state.next ? state.byId.get(state.next) : null;
  $('next').textContent = state.next || (state.total ? 'all done' : '-');
  $('next').dataset.unit = state.next || '';
  $('next-strip').textContent = next && next.strip ? `strip ${next.strip}` : '';
  const operator = state.role === 'operator';
  const holder = state.next ? state.claims.get(state.next) : undefined;
  $('claim').disabled = !operator || !state.next || holder !== undefined;
  $('complete').disabled = !operator || !state.next || (holder !== undefined && holder !== state.clientId);
  renderView();
}

function unitColour(id) {
  if (state.lastCheck && state.lastCheck.unit === id) {
    return state.lastCheck.ok ? COLOURS.ok : COLOURS.bad;
  }
  if (state.completed.has(id)) return COLOURS.done;
  const holder = state.claims.get(id);
  if (holder !== undefined) return holder === state.clientId ? COLOURS.mine : COLOURS.claimed;
  return COLOURS.idle;
}

function renderView() {
  const v = state.view;
  if (!v) return;
  try {
    v.setColours((id) => unitColour(id));
    v.highlight(state.next);
    for (const u of state.units) {
      if (u.id !== state.next) v.setGhost(u.id, null);
    }
    const next = state.next ? state.byId.get(state.next) : null;
    if (next) v.setGhost(next.id, next.hub_pose);
  } catch (e) {
    console.error('viewer', e);
  }
}

function createView() {
  if (state.view) {
    try { state.view.dispose(); } catch (_) { /* ignore */ }
    state.view = null;
  }
  const container = $('view');
  container.replaceChildren();
  try {
    state.view = createFrameView(container, { units: state.units, background: '#101317' });
    state.view.onPick((id) => {
      const u = state.byId.get(id);
      if (u) message(`unit ${id}${u.strip ? ` (strip ${u.strip})` : ''}` +
        (state.completed.has(id) ? ', complete' : '') +
        (state.claims.has(id) ? `, claimed by ${state.claims.get(id)}` : ''));
    });
  } catch (e) {
    // no WebGL (or no viewer): the page still works, checks and progress included
    console.error('3D view unavailable', e);
    const p = document.createElement('p');
    p.className = 'fallback';
    p.textContent = `3D view unavailable: ${e && e.message ? e.message : e}`;
    container.append(p);
  }
  renderProgress();
}

// ---- protocol -----------------------------------------------------------------------------

function send(msg) {
  if (state.ws && state.ws.readyState === WebSocket.OPEN) {
    state.ws.send(JSON.stringify(msg));
    return true;
  }
  return false;
}

function wsUrl() {
  return `${location.protocol === 'https:' ? 'wss' : 'ws'}://${location.host}/ws`;
}

function connect() {
  setConnection('connecting');
  let ws;
  try {
    ws = new WebSocket(wsUrl(), SUBPROTOCOL);
  } catch (e) {
    message(`cannot connect: ${e.message}`);
    reconnect();
    return;
  }
  state.ws = ws;
  ws.onmessage = (ev) => {
    let msg;
    try {
      msg = JSON.parse(ev.data);
    } catch (_) {
      return;
    }
    try {
      handle(msg);
    } catch (e) {
      console.error('handling', msg, e);
    }
  };
  ws.onclose = (ev) => {
    if (state.ws !== ws) return;
    state.ws = null;
    state.role = null;
    setConnection('closed');
    if (ev.code === 4401) {
      message('wrong token: enter the operator or viewer token');
      state.stopped = true;
      $('token').focus();
      return;
    }
    reconnect();
  };
}

let retryTimer = null;
function reconnect(delay) {
  clearTimeout(retryTimer);
  if (state.ws) {
    const old = state.ws;
    state.ws = null;
    old.close();
  }
  if (state.stopped) return;
  const wait = delay !== undefined ? delay : Math.min(10000, 500 * 2 ** state.retry++);
  retryTimer = setTimeout(connect, wait);
}

function handle(msg) {
  switch (msg.type) {
    case 'welcome': {
      state.tolerance = msg.tolerance;
      const hello = { type: 'hello', token: state.token, client_id: state.clientId };
      if (state.epoch === msg.epoch && state.units.length) {
        hello.last = { epoch: state.epoch, seq: state.seq };
      }
      send(hello);
      break;
    }
    case 'ready': {
      state.retry = 0;
      state.role = msg.role;
      setConnection('ready');
      $('role').hidden = false;
      $('role').textContent = msg.role;
      $('sim-badge').hidden = !(SIM && msg.role === 'operator');
      if (SIM && msg.role !== 'operator') message('the simulated tracker needs the operator token');
      if (msg.mode === 'snapshot' || state.epoch !== msg.epoch) {
        const s = msg.snapshot || {};
        state.completed = new Set(s.completed || []);
        state.claims = new Map(Object.entries(s.claims || {}));
        state.done = s.done || 0;
        state.total = s.total || 0;
        state.next = s.next ?? null;
      }
      state.epoch = msg.epoch;
      state.seq = msg.seq;
      for (const ev of msg.events || []) applyEvent(ev);
      send({ type: 'get_targets' });
      renderProgress();
      break;
    }
    case 'targets': {
      state.units = msg.units;
      state.byId = new Map(msg.units.map((u) => [u.id, u]));
      if (!state.total) state.total = msg.units.length;
      createView();
      startSim();
      break;
    }
    case 'progress':
    case 'claimed':
    case 'released':
    case 'registration':
      applyEvent(msg);
      renderProgress();
      break;
    case 'check':
      onCheck(msg);
      break;
    case 'ack':
      if (msg.op === 'complete' && msg.applied) message(`${msg.unit} complete`);
      break;
    case 'overlap_check':
      message(`overlap ${msg.units.join('/')}: ${msg.measured_mm.toFixed(1)} mm measured, ` +
        `${msg.design_mm.toFixed(1)} mm design: ${msg.ok ? 'ok' : 'out of tolerance'}`);
      break;
    case 'fit':
      message(`registration RMS ${msg.transform.rms_mm.toFixed(2)} mm: ${msg.ok ? 'applied' : 'refused'}`);
      break;
    case 'error':
      $('errors').textContent = `${msg.code}: ${msg.message}`;
      break;
    default:
      break; // additions within v1 are ignored
  }
}

function applyEvent(ev) {
  if (typeof ev.seq === 'number') state.seq = Math.max(state.seq, ev.seq);
  switch (ev.type) {
    case 'progress':
      state.completed.add(ev.unit);
      state.claims.delete(ev.unit);
      state.done = ev.done;
      state.total = ev.total;
      if (state.next !== ev.next) {
        state.next = ev.next;
        simReset();
      }
      break;
    case 'claimed':
      state.claims.set(ev.unit, ev.by);
      break;
    case 'released':
      state.claims.delete(ev.unit);
      break;
    case 'registration':
      // targets move into the new site frame
      send({ type: 'get_targets' });
      break;
    default:
      break;
  }
}

function onCheck(c) {
  state.lastCheck = c;
  state.checks.push(c.ok);
  const text = `${c.unit} ${c.part}: ${c.ok ? 'in tolerance' : 'move it'} - ` +
    `${c.position_error_mm.toFixed(1)} mm, ${c.angle_error_deg.toFixed(2)} deg`;
  setCheck(c.ok ? 'ok' : 'bad', text);
  const [dx, dy, dz] = c.move_mm;
  $('move').textContent = `move x ${dx.toFixed(1)}, y ${dy.toFixed(1)}, z ${dz.toFixed(1)} mm` +
    ` (tolerance ${state.tolerance.position_mm} mm, ${state.tolerance.angle_deg} deg)`;
  const u = state.byId.get(c.unit);
  if (u && state.view) {
    const target = c.part === 'primary' ? u.primary_pose : u.hub_pose;
    const p = target.position;
    const tracked = [p[0] - dx, p[1] - dy, p[2] - dz];
    try {
      state.view.setMarker(tracked, c.move_mm, c.ok ? COLOURS.ok : COLOURS.bad);
    } catch (e) {
      console.error('viewer', e);
    }
  }
  renderView();
}

// ---- operator buttons -------------------------------------------------------------------

$('claim').addEventListener('click', () => {
  if (state.next) send({ type: 'claim', unit: state.next });
});
$('complete').addEventListener('click', () => {
  if (state.next) send({ type: 'complete', unit: state.next, op_id: uuid() });
});

// ---- simulated tracker (?sim=1) -----------------------------------------------------------
// Sends `track` messages (source "sim") for the next unit's hub, starting a few centimetres
// and degrees off its target and converging on it, at 10 Hz (under the 30 Hz rate limit).

const sim = { timer: null, step: 0, offset: [0, 0, 0], turn: 0 };

function simReset() {
  sim.step = 0;
  sim.offset = [38, -24, 16];
  sim.turn = 3; // degrees about the tile normal
}

function startSim() {
  if (!SIM || sim.timer) return;
  simReset();
  sim.timer = setInterval(simTick, 100);
}

function quatMul(a, b) {
  const [ax, ay, az, aw] = a;
  const [bx, by, bz, bw] = b;
  return [
    aw * bx + ax * bw + ay * bz - az * by,
    aw * by - ax * bz + ay * bw + az * bx,
    aw * bz + ax * by - ay * bx + az * bw,
    aw * bw - ax * bx - ay * by - az * bz,
  ];
}

function simTick() {
  if (state.role !== 'operator' || !state.next) return;
  const u = state.byId.get(state.next);
  if (!u) return;
  const k = 0.72 ** sim.step;
  sim.step += 1;
  const jitter = () => (Math.random() - 0.5) * 0.6; // +-0.3 mm of tracker noise
  const p = u.hub_pose.position;
  const position = [0, 1, 2].map((i) => p[i] + sim.offset[i] * k + jitter());
  const half = ((sim.turn * k) * Math.PI) / 360;
  // turn about the tile's own z axis: target * rot_z
  const rotation = quatMul(u.hub_pose.rotation, [0, 0, Math.sin(half), Math.cos(half)]);
  send({
    type: 'track',
    unit: u.id,
    part: 'hub',
    pose: { position, rotation },
    source: 'sim',
    ref: sim.step,
  });
}

// ---- WebXR ----------------------------------------------------------------------------------

async function setupXR() {
  const button = $('enter-ar');
  if (!navigator.xr || !navigator.xr.isSessionSupported) return;
  let supported = false;
  try {
    supported = await navigator.xr.isSessionSupported('immersive-ar');
  } catch (_) {
    supported = false;
  }
  if (!supported) return;
  button.hidden = false;
  button.addEventListener('click', enterAR);
}

let xrSession = null;
async function enterAR() {
  const v = state.view;
  if (!v || !v.renderer) {
    message('AR needs the 3D view');
    return;
  }
  if (xrSession) {
    await xrSession.end();
    return;
  }
  try {
    const session = await navigator.xr.requestSession('immersive-ar', {
      optionalFeatures: ['local-floor', 'dom-overlay'],
      domOverlay: { root: $('overlay') },
    });
    xrSession = session;
    const scene = v.scene;
    const saved = {
      background: scene.background,
      scale: scene.scale.clone(),
      position: scene.position.clone(),
      rotation: scene.rotation.clone(),
    };
    // the frame is in mm with Z up; WebXR is in metres with Y up. Until a site registration
    // places it, the frame's origin is put 1.5 m in front of the device at floor level.
    scene.background = null;
    scene.scale.setScalar(0.001);
    scene.rotation.set(-Math.PI / 2, 0, 0);
    scene.position.set(0, 0, -1.5);
    v.renderer.xr.enabled = true;
    v.renderer.xr.setReferenceSpaceType('local-floor');
    await v.renderer.xr.setSession(session);
    v.renderer.setAnimationLoop(() => v.renderer.render(scene, v.camera));
    document.body.classList.add('xr');
    $('enter-ar').textContent = 'Exit AR';
    session.addEventListener('end', () => {
      xrSession = null;
      v.renderer.setAnimationLoop(null);
      v.renderer.xr.enabled = false;
      scene.background = saved.background;
      scene.scale.copy(saved.scale);
      scene.position.copy(saved.position);
      scene.rotation.copy(saved.rotation);
      document.body.classList.remove('xr');
      $('enter-ar').textContent = 'Enter AR';
      // let the viewer resume its own rendering
      window.dispatchEvent(new Event('resize'));
    });
  } catch (e) {
    xrSession = null;
    message(`AR failed: ${e.message || e}`);
  }
}

// ---- start ------------------------------------------------------------------------------------

state.token = tokenFromFragment();
$('token').value = state.token;
setCheck('none', 'no tracking yet');
renderProgress();
setupXR();
connect();
