// Spin-Valence deployment page: the client of `spinvalence serve` (protocol v1,
// docs/protocol.md). Shows the frame, the next unit with its target pose as a ghost, live
// checks with the move arrow and the progress; a simulated tracker (?sim=1); and WebXR AR
// (headset or phone): the frame placed by the site registration, a head-up panel with the
// connection, the next unit and its check, and measuring a part by picking its corners.
//
// State for tests is in DOM attributes on <body>: data-check ("none" | "ok" | "bad" |
// "stale"), data-progress ("done/total"), data-connection ("connecting" | "ready" |
// "closed"), data-units (units loaded), data-queued (actions waiting for the server),
// data-xr ("on" | "off"), data-registered ("yes" | "no"), data-hud (the AR panel's text).

import * as THREE from './vendor/three.module.js';
import { createFrameView } from './viewer.js';

const SUBPROTOCOL = 'spinvalence.v1';
const COLOURS = {
  idle: '#9aa0a6',
  done: '#3d7a57',
  mine: '#4f9cf7',
  claimed: '#e0a526',
  ok: '#1fa34a',
  bad: '#d93025',
  stale: '#8a7a2a',
};
/** A check older than this is shown as stale, never as a current verdict. */
const CHECK_STALE_MS = 4000;
/** Complete must be confirmed within this time. */
const CONFIRM_MS = 8000;
/** Undo is offered this long after Complete (the server allows 60 s). */
const UNDO_MS = 15000;

const $ = (id) => document.getElementById(id);
const params = new URLSearchParams(location.search);
const SIM = params.get('sim') === '1';
const num = (x) => typeof x === 'number' && Number.isFinite(x);

// ---- state -------------------------------------------------------------------------------

const state = {
  ws: null,
  token: '',
  clientId: clientId(),
  role: null,
  lastRole: null, // kept while offline: an operator may queue actions
  epoch: null,
  seq: 0,
  tolerance: { position_mm: 5, angle_deg: 1, overlap_mm: 2 },
  units: [], // model-frame targets
  byId: new Map(),
  frameKey: '',
  incoming: null, // targets pages being received
  completed: new Set(),
  claims: new Map(), // unit -> client id
  done: 0,
  total: 0,
  next: null,
  registration: null, // {rotation, translation, rms_mm}: site = R model + t
  lastCheck: null,
  checkAt: 0,
  checks: [], // ok flags, for tests and the log
  queue: [], // complete / undo messages not yet sent
  inflight: [], // sent, not yet answered (re-sent after a reconnect: op ids make it safe)
  confirm: null, // {unit, until}
  undo: null, // {unit, op_id, until}
  measure: null, // {kind: 'hub' | 'overlap', unit, points: [site mm], need}
  view: null,
  retry: 0,
  stopped: false,
  xrFrames: 0,
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

const online = () => state.ws !== null && state.role !== null;

function setConnection(text) {
  document.body.dataset.connection = text;
  $('connection').textContent = text === 'ready' ? 'online'
    : text === 'closed' ? 'OFFLINE: reconnecting' : 'connecting';
  if (text !== 'ready') staleNow();
  renderControls();
}

function message(text) {
  $('message').textContent = text;
  hudDirty();
}

function setCheck(kind, text) {
  document.body.dataset.check = kind;
  $('check').dataset.check = kind;
  $('check').textContent = text;
  hudDirty();
}

/** A length or angle with enough digits to tell it from its tolerance, and the comparison. */
function versus(value, tol, unit) {
  let digits = 2;
  while (digits < 6 && value.toFixed(digits) === tol.toFixed(digits) && value !== tol) digits += 1;
  return `${value.toFixed(digits)} ${unit} ${value <= tol ? '<=' : '>'} ${tol.toFixed(2)} ${unit}`;
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
  renderControls();
  renderView();
}

function renderControls() {
  const operator = (state.role || state.lastRole) === 'operator';
  const holder = state.next ? state.claims.get(state.next) : undefined;
  const mayComplete = operator && state.next && (holder === undefined || holder === state.clientId);
  $('claim').disabled = !online() || !operator || !state.next || holder !== undefined;
  const confirming = state.confirm && state.confirm.until > Date.now();
  $('complete').disabled = !mayComplete && !confirming;
  $('complete').textContent = confirming ? 'Cancel' : 'Complete';
  $('confirm-row').hidden = !confirming;
  if (confirming) $('confirm').textContent = `Confirm complete ${state.confirm.unit}`;
  const undoing = state.undo && state.undo.until > Date.now();
  $('undo-row').hidden = !undoing;
  if (undoing) {
    const s = Math.ceil((state.undo.until - Date.now()) / 1000);
    $('undo').textContent = `Undo complete ${state.undo.unit} (${s} s)`;
  }
  const waiting = state.queue.length + state.inflight.length;
  document.body.dataset.queued = String(state.queue.length);
  $('queued').textContent = state.queue.length
    ? `${state.queue.map(describe).join(', ')}: queued, sent when back online`
    : (waiting ? 'waiting for the server' : '');
  $('measure-row').hidden = !xr.session;
  $('measure').disabled = !operator || !state.next;
  $('measure-overlap').disabled = !operator || !state.next;
  document.body.dataset.registered = state.registration ? 'yes' : 'no';
  $('registered').textContent = state.registration
    ? `registered (${state.registration.rms_mm.toFixed(1)} mm RMS)` : 'not registered';
  hudDirty();
}

function describe(m) {
  return m.type === 'undo' ? `Undo ${m.unit}` : `Complete ${m.unit}`;
}

function unitColour(id) {
  if (state.lastCheck && state.lastCheck.unit === id) {
    if (Date.now() - state.checkAt > CHECK_STALE_MS || !online()) return COLOURS.stale;
    return state.lastCheck.ok ? COLOURS.ok : COLOURS.bad;
  }
  if (state.completed.has(id)) return COLOURS.done;
  const holder = state.claims.get(id);
  if (holder !== undefined) return holder === state.clientId ? COLOURS.mine : COLOURS.claimed;
  return COLOURS.idle;
}

let ghostId = null;
function renderView() {
  const v = state.view;
  if (!v) return;
  try {
    v.setColours((id) => unitColour(id));
    v.highlight(state.next);
    if (ghostId && ghostId !== state.next) v.setGhost(ghostId, null);
    const next = state.next ? state.byId.get(state.next) : null;
    ghostId = next ? next.id : null;
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
  ghostId = null;
  const container = $('view');
  container.replaceChildren();
  try {
    state.view = createFrameView(container, { units: state.units, background: '#101317' });
    state.view.renderer.domElement.id = 'frame-canvas';
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

/** Targets arrived (all pages): keep the view when they are the frame it shows. */
function loadUnits(units) {
  const key = `${units.length}:${units.map((u) => u.id).join(',')}:` +
    JSON.stringify([units[0] && units[0].hub, units[units.length - 1] && units[units.length - 1].hub]);
  state.units = units;
  state.byId = new Map(units.map((u) => [u.id, u]));
  document.body.dataset.units = String(units.length);
  if (!state.total) state.total = units.length;
  if (key === state.frameKey && state.view) {
    renderProgress();
    return;
  }
  if (xr.session) {
    // never pull the scene from under a running AR session
    message('the server has another frame: exit AR to load it');
    return;
  }
  state.frameKey = key;
  createView();
  startSim();
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
    // answers that did not come are asked again on the next connection (op ids: once)
    state.queue = state.inflight.concat(state.queue);
    state.inflight = [];
    setConnection('closed');
    if (ev.code === 4401 || ev.code === 4429) {
      message(ev.code === 4401 ? 'wrong token: enter the operator or viewer token'
        : 'too many wrong tokens from this device: wait, then enter the token');
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
      if (msg.tolerance && num(msg.tolerance.position_mm)) state.tolerance = msg.tolerance;
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
      state.lastRole = msg.role;
      $('role').hidden = false;
      $('role').textContent = msg.role;
      $('sim-badge').hidden = !(SIM && msg.role === 'operator');
      if (SIM && msg.role !== 'operator') message('the simulated tracker needs the operator token');
      const newEpoch = state.epoch !== msg.epoch;
      if (msg.mode === 'snapshot' || newEpoch) {
        const s = msg.snapshot || {};
        state.completed = new Set(s.completed || []);
        state.claims = new Map(Object.entries(s.claims || {}));
        state.done = s.done || 0;
        state.total = s.total || 0;
        state.next = s.next ?? null;
        setRegistration(s.registration || null);
      }
      state.epoch = msg.epoch;
      state.seq = msg.seq;
      for (const ev of msg.events || []) applyEvent(ev);
      setConnection('ready');
      if (!state.units.length || newEpoch) send({ type: 'get_targets', frame: 'model' });
      flushQueue();
      renderProgress();
      break;
    }
    case 'targets': {
      if (msg.offset === 0) state.incoming = [];
      if (!state.incoming || msg.offset !== state.incoming.length) {
        state.incoming = null; // out of step: the next answer starts over
        break;
      }
      for (const u of msg.units) state.incoming.push(u);
      if (state.incoming.length >= msg.total) {
        const units = state.incoming;
        state.incoming = null;
        loadUnits(units);
      }
      break;
    }
    case 'progress':
    case 'reopened':
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
      answered();
      if (msg.op === 'complete') message(`${msg.unit} complete${msg.applied ? '' : ' (already recorded)'}`);
      if (msg.op === 'undo') message(`${msg.unit} taken back`);
      renderControls();
      break;
    case 'overlap_check':
      if ([msg.measured_mm, msg.design_mm, msg.error_mm].every(num) && typeof msg.ok === 'boolean') {
        message(`overlap ${msg.units.join('/')}: ${msg.measured_mm.toFixed(2)} mm measured, ` +
          `${msg.design_mm.toFixed(2)} mm design, ${versus(Math.abs(msg.error_mm), state.tolerance.overlap_mm, 'mm')}: ` +
          `${msg.ok ? 'ok' : 'OUT OF TOLERANCE'}`);
      } else {
        message('overlap answer unreadable');
      }
      break;
    case 'fit':
      if (msg.transform && num(msg.transform.rms_mm)) {
        message(`registration RMS ${msg.transform.rms_mm.toFixed(2)} mm: ${msg.ok ? 'applied' : 'refused'}`);
      }
      break;
    case 'error':
      if (['already_done', 'claimed', 'not_undoable', 'unknown_unit', 'not_claimed'].includes(msg.code)) answered();
      $('errors').textContent = `${msg.code}: ${msg.message}`;
      hudDirty();
      break;
    default:
      break; // additions within v1 are ignored
  }
}

state.handle = handle; // tests feed it hostile server messages

function applyEvent(ev) {
  if (typeof ev.seq === 'number') state.seq = Math.max(state.seq, ev.seq);
  switch (ev.type) {
    case 'progress':
    case 'reopened':
      if (ev.type === 'progress') {
        state.completed.add(ev.unit);
        state.claims.delete(ev.unit);
      } else {
        state.completed.delete(ev.unit);
      }
      state.done = ev.done;
      state.total = ev.total;
      if (state.next !== ev.next) {
        state.next = ev.next;
        simReset();
        if (state.measure) state.measure = null;
      }
      break;
    case 'claimed':
      state.claims.set(ev.unit, ev.by);
      break;
    case 'released':
      state.claims.delete(ev.unit);
      break;
    case 'registration':
      setRegistration(ev.transform);
      break;
    default:
      break;
  }
}

function setRegistration(t) {
  const valid = t && Array.isArray(t.rotation) && t.rotation.length === 4 && t.rotation.every(num) &&
    Array.isArray(t.translation) && t.translation.length === 3 && t.translation.every(num);
  state.registration = valid ? t : null;
  placeWorld(); // the AR scene moves in place; nothing is rebuilt
  renderControls();
}

function onCheck(c) {
  const valid = typeof c.unit === 'string' && (c.part === 'hub' || c.part === 'primary') &&
    typeof c.ok === 'boolean' && num(c.position_error_mm) && num(c.angle_error_deg) &&
    Array.isArray(c.move_mm) && c.move_mm.length === 3 && c.move_mm.every(num);
  if (!valid) {
    // never leave an old verdict on screen when the new one cannot be read
    state.lastCheck = null;
    setCheck('none', 'check unreadable: no verdict');
    $('move').textContent = '';
    if (state.view) state.view.setMarker(null);
    renderView();
    return;
  }
  state.lastCheck = c;
  state.checkAt = Date.now();
  state.checks.push(c.ok);
  const tol = state.tolerance;
  const text = `${c.unit} ${c.part}: ${c.ok ? 'IN TOLERANCE' : 'MOVE IT'} - ` +
    `${versus(c.position_error_mm, tol.position_mm, 'mm')}, ${versus(c.angle_error_deg, tol.angle_deg, 'deg')}`;
  setCheck(c.ok ? 'ok' : 'bad', text);
  const move = modelVector(c.move_mm, c.frame);
  $('move').textContent = `move x ${c.move_mm[0].toFixed(1)}, y ${c.move_mm[1].toFixed(1)}, ` +
    `z ${c.move_mm[2].toFixed(1)} mm (${c.frame || 'site'} frame)`;
  const u = state.byId.get(c.unit);
  if (u && state.view) {
    const target = c.part === 'primary' ? u.primary_pose : u.hub_pose;
    const p = target.position;
    const tracked = [p[0] - move[0], p[1] - move[1], p[2] - move[2]];
    try {
      state.view.setMarker(tracked, move, c.ok ? COLOURS.ok : COLOURS.bad);
    } catch (e) {
      console.error('viewer', e);
    }
  }
  renderView();
}

/** A site-frame vector in model coordinates (the view is in the model frame). */
function modelVector(v, frame) {
  if (frame === 'model' || !state.registration) return v;
  const [x, y, z, w] = state.registration.rotation;
  const q = new THREE.Quaternion(x, y, z, w).normalize().invert();
  const r = new THREE.Vector3(v[0], v[1], v[2]).applyQuaternion(q);
  return [r.x, r.y, r.z];
}

function staleNow() {
  if (state.lastCheck && document.body.dataset.check !== 'stale') {
    setCheck('stale', `${$('check').textContent} (stale: not current)`);
    renderView();
  }
}

setInterval(() => {
  if (state.lastCheck && Date.now() - state.checkAt > CHECK_STALE_MS) staleNow();
  if (state.confirm && state.confirm.until <= Date.now()) state.confirm = null;
  if (state.undo && state.undo.until <= Date.now()) state.undo = null;
  renderControls();
}, 500);

// ---- operator actions: confirmed, queued while offline, undoable ------------------------

function submit(msg) {
  state.queue.push(msg);
  flushQueue();
  renderControls();
}

function flushQueue() {
  while (online() && state.queue.length) {
    const m = state.queue.shift();
    if (!send(m)) {
      state.queue.unshift(m);
      break;
    }
    state.inflight.push(m);
  }
}

function answered() {
  state.inflight.shift();
}

function pressComplete() {
  if (state.confirm && state.confirm.until > Date.now()) {
    state.confirm = null; // the same button is Cancel while confirming
  } else if (state.next) {
    state.confirm = { unit: state.next, until: Date.now() + CONFIRM_MS };
  }
  renderControls();
}

function confirmComplete() {
  if (!state.confirm || state.confirm.until <= Date.now()) return;
  const unit = state.confirm.unit;
  state.confirm = null;
  const op_id = uuid();
  submit({ type: 'complete', unit, op_id });
  state.undo = { unit, op_id, until: Date.now() + UNDO_MS };
  message(online() ? `completing ${unit}` : `${unit}: Complete queued, sent when back online`);
  renderControls();
}

function pressUndo() {
  const u = state.undo;
  if (!u) return;
  state.undo = null;
  const queued = state.queue.findIndex((m) => m.type === 'complete' && m.op_id === u.op_id);
  if (queued >= 0) {
    state.queue.splice(queued, 1); // never sent: nothing to take back
    message(`Complete ${u.unit} cancelled`);
  } else {
    submit({ type: 'undo', unit: u.unit, op_id: u.op_id });
  }
  renderControls();
}

$('claim').addEventListener('click', () => {
  if (state.next) send({ type: 'claim', unit: state.next });
});
$('complete').addEventListener('click', pressComplete);
$('confirm').addEventListener('click', confirmComplete);
$('undo').addEventListener('click', pressUndo);
$('measure').addEventListener('click', () => startMeasure('hub'));
$('measure-overlap').addEventListener('click', () => startMeasure('overlap'));

// ---- simulated tracker (?sim=1) -----------------------------------------------------------
// Sends `track` messages (source "sim", model frame) for the next unit's hub, starting a few
// centimetres and degrees off its target and converging on it, at 10 Hz (under the 30 Hz
// rate limit).

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
    frame: 'model',
    ref: sim.step,
  });
}

// ---- measuring a part: picked corners -> fitted pose -> track ---------------------------

/** Rigid fit measured ~ R model + t (Horn's quaternion method, Jacobi eigen-solver). */
export function fitRigid(model, measured) {
  const n = model.length;
  const mean = (pts) => [0, 1, 2].map((k) => pts.reduce((s, p) => s + p[k], 0) / n);
  const cm = mean(model);
  const cs = mean(measured);
  const S = [[0, 0, 0], [0, 0, 0], [0, 0, 0]];
  for (let i = 0; i < n; i++) {
    for (let r = 0; r < 3; r++) {
      for (let c = 0; c < 3; c++) S[r][c] += (model[i][r] - cm[r]) * (measured[i][c] - cs[c]);
    }
  }
  const [[xx, xy, xz], [yx, yy, yz], [zx, zy, zz]] = S;
  const N = [
    [xx + yy + zz, yz - zy, zx - xz, xy - yx],
    [yz - zy, xx - yy - zz, xy + yx, zx + xz],
    [zx - xz, xy + yx, -xx + yy - zz, yz + zy],
    [xy - yx, zx + xz, yz + zy, -xx - yy + zz],
  ];
  // Jacobi rotations until N is diagonal; V holds its eigenvectors
  const V = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]];
  for (let sweep = 0; sweep < 50; sweep++) {
    let off = 0;
    for (let p = 0; p < 4; p++) for (let q = p + 1; q < 4; q++) off += N[p][q] * N[p][q];
    if (off < 1e-30) break;
    for (let p = 0; p < 4; p++) {
      for (let q = p + 1; q < 4; q++) {
        if (Math.abs(N[p][q]) < 1e-300) continue;
        const theta = (N[q][q] - N[p][p]) / (2 * N[p][q]);
        const t = Math.sign(theta || 1) / (Math.abs(theta) + Math.sqrt(theta * theta + 1));
        const c = 1 / Math.sqrt(t * t + 1);
        const s = t * c;
        for (let k = 0; k < 4; k++) {
          const a = N[k][p];
          const b = N[k][q];
          N[k][p] = c * a - s * b;
          N[k][q] = s * a + c * b;
        }
        for (let k = 0; k < 4; k++) {
          const a = N[p][k];
          const b = N[q][k];
          N[p][k] = c * a - s * b;
          N[q][k] = s * a + c * b;
        }
        for (let k = 0; k < 4; k++) {
          const a = V[k][p];
          const b = V[k][q];
          V[k][p] = c * a - s * b;
          V[k][q] = s * a + c * b;
        }
      }
    }
  }
  let best = 0;
  for (let k = 1; k < 4; k++) if (N[k][k] > N[best][best]) best = k;
  const [w, x, y, z] = [V[0][best], V[1][best], V[2][best], V[3][best]];
  const q = new THREE.Quaternion(x, y, z, w).normalize();
  const c = new THREE.Vector3(...cm).applyQuaternion(q);
  return { rotation: [q.x, q.y, q.z, q.w], translation: [cs[0] - c.x, cs[1] - c.y, cs[2] - c.z] };
}

function startMeasure(kind) {
  if (!state.next) return;
  const u = state.byId.get(state.next);
  if (!u) return;
  if (kind === 'overlap' && !(u.neighbours || []).length) {
    message(`${u.id} has no linked neighbour to measure an overlap with`);
    return;
  }
  state.measure = { kind, unit: u.id, points: [], need: kind === 'hub' ? 3 : 2 };
  showPickHint();
  message(measurePrompt());
  renderControls();
}

function measurePrompt() {
  const m = state.measure;
  if (!m) return '';
  const k = m.points.length + 1;
  return m.kind === 'hub'
    ? `measure ${m.unit}: pick hub corner ${k} of 3 (marked on the ghost)`
    : `overlap of ${m.unit}: pick ${k === 1 ? 'one end' : 'the other end'} of the overlap`;
}

/** A picked point (site mm): collect it, and fit and send when the part has enough. */
function addPick(site) {
  const m = state.measure;
  if (!m) return;
  m.points.push(site);
  if (m.points.length < m.need) {
    showPickHint();
    message(measurePrompt());
    return;
  }
  state.measure = null;
  showPickHint();
  const u = state.byId.get(m.unit);
  if (!u) return;
  if (m.kind === 'overlap') {
    const [a, b] = m.points;
    const measured = Math.hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
    const neighbour = u.neighbours.find((n) => state.completed.has(n)) || u.neighbours[0];
    send({ type: 'overlap', units: [u.id, neighbour], measured_mm: measured });
    message(`overlap ${u.id}/${neighbour}: ${measured.toFixed(2)} mm picked, checking`);
    return;
  }
  const fit = fitRigid(u.hub.slice(0, 3), m.points);
  const q = new THREE.Quaternion(...fit.rotation);
  const p = new THREE.Vector3(...u.hub_pose.position).applyQuaternion(q)
    .add(new THREE.Vector3(...fit.translation));
  const r = q.clone().multiply(new THREE.Quaternion(...u.hub_pose.rotation));
  state.arTracks = (state.arTracks || 0) + 1;
  send({
    type: 'track',
    unit: u.id,
    part: 'hub',
    pose: { position: [p.x, p.y, p.z], rotation: [r.x, r.y, r.z, r.w] },
    source: 'ar',
    frame: 'site',
    ref: `ar-${state.arTracks}`,
  });
  message(`${u.id}: pose fitted to 3 corners, checking`);
}

let hint = null;
function showPickHint() {
  const v = state.view;
  if (!v) return;
  if (!hint) {
    hint = new THREE.Mesh(new THREE.SphereGeometry(v.edge * 0.04, 16, 12),
      new THREE.MeshBasicMaterial({ color: 0xff00ff, depthTest: false }));
    hint.renderOrder = 20;
    v.world.add(hint);
  }
  const m = state.measure;
  const u = m && state.byId.get(m.unit);
  hint.visible = Boolean(u && m.kind === 'hub');
  if (hint.visible) hint.position.set(...u.hub[m.points.length]);
  v.render();
  hudDirty();
}

// ---- WebXR ----------------------------------------------------------------------------------

const xr = {
  session: null,
  refSpace: null,
  viewerSpace: null,
  hud: null,
  saved: null,
  picks: [],
  dirty: true,
};

/** XR local-floor (m, Y up) from site (mm, Z up): the inverse is `siteOfXr`. */
const SITE_TO_XR = new THREE.Matrix4().makeRotationX(-Math.PI / 2)
  .multiply(new THREE.Matrix4().makeScale(0.001, 0.001, 0.001));

function siteOfXr(p) {
  return [p.x * 1000, -p.z * 1000, p.y * 1000];
}

/** Where the frame goes in AR: the site registration, or until there is one, its centre
 * 1.5 m in front of the start position with its lowest point on the floor. */
function placementMatrix() {
  const reg = state.registration;
  if (reg) {
    const [x, y, z, w] = reg.rotation;
    const t = new THREE.Matrix4().compose(new THREE.Vector3(...reg.translation),
      new THREE.Quaternion(x, y, z, w).normalize(), new THREE.Vector3(1, 1, 1));
    return SITE_TO_XR.clone().multiply(t);
  }
  const b = state.view.bounds;
  const c = b.isEmpty() ? new THREE.Vector3() : b.getCenter(new THREE.Vector3());
  const floor = b.isEmpty() ? 0 : b.min.z;
  return new THREE.Matrix4().makeTranslation(0, 0, -1.5).multiply(SITE_TO_XR)
    .multiply(new THREE.Matrix4().makeTranslation(-c.x, -c.y, -floor));
}

function placeWorld() {
  const v = state.view;
  if (!v || !xr.session) return;
  v.world.matrixAutoUpdate = false;
  v.world.matrix.copy(placementMatrix());
  v.world.matrixWorldNeedsUpdate = true;
  hudDirty();
}

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

async function enterAR() {
  const v = state.view;
  if (!v || !v.renderer) {
    message('AR needs the 3D view');
    return;
  }
  if (xr.session) {
    await xr.session.end();
    return;
  }
  let session;
  try {
    session = await navigator.xr.requestSession('immersive-ar', {
      requiredFeatures: ['local-floor'],
      optionalFeatures: ['dom-overlay', 'hit-test'],
      domOverlay: { root: $('overlay') },
    });
  } catch (e) {
    message(`AR failed: ${e.message || e}`);
    return;
  }
  xr.session = session;
  const { scene, camera, renderer } = v;
  xr.saved = { background: scene.background, near: camera.near, far: camera.far };
  // the scene is in metres in AR: near and far planes for people and buildings, not mm
  scene.background = null;
  camera.near = 0.05;
  camera.far = 1000;
  camera.updateProjectionMatrix();
  renderer.xr.enabled = true;
  renderer.xr.setReferenceSpaceType('local-floor');
  try {
    await renderer.xr.setSession(session);
    xr.refSpace = renderer.xr.getReferenceSpace();
    xr.viewerSpace = await session.requestReferenceSpace('viewer');
  } catch (e) {
    message(`AR failed: ${e.message || e}`);
    session.end().catch(() => {});
    return;
  }
  placeWorld();
  xr.hud = createHud();
  scene.add(xr.hud.mesh);
  renderer.setAnimationLoop(onXRFrame);
  session.addEventListener('select', onXRSelect);
  session.addEventListener('end', onXREnd);
  document.addEventListener('pointerup', onScreenTap, true);
  document.body.classList.add('xr');
  document.body.dataset.xr = 'on';
  $('enter-ar').textContent = 'Exit AR';
  renderControls();
}

function onXREnd() {
  const v = state.view;
  xr.session = null;
  for (const p of xr.picks) p.resolve(null);
  xr.picks = [];
  document.removeEventListener('pointerup', onScreenTap, true);
  if (v) {
    v.renderer.setAnimationLoop(null);
    v.renderer.xr.enabled = false;
    v.scene.background = xr.saved.background;
    v.camera.near = xr.saved.near;
    v.camera.far = xr.saved.far;
    v.camera.updateProjectionMatrix();
    v.world.matrix.identity();
    v.world.matrixAutoUpdate = true;
    if (xr.hud) v.scene.remove(xr.hud.mesh);
  }
  xr.hud = null;
  document.body.classList.remove('xr');
  document.body.dataset.xr = 'off';
  $('enter-ar').textContent = 'Enter AR';
  state.measure = null;
  renderControls();
  // let the viewer resume its own rendering
  window.dispatchEvent(new Event('resize'));
}

function onXRFrame(time, frame) {
  const v = state.view;
  state.xrFrames += 1;
  if (frame) processPicks(frame); // three calls the loop without a frame outside XR frames
  positionHud();
  if (xr.dirty) drawHud();
  v.renderer.render(v.scene, v.camera);
}

// ---- picking: controller or hand ray (headset), screen tap (phone), both by hit-test ----

function rayOf(transform) {
  const m = new THREE.Matrix4().fromArray(transform.matrix);
  const origin = new THREE.Vector3().setFromMatrixPosition(m);
  const dir = new THREE.Vector3(0, 0, -1).transformDirection(m);
  return new THREE.Ray(origin, dir);
}

function onXRSelect(ev) {
  const src = ev.inputSource;
  if (src.targetRayMode === 'screen') return; // phones: taps come through onScreenTap
  const pose = ev.frame.getPose(src.targetRaySpace, xr.refSpace);
  if (!pose) return;
  const ray = rayOf(pose.transform);
  if (hudPress(ray)) return;
  if (!state.measure) return;
  // the controller's tip when nothing is hit: touch the corner with it
  const tip = [pose.transform.position.x, pose.transform.position.y, pose.transform.position.z];
  pickAlong(src.targetRaySpace, null).then((p) => {
    const at = p || new THREE.Vector3(...tip);
    addPick(siteOfXr(at));
  });
}

function onScreenTap(ev) {
  if (!xr.session) return;
  if (ev.target && ev.target.closest && ev.target.closest('button, input, form')) return;
  const cam = state.view.renderer.xr.getCamera();
  const view = cam.cameras && cam.cameras.length ? cam.cameras[0] : cam;
  const ndc = new THREE.Vector3((ev.clientX / innerWidth) * 2 - 1, -(ev.clientY / innerHeight) * 2 + 1, 0.5);
  const dir = ndc.clone().applyMatrix4(view.projectionMatrixInverse).normalize();
  // the HUD first (a phone without a DOM overlay), then the world
  const worldRay = new THREE.Ray(new THREE.Vector3().setFromMatrixPosition(view.matrix),
    dir.clone().transformDirection(view.matrix));
  if (hudPress(worldRay)) return;
  if (!state.measure) return;
  const offsetRay = new XRRay(new DOMPointReadOnly(0, 0, 0, 1), new DOMPointReadOnly(dir.x, dir.y, dir.z, 0));
  pickAlong(xr.viewerSpace, offsetRay).then((p) => {
    if (p) addPick(siteOfXr(p));
    else message('nothing hit there: aim at the part and tap again');
  });
}

/** The first hit-test result along a ray from `space` (next frames), or null. */
async function pickAlong(space, offsetRay) {
  const session = xr.session;
  if (!session || !session.requestHitTestSource) return null;
  let source;
  try {
    source = await session.requestHitTestSource(offsetRay ? { space, offsetRay } : { space });
  } catch (_) {
    return null; // no hit-test on this device
  }
  return new Promise((resolve) => xr.picks.push({ source, resolve, frames: 0 }));
}

function processPicks(frame) {
  xr.picks = xr.picks.filter((p) => {
    const results = frame.getHitTestResults(p.source);
    p.frames += 1;
    if (!results.length && p.frames < 30) return true;
    const pose = results.length ? results[0].getPose(xr.refSpace) : null;
    p.source.cancel();
    const t = pose && pose.transform.position;
    p.resolve(t ? new THREE.Vector3(t.x, t.y, t.z) : null);
    return false;
  });
}

// ---- the head-up panel: connection, next unit, check, queued actions, buttons -------------

const HUD_W = 0.40;
const HUD_H = 0.22;
const HUD_BUTTONS = ['measure', 'overlap', 'complete', 'undo'];

function createHud() {
  const canvas = document.createElement('canvas');
  canvas.width = 1024;
  canvas.height = 564;
  const texture = new THREE.CanvasTexture(canvas);
  texture.colorSpace = THREE.SRGBColorSpace;
  const mesh = new THREE.Mesh(new THREE.PlaneGeometry(HUD_W, HUD_H),
    new THREE.MeshBasicMaterial({ map: texture, transparent: true, depthTest: false }));
  mesh.renderOrder = 100;
  mesh.frustumCulled = false;
  xr.dirty = true;
  return { canvas, texture, mesh, lines: [] };
}

function hudDirty() {
  xr.dirty = true;
  if (!xr.session) document.body.dataset.hud = '';
}

function positionHud() {
  const hud = xr.hud;
  if (!hud) return;
  // the XR camera of the last frame, in the reference space (the scene has no transform)
  const cam = state.view.renderer.xr.getCamera();
  const q = cam.quaternion;
  const p = cam.position;
  hud.mesh.position.copy(p).add(new THREE.Vector3(0, -0.12, -0.6).applyQuaternion(q));
  hud.mesh.quaternion.copy(q);
  hud.mesh.updateMatrixWorld(true);
}

function hudLabels() {
  const confirming = state.confirm && state.confirm.until > Date.now();
  const undoing = state.undo && state.undo.until > Date.now();
  return {
    measure: state.measure ? 'Cancel' : 'Measure',
    overlap: 'Overlap',
    complete: confirming ? 'Cancel' : 'Complete',
    undo: confirming ? 'CONFIRM' : (undoing ? 'Undo' : ''),
  };
}

function drawHud() {
  const hud = xr.hud;
  xr.dirty = false;
  if (!hud) return;
  const g = hud.canvas.getContext('2d');
  const W = hud.canvas.width;
  g.clearRect(0, 0, W, hud.canvas.height);
  g.fillStyle = 'rgba(20, 24, 29, 0.82)';
  g.fillRect(0, 0, W, hud.canvas.height);
  const conn = document.body.dataset.connection;
  const check = document.body.dataset.check;
  const next = state.next ? state.byId.get(state.next) : null;
  const lines = [
    [conn === 'ready' ? 'ONLINE' : 'OFFLINE - reconnecting', conn === 'ready' ? COLOURS.ok : COLOURS.bad],
    [`Next: ${state.next || 'all done'}${next && next.strip ? ` (strip ${next.strip})` : ''}` +
      `   ${state.done}/${state.total}   ${state.registration ? 'registered' : 'NOT REGISTERED'}`, '#e8eaed'],
    [$('check').textContent, { ok: COLOURS.ok, bad: COLOURS.bad, stale: COLOURS.stale }[check] || '#9aa0a6'],
    [$('queued').textContent || (state.measure ? measurePrompt() : $('message').textContent), '#f6c344'],
  ];
  hud.lines = lines.map((l) => l[0]);
  g.font = 'bold 40px system-ui, sans-serif';
  lines.forEach(([text, colour], i) => {
    g.fillStyle = colour;
    g.fillText(String(text).slice(0, 60), 24, 60 + i * 80);
  });
  const labels = hudLabels();
  const bw = W / HUD_BUTTONS.length;
  HUD_BUTTONS.forEach((b, i) => {
    if (!labels[b]) return;
    g.fillStyle = b === 'undo' && labels[b] === 'CONFIRM' ? '#b06000' : '#2d333b';
    g.fillRect(i * bw + 12, 400, bw - 24, 140);
    g.fillStyle = '#e8eaed';
    g.fillText(labels[b], i * bw + 30, 485);
  });
  hud.texture.needsUpdate = true;
  document.body.dataset.hud = hud.lines.join(' | ');
}

/** The world position of a HUD button's centre (for tests and for aiming). */
function hudButtonAt(name) {
  const hud = xr.hud;
  const i = HUD_BUTTONS.indexOf(name);
  if (!hud || i < 0) return null;
  const u = (i + 0.5) / HUD_BUTTONS.length;
  const v = 1 - 470 / hud.canvas.height;
  const local = new THREE.Vector3((u - 0.5) * HUD_W, (v - 0.5) * HUD_H, 0);
  const p = local.applyMatrix4(hud.mesh.matrixWorld);
  return [p.x, p.y, p.z];
}
state.hudButtonAt = hudButtonAt;

/** A ray that hits a HUD button presses it; true when the ray hit the HUD at all. */
function hudPress(ray) {
  const hud = xr.hud;
  if (!hud) return false;
  const hits = new THREE.Raycaster(ray.origin, ray.direction).intersectObject(hud.mesh, false);
  if (!hits.length || !hits[0].uv) return false;
  const { x: u, y: v } = hits[0].uv;
  const py = (1 - v) * hud.canvas.height;
  if (py < 400) return true; // the text area
  const name = HUD_BUTTONS[Math.min(HUD_BUTTONS.length - 1, Math.floor(u * HUD_BUTTONS.length))];
  const labels = hudLabels();
  if (!labels[name]) return true;
  if (name === 'measure') {
    if (state.measure) {
      state.measure = null;
      showPickHint();
    } else {
      startMeasure('hub');
    }
  } else if (name === 'overlap') {
    startMeasure('overlap');
  } else if (name === 'complete') {
    pressComplete();
  } else if (labels.undo === 'CONFIRM') {
    confirmComplete();
  } else {
    pressUndo();
  }
  hudDirty();
  return true;
}

// ---- start ------------------------------------------------------------------------------------

state.token = tokenFromFragment();
$('token').value = state.token;
setCheck('none', 'no tracking yet');
renderProgress();
setupXR();
connect();
