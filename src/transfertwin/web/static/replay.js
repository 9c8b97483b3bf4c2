// The 3-D replay of one virtual experiment (three.js, vendored under /static/vendor/three).
// The page's query names the experiment; /api/replay answers the document of
// transfertwin.replay.replay_payload. World frame = the TM tip frame F_T, z up, metres.
// window.__replay exposes the view's state (tests read it; nothing else depends on it).
import * as THREE from './vendor/three/three.module.js';
import { OrbitControls } from './vendor/three/OrbitControls.js';

const $ = (id) => document.getElementById(id);
const state = {
  ready: false, error: null, t: 0, duration: 0, playing: false, speed: 1, frame: 0,
  ots: null, barriers: {}, objectCentre: null, inGap: false, markers: [], loadMs: null,
  frames: 0, renders: 0,
};
window.__replay = state;

// what a sample's OTS state means, in words first, the set second
const OTS_NAMES = { '-2': 'no transfer (placing, settling)', '2': 'start state (s(t0) ∈ S_pre)',
  '-1': "crossing (non-terminal, S')", '1': 'arrived (success, S+)', '0': 'failed (S−)',
  '3': 'not a start state (not in S_pre)' };
const WAY = { 1: 'TM → TU', '-1': 'TU → TM' };
const OTS_COLOURS = { '-2': '#555b66', '2': '#6aa8ff', '-1': '#d8c35a', '1': '#5fd27a',
  '0': '#ff5a4f', '3': '#c58bff' };
const STRIPE_M = 0.04;  // belt texture period along the belt (m)

function decode(b64, Type) {
  const bin = atob(b64);
  const bytes = new Uint8Array(bin.length);
  for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
  return new Type(bytes.buffer);
}

function meshGeometry(mesh) {
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.BufferAttribute(decode(mesh.vertices, Float32Array), 3));
  g.setIndex(new THREE.BufferAttribute(decode(mesh.faces, Uint32Array), 1));
  const flat = g.toNonIndexed();  // crisp facets
  flat.computeVertexNormals();
  return flat;
}

function setPose(obj, pos, quatWxyz) {
  obj.position.set(pos[0], pos[1], pos[2]);
  obj.quaternion.set(quatWxyz[1], quatWxyz[2], quatWxyz[3], quatWxyz[0]).normalize();
}

function colour(rgba) { return new THREE.Color(rgba[0], rgba[1], rgba[2]); }

function stripeTexture() {
  const c = document.createElement('canvas');
  c.width = 64; c.height = 8;
  const g = c.getContext('2d');
  g.fillStyle = '#26272c'; g.fillRect(0, 0, 64, 8);
  g.fillStyle = '#4a4c55'; g.fillRect(0, 0, 10, 8);
  const tex = new THREE.CanvasTexture(c);
  tex.colorSpace = THREE.SRGBColorSpace;
  tex.wrapS = tex.wrapT = THREE.RepeatWrapping;
  return tex;
}

// -- building the scene ---------------------------------------------------------------------
function buildUnits(doc, bodies, ghost) {
  const belts = {};  // 'tm_left' -> {texture, pivots: [pivot], length}
  const base = stripeTexture();
  for (const p of doc.scene.parts) {
    if (p.body === 'object') continue;
    let geom;
    if (p.kind === 'box') geom = new THREE.BoxGeometry(2 * p.size[0], 2 * p.size[1], 2 * p.size[2]);
    else if (p.kind === 'cylinder') {
      geom = new THREE.CylinderGeometry(p.size[0], p.size[0], 2 * p.size[1], 32);
      geom.rotateX(Math.PI / 2);  // three's axis y -> MuJoCo's z
    } else geom = meshGeometry(p.mesh);
    const m = /^(tm|tu)_(left|right)_(deck|pulley_start|pulley_end)$/.exec(p.name);
    const key = m ? `${m[1]}_${m[2]}` : null;
    if (key && !belts[key]) belts[key] = { texture: null, pivots: [], length: 0 };
    let material;
    if (m && m[3] === 'deck') {
      const tex = base.clone();
      tex.needsUpdate = true;
      tex.repeat.set(2 * p.size[0] / STRIPE_M, 1);
      belts[key].texture = tex;
      belts[key].length = 2 * p.size[0];
      material = new THREE.MeshLambertMaterial({ map: tex });
    } else {
      material = new THREE.MeshLambertMaterial({ color: colour(p.rgba) });
    }
    const mesh = new THREE.Mesh(geom, material);
    if (m && m[3] !== 'deck') {  // a pulley spins about the unit's y axis through its centre
      const pivot = new THREE.Group();
      pivot.position.set(p.pos[0], p.pos[1], p.pos[2]);
      setPose(mesh, [0, 0, 0], p.quat);
      pivot.add(mesh);
      bodies[p.body].add(pivot);
      belts[key].pivots.push(pivot);
    } else {
      setPose(mesh, p.pos, p.quat);
      bodies[p.body].add(mesh);
    }
    if (p.body === 'tu') {  // the same part at the nominal TU pose, as a wireframe ghost
      const g = new THREE.Mesh(geom, new THREE.MeshBasicMaterial({ color: 0xffa040,
        wireframe: true, transparent: true, opacity: 0.35 }));
      setPose(g, p.pos, p.quat);
      ghost.add(g);
    }
  }
  return belts;
}

function buildBarriers(doc, bodies) {
  const out = {};
  const L = doc.scene.beam_m;
  for (const b of doc.scene.barriers) {
    const geom = new THREE.CylinderGeometry(0.0025, 0.0025, L, 8);
    geom.rotateX(Math.PI / 2);
    geom.translate(0, 0, L / 2);  // the rangefinder looks along its site's +z
    const mat = new THREE.MeshBasicMaterial({ color: 0x5fd27a });
    const beam = new THREE.Mesh(geom, mat);
    setPose(beam, b.pos, b.quat);
    bodies[b.body].add(beam);
    const head = new THREE.Mesh(new THREE.BoxGeometry(0.012, 0.012, 0.02),
      new THREE.MeshLambertMaterial({ color: 0x303540 }));
    setPose(head, b.pos, b.quat);
    bodies[b.body].add(head);
    out[b.name.replace('_barrier_', '_')] = mat;
  }
  return out;
}

function deckSpan(doc, name) {
  const p = doc.scene.parts.find((q) => q.name === name);
  return p ? [p.pos[0] - p.size[0], p.pos[0] + p.size[0], p.pos[2] + p.size[2]] : null;
}

function buildGap(doc, tuBody) {
  // The gap: from the TM's tip (end of its decks) to the TU's near end, across both belts.
  const tm = deckSpan(doc, 'tm_left_deck');
  const tu = deckSpan(doc, 'tu_left_deck');
  const h = doc.scene.belt_half_span_m;
  const z = Math.min(tm[2], tu[2]) - 0.004;
  tuBody.updateMatrixWorld(true);
  const a = new THREE.Vector3(tu[0], h, z - doc.scene.tu.pos[2]).applyMatrix4(tuBody.matrixWorld);
  const b = new THREE.Vector3(tu[0], -h, z - doc.scene.tu.pos[2]).applyMatrix4(tuBody.matrixWorld);
  const verts = new Float32Array([tm[1], h, z, tm[1], -h, z, b.x, b.y, z, a.x, a.y, z]);
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.BufferAttribute(verts, 3));
  g.setIndex([0, 1, 2, 0, 2, 3]);
  const mesh = new THREE.Mesh(g, new THREE.MeshBasicMaterial({ color: 0xff3030, transparent: true,
    opacity: 0.35, side: THREE.DoubleSide }));
  const mid = a.clone().add(b).multiplyScalar(0.5);
  return { mesh, tmTip: tm[1], tuNear: tu[0], tuNearX: mid.x, halfSpan: h, top: z };
}

function buildObject(doc) {
  const group = new THREE.Group();
  const visual = new THREE.Mesh(meshGeometry(doc.scene.object_mesh),
    new THREE.MeshLambertMaterial({ color: 0xb09060, transparent: true, opacity: 1 }));
  group.add(visual);
  const hulls = new THREE.Group();
  let k = 0;
  for (const p of doc.scene.parts) {
    if (p.body !== 'object') continue;
    const mat = new THREE.MeshLambertMaterial({ color: new THREE.Color().setHSL((k++ * 0.13) % 1,
      0.6, 0.55) });
    const m = new THREE.Mesh(meshGeometry(p.mesh), mat);
    setPose(m, p.pos, p.quat);
    hulls.add(m);
  }
  hulls.visible = false;
  group.add(hulls);
  return { group, visual, hulls };
}

// -- the time line --------------------------------------------------------------------------
function bisect(ts, t) {
  let lo = 0, hi = ts.length - 1;
  const eps = 1e-7;  // marker times and sample times agree to 1 µs
  if (t <= ts[0]) return 0;
  if (t >= ts[hi] - eps) return hi;
  while (hi - lo > 1) {
    const mid = (lo + hi) >> 1;
    if (ts[mid] <= t + eps) lo = mid; else hi = mid;
  }
  return lo;
}

function drawStrip(doc) {
  const c = $('ots-strip');
  c.width = c.clientWidth || 600;
  const g = c.getContext('2d');
  const f = doc.frames;
  const T = state.duration || 1;
  for (let i = 0; i < f.t.length; i++) {
    const t0 = i === 0 ? 0 : f.t[i - 1];
    g.fillStyle = OTS_COLOURS[String(f.ots[i])] || '#555';
    g.fillRect(Math.floor(t0 / T * c.width), 0, Math.ceil((f.t[i] - t0) / T * c.width) + 1, 10);
  }
}

function textSprite(text, height = 0.05) {  // a label in the scene, `height` m high
  const c = document.createElement('canvas');
  c.width = 512; c.height = 96;
  const sprite = new THREE.Sprite(new THREE.SpriteMaterial({
    map: new THREE.CanvasTexture(c), depthTest: false }));
  sprite.userData = { canvas: c, text: null };
  sprite.renderOrder = 10;
  setSpriteText(sprite, text, height);
  return sprite;
}

function setSpriteText(sprite, text, height = 0.05) {
  if (sprite.userData.text === text) return;
  sprite.userData.text = text;
  const c = sprite.userData.canvas;
  const g = c.getContext('2d');
  g.font = '64px sans-serif';
  const w = Math.min(512, Math.ceil(g.measureText(text).width) + 32);
  g.clearRect(0, 0, c.width, c.height);
  g.fillStyle = 'rgba(20,22,28,0.85)'; g.fillRect(0, 0, w, 96);
  g.fillStyle = '#fff'; g.textBaseline = 'middle'; g.fillText(text, 16, 50);
  const tex = sprite.material.map;
  tex.colorSpace = THREE.SRGBColorSpace;
  tex.repeat.set(w / 512, 1);
  tex.needsUpdate = true;
  sprite.scale.set(height * w / 96, height, 1);
}

function buildLabels(doc, tuBody) {
  // TM and TU beside their near (right) belt edge, and an arrow for the direction the belts
  // run, as `transfertwin transfer --image` draws them
  const tm = deckSpan(doc, 'tm_left_deck');
  const tu = deckSpan(doc, 'tu_left_deck');
  const side = -(doc.scene.belt_half_span_m + 0.07);
  const group = new THREE.Group();
  const tmLabel = textSprite('TM');
  tmLabel.position.set((tm[0] + tm[1]) / 2, side, tm[2] + 0.02);
  const tuLabel = textSprite('TU');
  tuBody.updateMatrixWorld(true);
  tuLabel.position.copy(new THREE.Vector3((tu[0] + tu[1]) / 2, side,
    tu[2] - doc.scene.tu.pos[2] + 0.02).applyMatrix4(tuBody.matrixWorld));
  const y = side - 0.09, z = tm[2] + 0.01;
  const arrow = new THREE.ArrowHelper(new THREE.Vector3(1, 0, 0), new THREE.Vector3(-0.15, y, z),
    0.3, 0xe63c28, 0.07, 0.045);
  const travel = textSprite('belts stopped', 0.035);
  travel.position.set(0, y - 0.05, z);
  group.add(tmLabel, tuLabel, arrow, travel);
  return { group, arrow, travel, y, z, tmEnd: [tm[0], 0, tm[2]], tuLabel, tmLabel };
}

function fmt(v, d = 2) { return v === null || v === undefined ? '–' : Number(v).toFixed(d); }

function describe(doc) {
  const r = doc.result;
  const s = doc.spec;
  $('title').textContent = doc.title;
  const y2 = r.y2 === null ? 'not attempted' : r.y2;
  const src = doc.source || {};
  if (src.kind === 'plant') {  // a plant experiment's log: no y1, y2 or status
    $('result').textContent = `the plant's log: ${r.success ? 'success' : 'failure'}, ` +
      `transfer time ${fmt(r.transfer_time_s)} s, experiment ${r.experiment_id} at ` +
      `${r.transfer_unit}`;
  } else {
    $('result').textContent = doc.outcome || (r.status !== 'ok' ? `${r.status}: ${r.message || ''}` :
      `y1 = ${r.y1}, y2 = ${y2}, ${r.success ? 'success' : 'failure'}, t_end = ${fmt(r.t_end_s)} s`);
    $('result').title = `status ${r.status}, y1 = ${r.y1}, y2 = ${y2}, success = ${r.success}`;
  }
  const d = s.docking_error_mm_deg;
  const tu = doc.scene.tu_pose;
  $('dock').textContent = `x ${fmt(d[0])} mm, y ${fmt(d[1])} mm, θ ${fmt(d[2])}°; TU at ` +
    `(${fmt(tu[0] * 1000, 1)}, ${fmt(tu[1] * 1000, 1)}) mm, ${fmt(tu[2] * 180 / Math.PI)}° ` +
    `(nominal gap ${fmt(s.gap_m * 1000)} mm)`;
  if (src.kind === 'plant') {
    $('check').textContent = `recorded on the plant (${src.table} row ${src.row}; camera: ` +
      `${src.camera}); drawn with ${src.drawn}`;
    $('check').title = src.note || '';
  } else if (src.check) {
    $('check').textContent = src.check.same ? `same bits as the stored row of ${src.study}` :
      `differs from the stored row: ${src.check.differences.join('; ')}`;
  } else if (src.kind === 'study') {
    $('check').textContent = `not in ${src.study} yet`;
  } else if (src.kind === 'calibration') {
    const word = (y) => (y === null || y === undefined ? '–' : y ? 'success' : 'failure');
    $('check').textContent = `${src.calibration} row ${src.row}: real ${word(src.real_success)}; ` +
      `run ${src.run} predicted ${word(src.predicted)}, this replay ${word(src.replayed)}` +
      (src.agrees === null ? '' : src.agrees ? ' (agrees)' : ' (differs)');
    $('check').title = src.note || '';
  } else {
    $('check').textContent = `re-simulated (${src.kind || 'replay'}), seed ${s.seed}`;
  }
  if (src.kind === 'study' && src.runs > 1) {  // step through the state's runs
    const runs = document.createElement('span');
    runs.id = 'runs';
    runs.append(` · run ${s.run} of 0..${src.runs - 1}: `);
    for (const [text, r] of [['‹ previous', s.run - 1], ['next ›', s.run + 1]]) {
      if (r < 0 || r >= src.runs) continue;
      const q = new URLSearchParams({ study: src.study, object: doc.result.object_id, face: s.face,
        conveyor: s.conveyor, theta: s.theta_deg, run: r });
      const a = document.createElement('a');
      a.href = '/replay?' + q.toString();
      a.textContent = text + ' ';
      a.className = 'run-link';
      runs.append(a);
    }
    $('check').append(runs);
  }
}


// -- main -------------------------------------------------------------------------------------
const tModule = performance.now();  // the module graph (three.js) has loaded

async function main() {
  const doc = await window.__replayDoc;
  state.timing = { moduleMs: tModule, docMs: performance.now() };
  if (doc.version !== 1) throw new Error(`replay document version ${doc.version}, expected 1`);
  THREE.Object3D.DEFAULT_UP.set(0, 0, 1);
  const canvas = $('scene');
  const renderer = new THREE.WebGLRenderer({ canvas, antialias: true,
    preserveDrawingBuffer: true, context: window.__replayGl || undefined });
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  state.timing.rendererMs = performance.now();
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0x1b1e25);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x404050, 1.6));
  const sun = new THREE.DirectionalLight(0xffffff, 1.8);
  sun.position.set(-0.6, -0.8, 1.5);
  scene.add(sun);
  const grid = new THREE.GridHelper(3, 30, 0x3a3f4a, 0x2a2e36);
  grid.rotateX(Math.PI / 2);
  grid.position.z = doc.scene.floor_z;
  scene.add(grid);

  const bodies = { world: new THREE.Group(), tu: new THREE.Group() };
  setPose(bodies.tu, doc.scene.tu.pos, doc.scene.tu.quat);
  const ghost = new THREE.Group();
  setPose(ghost, doc.scene.nominal_tu.pos, doc.scene.nominal_tu.quat);
  scene.add(bodies.world, bodies.tu, ghost);
  const belts = buildUnits(doc, bodies, ghost);
  const beams = buildBarriers(doc, bodies);
  const gap = buildGap(doc, bodies.tu);
  scene.add(gap.mesh);
  const obj = buildObject(doc);
  scene.add(obj.group);
  const marks = buildLabels(doc, bodies.tu);
  scene.add(marks.group);
  const lastMarker = doc.markers.length ? doc.markers[doc.markers.length - 1] : null;
  const ended = lastMarker && ['success', 'failure', 'invalid'].includes(lastMarker.kind)
    ? lastMarker.t : Infinity;
  state.timing.sceneMs = performance.now();

  const camera = new THREE.PerspectiveCamera(40, 1, 0.01, 30);
  camera.position.set(-0.25, -1.05, 0.75);
  const controls = new OrbitControls(camera, canvas);
  controls.target.set(-0.05, 0, 0);
  controls.update();
  // Frame both units, from the TM's far end to the TU's, whatever the canvas's aspect (until
  // the user moves the camera): the view direction stays, the distance follows the width.
  const tuFar = new THREE.Vector3(deckSpan(doc, 'tu_left_deck')[1], 0, 0)
    .applyMatrix4(bodies.tu.matrixWorld).x;
  const spanX = [marks.tmEnd[0], tuFar];
  let userMoved = false;
  controls.addEventListener('start', () => { userMoved = true; });
  function frameUnits() {
    if (userMoved) return;
    const centreX = (spanX[0] + spanX[1]) / 2;
    const half = (spanX[1] - spanX[0]) / 2 + 0.12;
    const hfov = 2 * Math.atan(Math.tan(camera.fov * Math.PI / 360) * camera.aspect);
    const d = Math.max(1.3, 1.15 * half / Math.tan(hfov / 2));
    const dir = new THREE.Vector3(-0.2, -1.05, 0.75).normalize();
    controls.target.set(centreX, 0, 0);
    camera.position.copy(controls.target).addScaledVector(dir, d);
    controls.update();
  }

  const f = doc.frames;
  // the direction the belts last ran by each sample (+1 TM → TU, -1 TU → TM, 0 not yet)
  const lastWay = [];
  f.belts.reduce((w, b) => {
    const sum = b.reduce((x, v) => x + v, 0);
    const now = Math.abs(sum) < 1e-9 ? w : sum > 0 ? 1 : -1;
    lastWay.push(now);
    return now;
  }, 0);
  state.duration = f.t[f.t.length - 1];
  state.frames = f.t.length;
  state.markers = doc.markers;
  // tuNear: the TU's near belt end in its own frame; tuNearX: in F_T, on the TU's axis.
  state.gap = { tmTip: gap.tmTip, tuNear: gap.tuNear, tuNearX: gap.tuNearX,
    halfSpan: gap.halfSpan };
  describe(doc);

  const scrub = $('scrub');
  scrub.max = String(state.duration);
  scrub.disabled = false;
  const markerBox = $('markers');
  doc.markers.forEach((m, i) => {
    const b = document.createElement('button');
    b.type = 'button';
    b.className = `marker ${m.kind}`;
    b.dataset.kind = m.kind;
    b.dataset.index = String(i);
    b.title = `${fmt(m.t)} s: ${m.label}`;
    b.style.left = `${(100 * m.t / (state.duration || 1)).toFixed(3)}%`;
    b.addEventListener('click', () => { pause(); seek(m.t); });
    markerBox.appendChild(b);
  });

  const tuInv = new THREE.Matrix4().copy(bodies.tu.matrixWorld).invert();
  const box = new THREE.Box3();
  const centre = new THREE.Vector3();
  const qa = new THREE.Quaternion(), qb = new THREE.Quaternion();

  function apply(t) {
    const i = bisect(f.t, t);
    const j = Math.min(i + 1, f.t.length - 1);
    const span = f.t[j] - f.t[i];
    const a = span > 0 ? Math.min(1, Math.max(0, (t - f.t[i]) / span)) : 0;
    const p = f.pos[i], q = f.pos[j];
    obj.group.position.set(p[0] + a * (q[0] - p[0]), p[1] + a * (q[1] - p[1]),
      p[2] + a * (q[2] - p[2]));
    const u = f.quat[i], w = f.quat[j];
    qa.set(u[1], u[2], u[3], u[0]).normalize(); qb.set(w[1], w[2], w[3], w[0]).normalize();
    obj.group.quaternion.slerpQuaternions(qa, qb, a);
    f.belt_names.forEach((name, k) => {
      const belt = belts[name];
      if (!belt) return;
      const travel = f.travel[i][k] + a * (f.travel[j][k] - f.travel[i][k]);
      if (belt.texture) belt.texture.offset.x = -travel / STRIPE_M;
      for (const pv of belt.pivots) pv.rotation.y = travel / doc.scene.pulley_radius_m;
    });
    const bits = f.barriers[i];
    const chips = [];
    f.barrier_names.forEach((name, k) => {
      const cut = Boolean(bits & (1 << k));
      state.barriers[name] = cut;
      if (beams[name]) beams[name].color.set(cut ? 0xff3b30 : 0x5fd27a);
      chips.push(`<span class="chip ${cut ? 'cut' : 'free'}">${name.replace('_', ' ')}</span>`);
    });
    $('barriers').innerHTML = chips.join('');
    $('belts').textContent = f.belt_names.map((n, k) => `${n.replace('_', ' ')} ` +
      `${fmt(f.belts[i][k], 2)}`).join(', ') + ' m/s';
    const code = String(f.ots[i]);
    state.ots = code;
    $('ots').textContent = OTS_NAMES[code] || code;
    $('ots').style.color = OTS_COLOURS[code] || '';
    const speed = f.belts[i].reduce((x, v) => x + v, 0);
    const way = Math.abs(speed) < 1e-9 ? 0 : speed > 0 ? 1 : -1;
    state.lastWay = lastWay[i];
    state.travel = way;
    marks.arrow.visible = way !== 0;
    if (way) {
      marks.arrow.setDirection(new THREE.Vector3(way, 0, 0));
      marks.arrow.position.set(-0.15 * way, marks.y, marks.z);
    }
    setSpriteText(marks.travel, way ? `travel ${WAY[way]}` : 'belts stopped', 0.035);
    const doing = { '-2': state.lastWay ? 'belts stopped' : 'object placed, settling',
      '2': `start state: the transfer ${WAY[state.lastWay] || ''} begins`,
      '-1': `crossing ${WAY[state.lastWay] || ''}`,
      '1': state.lastWay === -1 ? 'brought back to the TM' : 'delivered to the TU',
      '0': `failed ${WAY[state.lastWay] || ''}`, '3': 'not a start state: no transfer' };
    const over = t >= ended - 1e-9 && doc.outcome;
    state.caption = over ? doc.outcome : (doing[code] || '');
    $('outcome').textContent = state.caption;
    $('outcome').className = over ? (doc.result.success ? 'success' : 'failure') : '';
    obj.group.updateMatrixWorld(true);
    box.setFromObject(obj.visual).getCenter(centre);
    const local = centre.clone().applyMatrix4(tuInv);
    state.objectCentre = [centre.x, centre.y, centre.z];
    state.inGap = centre.x > gap.tmTip && local.x < gap.tuNear && Math.abs(centre.y) < gap.halfSpan;
    $('object').textContent = `centre (${fmt(centre.x * 1000, 1)}, ${fmt(centre.y * 1000, 1)}, ` +
      `${fmt(centre.z * 1000, 1)}) mm${state.inGap ? ' — in the gap' : ''}`;
    state.t = t;
    state.frame = i;
    scrub.value = String(t);
    $('time').textContent = `${fmt(t)} s of ${fmt(state.duration)} s`;
    $('clock').textContent = `${fmt(t)} / ${fmt(state.duration)} s`;
  }

  function seek(t) { apply(Math.min(state.duration, Math.max(0, t))); }
  function play() {
    if (state.t >= state.duration) seek(0);
    state.playing = true;
    $('play').textContent = '❚❚ pause';
  }
  function pause() { state.playing = false; $('play').textContent = '▶ play'; }
  state.seek = seek; state.play = play; state.pause = pause;
  state.screenOf = (p) => {  // a world point's position on the canvas, CSS pixels
    const v = new THREE.Vector3(p[0], p[1], p[2]).project(camera);
    return [(v.x + 1) / 2 * canvas.clientWidth, (1 - v.y) / 2 * canvas.clientHeight];
  };
  state.setSpeed = (s) => { state.speed = s; $('speed').value = String(s); };
  state.tmEnd = marks.tmEnd;  // the far end of the TM's belts (the panel must not hide it)
  state.labelAt = (which) => {  // a label's position on the canvas, CSS pixels
    const p = (which === 'TU' ? marks.tuLabel : marks.tmLabel).position;
    return state.screenOf([p.x, p.y, p.z]);
  };

  $('play').disabled = false;
  $('play').addEventListener('click', () => (state.playing ? pause() : play()));
  $('speed').addEventListener('change', (e) => { state.speed = Number(e.target.value); });
  scrub.addEventListener('input', () => { pause(); seek(Number(scrub.value)); });
  $('hulls').addEventListener('change', (e) => {
    obj.hulls.visible = e.target.checked;
    obj.visual.material.opacity = e.target.checked ? 0.25 : 1;
  });
  $('ghost').addEventListener('change', (e) => { ghost.visible = e.target.checked; });
  window.addEventListener('keydown', (e) => {
    if (e.code === 'Space' && e.target.tagName !== 'SELECT') {
      e.preventDefault(); (state.playing ? pause() : play());
    }
  });

  function resize() {
    const w = canvas.clientWidth, h = canvas.clientHeight;
    if (canvas.width !== Math.floor(w * renderer.getPixelRatio()) ||
        canvas.height !== Math.floor(h * renderer.getPixelRatio())) {
      renderer.setSize(w, h, false);
      camera.aspect = w / Math.max(1, h);
      camera.updateProjectionMatrix();
      frameUnits();
      drawStrip(doc);
    }
  }
  seek(0);
  state.timing.builtMs = performance.now();
  let last = performance.now();
  function frame(now) {
    const dt = Math.min(0.1, (now - last) / 1000);
    last = now;
    if (state.playing) {
      const t = state.t + dt * state.speed;
      if (t >= state.duration) { seek(state.duration); pause(); } else seek(t);
    }
    resize();
    controls.update();
    renderer.render(scene, camera);
    state.renders += 1;
    if (!state.ready) {
      state.ready = true;
      state.loadMs = performance.now();
      state.timing.firstFrameMs = state.loadMs;
      document.body.dataset.ready = '1';
    }
    requestAnimationFrame(frame);
  }
  requestAnimationFrame(frame);
}

main().catch((err) => {
  state.error = String(err && err.message ? err.message : err);
  $('error').hidden = false;
  $('error').textContent = state.error;
  $('title').textContent = 'replay unavailable';
});
