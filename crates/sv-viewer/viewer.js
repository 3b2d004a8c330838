// 3D view of a deployed Spin-Valence frame (three.js, vendored ES modules). Shared by the
// deployment page (`spinvalence serve`) and the build report (`DIR/report.html`), which
// embeds this file (crate sv-viewer).
//
//   const view = createFrameView(container, { units, background, expansion, highlight });
//   units: [{ id, strip, hub: [[x, y, z] x 4], primary: [[x, y, z] x 4] }]  (mm, Z up;
//          frame.json order: leg i joins hub corner i to primary corner i + 1)
//   expansion: primary tiles drawn scaled by e about their centroids (fig. 11), default 1
//   highlight: css colour of the outline of the highlighted unit (default yellow)
//   view.setColours(fnOrMap)          per-unit css colour: fn(id) -> colour, or Map / object
//   view.setLayers({hubs, primaries, legs})  show or hide each layer (booleans)
//   view.highlight(id | null)         outline one unit
//   view.setGhost(id, pose | null)    the unit's hub as a translucent ghost at a pose
//                                     ({position: [x, y, z], rotation: [x, y, z, w]})
//   view.setMarker(position, move_mm, colour)  tracked point and the arrow to its target
//                                     (position null hides it)
//   view.onPick(cb)                   cb(id) when a unit is clicked
//   view.unitAt(x, y)                 id of the unit under a client point, or null
//   view.project(id)                  client {x, y} of the unit's hub centre, or null
//   view.resetCamera()                look at the whole frame again
//   view.renderer / view.scene / view.camera   for WebXR
//   view.world                        the group holding the frame, ghosts and marker (model
//                                     mm); an AR page places it with its matrix
//   view.bounds / view.edge           the frame's bounding box and mean hub edge (mm)
//   view.dispose()
//
// All units share one mesh per layer (hubs, primary tiles, edges, legs) with per-vertex
// colours, so a frame of thousands of units is a handful of draw calls.

import * as THREE from './vendor/three.module.js';
import { OrbitControls } from './vendor/OrbitControls.js';

const DEFAULT_COLOUR = '#9aa0a6';
const HIGHLIGHT = '#ffd400';
const GHOST = '#35d0ff';

function v3(p) {
  return new THREE.Vector3(p[0], p[1], p[2]);
}

// The pose convention of protocol v1: origin at the corner centroid, x toward corner 0,
// z along (c0 - c2) x (c1 - c3), y = z x x.
function tilePose(corners) {
  const c = corners.map(v3);
  const centroid = c[0].clone().add(c[1]).add(c[2]).add(c[3]).multiplyScalar(0.25);
  const z = c[0].clone().sub(c[2]).cross(c[1].clone().sub(c[3]));
  if (z.lengthSq() === 0) return null;
  z.normalize();
  const x0 = c[0].clone().sub(centroid);
  const x = x0.clone().sub(z.clone().multiplyScalar(x0.dot(z)));
  if (x.lengthSq() === 0) return null;
  x.normalize();
  const y = z.clone().cross(x);
  const m = new THREE.Matrix4().makeBasis(x, y, z);
  m.setPosition(centroid);
  return m;
}

function quadGeometry(corners) {
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.Float32BufferAttribute(corners.flat(), 3));
  g.setIndex([0, 1, 2, 0, 2, 3]);
  g.computeVertexNormals();
  return g;
}

function loopGeometry(corners) {
  return new THREE.BufferGeometry().setFromPoints(corners.map(v3));
}

function scaled(corners, e) {
  if (e === 1) return corners;
  const c = [0, 1, 2].map((k) => corners.reduce((s, p) => s + p[k], 0) / corners.length);
  return corners.map((p) => p.map((x, k) => c[k] + e * (x - c[k])));
}

// One geometry of quads (two triangles each, four vertices per unit) with vertex colours.
function quadsGeometry(quads) {
  const n = quads.length;
  const pos = new Float32Array(n * 12);
  const index = new Uint32Array(n * 6);
  quads.forEach((q, u) => {
    for (let i = 0; i < 4; i++) for (let k = 0; k < 3; k++) pos[12 * u + 3 * i + k] = q[i][k];
    index.set([0, 1, 2, 0, 2, 3].map((j) => 4 * u + j), 6 * u);
  });
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.BufferAttribute(pos, 3));
  g.setAttribute('color', new THREE.BufferAttribute(new Float32Array(n * 12), 3));
  g.setIndex(new THREE.BufferAttribute(index, 1));
  g.computeVertexNormals();
  return g;
}

// Line segments: `segments(u)` lists [a, b] point pairs of unit u; vertex colours.
function segmentsGeometry(units, segments) {
  const pts = [];
  const owner = [];
  units.forEach((u, i) => {
    for (const [a, b] of segments(u)) {
      pts.push(...a, ...b);
      owner.push(i, i);
    }
  });
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.Float32BufferAttribute(pts, 3));
  g.setAttribute('color', new THREE.Float32BufferAttribute(new Float32Array(pts.length), 3));
  g.userData.owner = owner;
  return g;
}

function edges(q) {
  return [0, 1, 2, 3].map((i) => [q[i], q[(i + 1) % 4]]);
}

export function createFrameView(container, {
  units = [], background = '#101317', expansion = 1, highlight = HIGHLIGHT,
} = {}) {
  const renderer = new THREE.WebGLRenderer({ antialias: true, alpha: true });
  renderer.setPixelRatio(Math.min(window.devicePixelRatio || 1, 2));
  container.append(renderer.domElement);

  const scene = new THREE.Scene();
  scene.background = background ? new THREE.Color(background) : null;
  scene.add(new THREE.HemisphereLight(0xffffff, 0x404040, 2.2));
  const sun = new THREE.DirectionalLight(0xffffff, 1.6);
  sun.position.set(1, -2, 3);
  scene.add(sun);

  // frame data, Z up, mm: one mesh per layer
  const e = Number.isFinite(expansion) && expansion > 0 ? expansion : 1;
  const tiles = units.map((u) => scaled(u.primary, e));
  // everything in model coordinates hangs from `world`, so an AR page can place the frame
  // (mm, Z up) in a metre, Y-up scene with one matrix while lights and overlays stay put
  const world = new THREE.Group();
  scene.add(world);
  const root = new THREE.Group();
  world.add(root);
  const hubs = new THREE.Mesh(quadsGeometry(units.map((u) => u.hub)),
    new THREE.MeshStandardMaterial({
      vertexColors: true, side: THREE.DoubleSide, metalness: 0.2, roughness: 0.6,
    }));
  const primaries = new THREE.Mesh(quadsGeometry(tiles),
    new THREE.MeshStandardMaterial({
      vertexColors: true, side: THREE.DoubleSide, transparent: true, opacity: 0.35,
      metalness: 0.1, roughness: 0.8, depthWrite: false,
    }));
  const hubEdges = new THREE.LineSegments(segmentsGeometry(units, (u) => edges(u.hub)),
    new THREE.LineBasicMaterial({ color: 0x202124 }));
  const primEdges = new THREE.LineSegments(segmentsGeometry(tiles, (q) => edges(q)),
    new THREE.LineBasicMaterial({ vertexColors: true }));
  // leg i: hub corner i to primary corner i + 1 (model.md, frame.obj)
  const legs = new THREE.LineSegments(
    segmentsGeometry(units, (u) => [0, 1, 2, 3].map((i) => [u.hub[i], u.primary[(i + 1) % 4]])),
    new THREE.LineBasicMaterial({ color: 0x5f6368 }));
  root.add(hubs, hubEdges, primaries, primEdges, legs);
  const layers = { hubs: [hubs, hubEdges], primaries: [primaries, primEdges], legs: [legs] };

  const index = new Map();
  units.forEach((u, i) => index.set(u.id, i));
  const box = new THREE.Box3();
  let edgeSum = 0;
  let edgeCount = 0;
  units.forEach((u, i) => {
    for (const p of u.hub.concat(tiles[i])) box.expandByPoint(v3(p));
    for (let k = 0; k < 4; k++) {
      edgeSum += v3(u.hub[k]).distanceTo(v3(u.hub[(k + 1) % 4]));
      edgeCount += 1;
    }
  });
  const edge = edgeCount ? edgeSum / edgeCount : 300;

  // camera: Z up, looking at the frame from the south-west, above
  const camera = new THREE.PerspectiveCamera(45, 1, 1, 1e6);
  camera.up.set(0, 0, 1);
  const centre = box.isEmpty() ? new THREE.Vector3() : box.getCenter(new THREE.Vector3());
  const radius = box.isEmpty() ? 1000 : Math.max(box.getSize(new THREE.Vector3()).length() / 2, edge);
  camera.near = radius / 100;
  camera.far = radius * 100;
  const controls = new OrbitControls(camera, renderer.domElement);
  function resetCamera() {
    camera.position.copy(centre)
      .add(new THREE.Vector3(-0.9, -1.6, 1.3).normalize().multiplyScalar(radius * 2.4));
    camera.lookAt(centre);
    controls.target.copy(centre);
    controls.update();
  }
  resetCamera();

  // highlight, ghost, marker
  const highlightMat = new THREE.LineBasicMaterial({ color: highlight, depthTest: false });
  let highlighted = null;
  const ghostGroup = new THREE.Group();
  world.add(ghostGroup);
  const ghosts = new Map();
  const locals = new Map();
  const marker = new THREE.Group();
  marker.visible = false;
  const dotMat = new THREE.MeshBasicMaterial({ color: 0xffffff, depthTest: false });
  const dot = new THREE.Mesh(new THREE.SphereGeometry(edge * 0.06, 16, 12), dotMat);
  dot.renderOrder = 10;
  const arrow = new THREE.ArrowHelper(new THREE.Vector3(1, 0, 0), new THREE.Vector3(), 1, 0xffffff);
  arrow.line.material.depthTest = false;
  arrow.cone.material.depthTest = false;
  arrow.renderOrder = 10;
  marker.add(dot, arrow);
  world.add(marker);

  function resolveColour(spec, id) {
    if (typeof spec === 'function') return spec(id);
    if (spec instanceof Map) return spec.get(id);
    if (spec && typeof spec === 'object') return spec[id];
    return undefined;
  }

  function paint(spec) {
    const colours = units.map((u) => new THREE.Color(resolveColour(spec, u.id) || DEFAULT_COLOUR));
    for (const mesh of [hubs, primaries]) {
      const attr = mesh.geometry.getAttribute('color');
      colours.forEach((c, u) => {
        for (let i = 0; i < 4; i++) attr.setXYZ(4 * u + i, c.r, c.g, c.b);
      });
      attr.needsUpdate = true;
    }
    const attr = primEdges.geometry.getAttribute('color');
    primEdges.geometry.userData.owner.forEach((u, v) => {
      attr.setXYZ(v, colours[u].r, colours[u].g, colours[u].b);
    });
    attr.needsUpdate = true;
  }
  paint(null);

  // ---- rendering: on demand, paused while a WebXR session drives the renderer ----
  let frameRequested = false;
  let disposed = false;
  function render() {
    frameRequested = false;
    if (disposed || renderer.xr.isPresenting) return;
    renderer.render(scene, camera);
  }
  function requestRender() {
    if (!frameRequested && !disposed) {
      frameRequested = true;
      requestAnimationFrame(render);
    }
  }
  controls.addEventListener('change', requestRender);

  function resize() {
    if (renderer.xr.isPresenting) return;
    const w = Math.max(1, container.clientWidth);
    const h = Math.max(1, container.clientHeight);
    renderer.setSize(w, h, false);
    renderer.domElement.style.width = '100%';
    renderer.domElement.style.height = '100%';
    camera.aspect = w / h;
    camera.updateProjectionMatrix();
    requestRender();
  }
  const observer = typeof ResizeObserver !== 'undefined' ? new ResizeObserver(resize) : null;
  if (observer) observer.observe(container);
  window.addEventListener('resize', resize);
  resize();

  // ---- picking ----
  const pickCallbacks = [];
  const raycaster = new THREE.Raycaster();
  function unitAt(x, y) {
    const r = renderer.domElement.getBoundingClientRect();
    if (r.width === 0 || r.height === 0) return null;
    const ndc = new THREE.Vector2(((x - r.left) / r.width) * 2 - 1, -((y - r.top) / r.height) * 2 + 1);
    raycaster.setFromCamera(ndc, camera);
    const pickable = [hubs, primaries].filter((m) => m.visible);
    const hit = raycaster.intersectObjects(pickable, false)[0];
    if (!hit || hit.faceIndex == null) return null;
    const u = units[Math.floor(hit.faceIndex / 2)];
    return u ? u.id : null;
  }
  let down = null;
  function onDown(ev) { down = [ev.clientX, ev.clientY]; }
  function onUp(ev) {
    if (!down || Math.hypot(ev.clientX - down[0], ev.clientY - down[1]) > 5) return;
    const id = unitAt(ev.clientX, ev.clientY);
    if (id != null) for (const cb of pickCallbacks) cb(id);
  }
  renderer.domElement.addEventListener('pointerdown', onDown);
  renderer.domElement.addEventListener('pointerup', onUp);

  const view = {
    renderer,
    scene,
    camera,
    controls,
    world,
    edge,
    bounds: box,

    setColours(spec) {
      paint(spec);
      requestRender();
    },

    setLayers(visible) {
      for (const [name, objects] of Object.entries(layers)) {
        if (visible && typeof visible[name] === 'boolean') {
          for (const o of objects) o.visible = visible[name];
        }
      }
      requestRender();
    },

    highlight(id) {
      if (highlighted) {
        highlighted.parent.remove(highlighted);
        highlighted.traverse((o) => o.geometry && o.geometry.dispose());
        highlighted = null;
      }
      const i = id != null ? index.get(id) : undefined;
      if (i !== undefined) {
        highlighted = new THREE.Group();
        const hub = new THREE.LineLoop(loopGeometry(units[i].hub), highlightMat);
        const prim = new THREE.LineLoop(loopGeometry(tiles[i]), highlightMat);
        hub.renderOrder = prim.renderOrder = 5;
        highlighted.add(hub, prim);
        root.add(highlighted);
      }
      requestRender();
    },

    setGhost(id, pose) {
      const old = ghosts.get(id);
      if (old) {
        ghostGroup.remove(old);
        old.traverse((o) => o.geometry && o.geometry.dispose());
        ghosts.delete(id);
      }
      const i = index.get(id);
      if (i === undefined || !pose) {
        requestRender();
        return;
      }
      if (!locals.has(id)) {
        // hub corners in the hub tile's own frame
        const m = tilePose(units[i].hub);
        if (!m) return;
        const inv = m.clone().invert();
        locals.set(id, units[i].hub.map((p) => v3(p).applyMatrix4(inv)));
      }
      const g = new THREE.Group();
      const pts = locals.get(id).map((p) => p.clone());
      const fill = new THREE.Mesh(quadGeometry(pts.map((p) => [p.x, p.y, p.z])),
        new THREE.MeshBasicMaterial({
          color: GHOST, transparent: true, opacity: 0.35, side: THREE.DoubleSide, depthWrite: false,
        }));
      const outline = new THREE.LineLoop(new THREE.BufferGeometry().setFromPoints(pts),
        new THREE.LineBasicMaterial({ color: GHOST }));
      g.add(fill, outline, new THREE.AxesHelper(edge * 0.3));
      const [x, y, z, w] = pose.rotation;
      g.quaternion.set(x, y, z, w).normalize();
      g.position.set(pose.position[0], pose.position[1], pose.position[2]);
      ghostGroup.add(g);
      ghosts.set(id, g);
      requestRender();
    },

    setMarker(position, move, colour) {
      if (!position) {
        marker.visible = false;
        requestRender();
        return;
      }
      marker.visible = true;
      marker.position.set(position[0], position[1], position[2]);
      const c = new THREE.Color(colour || '#ffffff');
      dotMat.color.copy(c);
      const d = move ? new THREE.Vector3(move[0], move[1], move[2]) : new THREE.Vector3();
      const len = d.length();
      arrow.visible = len > 1e-6;
      if (arrow.visible) {
        arrow.setDirection(d.clone().normalize());
        arrow.setLength(len, Math.min(len * 0.35, edge * 0.08), Math.min(len * 0.2, edge * 0.05));
        arrow.setColor(c);
      }
      requestRender();
    },

    onPick(cb) {
      if (typeof cb === 'function') pickCallbacks.push(cb);
    },

    unitAt,

    project(id) {
      const i = index.get(id);
      if (i === undefined) return null;
      const c = units[i].hub.map(v3).reduce((s, p) => s.add(p), new THREE.Vector3()).multiplyScalar(0.25);
      camera.updateMatrixWorld();
      c.project(camera);
      const r = renderer.domElement.getBoundingClientRect();
      return { x: r.left + (c.x + 1) / 2 * r.width, y: r.top + (1 - c.y) / 2 * r.height };
    },

    resetCamera() {
      resetCamera();
      requestRender();
    },

    render: requestRender,

    dispose() {
      disposed = true;
      if (observer) observer.disconnect();
      window.removeEventListener('resize', resize);
      controls.dispose();
      scene.traverse((o) => {
        if (o.geometry) o.geometry.dispose();
        if (o.material) [].concat(o.material).forEach((m) => m.dispose());
      });
      renderer.dispose();
      renderer.domElement.remove();
    },
  };
  return view;
}
