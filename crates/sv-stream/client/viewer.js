// 3D view of a deployed Spin-Valence frame (three.js, vendored ES modules). Shared by the
// deployment page (`spinvalence serve`) and the build report.
//
//   const view = createFrameView(container, { units, background });
//   units: [{ id, strip, hub: [[x, y, z] x 4], primary: [[x, y, z] x 4] }]  (mm, Z up)
//   view.setColours(fnOrMap)          per-unit css colour: fn(id) -> colour, or Map / object
//   view.highlight(id | null)         outline one unit
//   view.setGhost(id, pose | null)    the unit's hub as a translucent ghost at a pose
//                                     ({position: [x, y, z], rotation: [x, y, z, w]})
//   view.setMarker(position, move_mm, colour)  tracked point and the arrow to its target
//                                     (position null hides it)
//   view.onPick(cb)                   cb(id) when a unit is clicked
//   view.renderer / view.scene / view.camera   for WebXR
//   view.dispose()

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

export function createFrameView(container, { units = [], background = '#101317' } = {}) {
  const renderer = new THREE.WebGLRenderer({ antialias: true, alpha: true });
  renderer.setPixelRatio(Math.min(window.devicePixelRatio || 1, 2));
  container.append(renderer.domElement);

  const scene = new THREE.Scene();
  scene.background = background ? new THREE.Color(background) : null;
  scene.add(new THREE.HemisphereLight(0xffffff, 0x404040, 2.2));
  const sun = new THREE.DirectionalLight(0xffffff, 1.6);
  sun.position.set(1, -2, 3);
  scene.add(sun);

  // frame data, Z up, mm
  const root = new THREE.Group();
  scene.add(root);
  const records = new Map();
  const pickable = [];
  const box = new THREE.Box3();
  let edgeSum = 0;
  let edgeCount = 0;
  for (const u of units) {
    const colour = new THREE.Color(DEFAULT_COLOUR);
    const hubMat = new THREE.MeshStandardMaterial({
      color: colour, side: THREE.DoubleSide, metalness: 0.2, roughness: 0.6,
    });
    const hub = new THREE.Mesh(quadGeometry(u.hub), hubMat);
    hub.userData.unit = u.id;
    const hubEdge = new THREE.LineLoop(loopGeometry(u.hub),
      new THREE.LineBasicMaterial({ color: 0x202124 }));
    const primMat = new THREE.MeshStandardMaterial({
      color: colour, side: THREE.DoubleSide, transparent: true, opacity: 0.35,
      metalness: 0.1, roughness: 0.8, depthWrite: false,
    });
    const primary = new THREE.Mesh(quadGeometry(u.primary), primMat);
    primary.userData.unit = u.id;
    const primEdge = new THREE.LineLoop(loopGeometry(u.primary),
      new THREE.LineBasicMaterial({ color: colour }));
    // the legs: hub corner i to the nearest primary corner
    const legPts = [];
    for (const h of u.hub) {
      let best = u.primary[0];
      let bestD = Infinity;
      for (const p of u.primary) {
        const d = (p[0] - h[0]) ** 2 + (p[1] - h[1]) ** 2 + (p[2] - h[2]) ** 2;
        if (d < bestD) { bestD = d; best = p; }
      }
      legPts.push(v3(h), v3(best));
    }
    const legs = new THREE.LineSegments(new THREE.BufferGeometry().setFromPoints(legPts),
      new THREE.LineBasicMaterial({ color: 0x5f6368 }));
    const group = new THREE.Group();
    group.add(hub, hubEdge, primary, primEdge, legs);
    root.add(group);
    pickable.push(hub, primary);
    for (const p of u.hub.concat(u.primary)) box.expandByPoint(v3(p));
    for (let i = 0; i < 4; i++) {
      edgeSum += v3(u.hub[i]).distanceTo(v3(u.hub[(i + 1) % 4]));
      edgeCount += 1;
    }
    records.set(u.id, { unit: u, group, hubMat, primMat, primEdge, local: null });
  }
  const edge = edgeCount ? edgeSum / edgeCount : 300;

  // camera: Z up, looking at the frame from the south-west, above
  const camera = new THREE.PerspectiveCamera(45, 1, 1, 1e6);
  camera.up.set(0, 0, 1);
  const centre = box.isEmpty() ? new THREE.Vector3() : box.getCenter(new THREE.Vector3());
  const radius = box.isEmpty() ? 1000 : Math.max(box.getSize(new THREE.Vector3()).length() / 2, edge);
  camera.position.copy(centre).add(new THREE.Vector3(-0.9, -1.6, 1.3).normalize().multiplyScalar(radius * 2.4));
  camera.near = radius / 100;
  camera.far = radius * 100;
  camera.lookAt(centre);
  const controls = new OrbitControls(camera, renderer.domElement);
  controls.target.copy(centre);
  controls.update();

  // highlight, ghost, marker
  const highlightMat = new THREE.LineBasicMaterial({ color: HIGHLIGHT, depthTest: false });
  let highlighted = null;
  const ghostGroup = new THREE.Group();
  scene.add(ghostGroup);
  const ghosts = new Map();
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
  scene.add(marker);

  function resolveColour(spec, id) {
    if (typeof spec === 'function') return spec(id);
    if (spec instanceof Map) return spec.get(id);
    if (spec && typeof spec === 'object') return spec[id];
    return undefined;
  }

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
  let down = null;
  function onDown(e) { down = [e.clientX, e.clientY]; }
  function onUp(e) {
    if (!down || Math.hypot(e.clientX - down[0], e.clientY - down[1]) > 5) return;
    const r = renderer.domElement.getBoundingClientRect();
    const ndc = new THREE.Vector2(((e.clientX - r.left) / r.width) * 2 - 1,
      -((e.clientY - r.top) / r.height) * 2 + 1);
    raycaster.setFromCamera(ndc, camera);
    const hit = raycaster.intersectObjects(pickable, false)[0];
    const id = hit ? hit.object.userData.unit : null;
    if (id != null) for (const cb of pickCallbacks) cb(id);
  }
  renderer.domElement.addEventListener('pointerdown', onDown);
  renderer.domElement.addEventListener('pointerup', onUp);

  const view = {
    renderer,
    scene,
    camera,
    controls,

    setColours(spec) {
      for (const [id, rec] of records) {
        const c = resolveColour(spec, id) || DEFAULT_COLOUR;
        rec.hubMat.color.set(c);
        rec.primMat.color.set(c);
        rec.primEdge.material.color.set(c);
      }
      requestRender();
    },

    highlight(id) {
      if (highlighted) {
        highlighted.parent.remove(highlighted);
        highlighted.traverse((o) => o.geometry && o.geometry.dispose());
        highlighted = null;
      }
      const rec = id != null ? records.get(id) : null;
      if (rec) {
        highlighted = new THREE.Group();
        const hub = new THREE.LineLoop(loopGeometry(rec.unit.hub), highlightMat);
        const prim = new THREE.LineLoop(loopGeometry(rec.unit.primary), highlightMat);
        hub.renderOrder = prim.renderOrder = 5;
        highlighted.add(hub, prim);
        rec.group.add(highlighted);
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
      const rec = records.get(id);
      if (!rec || !pose) {
        requestRender();
        return;
      }
      if (!rec.local) {
        // hub corners in the hub tile's own frame
        const m = tilePose(rec.unit.hub);
        if (!m) return;
        const inv = m.clone().invert();
        rec.local = rec.unit.hub.map((p) => v3(p).applyMatrix4(inv));
      }
      const g = new THREE.Group();
      const pts = rec.local.map((p) => p.clone());
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
