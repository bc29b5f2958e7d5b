// A small PLY reader (binary little/big endian and ASCII) that keeps every vertex property,
// including semap's `label` (uchar class id) and `instance` (uint), which three's PLYLoader drops.
// Returns { vertexCount, properties: {name: TypedArray}, indices: Uint32Array|null }.

const SCALAR_TYPES = {
  char: ['Int8', 1], int8: ['Int8', 1],
  uchar: ['Uint8', 1], uint8: ['Uint8', 1],
  short: ['Int16', 2], int16: ['Int16', 2],
  ushort: ['Uint16', 2], uint16: ['Uint16', 2],
  int: ['Int32', 4], int32: ['Int32', 4],
  uint: ['Uint32', 4], uint32: ['Uint32', 4],
  float: ['Float32', 4], float32: ['Float32', 4],
  double: ['Float64', 8], float64: ['Float64', 8],
};

const ARRAY_FOR = {
  Int8: Int8Array, Uint8: Uint8Array, Int16: Int16Array, Uint16: Uint16Array,
  Int32: Int32Array, Uint32: Uint32Array, Float32: Float32Array, Float64: Float64Array,
};

function scalarType(name) {
  const t = SCALAR_TYPES[name];
  if (!t) throw new Error(`PLY: unsupported property type '${name}'`);
  return t;
}

function parseHeader(bytes) {
  // The header is ASCII and ends with "end_header\n" (or \r\n).
  const probe = new TextDecoder('latin1').decode(bytes.subarray(0, Math.min(bytes.length, 65536)));
  const endMatch = /end_header\r?\n/.exec(probe);
  if (!probe.startsWith('ply') || !endMatch) throw new Error('PLY: not a PLY file (no header)');
  const headerLength = endMatch.index + endMatch[0].length;
  const lines = probe.slice(0, endMatch.index).split(/\r?\n/);
  let format = null;
  const elements = [];
  for (const raw of lines) {
    const words = raw.trim().split(/\s+/);
    if (words[0] === 'format') format = words[1];
    else if (words[0] === 'element') elements.push({ name: words[1], count: parseInt(words[2], 10), properties: [] });
    else if (words[0] === 'property') {
      const element = elements[elements.length - 1];
      if (!element) throw new Error('PLY: property before element');
      if (words[1] === 'list') {
        element.properties.push({ name: words[4], list: true, countType: scalarType(words[2]), itemType: scalarType(words[3]) });
      } else {
        element.properties.push({ name: words[2], list: false, type: scalarType(words[1]) });
      }
    }
  }
  if (!['ascii', 'binary_little_endian', 'binary_big_endian'].includes(format)) {
    throw new Error(`PLY: unsupported format '${format}'`);
  }
  return { format, elements, headerLength };
}

/** Parses a PLY file from an ArrayBuffer. */
export function parsePly(buffer) {
  const bytes = new Uint8Array(buffer);
  const { format, elements, headerLength } = parseHeader(bytes);
  const result = { vertexCount: 0, properties: {}, indices: null };
  const faceIndices = [];

  if (format === 'ascii') {
    const text = new TextDecoder('latin1').decode(bytes.subarray(headerLength));
    const tokens = text.split(/\s+/).filter((t) => t.length > 0);
    let at = 0;
    const next = () => {
      if (at >= tokens.length) throw new Error('PLY: truncated ASCII data');
      return Number(tokens[at++]);
    };
    for (const element of elements) readElement(element, next, () => next(), result, faceIndices);
  } else {
    const view = new DataView(buffer, headerLength);
    const little = format === 'binary_little_endian';
    let offset = 0;
    // Fast paths for the common layouts (fixed-size vertex records; faces as one
    // 'list uchar int vertex_indices' of triangles): column-wise reads, no per-value dispatch.
    const readFast = (element) => {
      if (element.name === 'vertex' && element.properties.every((p) => !p.list)) {
        const stride = element.properties.reduce((sum, p) => sum + p.type[1], 0);
        if (offset + stride * element.count > view.byteLength) throw new Error('PLY: truncated binary data');
        result.vertexCount = element.count;
        let at = 0;
        for (const p of element.properties) {
          const column = new ARRAY_FOR[p.type[0]](element.count);
          const get = DataView.prototype[`get${p.type[0]}`];
          for (let i = 0, o = offset + at; i < element.count; ++i, o += stride) column[i] = get.call(view, o, little);
          result.properties[p.name] = column;
          at += p.type[1];
        }
        offset += stride * element.count;
        return true;
      }
      const p = element.properties[0];
      if (element.name === 'face' && element.properties.length === 1 && p.list && p.countType[1] === 1 &&
          p.itemType[1] === 4 && (p.name === 'vertex_indices' || p.name === 'vertex_index')) {
        const start = faceIndices.length;
        let o = offset;
        let triangles = true;
        for (let i = 0; i < element.count; ++i) {
          if (o + 1 > view.byteLength) throw new Error('PLY: truncated binary data');
          if (view.getUint8(o) !== 3) { triangles = false; break; }
          if (o + 13 > view.byteLength) throw new Error('PLY: truncated binary data');
          faceIndices.push(view.getUint32(o + 1, little), view.getUint32(o + 5, little), view.getUint32(o + 9, little));
          o += 13;
        }
        if (triangles) { offset = o; return true; }
        faceIndices.length = start;  // polygons: take the general path
      }
      return false;
    };
    const read = ([kind, size]) => {
      if (offset + size > view.byteLength) throw new Error('PLY: truncated binary data');
      const value = view[`get${kind}`](offset, little);
      offset += size;
      return value;
    };
    for (const element of elements) {
      if (!readFast(element)) readElement(element, read, read, result, faceIndices);
    }
  }
  if (faceIndices.length > 0) result.indices = Uint32Array.from(faceIndices);
  return result;
}

// Reads one element block. `readScalar(type)` returns the next number of that type.
function readElement(element, readScalar, readCount, result, faceIndices) {
  if (element.name === 'vertex') {
    result.vertexCount = element.count;
    const columns = element.properties.map((p) =>
      p.list ? null : new ARRAY_FOR[p.type[0]](element.count));
    for (let i = 0; i < element.count; ++i) {
      element.properties.forEach((p, k) => {
        if (p.list) {
          const n = readCount(p.countType);
          for (let j = 0; j < n; ++j) readScalar(p.itemType);
        } else {
          columns[k][i] = readScalar(p.type);
        }
      });
    }
    element.properties.forEach((p, k) => { if (columns[k]) result.properties[p.name] = columns[k]; });
  } else if (element.name === 'face') {
    for (let i = 0; i < element.count; ++i) {
      for (const p of element.properties) {
        if (p.list) {
          const n = readCount(p.countType);
          const polygon = [];
          for (let j = 0; j < n; ++j) polygon.push(readScalar(p.itemType));
          if (p.name === 'vertex_indices' || p.name === 'vertex_index') {
            // Fan-triangulate polygons with more than three corners.
            for (let j = 1; j + 1 < polygon.length; ++j) faceIndices.push(polygon[0], polygon[j], polygon[j + 1]);
          }
        } else {
          readScalar(p.type);
        }
      }
    }
  } else {
    // Unknown element: skip it entry by entry.
    for (let i = 0; i < element.count; ++i) {
      for (const p of element.properties) {
        if (p.list) {
          const n = readCount(p.countType);
          for (let j = 0; j < n; ++j) readScalar(p.itemType);
        } else {
          readScalar(p.type);
        }
      }
    }
  }
}
