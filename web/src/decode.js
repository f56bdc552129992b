// Base64 -> typed arrays for the mesh buffers of the report data (little-endian, as the
// vcut CLI writes them). A 2-million-triangle mesh is ~60 MB of base64, so decoding works
// in chunks: no giant intermediate binary string, one pass filling a Uint8Array.

const CHUNK_CHARS = 1 << 22; // multiple of 4: each chunk decodes on its own

function decodedLength(b64) {
  let n = b64.length;
  while (n > 0 && b64.charCodeAt(n - 1) === 61 /* = */) n--;
  return Math.floor((n * 3) / 4);
}

export function base64ToBytes(b64) {
  if (typeof b64 !== 'string') throw new Error('expected a base64 string');
  b64 = b64.replace(/\s+/g, '');
  if (typeof Uint8Array.fromBase64 === 'function') {
    return Uint8Array.fromBase64(b64);
  }
  const out = new Uint8Array(decodedLength(b64));
  let o = 0;
  for (let i = 0; i < b64.length; i += CHUNK_CHARS) {
    const bin = atob(b64.slice(i, i + CHUNK_CHARS));
    const n = bin.length;
    for (let k = 0; k < n; k++) out[o + k] = bin.charCodeAt(k);
    o += n;
  }
  return o === out.length ? out : out.subarray(0, o);
}

const littleEndianHost = new Uint8Array(new Uint16Array([1]).buffer)[0] === 1;

export function typed(b64, Ctor, expectedCount, what) {
  if (b64 == null) return null;
  const bytes = base64ToBytes(b64);
  if (bytes.length % Ctor.BYTES_PER_ELEMENT !== 0) {
    throw new Error(`${what}: ${bytes.length} bytes is not a multiple of ${Ctor.BYTES_PER_ELEMENT}`);
  }
  const count = bytes.length / Ctor.BYTES_PER_ELEMENT;
  if (expectedCount != null && count !== expectedCount) {
    throw new Error(`${what}: expected ${expectedCount} values, got ${count}`);
  }
  // fromBase64/atob paths give a fresh, offset-0 buffer: view it directly.
  let arr = bytes.byteOffset === 0 && bytes.buffer.byteLength >= bytes.length
    ? new Ctor(bytes.buffer, 0, count)
    : new Ctor(bytes.slice().buffer);
  if (!littleEndianHost && Ctor.BYTES_PER_ELEMENT > 1) {
    const dv = new DataView(arr.buffer, arr.byteOffset, arr.byteLength);
    const fixed = new Ctor(count);
    const isFloat = Ctor === Float32Array;
    for (let i = 0; i < count; i++) {
      fixed[i] = isFloat ? dv.getFloat32(i * 4, true) : dv.getInt32(i * 4, true);
    }
    arr = fixed;
  }
  return arr;
}

// Decodes {vertices, triangles, positions, indices, deviation?, source?, block?} into typed arrays.
// Releases the base64 strings on the input object so the parsed JSON can be collected.
export function decodeMesh(m, what) {
  if (!m) return null;
  const nv = m.vertices != null ? Number(m.vertices) : null;
  const nt = m.triangles != null ? Number(m.triangles) : null;
  const out = {
    vertices: 0,
    triangles: 0,
    positions: typed(m.positions, Float32Array, nv != null ? nv * 3 : null, `${what}.positions`),
    indices: typed(m.indices, Uint32Array, nt != null ? nt * 3 : null, `${what}.indices`),
    deviation: typed(m.deviation, Float32Array, nv, `${what}.deviation`),
    source: typed(m.source, Int32Array, nv, `${what}.source`),
    block: typed(m.block, Int32Array, nv, `${what}.block`),
  };
  if (!out.positions || !out.indices) throw new Error(`${what}: positions and indices are required`);
  out.vertices = out.positions.length / 3;
  out.triangles = out.indices.length / 3;
  const nvert = out.vertices;
  const idx = out.indices;
  for (let i = 0; i < idx.length; i++) {
    if (idx[i] >= nvert) throw new Error(`${what}: index ${idx[i]} out of range (${nvert} vertices)`);
  }
  m.positions = m.indices = m.deviation = m.source = m.block = null;
  return out;
}
