// GLB container reading and writing, accessor reading, and Draco decoding of
// KHR_draco_mesh_compression primitives with draco3dgltf (the decoder the
// browsers' glTF loaders ship). Everything throws Error with a message that
// names the primitive; callers turn that into a checker finding.
import draco3d from 'draco3dgltf';
import { IDENTITY, fromTrs, multiply } from './geodesy.mjs';

const GLB_MAGIC = 0x46546c67; // "glTF"
const CHUNK_JSON = 0x4e4f534a;
const CHUNK_BIN = 0x004e4942;

// GLB bytes -> { json, bin } (bin: Uint8Array or null). Checks the header,
// the declared length and chunk bounds; the validator reports the finer rules.
export function parseGlb(bytes) {
  const buf = Buffer.from(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  if (buf.length < 20) throw new Error(`GLB too short (${buf.length} bytes)`);
  if (buf.readUInt32LE(0) !== GLB_MAGIC) throw new Error('not a GLB (bad magic)');
  if (buf.readUInt32LE(4) !== 2) throw new Error(`GLB version ${buf.readUInt32LE(4)}, expected 2`);
  const length = buf.readUInt32LE(8);
  if (length !== buf.length) throw new Error(`GLB header length ${length} != file size ${buf.length}`);
  let offset = 12;
  let json = null;
  let bin = null;
  while (offset + 8 <= length) {
    const chunkLength = buf.readUInt32LE(offset);
    const chunkType = buf.readUInt32LE(offset + 4);
    const start = offset + 8;
    if (start + chunkLength > length) throw new Error('GLB chunk runs past the end of the file');
    const data = buf.subarray(start, start + chunkLength);
    if (chunkType === CHUNK_JSON && json === null) json = JSON.parse(data.toString('utf8'));
    else if (chunkType === CHUNK_BIN && bin === null) bin = new Uint8Array(data);
    offset = start + chunkLength;
  }
  if (json === null) throw new Error('GLB has no JSON chunk');
  return { json, bin };
}

// { json, bin } -> GLB bytes (Buffer); pads JSON with spaces and BIN with 0.
export function buildGlb(json, bin) {
  const pad4 = (n) => (n + 3) & ~3;
  const jsonBytes = Buffer.from(JSON.stringify(json), 'utf8');
  const jsonChunk = Buffer.alloc(pad4(jsonBytes.length), 0x20);
  jsonBytes.copy(jsonChunk);
  const binChunk = bin ? Buffer.alloc(pad4(bin.length), 0) : null;
  if (bin) Buffer.from(bin.buffer, bin.byteOffset, bin.byteLength).copy(binChunk);
  const total = 12 + 8 + jsonChunk.length + (binChunk ? 8 + binChunk.length : 0);
  const out = Buffer.alloc(total);
  out.writeUInt32LE(GLB_MAGIC, 0);
  out.writeUInt32LE(2, 4);
  out.writeUInt32LE(total, 8);
  out.writeUInt32LE(jsonChunk.length, 12);
  out.writeUInt32LE(CHUNK_JSON, 16);
  jsonChunk.copy(out, 20);
  if (binChunk) {
    const o = 20 + jsonChunk.length;
    out.writeUInt32LE(binChunk.length, o);
    out.writeUInt32LE(CHUNK_BIN, o + 4);
    binChunk.copy(out, o + 8);
  }
  return out;
}

const COMPONENTS = { SCALAR: 1, VEC2: 2, VEC3: 3, VEC4: 4, MAT2: 4, MAT3: 9, MAT4: 16 };
const COMPONENT_READ = {
  5120: [1, 'getInt8', 127], 5121: [1, 'getUint8', 255],
  5122: [2, 'getInt16', 32767], 5123: [2, 'getUint16', 65535],
  5125: [4, 'getUint32', 0], 5126: [4, 'getFloat32', 0],
};

// The bytes of bufferView `index` of a GLB's BIN buffer (buffer 0 only: tiles
// are self-contained).
export function bufferViewBytes(gltf, bin, index) {
  const view = gltf.bufferViews?.[index];
  if (!view) throw new Error(`bufferView ${index} does not exist`);
  if ((view.buffer ?? 0) !== 0 || !bin) throw new Error(`bufferView ${index} is not in the GLB's BIN chunk`);
  const start = view.byteOffset ?? 0;
  if (start + view.byteLength > bin.length) throw new Error(`bufferView ${index} runs past the BIN chunk`);
  return bin.subarray(start, start + view.byteLength);
}

// Accessor -> Float64Array of count * components (normalized integers mapped
// to [-1, 1] / [0, 1] as glTF says). Sparse accessors are not supported.
export function readAccessor(gltf, bin, index) {
  const acc = gltf.accessors?.[index];
  if (!acc) throw new Error(`accessor ${index} does not exist`);
  if (acc.sparse) throw new Error(`accessor ${index} is sparse (not supported by this checker)`);
  if (acc.bufferView === undefined) throw new Error(`accessor ${index} has no bufferView`);
  const n = COMPONENTS[acc.type];
  const [size, getter, normMax] = COMPONENT_READ[acc.componentType] ?? [];
  if (!n || !size) throw new Error(`accessor ${index}: unknown type ${acc.type}/${acc.componentType}`);
  const bytes = bufferViewBytes(gltf, bin, acc.bufferView);
  const stride = gltf.bufferViews[acc.bufferView].byteStride ?? n * size;
  const dv = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  const out = new Float64Array(acc.count * n);
  const base = acc.byteOffset ?? 0;
  if (acc.count > 0 && base + (acc.count - 1) * stride + n * size > bytes.length)
    throw new Error(`accessor ${index} runs past its bufferView`);
  for (let i = 0; i < acc.count; ++i)
    for (let c = 0; c < n; ++c) {
      let v = dv[getter](base + i * stride + c * size, true);
      if (acc.normalized && normMax) v = Math.max(v / normMax, -1);
      out[i * n + c] = v;
    }
  return out;
}

let decoderModule = null;
async function decoder() {
  if (!decoderModule) decoderModule = await draco3d.createDecoderModule({});
  return decoderModule;
}

// Decodes one Draco payload. Returns { positions, normals (or null),
// indices, numPoints } with the attributes named by the extension's
// `attributes` map (glTF semantic -> Draco unique id). Throws on any
// decoder failure; a WASM abort discards the module so the next call starts
// from a fresh one.
export async function decodeDraco(bytes, attributeIds) {
  const m = await decoder();
  let dec = null;
  let mesh = null;
  try {
    dec = new m.Decoder();
    const type = dec.GetEncodedGeometryType(bytes);
    if (type !== m.TRIANGULAR_MESH) throw new Error(`Draco geometry type ${type} is not a triangular mesh`);
    mesh = new m.Mesh();
    const status = dec.DecodeArrayToMesh(bytes, bytes.length, mesh);
    if (!status.ok()) throw new Error(`Draco decode failed: ${status.error_msg()}`);
    const numPoints = mesh.num_points();
    const numFaces = mesh.num_faces();
    const attrs = {};
    for (const [semantic, id] of Object.entries(attributeIds)) {
      const attr = dec.GetAttributeByUniqueId(mesh, id);
      if (!attr || attr.ptr === 0) throw new Error(`Draco payload has no attribute with unique id ${id} (${semantic})`);
      const comps = attr.num_components();
      const byteLength = numPoints * comps * 4;
      const ptr = m._malloc(byteLength);
      try {
        if (!dec.GetAttributeDataArrayForAllPoints(mesh, attr, m.DT_FLOAT32, byteLength, ptr))
          throw new Error(`Draco attribute ${semantic} could not be read as float32`);
        attrs[semantic] = { comps, data: Float64Array.from(new Float32Array(m.HEAPF32.buffer, ptr, numPoints * comps)) };
      } finally {
        m._free(ptr);
      }
    }
    const indexBytes = numFaces * 3 * 4;
    const iptr = m._malloc(indexBytes);
    let indices;
    try {
      if (!dec.GetTrianglesUInt32Array(mesh, indexBytes, iptr)) throw new Error('Draco triangles could not be read');
      indices = Uint32Array.from(new Uint32Array(m.HEAPU32.buffer, iptr, numFaces * 3));
    } finally {
      m._free(iptr);
    }
    return { attrs, indices, numPoints, numFaces };
  } catch (e) {
    if (!(e instanceof Error) || e instanceof WebAssembly.RuntimeError || /abort/i.test(String(e.message))) {
      decoderModule = null;
    }
    throw e instanceof Error ? e : new Error(`Draco decoder aborted: ${e}`);
  } finally {
    try { if (mesh) m.destroy(mesh); if (dec) m.destroy(dec); } catch { decoderModule = null; }
  }
}

// Every mesh primitive reachable from the default scene (or scene 0), with
// its node's world matrix (glTF space, before the y-up turn).
export function scenePrimitives(gltf) {
  const out = [];
  const sceneIndex = gltf.scene ?? 0;
  const roots = gltf.scenes?.[sceneIndex]?.nodes ?? [];
  const visit = (nodeIndex, parent, depth) => {
    const node = gltf.nodes?.[nodeIndex];
    if (!node) throw new Error(`node ${nodeIndex} does not exist`);
    if (depth > 64) throw new Error('node hierarchy deeper than 64 (a cycle?)');
    const local = node.matrix ?? fromTrs(node.translation, node.rotation, node.scale);
    const world = multiply(parent, local);
    if (node.mesh !== undefined) {
      const mesh = gltf.meshes?.[node.mesh];
      if (!mesh) throw new Error(`mesh ${node.mesh} does not exist`);
      mesh.primitives.forEach((primitive, p) =>
        out.push({ node: nodeIndex, mesh: node.mesh, primitiveIndex: p, primitive, matrix: world }));
    }
    for (const child of node.children ?? []) visit(child, world, depth + 1);
  };
  for (const r of roots) visit(r, IDENTITY, 0);
  return out;
}

// Geometry of one primitive: { positions, normals|null, indices, draco }
// (positions/normals Float64Array xyz, indices Uint32Array; triangles only).
export async function primitiveGeometry(gltf, bin, primitive) {
  const mode = primitive.mode ?? 4;
  if (mode !== 4) throw new Error(`primitive mode ${mode} is not TRIANGLES`);
  const ext = primitive.extensions?.KHR_draco_mesh_compression;
  if (ext) {
    const bytes = bufferViewBytes(gltf, bin, ext.bufferView);
    const decoded = await decodeDraco(new Int8Array(bytes.buffer, bytes.byteOffset, bytes.byteLength), ext.attributes ?? {});
    const pos = decoded.attrs.POSITION;
    if (!pos) throw new Error('Draco extension maps no POSITION attribute');
    if (pos.comps !== 3) throw new Error(`Draco POSITION has ${pos.comps} components`);
    const nrm = decoded.attrs.NORMAL;
    if (nrm && nrm.comps !== 3) throw new Error(`Draco NORMAL has ${nrm.comps} components`);
    return {
      positions: pos.data, normals: nrm ? nrm.data : null, indices: decoded.indices,
      draco: { numPoints: decoded.numPoints, numFaces: decoded.numFaces, byteLength: bytes.length },
    };
  }
  if (primitive.attributes?.POSITION === undefined) throw new Error('primitive has no POSITION');
  const positions = readAccessor(gltf, bin, primitive.attributes.POSITION);
  const normals = primitive.attributes.NORMAL !== undefined ? readAccessor(gltf, bin, primitive.attributes.NORMAL) : null;
  let indices;
  if (primitive.indices !== undefined) indices = Uint32Array.from(readAccessor(gltf, bin, primitive.indices));
  else indices = Uint32Array.from({ length: positions.length / 3 }, (_, i) => i);
  if (indices.length % 3) throw new Error(`index count ${indices.length} is not a multiple of 3`);
  return { positions, normals, indices, draco: null };
}
