// The pyramid a web developer builds with npm @mapbox/martini and draco3d, for
// vs_martini.sh: for every tile of OUT.grids (tile_error_bench grids: the DEM
// resampled onto a (2^k + 1)² grid over each of tinsmith's tile squares) an
// RTIN mesh by martini at that zoom's tolerance, then what tinsmith's content
// has too: triangles with no grid node inside the TIN dropped, skirts along the
// tile's sides (two triangles below each side edge, depth 2 × the zoom's
// tolerance), area-weighted vertex normals, and a Draco glTF .glb (edgebreaker,
// speed 3/3, normals 10 bits, position bits chosen as tinsmith chooses them:
// the fewest whose rounding moves no position more than clamp(0.1 × tolerance,
// 0.5 mm, 1 cm) on the bounding cube — core/encode/glb.cpp,
// core/tiles/tile_content.cpp). Positions are project coordinates relative to
// the tile's centre, x east, y north, z up.
//
//   node martini_tiles.mjs OUT.grids MESHES.bin
// Prints one JSON line per zoom (tiles, triangles with skirts, surface
// triangles, .glb bytes, Draco payload bytes, seconds) and a total; writes the
// surface meshes in project coordinates to MESHES.bin (format in
// tile_error_bench.cpp) for the error measurement. Seconds count meshing,
// normals, skirts and encoding (one thread), not reading the grids or writing
// MESHES.bin.
import fs from 'node:fs';
import { performance } from 'node:perf_hooks';
import Martini from '@mapbox/martini';
import draco3d from 'draco3d';

const [gridsPath, meshesPath] = process.argv.slice(2);
if (!gridsPath || !meshesPath) {
  console.error('usage: node martini_tiles.mjs OUT.grids MESHES.bin');
  process.exit(2);
}

const draco = await draco3d.createEncoderModule({});
const grids = fs.readFileSync(gridsPath);
const meshesOut = fs.openSync(meshesPath, 'w');
const martinis = new Map();
const zooms = new Map();
let totalSeconds = 0;

function positionBits(range, maxError) {
  if (range === 0) range = 1;
  for (let b = 1; b <= 30; ++b) {
    if ((Math.sqrt(3) * range) / (2 ** b - 1) / 2 <= maxError) return b;
  }
  return 30;
}

function dracoEncode(positions, normals, indices, bits) {
  const mesh = new draco.Mesh();
  const builder = new draco.MeshBuilder();
  const encoder = new draco.Encoder();
  const points = positions.length / 3;
  builder.AddFacesToMesh(mesh, indices.length / 3, indices);
  const positionId = builder.AddFloatAttributeToMesh(mesh, draco.POSITION, points, 3, positions);
  const normalId = builder.AddFloatAttributeToMesh(mesh, draco.NORMAL, points, 3, normals);
  encoder.SetSpeedOptions(3, 3);
  encoder.SetAttributeQuantization(draco.POSITION, bits);
  encoder.SetAttributeQuantization(draco.NORMAL, 10);
  encoder.SetEncodingMethod(draco.MESH_EDGEBREAKER_ENCODING);
  encoder.SetTrackEncodedProperties(true);
  const data = new draco.DracoInt8Array();
  const length = encoder.EncodeMeshToDracoBuffer(mesh, data);
  if (length <= 0) throw new Error('Draco could not encode a tile');
  const bytes = new Uint8Array(length);
  for (let i = 0; i < length; ++i) bytes[i] = data.GetValue(i) & 255;
  const encodedPoints = encoder.GetNumberOfEncodedPoints();
  const encodedFaces = encoder.GetNumberOfEncodedFaces();
  for (const o of [data, encoder, builder, mesh]) draco.destroy(o);
  return { bytes, positionId, normalId, encodedPoints, encodedFaces };
}

// A .glb as tinsmith writes it (core/encode/glb.cpp), without its asset.extras.
function glb(encoded, min, max, centre) {
  const doc = {
    asset: { version: '2.0', generator: 'martini 0.2.0 + draco3d' },
    extensionsUsed: ['KHR_draco_mesh_compression'],
    extensionsRequired: ['KHR_draco_mesh_compression'],
    scene: 0,
    scenes: [{ nodes: [0] }],
    nodes: [{ mesh: 0, matrix: [1, 0, 0, 0, 0, 0, -1, 0, 0, 1, 0, 0, centre[0], centre[1], centre[2], 1] }],
    bufferViews: [{ buffer: 0, byteLength: encoded.bytes.length }],
    meshes: [{
      primitives: [{
        attributes: { POSITION: 0, NORMAL: 1 }, indices: 2, mode: 4,
        extensions: { KHR_draco_mesh_compression: {
          bufferView: 0, attributes: { POSITION: encoded.positionId, NORMAL: encoded.normalId } } },
      }],
    }],
    accessors: [
      { componentType: 5126, count: encoded.encodedPoints, type: 'VEC3', min, max },
      { componentType: 5126, count: encoded.encodedPoints, type: 'VEC3' },
      { componentType: encoded.encodedPoints < 65536 ? 5123 : 5125, count: 3 * encoded.encodedFaces, type: 'SCALAR' },
    ],
    buffers: [{ byteLength: encoded.bytes.length }],
  };
  let json = Buffer.from(JSON.stringify(doc));
  json = Buffer.concat([json, Buffer.alloc((4 - (json.length % 4)) % 4, 0x20)]);
  const bin = Buffer.concat([encoded.bytes, Buffer.alloc((4 - (encoded.bytes.length % 4)) % 4)]);
  const header = Buffer.alloc(12);
  header.writeUInt32LE(0x46546c67, 0);
  header.writeUInt32LE(2, 4);
  header.writeUInt32LE(12 + 8 + json.length + 8 + bin.length, 8);
  const chunk = (length, type) => {
    const b = Buffer.alloc(8);
    b.writeUInt32LE(length, 0);
    b.writeUInt32LE(type, 4);
    return b;
  };
  return Buffer.concat([header, chunk(json.length, 0x4e4f534a), json, chunk(bin.length, 0x004e4942), bin]);
}

function buildTile(tile) {
  const { n, x0, y0, x1, tolerance, heights, inside } = tile;
  if (!martinis.has(n)) martinis.set(n, new Martini(n));
  const step = (x1 - x0) / (n - 1);
  const rtin = martinis.get(n).createTile(heights);
  const { vertices: gv, triangles: gt } = rtin.getMesh(tolerance);

  // Keep triangles with a grid node inside the TIN; renumber their vertices.
  const newIndex = new Int32Array(gv.length / 2).fill(-1);
  const kept = [];
  for (let t = 0; t < gt.length; t += 3) {
    const a = gt[t], b = gt[t + 1], c = gt[t + 2];
    const node = (v) => gv[2 * v + 1] * n + gv[2 * v];
    if (!inside[node(a)] && !inside[node(b)] && !inside[node(c)]) continue;
    // Counter-clockwise in x east, y north (grid rows run south to north).
    const cross = (gv[2 * b] - gv[2 * a]) * (gv[2 * c + 1] - gv[2 * a + 1]) -
                  (gv[2 * b + 1] - gv[2 * a + 1]) * (gv[2 * c] - gv[2 * a]);
    kept.push(...(cross > 0 ? [a, b, c] : [a, c, b]));
  }
  const order = [];
  for (const v of kept) if (newIndex[v] < 0) { newIndex[v] = order.length; order.push(v); }
  const surface = order.length;
  const gx = order.map((v) => gv[2 * v]), gy = order.map((v) => gv[2 * v + 1]);
  const px = gx.map((i) => (i === n - 1 ? x1 : x0 + i * step));
  const py = gy.map((j) => (j === n - 1 ? tile.y1 : y0 + j * step));
  const pz = order.map((v) => heights[gv[2 * v + 1] * n + gv[2 * v]]);
  const tris = kept.map((v) => newIndex[v]);
  const surfaceTriangles = tris.length / 3;

  // Skirts: below each edge that lies along a side of the tile.
  const depth = 2 * tolerance;
  const below = new Int32Array(surface).fill(-1);
  const side = (v) => (gx[v] === 0 ? 1 : 0) | (gx[v] === n - 1 ? 2 : 0) | (gy[v] === 0 ? 4 : 0) | (gy[v] === n - 1 ? 8 : 0);
  const all = tris.slice();
  for (let t = 0; t < surfaceTriangles * 3; t += 3) {
    for (let i = 0; i < 3; ++i) {
      const a = tris[t + i], b = tris[t + ((i + 1) % 3)];
      if ((side(a) & side(b)) === 0) continue;
      for (const v of [a, b]) {
        if (below[v] < 0) {
          below[v] = px.length;
          px.push(px[v]); py.push(py[v]); pz.push(pz[v] - depth);
        }
      }
      all.push(a, below[a], below[b], a, below[b], b);
    }
  }

  // Positions relative to the centre of their bounding box; normals.
  const count = px.length;
  const lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
  for (let v = 0; v < count; ++v) {
    [px[v], py[v], pz[v]].forEach((p, c) => { lo[c] = Math.min(lo[c], p); hi[c] = Math.max(hi[c], p); });
  }
  const centre = [0, 1, 2].map((c) => 0.5 * (lo[c] + hi[c]));
  const positions = new Float32Array(3 * count);
  for (let v = 0; v < count; ++v) {
    positions[3 * v] = px[v] - centre[0];
    positions[3 * v + 1] = py[v] - centre[1];
    positions[3 * v + 2] = pz[v] - centre[2];
  }
  const normals = new Float64Array(3 * count);
  for (let t = 0; t < surfaceTriangles * 3; t += 3) {
    const [a, b, c] = [tris[t], tris[t + 1], tris[t + 2]];
    const u = [px[b] - px[a], py[b] - py[a], pz[b] - pz[a]];
    const w = [px[c] - px[a], py[c] - py[a], pz[c] - pz[a]];
    const nx = u[1] * w[2] - u[2] * w[1], ny = u[2] * w[0] - u[0] * w[2], nz = u[0] * w[1] - u[1] * w[0];
    for (const v of [a, b, c]) { normals[3 * v] += nx; normals[3 * v + 1] += ny; normals[3 * v + 2] += nz; }
  }
  for (let v = 0; v < surface; ++v) {
    if (below[v] >= 0) for (let c = 0; c < 3; ++c) normals[3 * below[v] + c] = normals[3 * v + c];
  }
  const unit = new Float32Array(3 * count);
  for (let v = 0; v < count; ++v) {
    const l = Math.hypot(normals[3 * v], normals[3 * v + 1], normals[3 * v + 2]);
    if (l > 0) for (let c = 0; c < 3; ++c) unit[3 * v + c] = normals[3 * v + c] / l;
    else unit[3 * v + 2] = 1;
  }
  let range = 0;
  for (let c = 0; c < 3; ++c) range = Math.max(range, Math.fround(hi[c] - centre[c]) - Math.fround(lo[c] - centre[c]));
  const bits = positionBits(range, Math.min(Math.max(0.1 * tolerance, 0.0005), 0.01));
  const encoded = dracoEncode(positions, unit, Uint32Array.from(all), bits);
  const min = [0, 1, 2].map((c) => Math.fround(lo[c] - centre[c]));
  const max = [0, 1, 2].map((c) => Math.fround(hi[c] - centre[c]));
  const file = glb(encoded, min, max, centre);
  return {
    triangles: all.length / 3, surfaceTriangles, bytes: file.length, payload: encoded.bytes.length, bits,
    surface: { px: px.slice(0, surface), py: py.slice(0, surface), pz: pz.slice(0, surface), tris },
  };
}

function writeMesh(id, surface) {
  const nv = surface.px.length, nt = surface.tris.length / 3;
  const b = Buffer.alloc(20 + 24 * nv + 12 * nt);
  b.writeInt32LE(id[0], 0); b.writeInt32LE(id[1], 4); b.writeInt32LE(id[2], 8);
  b.writeUInt32LE(nv, 12); b.writeUInt32LE(nt, 16);
  let o = 20;
  for (let v = 0; v < nv; ++v, o += 24) {
    b.writeDoubleLE(surface.px[v], o); b.writeDoubleLE(surface.py[v], o + 8); b.writeDoubleLE(surface.pz[v], o + 16);
  }
  for (const v of surface.tris) { b.writeUInt32LE(v, o); o += 4; }
  fs.writeSync(meshesOut, b);
}

for (let at = 0; at < grids.length;) {
  const z = grids.readInt32LE(at), x = grids.readInt32LE(at + 4), y = grids.readInt32LE(at + 8);
  const n = grids.readInt32LE(at + 12);
  const [x0, y0, x1, y1, tolerance] = [0, 1, 2, 3, 4].map((i) => grids.readDoubleLE(at + 16 + 8 * i));
  at += 56;
  const heights = new Float64Array(n * n);
  for (let k = 0; k < n * n; ++k) heights[k] = grids.readDoubleLE(at + 8 * k);
  at += 8 * n * n;
  const inside = grids.subarray(at, at + n * n);
  at += n * n;

  const start = performance.now();
  const built = buildTile({ n, x0, y0, x1, y1, tolerance, heights, inside });
  const seconds = (performance.now() - start) / 1000;
  totalSeconds += seconds;
  writeMesh([z, x, y], built.surface);
  if (!zooms.has(z)) {
    zooms.set(z, { zoom: z, tolerance, grid: n, tiles: 0, triangles: 0, surfaceTriangles: 0, bytes: 0, payload: 0,
                   bitsMin: 99, bitsMax: 0, seconds: 0 });
  }
  const row = zooms.get(z);
  row.tiles += 1;
  row.grid = Math.max(row.grid, n);
  row.triangles += built.triangles;
  row.surfaceTriangles += built.surfaceTriangles;
  row.bytes += built.bytes;
  row.payload += built.payload;
  row.bitsMin = Math.min(row.bitsMin, built.bits);
  row.bitsMax = Math.max(row.bitsMax, built.bits);
  row.seconds += seconds;
}
fs.closeSync(meshesOut);
for (const row of [...zooms.values()].sort((a, b) => a.zoom - b.zoom)) console.log(JSON.stringify(row));
console.log(JSON.stringify({ seconds: totalSeconds }));
