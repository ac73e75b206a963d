#!/usr/bin/env node
// Writes a small tileset shaped like tinsmith's output, for developing and
// testing the checkers before (and besides) the C++ tiler:
//
//   OUTDIR/draco/   tileset.json, tiles/{z}/{x}/{y}.glb (Draco), tilesets/1/1/1.json
//   OUTDIR/plain/   the same tiles uncompressed (the --compression none twin)
//   OUTDIR/sample.3dtiles  the Draco directory as media(key, content) rows
//
// A synthetic hill (300 m plain, 1.2 km peak, ripples) over lon 7.40..7.60°,
// lat 46.40..46.60°; a quadtree of 1 + 4 + 16 tiles (y counts from the north),
// each a 17 x 17 grid sampled from the same height function. The z1 tile
// (1, 1, 1) is an external tileset holding its own four children.
// Tile content: positions are ECEF offsets from the tile centre (ECEF axes),
// the root node's matrix is Z_UP_TO_Y_UP * translate(centre), so that the
// 3D Tiles y-up -> z-up turn lands them in ECEF.
//
//   node tests/js/make_sample_tileset.mjs OUTDIR
import fs from 'node:fs';
import path from 'node:path';
import draco3d from 'draco3dgltf';
import { buildGlb } from './glb.mjs';
import { geodeticToEcef, multiply, translation, Z_UP_TO_Y_UP } from './geodesy.mjs';
import { writeMedia } from './media_db.mjs';

const DEG = Math.PI / 180;
const ROOT = { west: 7.4 * DEG, south: 46.4 * DEG, east: 7.6 * DEG, north: 46.6 * DEG };
const GRID = 17; // vertices per tile edge
const MAX_LEVEL = 2;
// Nominal errors per level (metres), not measured: large enough that Cesium,
// looking down on the whole root region (cesium_smoke.mjs), renders the
// tileset and refines the root once (into the external tileset too).
const GEOMETRIC_ERROR = [1024, 256, 0];
const TILESET_GEOMETRIC_ERROR = 4096;
const POSITION_BITS = 14;
const NORMAL_BITS = 10;
const HEIGHT_PAD = 0.5; // m: covers the chords' sag below the vertices
const EXTERNAL = [1, 1, 1]; // z, x, y of the tile that is an external tileset

function heightAt(lon, lat) {
  const lon0 = 7.5 * DEG, lat0 = 46.5 * DEG;
  const dx = (lon - lon0) * Math.cos(lat0) * 6371000;
  const dy = (lat - lat0) * 6371000;
  const r2 = dx * dx + dy * dy;
  return 300 + 1200 * Math.exp(-r2 / (2 * 4000 * 4000)) + 40 * Math.sin(dx / 900) * Math.cos(dy / 1300);
}

function tileRect(z, x, y) {
  const n = 1 << z;
  const dLon = (ROOT.east - ROOT.west) / n;
  const dLat = (ROOT.north - ROOT.south) / n;
  const west = ROOT.west + x * dLon;
  const north = ROOT.north - y * dLat;
  return { west, south: north - dLat, east: west + dLon, north };
}

// The tile's grid: ECEF vertices, per-vertex normals, triangles (CCW seen
// from above), min/max height.
function tileMesh(z, x, y) {
  const r = tileRect(z, x, y);
  const ecef = [];
  let minH = Infinity, maxH = -Infinity;
  for (let j = 0; j < GRID; ++j)
    for (let i = 0; i < GRID; ++i) {
      const lon = r.west + ((r.east - r.west) * i) / (GRID - 1);
      const lat = r.north - ((r.north - r.south) * j) / (GRID - 1);
      const h = heightAt(lon, lat);
      minH = Math.min(minH, h); maxH = Math.max(maxH, h);
      ecef.push(geodeticToEcef(lon, lat, h));
    }
  const triangles = [];
  for (let j = 0; j + 1 < GRID; ++j)
    for (let i = 0; i + 1 < GRID; ++i) {
      const a = j * GRID + i, b = a + 1, c = a + GRID, d = c + 1; // a b (north row) / c d
      triangles.push(a, c, b, b, c, d);
    }
  const normals = ecef.map(() => [0, 0, 0]);
  for (let t = 0; t < triangles.length; t += 3) {
    const [p, q, s] = [ecef[triangles[t]], ecef[triangles[t + 1]], ecef[triangles[t + 2]]];
    const u = [q[0] - p[0], q[1] - p[1], q[2] - p[2]];
    const v = [s[0] - p[0], s[1] - p[1], s[2] - p[2]];
    const n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
    for (const k of [triangles[t], triangles[t + 1], triangles[t + 2]]) for (let c = 0; c < 3; ++c) normals[k][c] += n[c];
  }
  for (const n of normals) {
    const l = Math.hypot(...n);
    for (let c = 0; c < 3; ++c) n[c] /= l;
  }
  return { rect: r, ecef, normals, triangles, minH, maxH };
}

let encoderModule = null;
let decoderModule = null;

// Draco payload for positions (float32 ECEF offsets) + normals + triangles.
function dracoEncode(positions, normals, indices) {
  const m = encoderModule;
  const encoder = new m.Encoder();
  const builder = new m.MeshBuilder();
  const mesh = new m.Mesh();
  builder.AddFacesToMesh(mesh, indices.length / 3, indices);
  const positionId = builder.AddFloatAttributeToMesh(mesh, m.POSITION, positions.length / 3, 3, positions);
  const normalId = builder.AddFloatAttributeToMesh(mesh, m.NORMAL, normals.length / 3, 3, normals);
  encoder.SetAttributeQuantization(m.POSITION, POSITION_BITS);
  encoder.SetAttributeQuantization(m.NORMAL, NORMAL_BITS);
  encoder.SetEncodingMethod(m.MESH_EDGEBREAKER_ENCODING);
  const out = new m.DracoInt8Array();
  const length = encoder.EncodeMeshToDracoBuffer(mesh, out);
  if (length <= 0) throw new Error('Draco encoding failed');
  const bytes = new Uint8Array(length);
  for (let i = 0; i < length; ++i) bytes[i] = out.GetValue(i) & 0xff;
  m.destroy(out); m.destroy(mesh); m.destroy(builder); m.destroy(encoder);
  return { bytes, positionId, normalId };
}

// Decoded point and face counts and POSITION min/max, for the accessors
// (glTF wants them to describe the decoded data).
function dracoSummary(bytes) {
  const m = decoderModule;
  const dec = new m.Decoder();
  const mesh = new m.Mesh();
  const status = dec.DecodeArrayToMesh(new Int8Array(bytes.buffer, bytes.byteOffset, bytes.length), bytes.length, mesh);
  if (!status.ok()) throw new Error(`sample: own Draco payload does not decode: ${status.error_msg()}`);
  const attr = dec.GetAttribute(mesh, dec.GetAttributeId(mesh, m.POSITION));
  const arr = new m.DracoFloat32Array();
  dec.GetAttributeFloatForAllPoints(mesh, attr, arr);
  const min = [Infinity, Infinity, Infinity], max = [-Infinity, -Infinity, -Infinity];
  for (let i = 0; i < arr.size(); ++i) {
    const v = arr.GetValue(i);
    min[i % 3] = Math.min(min[i % 3], v); max[i % 3] = Math.max(max[i % 3], v);
  }
  const r = { numPoints: mesh.num_points(), numFaces: mesh.num_faces(), min, max };
  m.destroy(arr); m.destroy(mesh); m.destroy(dec);
  return r;
}

function minMax(values) {
  const min = [Infinity, Infinity, Infinity], max = [-Infinity, -Infinity, -Infinity];
  values.forEach((v, i) => { min[i % 3] = Math.min(min[i % 3], v); max[i % 3] = Math.max(max[i % 3], v); });
  return { min, max };
}

const MATERIAL = { pbrMetallicRoughness: { baseColorFactor: [0.62, 0.55, 0.42, 1], metallicFactor: 0, roughnessFactor: 1 } };

// Both GLBs of one tile: { draco, plain } Buffers.
function tileGlbs(z, x, y, mesh) {
  const { rect, ecef, normals, triangles } = mesh;
  const centre = geodeticToEcef((rect.west + rect.east) / 2, (rect.south + rect.north) / 2, (mesh.minH + mesh.maxH) / 2);
  const positions = new Float32Array(ecef.length * 3);
  ecef.forEach((p, i) => { for (let c = 0; c < 3; ++c) positions[i * 3 + c] = p[c] - centre[c]; });
  const normalArray = Float32Array.from(normals.flat());
  const indices = Uint32Array.from(triangles);
  const matrix = multiply(Z_UP_TO_Y_UP, translation(centre));
  const { min, max } = minMax(positions);
  const range = Math.max(max[0] - min[0], max[1] - min[1], max[2] - min[2]);
  // Draco quantizes every axis with step range / (2^bits - 1) and rounds to
  // the nearest step: at most half a step per axis.
  const positionErrorBound = (Math.sqrt(3) / 2) * (range / ((1 << POSITION_BITS) - 1));
  const extras = (bound) => ({ tinsmith: { tile: [z, x, y], geometricError: GEOMETRIC_ERROR[z], ...(bound !== undefined ? { positionErrorBound: bound } : {}), sample: true } });
  const common = {
    scene: 0, scenes: [{ nodes: [0] }], nodes: [{ matrix, mesh: 0 }], materials: [MATERIAL],
  };

  const d = dracoEncode(positions, normalArray, indices);
  const s = dracoSummary(d.bytes);
  const dracoJson = {
    asset: { version: '2.0', generator: 'tinsmith tests/js/make_sample_tileset.mjs', extras: extras(positionErrorBound) },
    extensionsUsed: ['KHR_draco_mesh_compression'], extensionsRequired: ['KHR_draco_mesh_compression'],
    ...common,
    meshes: [{ primitives: [{
      attributes: { POSITION: 0, NORMAL: 1 }, indices: 2, material: 0, mode: 4,
      extensions: { KHR_draco_mesh_compression: { bufferView: 0, attributes: { POSITION: d.positionId, NORMAL: d.normalId } } },
    }] }],
    accessors: [
      { componentType: 5126, count: s.numPoints, type: 'VEC3', min: s.min, max: s.max },
      { componentType: 5126, count: s.numPoints, type: 'VEC3' },
      { componentType: 5125, count: s.numFaces * 3, type: 'SCALAR' },
    ],
    bufferViews: [{ buffer: 0, byteOffset: 0, byteLength: d.bytes.length }],
    buffers: [{ byteLength: (d.bytes.length + 3) & ~3 }],
  };

  const bin = Buffer.concat([Buffer.from(positions.buffer), Buffer.from(normalArray.buffer), Buffer.from(indices.buffer)]);
  const plainJson = {
    asset: { version: '2.0', generator: 'tinsmith tests/js/make_sample_tileset.mjs', extras: extras(undefined) },
    ...common,
    meshes: [{ primitives: [{ attributes: { POSITION: 0, NORMAL: 1 }, indices: 2, material: 0, mode: 4 }] }],
    accessors: [
      { bufferView: 0, componentType: 5126, count: ecef.length, type: 'VEC3', min, max },
      { bufferView: 1, componentType: 5126, count: ecef.length, type: 'VEC3' },
      { bufferView: 2, componentType: 5125, count: indices.length, type: 'SCALAR' },
    ],
    bufferViews: [
      { buffer: 0, byteOffset: 0, byteLength: positions.byteLength, byteStride: 12, target: 34962 },
      { buffer: 0, byteOffset: positions.byteLength, byteLength: normalArray.byteLength, byteStride: 12, target: 34962 },
      { buffer: 0, byteOffset: positions.byteLength + normalArray.byteLength, byteLength: indices.byteLength, target: 34963 },
    ],
    buffers: [{ byteLength: bin.length }],
  };
  const dracoBuf = Buffer.alloc((d.bytes.length + 3) & ~3);
  Buffer.from(d.bytes).copy(dracoBuf);
  return { draco: buildGlb(dracoJson, dracoBuf), plain: buildGlb(plainJson, bin) };
}

// The quadtree below (z, x, y): writes both GLBs of every tile and returns
// the tile JSON (uris relative to the tileset root) and its height range.
function buildTile(z, x, y, out) {
  const mesh = tileMesh(z, x, y);
  const glbs = tileGlbs(z, x, y, mesh);
  const rel = `tiles/${z}/${x}/${y}.glb`;
  for (const [kind, bytes] of Object.entries(glbs)) {
    const file = path.join(out[kind], rel);
    fs.mkdirSync(path.dirname(file), { recursive: true });
    fs.writeFileSync(file, bytes);
  }
  let minH = mesh.minH, maxH = mesh.maxH;
  const children = [];
  if (z < MAX_LEVEL)
    for (const [dx, dy] of [[0, 0], [1, 0], [0, 1], [1, 1]]) {
      const child = buildTile(z + 1, 2 * x + dx, 2 * y + dy, out);
      minH = Math.min(minH, child.minH); maxH = Math.max(maxH, child.maxH);
      children.push(child.json);
    }
  const r = mesh.rect;
  const json = {
    boundingVolume: { region: [r.west, r.south, r.east, r.north, minH - HEIGHT_PAD, maxH + HEIGHT_PAD] },
    geometricError: GEOMETRIC_ERROR[z],
    content: { uri: rel },
    ...(children.length ? { children } : {}),
  };
  return { json, minH, maxH };
}

// Rewrites uris of a subtree for a tileset file stored at `prefix` (a path
// like "tilesets/1/1/1.json"), relative to the root directory.
function rebase(tile, fromFile) {
  const up = path.posix.relative(path.posix.dirname(fromFile), '.');
  const copy = structuredClone(tile);
  const visit = (t) => {
    if (t.content) t.content.uri = path.posix.join(up, t.content.uri);
    (t.children ?? []).forEach(visit);
  };
  visit(copy);
  return copy;
}

function writeJson(file, value) {
  fs.mkdirSync(path.dirname(file), { recursive: true });
  fs.writeFileSync(file, JSON.stringify(value, null, 1) + '\n');
}

async function main() {
  const outDir = process.argv[2];
  if (!outDir || process.argv.length > 3) {
    console.error('usage: node make_sample_tileset.mjs OUTDIR');
    process.exit(2);
  }
  encoderModule = await draco3d.createEncoderModule({});
  decoderModule = await draco3d.createDecoderModule({});
  const out = { draco: path.join(outDir, 'draco'), plain: path.join(outDir, 'plain') };
  for (const dir of Object.values(out)) fs.rmSync(dir, { recursive: true, force: true });
  fs.rmSync(path.join(outDir, 'sample.3dtiles'), { force: true });

  const root = buildTile(0, 0, 0, out).json;
  root.refine = 'REPLACE';

  // Move the subtree of EXTERNAL into its own tileset file.
  const [ez, ex, ey] = EXTERNAL;
  const externalFile = `tilesets/${ez}/${ex}/${ey}.json`;
  const index = (ex % 2) + 2 * (ey % 2);
  const subtree = root.children[index];
  const external = {
    asset: { version: '1.1' },
    geometricError: subtree.geometricError,
    root: { ...rebase(subtree, externalFile), refine: 'REPLACE' },
  };
  root.children[index] = {
    boundingVolume: subtree.boundingVolume, geometricError: subtree.geometricError, content: { uri: externalFile },
  };
  const tileset = {
    asset: { version: '1.1', generator: 'tinsmith tests/js/make_sample_tileset.mjs' },
    geometricError: TILESET_GEOMETRIC_ERROR,
    root,
  };
  for (const dir of Object.values(out)) {
    writeJson(path.join(dir, 'tileset.json'), tileset);
    writeJson(path.join(dir, externalFile), external);
  }

  // The archive: every file of the Draco directory, keys sorted.
  const files = [];
  const walk = (d, rel) => {
    for (const e of fs.readdirSync(d, { withFileTypes: true })) {
      const r = rel ? `${rel}/${e.name}` : e.name;
      if (e.isDirectory()) walk(path.join(d, e.name), r);
      else files.push(r);
    }
  };
  walk(out.draco, '');
  files.sort();
  writeMedia(path.join(outDir, 'sample.3dtiles'), files.map((k) => [k, fs.readFileSync(path.join(out.draco, k))]));
  console.log(`sample: ${files.filter((f) => f.endsWith('.glb')).length} tiles in ${out.draco} and ${out.plain}, archive ${path.join(outDir, 'sample.3dtiles')}`);
}

main().catch((e) => { console.error(`ERROR: ${e.stack ?? e}`); process.exit(1); });
