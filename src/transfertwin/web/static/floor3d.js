// The running floor in 3-D (three.js, vendored): the static layout from /api/floor, what
// moves from the console's live feed /api/live (server-sent events): each transport module's
// PoseX/PoseY/PoseTheta, each object's PossessedBy, the orders. World: floor metres, z up.
// window.__floor exposes the view's state (tests read it).
import * as THREE from './vendor/three/three.module.js';
import { OrbitControls } from './vendor/three/OrbitControls.js';

const $ = (id) => document.getElementById(id);
const state = { ready: false, error: null, updates: 0, renders: 0, modules: {}, start: {},
  moved: {}, objects: {}, orders: [], offline: {}, trails: {} };
const TRAIL_MAX = 2000;  // points a module's path keeps (a fixed buffer: no reallocation)
window.__floor = state;

function drawLabel(c, text, color) {
  const g = c.getContext('2d');
  g.clearRect(0, 0, c.width, c.height);
  g.fillStyle = 'rgba(20,22,28,0.8)'; g.fillRect(0, 0, c.width, c.height);
  g.fillStyle = color || '#fff'; g.font = '36px sans-serif'; g.textAlign = 'center';
  g.fillText(text, c.width / 2, 45);
}

function label(text, width = 256) {  // a sprite with the text, ~0.25 m high
  const c = document.createElement('canvas');
  c.width = width; c.height = 64;
  drawLabel(c, text);
  const tex = new THREE.CanvasTexture(c);
  tex.colorSpace = THREE.SRGBColorSpace;
  const s = new THREE.Sprite(new THREE.SpriteMaterial({ map: tex, depthTest: false }));
  s.scale.set(width / 256, 0.25, 1);
  s.userData = { canvas: c, text };
  return s;
}

function relabel(sprite, text, color) {  // redraw a label's text (offline, unknown)
  if (sprite.userData.text === text) return;
  sprite.userData.text = text;
  drawLabel(sprite.userData.canvas, text, color);
  sprite.material.map.needsUpdate = true;
}

async function main() {
  const res = await fetch('/api/floor' + location.search);
  const layout = await res.json();
  if (!res.ok) throw new Error(layout.error || `HTTP ${res.status}`);
  state.layout = layout;
  $('title').textContent = `floor ${layout.name}: ${layout.stations.length} stations, ` +
    `${layout.modules.length} modules`;
  THREE.Object3D.DEFAULT_UP.set(0, 0, 1);
  const canvas = $('scene');
  const renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0x1b1e25);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x404050, 1.6));
  const sun = new THREE.DirectionalLight(0xffffff, 1.6);
  sun.position.set(3, -4, 8);
  scene.add(sun);
  const [W, H] = layout.size_m;
  const ground = new THREE.Mesh(new THREE.PlaneGeometry(W, H),
    new THREE.MeshLambertMaterial({ color: 0x30343c }));
  ground.position.set(W / 2, H / 2, 0);
  scene.add(ground);
  const grid = new THREE.GridHelper(Math.max(W, H), Math.max(W, H), 0x4a505c, 0x3a3f4a);
  grid.rotateX(Math.PI / 2);
  grid.position.set(Math.max(W, H) / 2, Math.max(W, H) / 2, 0.002);
  scene.add(grid);

  const holders = {};  // asset id -> Object3D an object rides on
  const assets = {};  // asset id -> its body and label, drawn offline when it is
  for (const s of layout.stations) {
    const yaw = s.yaw_deg * Math.PI / 180;
    const body = new THREE.Group();
    body.position.set(s.x_m, s.y_m, 0);
    body.rotation.z = yaw;
    const box = new THREE.Mesh(new THREE.BoxGeometry(0.8, 1.0, 0.75),
      new THREE.MeshLambertMaterial({ color: 0x8a8f99, transparent: true }));
    box.position.set(0.4, 0, 0.375);  // behind its front face, along its yaw
    body.add(box);
    const top = new THREE.Object3D();
    top.position.set(0.4, 0, 0.8);
    body.add(top);
    const tag = label(s.unit, 384);
    assets[s.unit] = { box, tag, color: 0x8a8f99, name: s.unit };
    tag.position.set(0.4, 0, 1.2);
    body.add(tag);
    scene.add(body);
    holders[s.unit] = top;
  }
  const modules = {};
  for (const m of layout.modules) {
    const g = new THREE.Group();
    const color = m.standby ? 0x4a5a7a : 0x3d7ff5;
    const box = new THREE.Mesh(new THREE.BoxGeometry(0.7, 0.5, 0.35),
      new THREE.MeshLambertMaterial({ color, transparent: true }));
    box.position.z = 0.175;
    const nose = new THREE.Mesh(new THREE.ConeGeometry(0.12, 0.25, 12),
      new THREE.MeshLambertMaterial({ color: 0xffd060 }));
    nose.rotation.z = -Math.PI / 2;
    nose.position.set(0.45, 0, 0.2);
    const top = new THREE.Object3D();
    top.position.z = 0.4;
    const tag = label(m.id, 384);
    tag.position.z = 0.8;
    assets[m.id] = { box, tag, color, name: m.id };
    g.add(box, nose, top, tag);
    g.position.set(m.x_m, m.y_m, 0);
    g.rotation.z = m.theta_deg * Math.PI / 180;
    scene.add(g);
    // the path: a buffer allocated once for TRAIL_MAX points, drawn up to the points so far
    // (setFromPoints on a growing path would overflow the first buffer three.js made)
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.BufferAttribute(new Float32Array(3 * TRAIL_MAX), 3));
    geometry.setDrawRange(0, 0);
    const trail = new THREE.Line(geometry, new THREE.LineBasicMaterial({ color: 0x7fb0ff }));
    trail.frustumCulled = false;
    scene.add(trail);
    modules[m.id] = { group: g, trail, points: [] };
    holders[m.id] = top;
    state.start[m.id] = [m.x_m, m.y_m];
    state.modules[m.id] = [m.x_m, m.y_m, m.theta_deg * Math.PI / 180];
    state.moved[m.id] = 0;
  }
  const objects = {};
  for (const o of layout.objects) {
    const mesh = new THREE.Mesh(new THREE.CylinderGeometry(0.08, 0.08, 0.2, 16),
      new THREE.MeshLambertMaterial({ color: 0xb09060 }));
    mesh.rotation.x = Math.PI / 2;
    objects[o.id] = mesh;
    state.objects[o.id] = o.unit;
    (holders[o.unit] || scene).add(mesh);
  }

  function place(oid, holder) {
    const mesh = objects[oid];
    if (!mesh || !holders[holder] || state.objects[oid] === holder) return;
    holders[holder].add(mesh);
    const k = Object.keys(objects).filter((o) => state.objects[o] === holder).length;
    mesh.position.set(0, 0.2 * k - 0.2, 0.1);
    mesh.visible = true;
    state.objects[oid] = holder;
  }

  // an object the ledger has lost (PossessedBy '') is drawn nowhere: not on the unit it
  // was last seen on; the list beside the view says it is unknown
  function lose(oid) {
    const mesh = objects[oid];
    if (!mesh || state.objects[oid] === 'unknown') return;
    if (mesh.parent) mesh.parent.remove(mesh);
    mesh.visible = false;
    state.objects[oid] = 'unknown';
  }

  function markOnline(id, online) {
    const a = assets[id];
    if (!a || state.offline[id] === !online) return;
    state.offline[id] = !online;
    a.box.material.color.setHex(online ? a.color : 0x555555);
    a.box.material.opacity = online ? 1.0 : 0.35;
    relabel(a.tag, online ? a.name : a.name + ' offline', online ? '#fff' : '#ff8a80');
  }

  function extendTrail(m, id, x, y) {
    const last = m.points[m.points.length - 1];
    if (last && Math.hypot(last[0] - x, last[1] - y) <= 0.01) return;
    m.points.push([x, y]);
    if (m.points.length > TRAIL_MAX) m.points.shift();
    const pos = m.trail.geometry.attributes.position;
    m.points.forEach(([px, py], i) => pos.setXYZ(i, px, py, 0.01));
    pos.needsUpdate = true;
    m.trail.geometry.setDrawRange(0, m.points.length);
    state.trails[id] = m.points.length;
  }
  Object.keys(objects).forEach((oid) => { const h = state.objects[oid]; state.objects[oid] = null; place(oid, h); });

  function onLive(data) {
    state.updates += 1;
    const values = data.values || {};
    for (const [id, m] of Object.entries(modules)) {
      const v = values[id] || {};
      if (typeof v.PoseX !== 'number' || typeof v.PoseY !== 'number') continue;
      const th = typeof v.PoseTheta === 'number' ? v.PoseTheta : 0;
      m.group.position.set(v.PoseX, v.PoseY, 0);
      m.group.rotation.z = th;
      state.modules[id] = [v.PoseX, v.PoseY, th];
      const s = state.start[id];
      state.moved[id] = Math.max(state.moved[id], Math.hypot(v.PoseX - s[0], v.PoseY - s[1]));
      extendTrail(m, id, v.PoseX, v.PoseY);
    }
    for (const [id, online] of Object.entries(data.online || {})) markOnline(id, online);
    for (const oid of Object.keys(objects)) {
      const holder = (values[oid] || {}).PossessedBy;
      if (holder) place(oid, holder);
      else if (holder === '') lose(oid);
    }
    state.orders = (data.orders || []).filter((o) => !['finished', 'failed'].includes(o.state));
    $('live').textContent = `${state.updates} updates, ` +
      `${Object.values(data.online || {}).filter(Boolean).length} assets online`;
    $('modules').textContent = Object.entries(state.modules).map(([id, p]) =>
      `${id} (${p[0].toFixed(2)}, ${p[1].toFixed(2)}) m` + (state.offline[id] ? ' offline' : ''))
      .join('; ');
    $('objects').textContent = Object.entries(state.objects).map(([o, h]) =>
      h === 'unknown' ? `${o}: place unknown` : `${o} on ${h}`).join(', ');
    $('orders').textContent = state.orders.length ? state.orders.map((o) =>
      `${o.operation || o.id || ''} ${o.object || ''} → ${o.target || ''}: ${o.state}`).join('; ')
      : 'none running';
  }
  const live = new EventSource('/api/live' + location.search);
  live.addEventListener('live', (e) => onLive(JSON.parse(e.data)));
  live.onerror = () => { $('live').textContent = 'live feed interrupted; reconnecting…'; };

  const camera = new THREE.PerspectiveCamera(45, 1, 0.05, 200);
  camera.position.set(W / 2, -H * 0.45, Math.max(W, H) * 0.85);
  const controls = new OrbitControls(camera, canvas);
  controls.target.set(W / 2, H / 2, 0);
  controls.update();
  function frame() {
    const w = canvas.clientWidth, h = canvas.clientHeight;
    if (canvas.width !== w || canvas.height !== h) {
      renderer.setSize(w, h, false);
      camera.aspect = w / Math.max(1, h);
      camera.updateProjectionMatrix();
    }
    controls.update();
    renderer.render(scene, camera);
    state.renders += 1;
    state.ready = true;
    requestAnimationFrame(frame);
  }
  requestAnimationFrame(frame);
}

main().catch((err) => {
  state.error = String(err && err.message ? err.message : err);
  $('error').hidden = false;
  $('error').textContent = state.error;
});
