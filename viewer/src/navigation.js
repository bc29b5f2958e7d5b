// The robot-facing maps of a semap output folder (issue 39) as three.js layers:
//   - the occupancy grid (map.pgm + map.yaml, ROS map_server format) as a translucent plane
//     just above the floor: free cells light blue, occupied cells red, unknown cells clear;
//   - the scene graph (scene_graph.json): its edges as lines between object box centres
//     (on orange, in magenta; near grey and in_place cyan, to the place's label on the floor,
//     in a second layer, off by default: every object has one, a fan of lines), the places as
//     labels, `connected` places (green) joined through their passage's centre with its width
//     written there, and the walls as outlined rectangles.
// Both live in the gravity frame G of the run (z up, z = 0 on the floor); T_W_G (in map.yaml
// and scene_graph.json) places them in the world frame of mesh.ply.
import * as THREE from 'three';
import { CSS2DObject } from 'three/examples/jsm/renderers/CSS2DRenderer.js';

export const GRID_COLOURS = { free: [120, 190, 255], occupied: [235, 70, 55] };
export const EDGE_COLOURS = { on: [255, 170, 30], in: [230, 80, 230], near: [150, 150, 150], in_place: [60, 220, 220], connected: [90, 230, 110], wall: [240, 240, 240] };
const GRID_LIFT_M = 0.02;  // above the floor surface, so that the floor mesh does not hide it

function matrixFromRows(rows) {
  const flat = rows.flat();
  if (flat.length !== 16 || !flat.every(Number.isFinite)) throw new Error('T_W_G must hold 16 numbers');
  return new THREE.Matrix4().set(...flat);
}

// The keys of map.yaml the viewer needs (semap writes flow-style one-line values).
export function parseMapYaml(text) {
  const value = (key) => {
    const m = text.match(new RegExp(`^${key}:\\s*(.+)$`, 'm'));
    return m ? m[1].trim() : null;
  };
  const list = (key) => {
    const v = value(key);
    if (!v || !v.startsWith('[')) return null;
    return v.replace(/[[\]]/g, '').split(',').map(Number);
  };
  const resolution = Number(value('resolution'));
  const origin = list('origin');
  const T = list('T_W_G');
  if (!(resolution > 0) || !origin || origin.length < 2 || !origin.every(Number.isFinite)) {
    throw new Error('map.yaml: no valid resolution / origin');
  }
  const rows = T && T.length === 16 ? [T.slice(0, 4), T.slice(4, 8), T.slice(8, 12), T.slice(12, 16)] : null;
  return { resolution, origin, T_W_G: rows ? matrixFromRows(rows) : new THREE.Matrix4() };
}

// Binary PGM (P5, maxval < 256): { width, height, pixels } with row 0 the image's top row.
export function parsePgm(buffer) {
  const bytes = new Uint8Array(buffer);
  let at = 0;
  const token = () => {
    for (;;) {  // whitespace and comments
      while (at < bytes.length && /\s/.test(String.fromCharCode(bytes[at]))) ++at;
      if (bytes[at] !== 0x23) break;
      while (at < bytes.length && bytes[at] !== 0x0a) ++at;
    }
    let s = '';
    while (at < bytes.length && !/\s/.test(String.fromCharCode(bytes[at]))) s += String.fromCharCode(bytes[at++]);
    return s;
  };
  if (token() !== 'P5') throw new Error('map.pgm: not a binary PGM (P5)');
  const width = Number(token()), height = Number(token()), maxval = Number(token());
  ++at;  // the single whitespace after maxval
  if (!(width > 0 && height > 0 && maxval > 0 && maxval < 256) || at + width * height > bytes.length) {
    throw new Error('map.pgm: bad header or truncated pixels');
  }
  return { width, height, pixels: bytes.subarray(at, at + width * height) };
}

// The grid as a textured plane in the world frame. Cells follow map_server's trinary reading:
// 0 occupied, 254 free, anything else (205) unknown.
export function buildGridLayer(yaml, pgm) {
  const { width, height, pixels } = pgm;
  const rgba = new Uint8Array(width * height * 4);
  let free = 0, occupied = 0;
  for (let row = 0; row < height; ++row) {
    const textureRow = height - 1 - row;  // texture row 0 is the bottom (lowest y)
    for (let x = 0; x < width; ++x) {
      const v = pixels[row * width + x];
      const o = 4 * (textureRow * width + x);
      const colour = v === 0 ? GRID_COLOURS.occupied : v === 254 ? GRID_COLOURS.free : null;
      if (!colour) continue;
      if (v === 0) ++occupied; else ++free;
      rgba.set([colour[0], colour[1], colour[2], v === 0 ? 200 : 150], o);
    }
  }
  const texture = new THREE.DataTexture(rgba, width, height, THREE.RGBAFormat);
  texture.magFilter = THREE.NearestFilter;
  texture.minFilter = THREE.NearestFilter;
  texture.colorSpace = THREE.SRGBColorSpace;
  texture.needsUpdate = true;
  const w = width * yaml.resolution, h = height * yaml.resolution;
  const plane = new THREE.Mesh(
    new THREE.PlaneGeometry(w, h),
    new THREE.MeshBasicMaterial({ map: texture, transparent: true, side: THREE.DoubleSide, depthWrite: false }));
  plane.renderOrder = 1;  // after the opaque mesh
  plane.matrixAutoUpdate = false;
  plane.matrix.copy(yaml.T_W_G).multiply(
    new THREE.Matrix4().makeTranslation(yaml.origin[0] + w / 2, yaml.origin[1] + h / 2, GRID_LIFT_M));
  return { object: plane, free, occupied };
}

function colourOf(rgb) {
  return new THREE.Color(`rgb(${rgb[0]}, ${rgb[1]}, ${rgb[2]})`);
}

function lines(points, rgb, opacity = 1) {
  const material = new THREE.LineBasicMaterial({ color: colourOf(rgb), transparent: opacity < 1, opacity, depthTest: false });
  const segments = new THREE.LineSegments(new THREE.BufferGeometry().setFromPoints(points), material);
  segments.renderOrder = 2;  // drawn over the mesh: edges pass through table tops
  return segments;
}

function tag(text, className, rgb) {
  const div = document.createElement('div');
  div.className = className;
  div.textContent = text;
  if (rgb) div.style.borderColor = `rgb(${rgb[0]}, ${rgb[1]}, ${rgb[2]})`;
  return new CSS2DObject(div);
}

// Scene graph layers: { graph, near } groups (near and in_place edges apart: there are many)
// and counts per relation. Node positions: object box centres, the places' centroids on the floor.
export function buildGraphLayers(json) {
  if (!json || json.schema !== 'semap.scene_graph') throw new Error('scene_graph.json: not a semap scene graph');
  const T = matrixFromRows(json.T_W_G);
  const toWorld = (x, y, z) => new THREE.Vector3(x, y, z).applyMatrix4(T);
  const positionG = new Map();  // node id -> position in G
  for (const o of json.objects || []) positionG.set(o.id, new THREE.Vector3(...o.box_G.center));
  for (const p of json.places || []) positionG.set(p.id, new THREE.Vector3(p.centroid_G[0], p.centroid_G[1], GRID_LIFT_M));
  const graph = new THREE.Group();
  const near = new THREE.Group();
  const byRelation = { on: [], in: [], near: [], in_place: [], connected: [] };
  const counts = { on: 0, in: 0, near: 0, in_place: 0, connected: 0, places: (json.places || []).length, walls: 0 };
  for (const e of json.edges || []) {
    if (e.relation === 'connected') {  // place to place through the passage's centre
      const a = positionG.get(e.source), b = positionG.get(e.target), c = e.evidence && e.evidence.passage_centre_G;
      if (!a || !b || !Array.isArray(c) || c.length !== 3 || !c.every(Number.isFinite)) continue;
      const door = new THREE.Vector3(c[0], c[1], GRID_LIFT_M).applyMatrix4(T);
      byRelation.connected.push(a.clone().applyMatrix4(T), door, door, b.clone().applyMatrix4(T));
      const width = Number(e.evidence.passage_width_m);
      const label = tag(`${Number.isFinite(width) ? width.toFixed(2) : '?'} m`, 'place-label', EDGE_COLOURS.connected);
      label.position.copy(door);
      graph.add(label);
      ++counts.connected;
      continue;
    }
    const a = positionG.get(e.source);
    // `on` the floor: straight down to the floor under the object's centre.
    const b = e.target === 'floor' && a ? a.clone().setZ(0) : positionG.get(e.target);
    if (!a || !b || !byRelation[e.relation]) continue;
    byRelation[e.relation].push(a.clone().applyMatrix4(T), b.clone().applyMatrix4(T));
    ++counts[e.relation];
  }
  for (const relation of ['on', 'in', 'connected']) {
    if (byRelation[relation].length > 0) graph.add(lines(byRelation[relation], EDGE_COLOURS[relation]));
  }
  if (byRelation.near.length > 0) near.add(lines(byRelation.near, EDGE_COLOURS.near, 0.7));
  if (byRelation.in_place.length > 0) near.add(lines(byRelation.in_place, EDGE_COLOURS.in_place, 0.6));
  for (const p of json.places || []) {
    const label = tag(`${p.id} · ${Number(p.area_m2).toFixed(1)} m²`, 'place-label', EDGE_COLOURS.in_place);
    label.position.copy(positionG.get(p.id).clone().applyMatrix4(T));
    graph.add(label);
  }
  // Walls: the observed rectangle of each vertical plane.
  const wallPoints = [];
  for (const s of json.surfaces || []) {
    if (s.kind !== 'wall' || !Array.isArray(s.segment_G)) continue;
    const [a, b] = s.segment_G;
    const c = [toWorld(a[0], a[1], s.bottom_m), toWorld(b[0], b[1], s.bottom_m), toWorld(b[0], b[1], s.height_m), toWorld(a[0], a[1], s.height_m)];
    for (let k = 0; k < 4; ++k) wallPoints.push(c[k], c[(k + 1) % 4]);
    ++counts.walls;
  }
  if (wallPoints.length > 0) graph.add(lines(wallPoints, EDGE_COLOURS.wall, 0.5));
  return { graph, near, counts };
}
