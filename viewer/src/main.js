// semap viewer: labelled mesh with per-class toggles, object boxes with labels (click -> class
// distribution and point count), the camera trajectory, and the occupancy grid and scene graph
// (navigation.js) when the folder has them. Loads its data relative to the page
// as listed by viewer.json (written by `semap view`), so optional files that are absent are
// never fetched (no 404s in the console). With a "live" entry (`semap run --view`) it polls the
// run's live.json and reloads the map whenever a new snapshot is out.
import * as THREE from 'three';
import { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';
import { CSS2DRenderer, CSS2DObject } from 'three/examples/jsm/renderers/CSS2DRenderer.js';
import { parsePly } from './ply.js';
import { declutterLabels, labelPriority } from './labels.js';
import { parseMapYaml, parsePgm, buildGridLayer, buildGraphLayers, GRID_COLOURS, EDGE_COLOURS } from './navigation.js';

const CLEAR_COLOUR = 0x1e2228;  // the screenshot test counts pixels differing from this

const state = {
  classes: [],            // [{id, name, colour:[r,g,b]}] from classes.json
  meshGeometry: null,
  trianglesByClass: new Map(),  // class id -> Uint32Array of vertex indices
  visibleClasses: new Set(),
  objects: [],            // entries of objects.json with their three objects
  pickTargets: [],
  hoveredObject: null,    // the object under the pointer (its label shows above the others)
  labelStats: { shown: 0, hidden: 0, rects: [] },  // the last declutterLabels() result
  ready: false,
  errors: [],
  messages: [],
};

const dom = {
  status: document.getElementById('status'),
  classList: document.getElementById('class-list'),
  info: document.getElementById('object-info'),
  title: document.getElementById('title'),
};

// ------------------------------------------------------------------ three.js scene

const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(window.devicePixelRatio || 1);
renderer.setSize(window.innerWidth, window.innerHeight);
renderer.setClearColor(CLEAR_COLOUR, 1);
document.getElementById('viewport').appendChild(renderer.domElement);

const labelRenderer = new CSS2DRenderer();
labelRenderer.setSize(window.innerWidth, window.innerHeight);
labelRenderer.domElement.className = 'label-layer';
document.getElementById('viewport').appendChild(labelRenderer.domElement);

const scene = new THREE.Scene();
const camera = new THREE.PerspectiveCamera(50, window.innerWidth / window.innerHeight, 0.01, 1000);
const controls = new OrbitControls(camera, renderer.domElement);
controls.enableDamping = false;

const hemisphere = new THREE.HemisphereLight(0xffffff, 0x555555, 1.6);
scene.add(hemisphere);
const sun = new THREE.DirectionalLight(0xffffff, 1.2);
scene.add(sun);

const meshGroup = new THREE.Group();
const boxGroup = new THREE.Group();
const trajectoryGroup = new THREE.Group();
const gridGroup = new THREE.Group();   // occupancy grid (map.pgm)
const graphGroup = new THREE.Group();  // scene graph: on / in / in_place edges, places, walls
const nearGroup = new THREE.Group();   // scene graph: near and in_place edges (many; off by default)
nearGroup.visible = false;
scene.add(meshGroup, boxGroup, trajectoryGroup, gridGroup, graphGroup, nearGroup);
const layers = { boxes: boxGroup, trajectory: trajectoryGroup, grid: gridGroup, graph: graphGroup, near: nearGroup };

let needsRender = true;
controls.addEventListener('change', () => { needsRender = true; });
window.addEventListener('resize', () => {
  camera.aspect = window.innerWidth / window.innerHeight;
  camera.updateProjectionMatrix();
  renderer.setSize(window.innerWidth, window.innerHeight);
  labelRenderer.setSize(window.innerWidth, window.innerHeight);
  needsRender = true;
});

// One frame: the scene, then the labels, then their decluttering (labels.js).
function renderFrame() {
  renderer.render(scene, camera);
  labelRenderer.render(scene, camera);
  state.labelStats = declutterLabels(state.objects.map((entry, order) => ({
    element: entry.element, priority: entry.priority, order, hovered: entry.object === state.hoveredObject,
  })));
}

function animate() {
  requestAnimationFrame(animate);
  if (!needsRender) return;
  needsRender = false;
  renderFrame();
}

// ------------------------------------------------------------------ helpers

function showMessage(text, kind = 'info') {
  const line = document.createElement('div');
  line.className = `msg msg-${kind}`;
  line.textContent = text;
  dom.status.appendChild(line);
  state.messages.push(text);
}

function classInfo(id) {
  return state.classes[id] || { id, name: `class ${id}`, colour: [127, 127, 127] };
}

function cssColour([r, g, b]) {
  return `rgb(${r}, ${g}, ${b})`;
}

async function fetchChecked(url, kind) {
  const response = await fetch(url);
  if (!response.ok) throw new Error(`${url}: HTTP ${response.status}`);
  return kind === 'json' ? response.json() : kind === 'text' ? response.text() : response.arrayBuffer();
}

// ------------------------------------------------------------------ mesh

function buildMesh(ply) {
  const props = ply.properties;
  if (!props.x || !props.y || !props.z) throw new Error('mesh.ply has no x/y/z vertex properties');
  const n = ply.vertexCount;
  const positions = new Float32Array(n * 3);
  for (let i = 0; i < n; ++i) {
    positions[3 * i] = props.x[i];
    positions[3 * i + 1] = props.y[i];
    positions[3 * i + 2] = props.z[i];
  }
  const labels = props.label || new Uint8Array(n);
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.BufferAttribute(positions, 3));

  // Two colourings: by class (palette) and the fused RGB (when present).
  // Vertex colours are in three's linear working space: convert the 8-bit sRGB values.
  const toLinear = new Float32Array(256);
  for (let v = 0; v < 256; ++v) {
    const c = v / 255;
    toLinear[v] = c < 0.04045 ? c * 0.0773993808 : Math.pow(c * 0.9478672986 + 0.0521327014, 2.4);
  }
  // Unlabelled vertices (palette black) show their RGB as dark-to-mid grey levels (shaded, never
  // black, and darker than the pastel wall and ceiling colours so that labelled and unlabelled
  // surfaces are told apart), else mid grey. An all-black RGB channel carries no colour (e.g. colour integration
  // off): ignore it. In RGB mode, a vertex whose voxel never saw colour is mid grey too.
  const hasRgb = Boolean(props.red && props.green && props.blue) &&
    (props.red.some((v) => v > 0) || props.green.some((v) => v > 0) || props.blue.some((v) => v > 0));
  const luma = (i) => 0.3 * props.red[i] + 0.59 * props.green[i] + 0.11 * props.blue[i];
  const classColours = new Float32Array(n * 3);
  for (let i = 0; i < n; ++i) {
    let c = classInfo(labels[i]).colour;
    if (labels[i] === 0) {
      const grey = hasRgb ? Math.round(55 + 0.3 * luma(i)) : 100;
      c = [grey, grey, grey];
    }
    classColours[3 * i] = toLinear[c[0]];
    classColours[3 * i + 1] = toLinear[c[1]];
    classColours[3 * i + 2] = toLinear[c[2]];
  }
  let rgbColours = null;
  if (hasRgb) {
    rgbColours = new Float32Array(n * 3);
    for (let i = 0; i < n; ++i) {
      const unseen = props.red[i] === 0 && props.green[i] === 0 && props.blue[i] === 0;
      rgbColours[3 * i] = toLinear[unseen ? 150 : props.red[i]];
      rgbColours[3 * i + 1] = toLinear[unseen ? 150 : props.green[i]];
      rgbColours[3 * i + 2] = toLinear[unseen ? 150 : props.blue[i]];
    }
  }
  const classAttribute = new THREE.BufferAttribute(classColours, 3);
  const rgbAttribute = rgbColours ? new THREE.BufferAttribute(rgbColours, 3) : null;
  geometry.setAttribute('color', classAttribute);

  const counts = new Map();
  let object3d;
  if (ply.indices && ply.indices.length >= 3) {
    // A triangle belongs to the class of the majority of its corners (first corner on ties).
    const buckets = new Map();
    const tri = ply.indices;
    for (let t = 0; t + 2 < tri.length; t += 3) {
      const a = labels[tri[t]], b = labels[tri[t + 1]], c = labels[tri[t + 2]];
      const cls = (b === c && b !== a) ? b : a;
      let bucket = buckets.get(cls);
      if (!bucket) { bucket = []; buckets.set(cls, bucket); }
      bucket.push(tri[t], tri[t + 1], tri[t + 2]);
    }
    for (const [cls, list] of buckets) {
      state.trianglesByClass.set(cls, Uint32Array.from(list));
      counts.set(cls, list.length / 3);
    }
    geometry.setIndex(new THREE.BufferAttribute(ply.indices, 1));
    geometry.computeVertexNormals();
    const material = new THREE.MeshLambertMaterial({ vertexColors: true, side: THREE.DoubleSide });
    object3d = new THREE.Mesh(geometry, material);
  } else {
    // A point cloud: toggles filter points by class instead of triangles.
    const buckets = new Map();
    for (let i = 0; i < n; ++i) {
      let bucket = buckets.get(labels[i]);
      if (!bucket) { bucket = []; buckets.set(labels[i], bucket); }
      bucket.push(i);
    }
    for (const [cls, list] of buckets) {
      state.trianglesByClass.set(cls, Uint32Array.from(list));
      counts.set(cls, list.length);
    }
    const material = new THREE.PointsMaterial({ vertexColors: true, size: 2, sizeAttenuation: false });
    object3d = new THREE.Points(geometry, material);
  }
  geometry.computeBoundingBox();
  geometry.computeBoundingSphere();
  meshGroup.add(object3d);
  state.meshGeometry = geometry;
  state.meshObject = object3d;
  state.classAttribute = classAttribute;
  state.rgbAttribute = rgbAttribute;
  state.isPointCloud = !(ply.indices && ply.indices.length >= 3);
  // The ceiling hides the room when seen from above: off by default (toggle to show it).
  const ceilingId = state.classes.findIndex((c) => c && c.name === 'ceiling');
  for (const cls of counts.keys()) if (cls !== ceilingId || counts.size === 1) state.visibleClasses.add(cls);
  return counts;
}

// Rebuilds the index buffer from the visible classes' triangles (or points).
function updateVisibleClasses() {
  const parts = [];
  let total = 0;
  for (const cls of state.visibleClasses) {
    const list = state.trianglesByClass.get(cls);
    if (list) { parts.push(list); total += list.length; }
  }
  const index = new Uint32Array(total);
  let at = 0;
  for (const list of parts) { index.set(list, at); at += list.length; }
  state.meshGeometry.setIndex(new THREE.BufferAttribute(index, 1));
  needsRender = true;
}

function setColourMode(mode) {
  if (!state.meshGeometry) return;
  const attribute = mode === 'rgb' && state.rgbAttribute ? state.rgbAttribute : state.classAttribute;
  state.meshGeometry.setAttribute('color', attribute);
  needsRender = true;
}

function buildClassToggles(counts) {
  const entries = [...counts.entries()].sort((a, b) => b[1] - a[1]);
  dom.classList.innerHTML = '';
  for (const [cls, count] of entries) {
    const info = classInfo(cls);
    const row = document.createElement('label');
    row.className = 'class-row';
    const box = document.createElement('input');
    box.type = 'checkbox';
    box.checked = state.visibleClasses.has(cls);
    box.dataset.classId = String(cls);
    box.addEventListener('change', () => {
      if (box.checked) state.visibleClasses.add(cls); else state.visibleClasses.delete(cls);
      updateVisibleClasses();
    });
    const swatch = document.createElement('span');
    swatch.className = 'swatch';
    swatch.style.background = cssColour(cls === 0 ? [95, 95, 95] : info.colour);  // unlabelled: shaded grey, as drawn
    const name = document.createElement('span');
    name.className = 'class-name';
    name.textContent = info.name;
    const number = document.createElement('span');
    number.className = 'class-count';
    number.textContent = count.toLocaleString();
    row.append(box, swatch, name, number);
    dom.classList.appendChild(row);
  }
}

function setAllClasses(visible) {
  for (const box of dom.classList.querySelectorAll('input[type=checkbox]')) {
    box.checked = visible;
    const cls = Number(box.dataset.classId);
    if (visible) state.visibleClasses.add(cls); else state.visibleClasses.delete(cls);
  }
  updateVisibleClasses();
}

// ------------------------------------------------------------------ objects

const BOX_EDGES = [[0, 1], [1, 3], [3, 2], [2, 0], [4, 5], [5, 7], [7, 6], [6, 4], [0, 4], [1, 5], [2, 6], [3, 7]];

// World matrix of an oriented box: rotation (row-major world_from_box) and centre; the unit
// cube scaled by the full extent.
function boxMatrix(obb) {
  const r = obb.rotation || [1, 0, 0, 0, 1, 0, 0, 0, 1];
  const c = obb.center;
  const m = new THREE.Matrix4().set(
    r[0], r[1], r[2], c[0],
    r[3], r[4], r[5], c[1],
    r[6], r[7], r[8], c[2],
    0, 0, 0, 1);
  return m.multiply(new THREE.Matrix4().makeScale(
    Math.max(obb.extent[0], 1e-4), Math.max(obb.extent[1], 1e-4), Math.max(obb.extent[2], 1e-4)));
}

function objectBox(object) {
  if (object.obb && object.obb.center && object.obb.extent) return object.obb;
  if (object.aabb && object.aabb.min && object.aabb.max) {
    const { min, max } = object.aabb;
    return { center: min.map((v, i) => (v + max[i]) / 2), extent: min.map((v, i) => max[i] - v) };
  }
  return null;
}

function buildObjects(json) {
  const list = Array.isArray(json) ? json : json.objects;
  if (!Array.isArray(list)) throw new Error('objects.json has no "objects" array');
  let skipped = 0;
  for (const object of list) {
    const obb = objectBox(object);
    if (!obb) { ++skipped; continue; }
    const classId = Number.isInteger(object.class_id) ? object.class_id : -1;
    const colour = classId >= 0 ? classInfo(classId).colour : [230, 230, 230];
    const matrix = boxMatrix(obb);

    const corners = [];
    for (let k = 0; k < 8; ++k) {
      corners.push(new THREE.Vector3((k & 1) ? 0.5 : -0.5, (k & 2) ? 0.5 : -0.5, (k & 4) ? 0.5 : -0.5).applyMatrix4(matrix));
    }
    const points = [];
    for (const [a, b] of BOX_EDGES) points.push(corners[a], corners[b]);
    const lines = new THREE.LineSegments(
      new THREE.BufferGeometry().setFromPoints(points),
      new THREE.LineBasicMaterial({ color: new THREE.Color(cssColour(colour)) }));
    boxGroup.add(lines);

    // Invisible solid box for picking.
    const picker = new THREE.Mesh(new THREE.BoxGeometry(1, 1, 1), new THREE.MeshBasicMaterial({ visible: false }));
    picker.matrixAutoUpdate = false;
    picker.matrix.copy(matrix);
    picker.userData.object = object;
    boxGroup.add(picker);
    state.pickTargets.push(picker);

    const name = object.class || (classId >= 0 ? classInfo(classId).name : 'object');
    const tag = document.createElement('div');
    tag.className = 'object-label';
    tag.textContent = `${name} #${object.id}`;
    tag.style.borderColor = cssColour(colour);
    tag.addEventListener('pointerdown', (event) => { event.stopPropagation(); showObject(object); });
    const label = new CSS2DObject(tag);
    const top = new THREE.Vector3(0, 0, 0).applyMatrix4(matrix);
    label.position.copy(top);
    boxGroup.add(label);
    state.objects.push({ object, centre: top, element: tag, priority: labelPriority(object, obb.extent) });
  }
  if (skipped > 0) showMessage(`${skipped} object(s) without a box were skipped`, 'warn');
  return state.objects.length;
}

function showObject(object) {
  const name = object.class || classInfo(object.class_id).name;
  const rows = [];
  rows.push(`<h3>${escapeHtml(name)} #${escapeHtml(String(object.id))}</h3>`);
  rows.push('<table>');
  const field = (key, value) => { if (value !== undefined && value !== null) rows.push(`<tr><th>${key}</th><td>${escapeHtml(String(value))}</td></tr>`); };
  field('point count', object.point_count);
  field('observations', object.n);
  field('associations', object.association_count);
  field('state', object.state);
  if (object.first_seen !== undefined) field('frames', `${object.first_seen} – ${object.last_seen}`);
  const obb = objectBox(object);
  if (obb) field('size (m)', obb.extent.map((v) => v.toFixed(2)).join(' × '));
  rows.push('</table>');
  const dist = object.class_distribution || {};
  const entries = Object.entries(dist).sort((a, b) => b[1] - a[1]);
  if (entries.length > 0) {
    rows.push('<h4>class distribution</h4><div class="dist">');
    for (const [cls, p] of entries) {
      const id = state.classes.findIndex((c) => c && c.name === cls);
      const colour = id >= 0 ? cssColour(state.classes[id].colour) : '#888';
      const pct = (100 * p).toFixed(1);
      rows.push(`<div class="dist-row"><span class="dist-name">${escapeHtml(cls)}</span>` +
        `<span class="dist-bar"><span style="width:${Math.min(100, Math.max(0, 100 * p))}%;background:${colour}"></span></span>` +
        `<span class="dist-value">${pct}%</span></div>`);
    }
    rows.push('</div>');
  }
  dom.info.innerHTML = rows.join('');
  dom.info.hidden = false;
  state.selected = object;
}

function escapeHtml(text) {
  return text.replace(/[&<>"']/g, (c) => ({ '&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;', "'": '&#39;' }[c]));
}

// Click (without dragging) on a box opens its panel.
const raycaster = new THREE.Raycaster();
let pointerDownAt = null;
renderer.domElement.addEventListener('pointerdown', (e) => { pointerDownAt = [e.clientX, e.clientY]; });
renderer.domElement.addEventListener('pointerup', (e) => {
  if (!pointerDownAt || Math.hypot(e.clientX - pointerDownAt[0], e.clientY - pointerDownAt[1]) > 4) return;
  const rect = renderer.domElement.getBoundingClientRect();
  const ndc = new THREE.Vector2(((e.clientX - rect.left) / rect.width) * 2 - 1, -((e.clientY - rect.top) / rect.height) * 2 + 1);
  raycaster.setFromCamera(ndc, camera);
  const hits = raycaster.intersectObjects(state.pickTargets.filter(() => boxGroup.visible), false);
  if (hits.length > 0) showObject(hits[0].object.userData.object);
  else dom.info.hidden = true;
});
// Hovering a box brings its label to the front, hidden or not (labels.js).
renderer.domElement.addEventListener('pointermove', (e) => {
  if (e.buttons !== 0 || state.pickTargets.length === 0) return;
  const rect = renderer.domElement.getBoundingClientRect();
  const ndc = new THREE.Vector2(((e.clientX - rect.left) / rect.width) * 2 - 1, -((e.clientY - rect.top) / rect.height) * 2 + 1);
  raycaster.setFromCamera(ndc, camera);
  const hits = boxGroup.visible ? raycaster.intersectObjects(state.pickTargets, false) : [];
  // Boxes nest (a cup's inside the table's): the smallest box under the pointer is the one meant.
  const volume = (hit) => { const m = hit.object.matrix.elements; return Math.hypot(m[0], m[1], m[2]) * Math.hypot(m[4], m[5], m[6]) * Math.hypot(m[8], m[9], m[10]); };
  const smallest = hits.reduce((best, hit) => (best === null || volume(hit) < volume(best) ? hit : best), null);
  const hovered = smallest ? smallest.object.userData.object : null;
  if (hovered !== state.hoveredObject) {
    state.hoveredObject = hovered;
    needsRender = true;
  }
});

// ------------------------------------------------------------------ trajectory

function parseTum(text) {
  const poses = [];
  let bad = 0;
  for (const raw of text.split('\n')) {
    const line = raw.trim();
    if (line === '' || line.startsWith('#')) continue;
    const v = line.split(/[\s,]+/).map(Number);
    if (v.length < 8 || v.slice(0, 8).some((x) => !Number.isFinite(x))) { ++bad; continue; }
    poses.push({ t: v[0], p: new THREE.Vector3(v[1], v[2], v[3]), q: new THREE.Quaternion(v[4], v[5], v[6], v[7]).normalize() });
  }
  return { poses, bad };
}

function buildTrajectory(poses) {
  const line = new THREE.Line(
    new THREE.BufferGeometry().setFromPoints(poses.map((pose) => pose.p)),
    new THREE.LineBasicMaterial({ color: 0xffd23f }));
  trajectoryGroup.add(line);
  const start = new THREE.Mesh(new THREE.SphereGeometry(1, 12, 8), new THREE.MeshBasicMaterial({ color: 0x3fff6a }));
  const end = new THREE.Mesh(new THREE.SphereGeometry(1, 12, 8), new THREE.MeshBasicMaterial({ color: 0xff3f3f }));
  start.position.copy(poses[0].p);
  end.position.copy(poses[poses.length - 1].p);
  trajectoryGroup.add(start, end);
  state.trajectoryMarkers = [start, end];
}

// ------------------------------------------------------------------ camera fit

// Up direction (gravity), whatever the world convention (TUM, 7-Scenes: the first camera or the
// motion-capture frame; ScanNet: z up): a hand-held or robot camera is held upright on average,
// so the mean of the cameras' "up" (-y in the optical frame) over the trajectory points against
// gravity. The floor plane refines it: the area-weighted mean normal of the floor triangles
// (class floor) or else of the horizontal triangles (within 25 deg of the trajectory's up:
// floor, table tops), each turned to agree with the trajectory. Without a trajectory: the floor
// triangles oriented toward the mesh centre, else +z.
function trajectoryUp(poses) {
  const sum = new THREE.Vector3();
  for (const pose of poses) sum.add(new THREE.Vector3(0, -1, 0).applyQuaternion(pose.q));
  return sum.lengthSq() > 1e-12 ? sum.normalize() : null;
}

function meanNormal(triangles, reference, minCos) {
  const pos = state.meshGeometry.getAttribute('position');
  const a = new THREE.Vector3(), b = new THREE.Vector3(), c = new THREE.Vector3();
  const normal = new THREE.Vector3(), sum = new THREE.Vector3();
  const centre = state.meshGeometry.boundingBox.getCenter(new THREE.Vector3());
  for (let t = 0; t + 2 < triangles.length; t += 3) {
    a.fromBufferAttribute(pos, triangles[t]);
    b.fromBufferAttribute(pos, triangles[t + 1]);
    c.fromBufferAttribute(pos, triangles[t + 2]);
    normal.subVectors(c, b).cross(new THREE.Vector3().subVectors(a, b));  // length = 2 * area
    const length = normal.length();
    if (length <= 0) continue;
    if (reference) {
      const cos = normal.dot(reference) / length;
      if (Math.abs(cos) < minCos) continue;
      if (cos < 0) normal.negate();
    } else if (normal.dot(new THREE.Vector3().subVectors(centre, a)) < 0) {
      normal.negate();  // winding may vary: orient toward the mesh centre
    }
    sum.add(normal);
  }
  return sum.lengthSq() > 0 ? sum.normalize() : null;
}

function estimateUp(floorId, poses) {
  const fromTrajectory = poses && poses.length > 0 ? trajectoryUp(poses) : null;
  const geometry = state.meshGeometry;
  if (geometry && !state.isPointCloud && geometry.index) {
    const floor = floorId >= 0 ? state.trianglesByClass.get(floorId) : null;
    if (floor && floor.length >= 3) {
      const up = meanNormal(floor, fromTrajectory, 0);
      if (up) return up;
    }
    if (fromTrajectory) {
      const all = [...state.trianglesByClass.values()];  // every class, the ceiling too
      const merged = new Uint32Array(all.reduce((n, l) => n + l.length, 0));
      let at = 0;
      for (const list of all) { merged.set(list, at); at += list.length; }
      const up = meanNormal(merged, fromTrajectory, Math.cos(THREE.MathUtils.degToRad(25)));
      if (up) return up;
    }
  }
  return fromTrajectory || new THREE.Vector3(0, 0, 1);
}

// Looks straight down at the map (the grid as a plan), keeping the current target and distance.
function viewFromAbove() {
  state.viewBeforeTop = { position: camera.position.clone(), target: controls.target.clone() };
  const up = camera.up.clone().normalize();
  const distance = camera.position.distanceTo(controls.target);
  // A hair off vertical so that OrbitControls keeps a defined azimuth.
  const side = new THREE.Vector3(1, 0, 0).sub(up.clone().multiplyScalar(up.x)).normalize();
  camera.position.copy(controls.target).addScaledVector(up, distance).addScaledVector(side, distance * 1e-3);
  controls.update();
  needsRender = true;
}

// Back to the view before viewFromAbove (tests).
function restoreView() {
  if (!state.viewBeforeTop) return;
  camera.position.copy(state.viewBeforeTop.position);
  controls.target.copy(state.viewBeforeTop.target);
  controls.update();
  needsRender = true;
}

function fitCamera(box, up) {
  const centre = box.getCenter(new THREE.Vector3());
  const size = box.getSize(new THREE.Vector3());
  const radius = Math.max(size.length() / 2, 1e-3);
  camera.up.copy(up);
  // Look from above and to the side, at a distance that fits the bounding sphere.
  const side = new THREE.Vector3(1, 0, 0);
  if (Math.abs(side.dot(up)) > 0.9) side.set(0, 1, 0);
  side.sub(up.clone().multiplyScalar(side.dot(up))).normalize();
  const forward = new THREE.Vector3().crossVectors(up, side).normalize();
  const direction = new THREE.Vector3().addScaledVector(up, 0.9).addScaledVector(side, 0.55).addScaledVector(forward, 0.75).normalize();
  const fov = THREE.MathUtils.degToRad(camera.fov);
  const distance = radius / Math.sin(Math.min(fov, fov * camera.aspect) / 2) * 1.05;
  camera.position.copy(centre).addScaledVector(direction, distance);
  camera.near = distance / 200;
  camera.far = distance * 10 + radius * 4;
  camera.updateProjectionMatrix();
  controls.target.copy(centre);
  controls.update();
  sun.position.copy(centre).addScaledVector(up, radius * 3).addScaledVector(side, radius);
  sun.target.position.copy(centre);
  sun.target.updateMatrixWorld();
  hemisphere.position.copy(up);
  if (state.trajectoryMarkers) for (const m of state.trajectoryMarkers) m.scale.setScalar(radius * 0.012);
  needsRender = true;
}

// ------------------------------------------------------------------ loading

// Loads the mesh, objects and trajectory listed in `files` into the (empty) scene groups.
// `quiet`: no status lines (live refreshes). Returns the bounds of what was loaded and the poses.
async function loadMap(files, quiet = false) {
  const say = quiet ? () => {} : showMessage;
  const bounds = new THREE.Box3();
  if (files.mesh) {
    try {
      const ply = parsePly(await fetchChecked(files.mesh, 'binary'));
      if (ply.vertexCount > 0) {
        const counts = buildMesh(ply);
        buildClassToggles(counts);
        updateVisibleClasses();
        // The surface colour by default (class colours one toggle away); the palette when the
        // mesh carries no colour. Chosen once: a live refresh keeps the user's choice.
        const select = document.getElementById('colour-mode');
        if (!state.colourModeChosen) {
          select.value = state.rgbAttribute ? 'rgb' : 'class';
          state.colourModeChosen = true;
        }
        setColourMode(select.value);
        bounds.union(state.meshGeometry.boundingBox);
      }
      const triangles = ply.indices ? ply.indices.length / 3 : 0;
      say(`mesh: ${ply.vertexCount.toLocaleString()} vertices, ${triangles.toLocaleString()} triangles`);
    } catch (error) {
      showMessage(`mesh.ply could not be shown: ${error.message}`, 'error');
    }
  } else {
    say('No mesh.ply in this folder.', 'warn');
  }

  if (files.objects) {
    try {
      const count = buildObjects(await fetchChecked(files.objects, 'json'));
      say(`objects: ${count}`);
    } catch (error) {
      showMessage(`objects.json could not be shown: ${error.message}`, 'error');
    }
  } else {
    say('No objects.json: no object boxes.', 'warn');
  }

  let poses = [];
  if (files.trajectory) {
    try {
      const parsed = parseTum(await fetchChecked(files.trajectory, 'text'));
      poses = parsed.poses;
      if (poses.length >= 1) buildTrajectory(poses);
      say(`trajectory: ${poses.length} poses${parsed.bad ? ` (${parsed.bad} bad lines skipped)` : ''}`);
      if (bounds.isEmpty()) for (const pose of poses) bounds.expandByPoint(pose.p);
    } catch (error) {
      showMessage(`trajectory.txt could not be shown: ${error.message}`, 'error');
    }
  } else {
    say('No trajectory.txt: no camera path.', 'warn');
  }
  await loadNavigation(files, say);
  if (bounds.isEmpty()) for (const entry of state.objects) bounds.expandByPoint(entry.centre);
  return { bounds, poses };
}

// The occupancy grid and the scene graph (issue 39), when the folder has them: each a layer
// with its toggle and legend row; absent files hide their rows.
async function loadNavigation(files, say) {
  state.layerCounts = {};
  if (files.grid && files.grid_yaml) {
    try {
      const yaml = parseMapYaml(await fetchChecked(files.grid_yaml, 'text'));
      const layer = buildGridLayer(yaml, parsePgm(await fetchChecked(files.grid, 'binary')));
      gridGroup.add(layer.object);
      state.layerCounts.grid = { free: layer.free, occupied: layer.occupied };
      say(`occupancy grid: ${layer.free.toLocaleString()} free, ${layer.occupied.toLocaleString()} occupied cells`);
    } catch (error) {
      showMessage(`map.pgm could not be shown: ${error.message}`, 'error');
    }
  }
  if (files.scene_graph) {
    try {
      const { graph, near, counts } = buildGraphLayers(await fetchChecked(files.scene_graph, 'json'));
      graphGroup.add(graph);
      nearGroup.add(near);
      state.layerCounts.graph = counts;
      say(`scene graph: ${counts.on} on, ${counts.in} in, ${counts.near} near, ${counts.places} place(s), ${counts.connected} passage(s), ${counts.walls} wall(s)`);
    } catch (error) {
      showMessage(`scene_graph.json could not be shown: ${error.message}`, 'error');
    }
  }
  for (const [id, present] of [['row-grid', Boolean(state.layerCounts.grid)], ['row-graph', Boolean(state.layerCounts.graph)],
    ['row-near', Boolean(state.layerCounts.graph)], ['row-top-view', Boolean(state.layerCounts.grid)],
    ['legend-navigation', Boolean(state.layerCounts.grid || state.layerCounts.graph)]]) {
    document.getElementById(id).hidden = !present;
  }
}

function buildNavigationLegend() {
  const swatch = (rgb, text) => `<span class="legend-item"><span class="swatch" style="background: rgb(${rgb.join(',')})"></span>${text}</span>`;
  document.getElementById('legend-navigation').innerHTML =
    swatch(GRID_COLOURS.free, 'free') + swatch(GRID_COLOURS.occupied, 'occupied') + '<br>' +
    swatch(EDGE_COLOURS.on, 'on') + swatch(EDGE_COLOURS.in, 'in') + swatch(EDGE_COLOURS.in_place, 'in place') +
    swatch(EDGE_COLOURS.connected, 'connected') +
    swatch(EDGE_COLOURS.near, 'near') + swatch(EDGE_COLOURS.wall, 'wall');
}
buildNavigationLegend();

// Empties the scene groups and what refers to them (before a live refresh loads the map again).
function clearMap() {
  for (const group of [meshGroup, boxGroup, trajectoryGroup, gridGroup, graphGroup, nearGroup]) {
    group.traverse((node) => {
      if (node.geometry) node.geometry.dispose();
      if (node.material) node.material.dispose();
      if (node.element && node.element.remove) node.element.remove();  // CSS2D labels
    });
    group.clear();
  }
  state.meshGeometry = null;
  state.trianglesByClass = new Map();
  state.objects = [];
  state.hoveredObject = null;
  state.pickTargets = [];
  state.trajectoryMarkers = null;
}

// `up`: [x, y, z] from semap (core/gravity: report.json for `semap view`, live.json for the live
// view), so both views open level the same way; the page's own estimate only without it.
function givenUp(up) {
  if (!Array.isArray(up) || up.length !== 3 || !up.every(Number.isFinite)) return null;
  const v = new THREE.Vector3(up[0], up[1], up[2]);
  return v.lengthSq() > 1e-12 ? v.normalize() : null;
}

function fitToMap(bounds, floorId, poses, up) {
  const box = bounds.isEmpty() ? new THREE.Box3(new THREE.Vector3(-1, -1, -1), new THREE.Vector3(1, 1, 1)) : bounds;
  fitCamera(box, givenUp(up) || estimateUp(floorId, poses));
}

async function main() {
  animate();
  let manifest;
  try {
    manifest = await fetchChecked('viewer.json', 'json');
  } catch (error) {
    showMessage(`Cannot read viewer.json (${error.message}); run \`semap view DIR\`.`, 'error');
    return finish();
  }
  const files = manifest.files || {};
  if (manifest.title) {
    dom.title.textContent = manifest.title;
    document.title = `semap · ${manifest.title}`;
  }

  try {
    state.classes = files.classes ? await fetchChecked(files.classes, 'json') : [];
  } catch (error) {
    showMessage(`Class names unavailable: ${error.message}`, 'warn');
  }
  const floorId = state.classes.findIndex((c) => c && c.name === 'floor');
  const { bounds, poses } = await loadMap(files, Boolean(manifest.live));
  fitToMap(bounds, floorId, poses, manifest.up);
  finish();
  if (manifest.live) startLive(manifest.live, files, floorId, bounds);
}

// ------------------------------------------------------------------ live mode (`semap run --view`)

// Polls the run's state; when a new snapshot is out, loads the map again. Until the user moves
// the view, every refresh fits the camera again, up direction included (the first frames'
// trajectory gives a poor up estimate: a rolling hand-held camera tilts it); afterwards the
// user's view is kept and the camera is fitted again only when the map outgrows it.
let stopLive = () => {};

function startLive(live, files, floorId, fittedBounds) {
  let userMovedView = false;
  controls.addEventListener('start', () => { userMovedView = true; });
  const line = document.createElement('div');
  line.className = 'msg';
  line.id = 'live-status';
  dom.status.prepend(line);
  let version = -1;
  let fitted = fittedBounds.isEmpty() ? null : fittedBounds.clone();
  let busy = false;
  const poll = async () => {
    if (busy) return;
    busy = true;
    try {
      const s = await fetchChecked(live.state, 'json');
      line.textContent = `live: ${s.frames} frames, ${Number(s.fps).toFixed(1)} fps, ${s.objects} objects` +
        (s.finished ? ' (finished: the run is writing its outputs)' : '');
      if (s.finished) stopLive();  // the last snapshot: the server closes with the run
      if (s.version !== version) {
        version = s.version;
        clearMap();
        const { bounds, poses } = await loadMap(files, true);
        const outgrown = fitted === null || !fitted.clone().expandByScalar(0.25 * fitted.getSize(new THREE.Vector3()).length()).containsBox(bounds);
        if (!bounds.isEmpty() && (outgrown || !userMovedView)) {
          fitToMap(bounds, floorId, poses, s.up);
          fitted = bounds.clone();
        }
        state.liveVersion = version;
        needsRender = true;
      }
    } catch (error) {
      line.textContent = `live: the run is over or unreachable (${error.message})`;
    } finally {
      busy = false;
    }
  };
  poll();
  const timer = setInterval(poll, Math.max(200, Number(live.interval_ms) || 1500));
  stopLive = () => clearInterval(timer);
}

function finish() {
  // Render synchronously once so that `ready` means "the first frame is on the canvas".
  renderFrame();
  state.ready = true;
  document.body.dataset.ready = 'true';
}

// Layer toggles: checkbox show-<name> for each of `layers`.
function setLayer(name, visible) {
  layers[name].visible = visible;
  document.getElementById(`show-${name}`).checked = visible;
  needsRender = true;
}
for (const name of Object.keys(layers)) {
  document.getElementById(`show-${name}`).addEventListener('change', (e) => setLayer(name, e.target.checked));
}
document.getElementById('colour-mode').addEventListener('change', (e) => setColourMode(e.target.value));
// "c" switches between the surface colour and the class colours.
window.addEventListener('keydown', (e) => {
  if (e.key !== 'c' || e.target instanceof HTMLInputElement || e.target instanceof HTMLSelectElement) return;
  const select = document.getElementById('colour-mode');
  select.value = select.value === 'rgb' ? 'class' : 'rgb';
  setColourMode(select.value);
});
document.getElementById('top-view').addEventListener('click', viewFromAbove);
document.getElementById('all-classes').addEventListener('click', () => setAllClasses(true));
document.getElementById('no-classes').addEventListener('click', () => setAllClasses(false));

// A small API for tests and the console.
window.semapViewer = {
  get ready() { return state.ready; },
  get messages() { return [...state.messages]; },
  objectCount: () => state.objects.length,
  vertexCount: () => (state.meshGeometry ? state.meshGeometry.getAttribute('position').count : 0),
  get liveVersion() { return state.liveVersion ?? null; },
  colourMode: () => document.getElementById('colour-mode').value,
  cameraUp: () => camera.up.toArray(),
  visibleTriangleCount: () => (state.meshGeometry && state.meshGeometry.index ? state.meshGeometry.index.count / 3 : 0),
  // Page coordinates of an object's box centre (for clicking it in tests).
  objectScreenPosition(index) {
    const entry = state.objects[index];
    if (!entry) return null;
    const p = entry.centre.clone().project(camera);
    const rect = renderer.domElement.getBoundingClientRect();
    return { x: rect.left + (p.x + 1) / 2 * rect.width, y: rect.top + (1 - p.y) / 2 * rect.height, id: entry.object.id };
  },
  setAllClasses,
  setLayer,
  viewFromAbove,
  restoreView,
  layerCounts: () => ({ ...state.layerCounts }),
  render: renderFrame,
  // Object labels after the last frame's decluttering: shown, hidden, and the shown labels'
  // page rectangles (none may overlap another).
  labelStats: () => ({ shown: state.labelStats.shown, hidden: state.labelStats.hidden, rects: state.labelStats.rects }),
};

main().catch((error) => {
  showMessage(`viewer failed: ${error.message}`, 'error');
  finish();
});
