// The snowscape editor page (Cordonnier et al. 2018, Section 3): a three.js view of the terrain
// and its snow, brushes painted on the server, the season timeline, the weather and parameter
// editors, live avalanches and skiers. The server owns the state; this page shows it and sends
// the user's actions (crates/editor/src/protocol.rs lists the messages).
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { applyFrame, setProtocol } from './wire.js';
import { bareColour, colourOf, LEGENDS, rampColour, setColours } from './shade.js';
import { setupPanels } from './panels.js';

const $ = (id) => document.getElementById(id);
const grids = {};
const app = { state: null, grids, frames: 0, errors: [], notices: [], messages: [], lastSkiers: null, lastAvalanche: null };
window.snowscape = app;

// ---------- connection ----------
let ws;
function send(msg) {
  if (ws && ws.readyState === WebSocket.OPEN) ws.send(JSON.stringify(msg));
}
app.send = send;
app.sendRaw = (text) => ws.send(text);

// Every request for the editor's data (/api, /files, the WebSocket) needs the server's access
// token, loopback included. The server sets it in the page's SameSite=Strict cookie (on the
// page's load on loopback, or from the printed URL's `?token=…`), which the page's fetches,
// downloads and WebSocket carry; a token in the page's URL is passed on as well.
const token = new URLSearchParams(location.search).get('token');
const wsPath = token ? `/ws?token=${encodeURIComponent(token)}` : '/ws';

function connect() {
  ws = new WebSocket(`${location.protocol === 'https:' ? 'wss' : 'ws'}://${location.host}${wsPath}`);
  ws.binaryType = 'arraybuffer';
  ws.onopen = () => status('connected');
  ws.onclose = () => { status('disconnected; reconnecting…'); setTimeout(connect, 1000); };
  ws.onmessage = (ev) => {
    if (typeof ev.data === 'string') onText(JSON.parse(ev.data));
    else onFrame(ev.data);
  };
}

function status(text) { $('status').textContent = text; }

// A job's line: a season step counts its days, the others say what they do.
function jobText(m) {
  const amount = m.kind === 'step' ? ` ${m.done.toFixed(2)} of ${m.total.toFixed(2)} days` : '';
  return `${m.message}: ${m.phase}${amount} (${m.elapsed_s.toFixed(1)} s)`;
}

function onText(m) {
  app.messages.push(m.type);
  if (app.messages.length > 200) app.messages.shift();
  switch (m.type) {
    case 'state': onState(m); break;
    case 'error': app.errors.push(m); status(`error (${m.code}): ${m.message}`); break;
    case 'notice': app.notices.push(m.message); status(m.message); break;
    case 'job': app.lastJob = m; app.lastJobAt = performance.now(); status(jobText(m)); break;
    case 'avalanche':
      app.lastAvalanche = m;
      status(`avalanche ${m.phase}: t=${m.time_s.toFixed(1)} s, ${m.flowing_m3.toFixed(0)} m³ moving` +
        `, ${(m.entrained_m3 ?? 0).toFixed(0)} m³ entrained` +
        (m.phase === 'ended' ? `, ${m.deposited_m3.toFixed(0)} m³ deposited (${m.stop})` : ''));
      if (m.phase === 'ended' && grids.flow) { grids.flow.fill(0); dirtyAll(); }
      break;
    case 'skiers': app.lastSkiers = m; showSkiers(m); break;
    case 'cell': app.lastCell = m; break;
    case 'done': onDone(m); break;
    default: break;
  }
}

// ---------- 3D view ----------
const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(Math.min(window.devicePixelRatio, 2));
// Shadows (`?noshadows` turns them off, for slow software renderers): the shadow map is redrawn
// only when the terrain or the sun changes, not at every orbit of the camera.
renderer.shadowMap.enabled = !new URLSearchParams(window.location.search).has('noshadows');
renderer.shadowMap.type = THREE.PCFSoftShadowMap;
renderer.shadowMap.autoUpdate = false;
$('view').appendChild(renderer.domElement);
const scene = new THREE.Scene();
// Sky: a gradient from a pale, hazy horizon to a deeper blue zenith; distance haze of the
// horizon's colour (its range set to the terrain's size when the view is framed).
const HORIZON = new THREE.Color(0xd9e4ee), ZENITH = new THREE.Color(0x5d8cc4);
scene.background = skyTexture();
scene.fog = new THREE.Fog(HORIZON, 1e5, 1e6);
const camera = new THREE.PerspectiveCamera(45, 1, 1, 1e6);
const controls = new OrbitControls(camera, renderer.domElement);
// Sky light, bluish (it alone lights the snow in the sun's shadows, which thus turn blue), and
// a warm ground bounce; the sun from the season's date and latitude (state.sun) casts shadows.
const skyLight = new THREE.HemisphereLight(0xbfd4ff, 0x6b6153, 1.0);
scene.add(skyLight);
const sun = new THREE.DirectionalLight(0xfff2dc, 2.1);
sun.position.set(-1, 1.2, -0.6);
sun.castShadow = true;
sun.shadow.mapSize.set(2048, 2048);
sun.shadow.bias = -0.0005;
sun.shadow.normalBias = 0.5;
scene.add(sun);
scene.add(sun.target);

function skyTexture() {
  const c = document.createElement('canvas');
  c.width = 2; c.height = 256;
  const g = c.getContext('2d');
  const grad = g.createLinearGradient(0, 0, 0, 256);
  grad.addColorStop(0, `#${ZENITH.getHexString()}`);
  grad.addColorStop(0.75, `#${HORIZON.getHexString()}`);
  grad.addColorStop(1, `#${HORIZON.getHexString()}`);
  g.fillStyle = grad;
  g.fillRect(0, 0, 2, 256);
  const t = new THREE.CanvasTexture(c);
  t.colorSpace = THREE.SRGBColorSpace;
  return t;
}

// Places the sun light along `state.sun` ([east, north, up]; the view's x is east, y up, z
// south) and fits its shadow camera to the valid cells; below the horizon, a low sky light only.
function placeSun() {
  const s = app.state;
  if (!s || !mesh) return;
  const cs = s.cell_size_m;
  const [c0, c1, r0, r1] = validBox || [0, s.width - 1, 0, s.height - 1];
  const ext = Math.max(c1 - c0 + 1, r1 - r0 + 1) * cs;
  const x = (c0 + c1 + 1) * cs / 2, z = (r0 + r1 + 1) * cs / 2, y = meshMid();
  const [e, n, u] = s.sun || [-0.5, 0.5, 0.7];
  const up = Math.max(u, 0.02);
  const len = Math.hypot(e, n, up);
  sun.target.position.set(x, y, z);
  sun.position.set(x + e / len * ext * 2, y + up / len * ext * 2, z - n / len * ext * 2);
  sun.intensity = u > 0 ? 2.1 * Math.min(1, 0.35 + u * 1.5) : 0;
  const cam = sun.shadow.camera;
  cam.left = -ext * 0.75; cam.right = ext * 0.75; cam.top = ext * 0.75; cam.bottom = -ext * 0.75;
  cam.near = ext * 0.5; cam.far = ext * 4;
  cam.updateProjectionMatrix();
  renderer.shadowMap.needsUpdate = true;
  app.sunElevationDeg = Math.asin(Math.max(-1, Math.min(1, u))) * 180 / Math.PI;
  redraw = true;
}
const skierGroup = new THREE.Group();
scene.add(skierGroup);

let mesh = null;
let geo = null;
let step = 1;
let meshW = 0, meshH = 0;
const dirty = new Set();
// Draws only when something changed (new data, the camera, the skiers, the window): on a
// machine without a GPU the software renderer would otherwise take the CPU the server needs.
let redraw = true;

function resize() {
  const el = $('view');
  renderer.setSize(el.clientWidth, el.clientHeight);
  camera.aspect = el.clientWidth / Math.max(1, el.clientHeight);
  camera.updateProjectionMatrix();
}
window.addEventListener('resize', resize);

function buildMesh(s) {
  if (mesh) { scene.remove(mesh); geo.dispose(); }
  step = Math.max(1, Math.ceil(Math.max(s.width, s.height) / 384));
  meshW = Math.ceil(s.width / step);
  meshH = Math.ceil(s.height / step);
  geo = new THREE.BufferGeometry();
  const n = meshW * meshH;
  geo.setAttribute('position', new THREE.BufferAttribute(new Float32Array(3 * n), 3));
  geo.setAttribute('color', new THREE.BufferAttribute(new Float32Array(3 * n), 3));
  geo.setAttribute('normal', new THREE.BufferAttribute(new Float32Array(3 * n), 3));
  // Quads with a nodata corner are not drawn (a clipped DEM's outline stays open instead of
  // walls down to altitude 0), and the views frame the valid cells only.
  const b = grids.bedrock;
  const validAt = (i, j) => {
    const k = Math.min(s.height - 1, j * step) * s.width + Math.min(s.width - 1, i * step);
    return !b || Number.isFinite(b[k]);
  };
  const idx = [];
  let [c0, c1, r0, r1] = [Infinity, -Infinity, Infinity, -Infinity];
  for (let j = 0; j < meshH - 1; j++) {
    for (let i = 0; i < meshW - 1; i++) {
      if (!(validAt(i, j) && validAt(i + 1, j) && validAt(i, j + 1) && validAt(i + 1, j + 1))) continue;
      const a = j * meshW + i;
      idx.push(a, a + meshW, a + 1, a + 1, a + meshW, a + meshW + 1);
      c0 = Math.min(c0, i * step); c1 = Math.max(c1, (i + 1) * step);
      r0 = Math.min(r0, j * step); r1 = Math.max(r1, (j + 1) * step);
    }
  }
  validBox = Number.isFinite(c0) ? [c0, Math.min(c1, s.width - 1), r0, Math.min(r1, s.height - 1)] : [0, s.width - 1, 0, s.height - 1];
  geo.setIndex(idx);
  app.meshTriangles = idx.length / 3;
  app.meshQuads = (meshW - 1) * (meshH - 1);
  mesh = new THREE.Mesh(geo, new THREE.MeshLambertMaterial({ vertexColors: true }));
  mesh.castShadow = true;
  mesh.receiveShadow = true;
  scene.add(mesh);
  // The camera stays where the artist put it across steps, scrubs and loads of the same
  // terrain; only a terrain of another size or cell size is framed anew.
  const key = `${s.width}x${s.height}x${s.cell_size_m}`;
  if (framedFor !== key) { framedFor = key; setView('home'); }
}

// Where the camera was last framed for (the grid's size and cell size).
let framedFor = null;
// The box of the valid cells [col0, col1, row0, row1].
let validBox = null;

// Home (an oblique view of the whole terrain) or top (straight down, north up).
function setView(kind) {
  const s = app.state;
  if (!s) return;
  const cs = s.cell_size_m;
  const [c0, c1, r0, r1] = validBox || [0, s.width - 1, 0, s.height - 1];
  const ext = Math.max(c1 - c0 + 1, r1 - r0 + 1) * cs;
  const mid = meshMid();
  const x = (c0 + c1 + 1) * cs / 2, z = (r0 + r1 + 1) * cs / 2;
  controls.target.set(x, mid, z);
  if (kind === 'top') camera.position.set(x, mid + ext * 1.2, z + 1e-3 * ext);
  else camera.position.set(x, mid + ext * 0.8, z + ext * 0.9);
  camera.far = Math.max(s.width, s.height) * cs * 20;
  camera.updateProjectionMatrix();
  // Haze: clear over the terrain's near half, the horizon's colour far beyond it.
  scene.fog.near = ext * 1.2;
  scene.fog.far = ext * 6;
  placeSun();
  controls.update();
  app.view = kind;
  redraw = true;
}
app.setView = setView;
// What the view is lit and drawn with (for the browser tests): shadows, haze, the sun light's
// direction [x east, y up, z south].
app.rendering = () => ({
  shadows: renderer.shadowMap.enabled && sun.castShadow && !!mesh && mesh.receiveShadow && mesh.castShadow,
  fog: !!scene.fog,
  sunIntensity: sun.intensity,
  sunDirection: sun.position.clone().sub(sun.target.position).normalize().toArray(),
});
// The canvas pixel (CSS px from its top-left corner) where cell (col, row) is drawn, or null
// when it has no vertex or lies off screen.
app.screenOf = (col, row) => {
  if (!mesh) return null;
  const i = Math.round(col / step), j = Math.round(row / step);
  if (i >= meshW || j >= meshH) return null;
  const p = geo.attributes.position.array, v = 3 * (j * meshW + i);
  const q = new THREE.Vector3(p[v], p[v + 1], p[v + 2]).project(camera);
  if (Math.abs(q.x) > 1 || Math.abs(q.y) > 1 || q.z > 1) return null;
  const el = renderer.domElement;
  return [(q.x + 1) / 2 * el.clientWidth, (1 - q.y) / 2 * el.clientHeight];
};
app.cameraPosition = () => camera.position.toArray();

// Keys: Ctrl+Z undo, Ctrl+Shift+Z or Ctrl+Y redo, H home view, T top view (not while typing
// in a field).
window.addEventListener('keydown', (e) => {
  const t = e.target;
  if (t && (t.tagName === 'INPUT' || t.tagName === 'TEXTAREA' || t.tagName === 'SELECT' || t.isContentEditable)) return;
  const mod = e.ctrlKey || e.metaKey;
  const k = e.key.toLowerCase();
  if (mod && k === 'z') { e.preventDefault(); send({ type: e.shiftKey ? 'redo' : 'undo' }); }
  else if (mod && k === 'y') { e.preventDefault(); send({ type: 'redo' }); }
  else if (!mod && !e.altKey && k === 'h') setView('home');
  else if (!mod && !e.altKey && k === 't') setView('top');
});

// The lowest and highest valid bedrock altitudes (sampled), m.
function bedrockRange() {
  const b = grids.bedrock;
  let lo = Infinity, hi = -Infinity;
  if (b) for (let i = 0; i < b.length; i += 7) { if (b[i] < lo) lo = b[i]; if (b[i] > hi) hi = b[i]; }
  return Number.isFinite(lo) ? [lo, hi] : [0, 1];
}

function meshMid() {
  const b = grids.bedrock;
  if (!b) return 0;
  let lo = Infinity, hi = -Infinity;
  for (let i = 0; i < b.length; i += 97) { if (b[i] < lo) lo = b[i]; if (b[i] > hi) hi = b[i]; }
  return (lo + hi) / 2;
}

function dirtyAll() { dirty.add('all'); }

// Updates mesh vertices of the dirty tiles (or all).
function refreshMesh() {
  if (!mesh || !app.state || dirty.size === 0) return;
  const s = app.state;
  const cs = s.cell_size_m;
  const pos = geo.attributes.position.array;
  const col = geo.attributes.color.array;
  const mode = $('shade').value;
  const ranges = [];
  if (dirty.has('all')) ranges.push([0, meshW - 1, 0, meshH - 1]);
  else {
    for (const key of dirty) {
      const [tx, ty, tile] = key.split(',').map(Number);
      ranges.push([Math.floor(tx * tile / step), Math.min(meshW - 1, Math.ceil(((tx + 1) * tile) / step)),
        Math.floor(ty * tile / step), Math.min(meshH - 1, Math.ceil(((ty + 1) * tile) / step))]);
    }
  }
  dirty.clear();
  const b = grids.bedrock;
  if (!b) return;
  const nodataZ = meshMid();
  const rgb = [0, 0, 0], bare = [0, 0, 0];
  const [zLo, zHi] = bedrockRange();
  const bz = (c, r) => {
    const v = b[Math.min(s.height - 1, Math.max(0, r)) * s.width + Math.min(s.width - 1, Math.max(0, c))];
    return Number.isFinite(v) ? v : NaN;
  };
  for (const [i0, i1, j0, j1] of ranges) {
    for (let j = j0; j <= j1; j++) {
      const r = Math.min(s.height - 1, j * step);
      for (let i = i0; i <= i1; i++) {
        const c = Math.min(s.width - 1, i * step);
        const k = r * s.width + c;
        const v = j * meshW + i;
        let depth = 0;
        for (const l of ['compacted', 'stable', 'unstable', 'powder']) depth += grids[l] ? grids[l][k] : 0;
        const flow = grids.flow ? grids.flow[k] || 0 : 0;
        const z = Number.isFinite(b[k]) ? b[k] : nodataZ;
        pos[3 * v] = c * cs;
        pos[3 * v + 1] = z + depth + flow;
        pos[3 * v + 2] = r * cs;
        const z0 = bz(c, r);
        const gx = (bz(c + step, r) - bz(c - step, r)) / (2 * step * cs);
        const gz = (bz(c, r + step) - bz(c, r - step)) / (2 * step * cs);
        bareColour(Math.hypot(gx, gz), (z0 - zLo) / Math.max(1, zHi - zLo), bare);
        colourOf(mode, grids, k, depth, flow, rgb, bare);
        col[3 * v] = rgb[0]; col[3 * v + 1] = rgb[1]; col[3 * v + 2] = rgb[2];
      }
    }
  }
  // Normals of the changed vertices and their neighbours only, from central differences of
  // the grid heights (the mesh is a regular grid: no need to recompute the whole geometry).
  const nrm = geo.attributes.normal.array;
  const h = (i, j) => pos[3 * (Math.min(meshH - 1, Math.max(0, j)) * meshW + Math.min(meshW - 1, Math.max(0, i))) + 1];
  const d = 2 * step * cs;
  for (const [i0, i1, j0, j1] of ranges) {
    for (let j = Math.max(0, j0 - 1); j <= Math.min(meshH - 1, j1 + 1); j++) {
      for (let i = Math.max(0, i0 - 1); i <= Math.min(meshW - 1, i1 + 1); i++) {
        const nx = -(h(i + 1, j) - h(i - 1, j)) / d, nz = -(h(i, j + 1) - h(i, j - 1)) / d;
        const inv = 1 / Math.sqrt(nx * nx + 1 + nz * nz);
        const v = 3 * (j * meshW + i);
        nrm[v] = nx * inv; nrm[v + 1] = inv; nrm[v + 2] = nz * inv;
      }
    }
  }
  geo.attributes.position.needsUpdate = true;
  geo.attributes.color.needsUpdate = true;
  geo.attributes.normal.needsUpdate = true;
  renderer.shadowMap.needsUpdate = true;
  if (ranges.length && ranges[0][1] - ranges[0][0] === meshW - 1) geo.computeBoundingSphere();
}

function onFrame(buf) {
  const f = applyFrame(buf, grids);
  if (!f) { status('malformed frame from the server'); return; }
  app.frames++;
  app.lastFrameAt = performance.now();
  if (f.channel === 'bedrock' && app.state) { buildMesh(app.state); dirtyAll(); return; }
  for (const [tx, ty] of f.tiles) dirty.add(`${tx},${ty},${f.tile}`);
  if (f.channel === 'wind' && $('shade').value === 'wind') updateArrows();
}

function onState(m) {
  const first = !app.state || app.state.width !== m.width || app.state.height !== m.height;
  const sunMoved = !app.state || String(app.state.sun) !== String(m.sun);
  app.state = m;
  if (first && grids.bedrock) { buildMesh(m); dirtyAll(); }
  else if (sunMoved) placeSun();
  panels.onState(m);
  if ($('shade').value === 'wind') updateArrows();
}

function showSkiers(m) {
  skierGroup.clear();
  redraw = true;
  if (!app.state || !grids.bedrock) return;
  const s = app.state, cs = s.cell_size_m;
  const h = (p) => {
    const c = Math.max(0, Math.min(s.width - 1, Math.round(p[0])));
    const r = Math.max(0, Math.min(s.height - 1, Math.round(p[1])));
    const k = r * s.width + c;
    let d = 0;
    for (const l of ['compacted', 'stable', 'unstable', 'powder']) d += grids[l] ? grids[l][k] : 0;
    return grids.bedrock[k] + d + 2;
  };
  for (const p of m.positions) {
    const ball = new THREE.Mesh(new THREE.SphereGeometry(cs * 0.8), new THREE.MeshBasicMaterial({ color: 0xff2020 }));
    ball.position.set(p[0] * cs, h(p), p[1] * cs);
    skierGroup.add(ball);
  }
  if (m.track.length > 1) {
    const pts = m.track.map((p) => new THREE.Vector3(p[0] * cs, h(p), p[1] * cs));
    skierGroup.add(new THREE.Line(new THREE.BufferGeometry().setFromPoints(pts), new THREE.LineBasicMaterial({ color: 0x202020 })));
  }
}

// ---------- picking and tools ----------
const ray = new THREE.Raycaster();
function pick(ev) {
  if (!mesh || !app.state) return null;
  const rect = renderer.domElement.getBoundingClientRect();
  const p = new THREE.Vector2(((ev.clientX - rect.left) / rect.width) * 2 - 1, -((ev.clientY - rect.top) / rect.height) * 2 + 1);
  ray.setFromCamera(p, camera);
  const hit = ray.intersectObject(mesh)[0];
  if (!hit) return null;
  const cs = app.state.cell_size_m;
  return { col: hit.point.x / cs, row: hit.point.z / cs };
}
app.pickAt = (x, y) => pick({ clientX: x, clientY: y });

let stroke = 1;
let painting = false;
let pending = null;
function dab(at) {
  send({
    type: 'brush', stroke, op: $('op').value, target: $('target').value, col: at.col, row: at.row,
    radius_m: Number($('radius').value), strength: Number($('strength').value), value: Number($('value').value),
  });
}
renderer.domElement.addEventListener('pointerdown', (ev) => {
  const tool = $('tool').value;
  if (tool === 'orbit') return;
  const at = pick(ev);
  if (!at) return;
  if (tool === 'brush') { painting = true; stroke++; dab(at); }
  if (tool === 'avalanche') send({ type: 'trigger_avalanche', col: at.col, row: at.row });
  if (tool === 'skier') send({ type: 'launch_skier', col: at.col, row: at.row });
});
renderer.domElement.addEventListener('pointermove', (ev) => {
  if (painting) pending = ev;
  hover = ev;
});
renderer.domElement.addEventListener('pointerleave', () => { hover = null; showHover(null); });

// ---------- hover readout and brush ring ----------
// What lies under the cursor, read from the grids the page holds (no server round trip):
// altitude, slope and aspect of the bedrock (central differences), each layer, and the
// environment channels.
let hover = null;
const readout = document.createElement('div');
readout.id = 'readout';
document.getElementById('view').appendChild(readout);
const ringPoints = 96;
const ringGeo = new THREE.BufferGeometry();
ringGeo.setAttribute('position', new THREE.BufferAttribute(new Float32Array(3 * ringPoints), 3));
const ring = new THREE.LineLoop(ringGeo, new THREE.LineBasicMaterial({ color: 0xff7a1a, depthTest: false }));
ring.renderOrder = 10;
ring.visible = false;
scene.add(ring);

// Surface height (bedrock + snow + flow) at fractional cell (c, r), nearest cell.
function surfaceAt(c, r) {
  const s = app.state;
  const cc = Math.max(0, Math.min(s.width - 1, Math.round(c)));
  const rr = Math.max(0, Math.min(s.height - 1, Math.round(r)));
  const k = rr * s.width + cc;
  let z = grids.bedrock[k];
  if (!Number.isFinite(z)) return null;
  for (const l of ['compacted', 'stable', 'unstable', 'powder', 'flow']) z += grids[l] ? grids[l][k] || 0 : 0;
  return z;
}

// The readout's numbers at cell (c, r): null outside the grid or on nodata.
function cellReadout(c, r) {
  const s = app.state, b = grids.bedrock;
  const col = Math.round(c), row = Math.round(r);
  if (col < 0 || row < 0 || col >= s.width || row >= s.height) return null;
  const k = row * s.width + col;
  if (!Number.isFinite(b[k])) return null;
  const at = (cc, rr) => b[Math.max(0, Math.min(s.height - 1, rr)) * s.width + Math.max(0, Math.min(s.width - 1, cc))];
  const cs = s.cell_size_m;
  // Rows run north to south: dz/dy (north) = (z above − z below) / 2 cs.
  const gx = (at(col + 1, row) - at(col - 1, row)) / (2 * cs);
  const gy = (at(col, row - 1) - at(col, row + 1)) / (2 * cs);
  const slope = Math.atan(Math.hypot(gx, gy)) * 180 / Math.PI;
  // Aspect: the compass direction the slope faces (downhill), 0 = north, clockwise.
  const aspect = (Math.atan2(-gx, -gy) * 180 / Math.PI + 360) % 360;
  const layer = (l) => (grids[l] ? grids[l][k] || 0 : 0);
  const depth = ['compacted', 'stable', 'unstable', 'powder'].reduce((d, l) => d + layer(l), 0);
  const out = { col, row, altitude: b[k], slope, aspect, depth,
    compacted: layer('compacted'), stable: layer('stable'), unstable: layer('unstable'), powder: layer('powder') };
  for (const e of ['temperature', 'sun', 'wind', 'flow']) if (grids[e] && Number.isFinite(grids[e][k])) out[e] = grids[e][k];
  return out;
}
app.cellReadout = cellReadout;

function showHover(at) {
  const v = at && app.state && grids.bedrock ? cellReadout(at.col, at.row) : null;
  app.hover = v;
  if (!v) { readout.style.display = 'none'; if (ring.visible) { ring.visible = false; redraw = true; } return; }
  const compass = ['N', 'NE', 'E', 'SE', 'S', 'SW', 'W', 'NW'][Math.round(v.aspect / 45) % 8];
  let text = `cell (${v.col}, ${v.row}) · ${v.altitude.toFixed(0)} m · slope ${v.slope.toFixed(0)}° · faces ${compass} (${v.aspect.toFixed(0)}°)\n`
    + `snow ${v.depth.toFixed(2)} m: compacted ${v.compacted.toFixed(2)}, stable ${v.stable.toFixed(2)}, unstable ${v.unstable.toFixed(2)}, powder ${v.powder.toFixed(2)}`;
  if (v.temperature !== undefined) text += `\nair ${v.temperature.toFixed(1)} °C`;
  if (v.sun !== undefined) text += ` · direct sun ${v.sun.toFixed(1)} h/day`;
  if (v.wind !== undefined) text += ` · wind ${v.wind.toFixed(1)} m/s`;
  if (v.flow) text += ` · flowing ${v.flow.toFixed(2)} m`;
  readout.textContent = text;
  readout.style.display = 'block';
  // The brush ring: the brush's radius drawn on the snow surface around the cursor.
  const brushing = $('tool').value === 'brush';
  if (brushing) {
    const s = app.state, cs = s.cell_size_m;
    const radius = Math.max(cs, Number($('radius').value) || 0);
    const pos = ringGeo.attributes.position.array;
    for (let k = 0; k < ringPoints; k++) {
      const a = (2 * Math.PI * k) / ringPoints;
      const x = at.col * cs + radius * Math.cos(a), z = at.row * cs + radius * Math.sin(a);
      const y = surfaceAt(x / cs, z / cs);
      pos[3 * k] = x; pos[3 * k + 1] = (y ?? v.altitude) + 1.5; pos[3 * k + 2] = z;
    }
    ringGeo.attributes.position.needsUpdate = true;
    ringGeo.computeBoundingSphere();
  }
  if (ring.visible !== brushing || brushing) { ring.visible = brushing; redraw = true; }
}
window.addEventListener('pointerup', () => { painting = false; pending = null; });
$('tool').addEventListener('change', () => { controls.enabled = $('tool').value === 'orbit'; });
$('shade').addEventListener('change', () => { dirtyAll(); renderLegend(); });

// ---------- DEM import ----------
// The file goes to `POST /api/dem`; the server reads it as `snowscape run --dem` does, in a job
// whose progress, failure (the reader's message) or end every tab sees.
async function importDem(file) {
  if (!file) return;
  if (!window.confirm(`Import ${file.name}? The season restarts on this terrain (save the project first to keep it).`)) return;
  status(`uploading ${file.name} (${(file.size / 1048576).toFixed(1)} MiB)`);
  try {
    const r = await fetch(`/api/dem?name=${encodeURIComponent(file.name)}`, { method: 'POST', body: file });
    const text = await r.text();
    app.lastImport = { status: r.status, text };
    status(r.ok ? `importing ${file.name}` : `import refused: ${text.trim()}`);
  } catch (e) {
    app.lastImport = { status: 0, text: String(e) };
    status(`import failed: ${e}`);
  }
}
app.importDem = importDem;
$('dem-file').addEventListener('change', (ev) => { importDem(ev.target.files[0]); ev.target.value = ''; });

// ---------- screenshot ----------
// The 3D view as a PNG download, named after the project and the day.
$('screenshot').addEventListener('click', () => {
  renderer.render(scene, camera);
  const a = document.createElement('a');
  const day = app.state ? app.state.day.toFixed(1) : '0';
  a.download = `${$('name').value || 'snowscape'}_day${day}.png`;
  a.href = renderer.domElement.toDataURL('image/png');
  document.body.appendChild(a);
  a.click();
  a.remove();
  app.screenshots = (app.screenshots || 0) + 1;
});

// ---------- legend and wind arrows ----------
// The legend of the shading mode (fixed physical ranges, LEGENDS in shade.js), top left of the
// view; with the wind, arrows over the terrain in the direction the current weather period's
// wind blows, their length the local speed (the channel carries the speed; the direction is the
// period's, which the terrain deflects locally).
const legend = document.createElement('div');
legend.id = 'legend';
document.getElementById('view').appendChild(legend);
const css = (rgb) => `rgb(${rgb.map((v) => Math.round(255 * Math.min(1, Math.max(0, v)))).join(',')})`;
function renderLegend() {
  const mode = $('shade').value;
  const l = LEGENDS[mode];
  legend.innerHTML = '';
  if (!l) return;
  const title = document.createElement('div');
  title.className = 'legend-title';
  title.textContent = l.unit ? `${l.title}, ${l.unit}` : l.title;
  legend.appendChild(title);
  if (l.classes) {
    for (const [name, rgb] of l.classes) {
      const row = document.createElement('div');
      row.className = 'legend-class';
      const sw = document.createElement('span'); sw.className = 'swatch'; sw.style.background = css(rgb);
      row.append(sw, name);
      legend.appendChild(row);
    }
  } else {
    const stops = [];
    const rgb = [0, 0, 0];
    for (let i = 0; i <= 20; i++) { rampColour(mode, l.lo + (l.hi - l.lo) * i / 20, rgb); stops.push(`${css(rgb)} ${i * 5}%`); }
    const bar = document.createElement('div'); bar.className = 'legend-bar'; bar.style.background = `linear-gradient(to right, ${stops.join(', ')})`;
    const ticks = document.createElement('div'); ticks.className = 'legend-ticks';
    for (const t of l.ticks) {
      const sp = document.createElement('span'); sp.textContent = `${t}`; sp.style.left = `${100 * (t - l.lo) / (l.hi - l.lo)}%`;
      ticks.appendChild(sp);
    }
    legend.append(bar, ticks);
  }
  app.legend = { mode, text: legend.textContent };
  updateArrows();
}

const arrows = new THREE.Group();
scene.add(arrows);
// The wind period in effect on the current day.
function windNow(s) {
  let w = null;
  for (const p of s.weather || []) if (p.from_day <= s.day + 1e-9) w = p;
  return w || (s.weather || [])[0] || null;
}
function updateArrows() {
  for (const c of [...arrows.children]) { arrows.remove(c); c.geometry.dispose(); }
  const s = app.state;
  const w = s && windNow(s);
  const speed = grids.wind, b = grids.bedrock;
  app.windArrows = 0;
  if ($('shade').value !== 'wind' || !w || !speed || !b) { redraw = true; return; }
  const cs = s.cell_size_m;
  const n = 14;
  const spacing = Math.max(s.width, s.height) * cs / n;
  // Blowing towards (east, north) = −(sin, cos) of the direction it comes from; north is −z.
  const from = w.wind_from_deg * Math.PI / 180;
  const dir = new THREE.Vector3(-Math.sin(from), 0, Math.cos(from));
  const side = new THREE.Vector3(-dir.z, 0, dir.x);
  const pts = [];
  for (let j = 0; j < n; j++) {
    for (let i = 0; i < n; i++) {
      const c = Math.min(s.width - 1, Math.round((i + 0.5) * s.width / n));
      const r = Math.min(s.height - 1, Math.round((j + 0.5) * s.height / n));
      const k = r * s.width + c;
      if (!Number.isFinite(b[k]) || !Number.isFinite(speed[k])) continue;
      let depth = 0;
      for (const l of ['compacted', 'stable', 'unstable', 'powder']) depth += grids[l] ? grids[l][k] : 0;
      const len = 0.8 * spacing * Math.min(1, speed[k] / LEGENDS.wind.hi);
      const tail = new THREE.Vector3(c * cs, b[k] + depth + 0.02 * spacing, r * cs).addScaledVector(dir, -len / 2);
      const head = tail.clone().addScaledVector(dir, len);
      const barb = (sgn) => head.clone().addScaledVector(dir, -0.3 * len).addScaledVector(side, sgn * 0.15 * len);
      pts.push(tail, head, head, barb(1), head, barb(-1));
      app.windArrows++;
    }
  }
  const g = new THREE.BufferGeometry().setFromPoints(pts);
  arrows.add(new THREE.LineSegments(g, new THREE.LineBasicMaterial({ color: 0xffffff, depthTest: false })));
  redraw = true;
}
renderLegend();

const panels = setupPanels(app, send);

function onDone(m) {
  status(`${m.what} ${m.name}`);
  if (m.what === 'exported') panels.showFiles(m.files);
}

app.redraw = () => { redraw = true; };
controls.addEventListener('change', app.redraw);
window.addEventListener('resize', app.redraw);
// When the oldest unpatched change arrived (0: none pending).
let dirtySince = 0;
function loop() {
  if (painting && pending) { const at = pick(pending); pending = null; if (at) dab(at); }
  if (hover) { const ev = hover; hover = null; showHover(pick(ev)); }
  // The tile frames of one step arrive as a burst: patch the mesh once they stop (40 ms
  // without one), or every 400 ms while a long burst lasts; one patch and one draw instead of
  // one per frame (a draw of a 1024² terrain takes hundreds of ms in a software renderer).
  if (dirty.size > 0) {
    const now = performance.now();
    if (!dirtySince) dirtySince = now;
    if (now - (app.lastFrameAt || 0) > 40 || now - dirtySince > 400 || !app.state) {
      refreshMesh(); redraw = true; dirtySince = 0;
      app.patches = (app.patches || 0) + 1;
    }
  }
  controls.update();
  if (redraw) {
    renderer.render(scene, camera);
    redraw = false;
    app.renders = (app.renders || 0) + 1;
    app.lastRenderAt = performance.now();
  }
  requestAnimationFrame(loop);
}
// The frame layout and the weather fields come from the server before the socket opens.
async function start() {
  for (;;) {
    try {
      const r = await fetch('/api/protocol');
      if (r.ok) {
        const p = await r.json();
        setProtocol(p);
        setColours(p.colours);
        renderLegend();
        panels.setProtocol(p);
        break;
      }
      status(`cannot read the protocol: HTTP ${r.status}; retrying`);
    } catch (e) {
      status(`cannot read the protocol: ${e}; retrying`);
    }
    await new Promise((ok) => setTimeout(ok, 1000));
  }
  connect();
}
resize();
start();
loop();
