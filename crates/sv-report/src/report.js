// The interactive part of report.html: the 3D view (viewer.js of crate sv-viewer, the
// same module as the AR deployment page), colour modes, layers and the unit panel.
// Data: the JSON in #sv-data (see sv-report html.rs). No network: everything is inline.
//
// State for tests: body[data-ready] ('no' | 'yes' | 'error'), body[data-mode],
// #info[data-unit] (the selected unit's label); window.__report = { view, data, select, setMode }.

import { createFrameView } from 'viewer.js';

const $ = (id) => document.getElementById(id);
const data = JSON.parse($('sv-data').textContent);
const units = data.units;
const byId = new Map(units.map((u, i) => [u.id, i]));
const deg = (rad) => (rad * 180) / Math.PI;
const fmt = (x, d) => (Number.isFinite(x) ? x.toFixed(d) : '-');
const NO_VALUE = '#8a8f96';

// per unit: neighbours with the link's gap and overlap; worst gap and overlap
const neighbours = units.map(() => []);
for (const [i, j, gap, overlap] of data.links) {
  neighbours[i].push({ unit: j, gap, overlap });
  neighbours[j].push({ unit: i, gap, overlap });
}
const gapMax = neighbours.map((ns) => (ns.length ? Math.max(...ns.map((n) => n.gap)) : NaN));
const overlapMin = neighbours.map((ns) => (ns.length ? Math.min(...ns.map((n) => n.overlap)) : NaN));

function rgb(hex) {
  const v = parseInt(hex.slice(1), 16);
  return [(v >> 16) & 255, (v >> 8) & 255, v & 255];
}
const stops = data.colour_map.map(rgb);
function mapColour(t) {
  const x = Math.min(1, Math.max(0, Number.isFinite(t) ? t : 0)) * (stops.length - 1);
  const i = Math.min(stops.length - 2, Math.floor(x));
  const f = x - i;
  const c = stops[i].map((a, k) => Math.round(a + f * (stops[i + 1][k] - a)));
  return `rgb(${c[0]}, ${c[1]}, ${c[2]})`;
}

const strips = [...new Set(units.map((u) => u.strip))];
const stripIndex = new Map(strips.map((s, k) => [s, k]));
function stripColour(strip) {
  // golden-angle hues: consecutive strips (neighbours on the surface) differ clearly
  const k = stripIndex.get(strip) || 0;
  return `hsl(${(k * 137.508) % 360}, 62%, ${k % 2 ? 48 : 62}%)`;
}

function range(values) {
  const v = values.filter(Number.isFinite);
  return v.length ? [Math.min(...v), Math.max(...v)] : [0, 1];
}

const MODES = {
  gap: {
    title: `largest ${data.gap_name || 'primary gap'} to a neighbour (mm)`,
    values: gapMax,
  },
  overlap: {
    title: 'smallest hub overlap with a neighbour (mm)',
    values: overlapMin,
  },
  strip: { title: 'strip' },
  goals: { title: 'goals not met here (red): the hub mesh\'s, and the worst place of each failing row of the fold check' },
};
const GOAL_RED = '#d62728';
const GOAL_GREY = '#c9ccd1';
const goals = data.goals || [];

let view = null;
let mode = 'gap';

function legend(m) {
  const el = $('legend');
  el.replaceChildren();
  const title = document.createElement('div');
  title.className = 'legend-title';
  title.textContent = MODES[m].title;
  el.append(title);
  if (m === 'goals') {
    const p = document.createElement('div');
    const n = goals.filter((g) => g.length).length;
    p.textContent = `${n} unit(s) where a goal is not met`;
    el.append(p);
    return;
  }
  if (m === 'strip') {
    const p = document.createElement('div');
    p.className = 'legend-strips';
    for (const s of strips) {
      const chip = document.createElement('span');
      chip.className = 'chip';
      chip.style.background = stripColour(s);
      chip.style.color = stripIndex.get(s) % 2 ? '#fff' : '#111';
      chip.textContent = s || '(none)';
      p.append(chip);
    }
    el.append(p);
    return;
  }
  const [lo, hi] = range(MODES[m].values);
  const bar = document.createElement('div');
  bar.className = 'colour-bar';
  bar.style.background = `linear-gradient(to right, ${data.colour_map.join(', ')})`;
  const ends = document.createElement('div');
  ends.className = 'colour-ends';
  const a = document.createElement('span');
  a.textContent = fmt(lo, 2);
  const b = document.createElement('span');
  b.textContent = fmt(hi, 2);
  ends.append(a, b);
  el.append(bar, ends);
}

function setMode(m) {
  if (!MODES[m]) return;
  mode = m;
  document.body.dataset.mode = m;
  for (const input of document.querySelectorAll('input[name="colour"]')) input.checked = input.value === m;
  legend(m);
  if (!view) return;
  if (m === 'strip') {
    view.setColours((id) => stripColour(units[byId.get(id)].strip));
  } else if (m === 'goals') {
    view.setColours((id) => ((goals[byId.get(id)] || []).length ? GOAL_RED : GOAL_GREY));
  } else {
    const values = MODES[m].values;
    const [lo, hi] = range(values);
    view.setColours((id) => {
      const v = values[byId.get(id)];
      return Number.isFinite(v) ? mapColour(hi > lo ? (v - lo) / (hi - lo) : 0.5) : NO_VALUE;
    });
  }
}

function cell(row, text, cls) {
  const td = document.createElement('td');
  td.textContent = text;
  if (cls) td.className = cls;
  row.append(td);
}

function select(id) {
  const i = byId.get(id);
  const info = $('info');
  if (i === undefined) {
    info.dataset.unit = '';
    info.replaceChildren(Object.assign(document.createElement('p'), {
      className: 'muted', textContent: 'Click a unit to see its label, angles, gaps and overlaps.',
    }));
    if (view) view.highlight(null);
    return;
  }
  const u = units[i];
  info.dataset.unit = u.id;
  const h = document.createElement('h3');
  h.textContent = u.id;
  const facts = document.createElement('table');
  facts.className = 'facts';
  for (const [k, v] of [
    ['strip', u.strip || '-'],
    ['theta', `${fmt(deg(u.theta), 2)} deg`],
    ['phi', `${fmt(deg(u.phi), 2)} deg`],
    ['depth', u.depth == null ? '-' : `${fmt(u.depth, 1)} mm`],
    ['largest gap', `${fmt(gapMax[i], 2)} mm`],
    ['smallest hub overlap', `${fmt(overlapMin[i], 2)} mm`],
    ...((goals[i] || []).length ? [['goals not met', goals[i].join(', ')]] : []),
  ]) {
    const tr = document.createElement('tr');
    const th = document.createElement('th');
    th.textContent = k;
    tr.append(th);
    cell(tr, v, 'num');
    facts.append(tr);
  }
  const links = document.createElement('table');
  links.className = 'links';
  const head = document.createElement('tr');
  for (const t of ['neighbour', 'gap (mm)', 'hub overlap (mm)']) {
    const th = document.createElement('th');
    th.textContent = t;
    head.append(th);
  }
  links.append(head);
  for (const n of neighbours[i]) {
    const tr = document.createElement('tr');
    tr.dataset.neighbour = units[n.unit].id;
    cell(tr, units[n.unit].id);
    cell(tr, fmt(n.gap, 2), 'num');
    cell(tr, fmt(n.overlap, 2), 'num');
    links.append(tr);
  }
  info.replaceChildren(h, facts, links);
  if (view) view.highlight(u.id);
}

function start() {
  document.body.dataset.mode = mode;
  for (const input of document.querySelectorAll('input[name="colour"]')) {
    input.addEventListener('change', () => setMode(input.value));
  }
  select(null);
  const container = $('view');
  try {
    view = createFrameView(container, {
      units, background: data.background, expansion: data.expansion, highlight: '#ff3dd4',
    });
  } catch (e) {
    const p = document.createElement('p');
    p.className = 'fallback';
    p.textContent = `3D view unavailable (${e && e.message ? e.message : e}); the plots below do not need it.`;
    container.replaceChildren(p);
    document.body.dataset.ready = 'error';
    legend(mode);
    return;
  }
  view.onPick(select);
  for (const input of document.querySelectorAll('input[data-layer]')) {
    input.addEventListener('change', () => view.setLayers({ [input.dataset.layer]: input.checked }));
  }
  $('reset-view').addEventListener('click', () => view.resetCamera());
  setMode(mode);
  window.__report = { view, data, select, setMode };
  // ready once the first frame is on screen
  requestAnimationFrame(() => requestAnimationFrame(() => { document.body.dataset.ready = 'yes'; }));
}

start();
