// Cesium terrain a web developer builds with npm @mapbox/martini, for
// terrain_vs_martini.sh: for every tile of OUT.grids (tile_error_bench
// terrain-grids: the DEM-TIN sampled on a (2^k + 1)² longitude/latitude grid
// over each tile of tinsmith's terrain, same levels and x/y) an RTIN mesh by
// martini at the level's error (TOLERANCES, "level:metres,…"), encoded as
// quantized-mesh-1.0 (github.com/CesiumGS/quantized-mesh) by the small
// encoder below: the 88-byte header (centre, height range, bounding sphere,
// horizon occlusion point, as Cesium computes them), u, v, height zig-zag
// delta coded, vertices in first-use order, high-water-mark indices (16-bit
// up to 65 536 vertices), the west/south/east/north edge index lists (no
// skirts: a client adds its own), and two extensions — octvertexnormals
// (area-weighted normals in ECEF, oct-encoded to 2 bytes) and a one-byte water
// mask (land), as tinsmith's tiles have; no metadata. The mesh covers the
// whole rectangle, as every Cesium tile must (outside the TIN the grid holds
// tile_error_bench's continuous extension, or the ellipsoid in a tile that
// misses the TIN).
//
//   node martini_terrain.mjs OUT.grids TOLERANCES OUTDIR
// Writes OUTDIR/terrain/{z}/{x}/{y}.terrain; prints one JSON line per level
// (tiles, vertices, triangles, those with a grid node in the TIN, bytes,
// gzip -6 bytes, seconds) and a total.
// Seconds count meshing and encoding (one thread), not reading the grids,
// gzip or writing the files.
import Martini from '@mapbox/martini';
import fs from 'node:fs';
import path from 'node:path';
import {performance} from 'node:perf_hooks';
import zlib from 'node:zlib';

const [gridsPath, tolerancesText, outDir] = process.argv.slice(2);
if (!gridsPath || !tolerancesText || !outDir) {
  console.error('usage: node martini_terrain.mjs OUT.grids LEVEL:TOL,... OUTDIR');
  process.exit(2);
}
const tolerances = new Map(tolerancesText.split(',').map((item) => {
  const [z, t] = item.split(':');
  return [Number(z), Number(t)];
}));

const A = 6378137.0, F = 1 / 298.257223563, E2 = F * (2 - F), B = A * (1 - F);
const RAD = Math.PI / 180;
function ecef(lon, lat, h) {
  const sl = Math.sin(lat * RAD), cl = Math.cos(lat * RAD);
  const n = A / Math.sqrt(1 - E2 * sl * sl);
  return [
    (n + h) * cl * Math.cos(lon * RAD), (n + h) * cl * Math.sin(lon * RAD), (n * (1 - E2) + h) * sl
  ];
}

// Cesium's EllipsoidalOccluder.computeHorizonCullingPointFromPoints on WGS84.
function horizonOcclusionPoint(points, direction) {
  const s = (p) => [p[0] / A, p[1] / A, p[2] / B];
  const d = s(direction);
  const dl = Math.hypot(...d);
  const dir = d.map((c) => c / dl);
  let magnitude = 0;
  for (const p of points) {
    const q = s(p);
    let m2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2];
    let m = Math.sqrt(m2);
    const u = q.map((c) => c / m);
    m2 = Math.max(1, m2);
    m = Math.max(1, m);
    const cosAlpha = u[0] * dir[0] + u[1] * dir[1] + u[2] * dir[2];
    const cx = u[1] * dir[2] - u[2] * dir[1], cy = u[2] * dir[0] - u[0] * dir[2],
          cz = u[0] * dir[1] - u[1] * dir[0];
    const sinAlpha = Math.hypot(cx, cy, cz);
    const cosBeta = 1 / m, sinBeta = Math.sqrt(m2 - 1) * cosBeta;
    magnitude = Math.max(magnitude, 1 / (cosAlpha * cosBeta - sinAlpha * sinBeta));
  }
  return dir.map((c) => c * magnitude);
}

// CesiumJS's AttributeCompression.octEncode to 8 bits a component.
function octEncode(x, y, z) {
  const l1 = Math.abs(x) + Math.abs(y) + Math.abs(z);
  let ox = x / l1, oy = y / l1;
  if (z < 0) {
    const tx = ox, ty = oy;
    ox = (1 - Math.abs(ty)) * (tx < 0 ? -1 : 1);
    oy = (1 - Math.abs(tx)) * (ty < 0 ? -1 : 1);
  }
  const q = (v) => Math.round((Math.min(Math.max(v, -1), 1) * 0.5 + 0.5) * 255);
  return [q(ox), q(oy)];
}

const zig = (v) => ((v << 1) ^ (v >> 31)) & 0xffff;

function encodeTile(tile, tolerance) {
  const {n, west, south, east, north, heights, inside} = tile;
  const rtin = martinis.get(n) ?? martinis.set(n, new Martini(n)).get(n);
  const {vertices: gv, triangles: gt} = rtin.createTile(heights).getMesh(tolerance);

  // Triangles counter-clockwise in lon/lat (grid rows run south to north);
  // vertices renumbered in first-use order.
  const newIndex = new Int32Array(gv.length / 2).fill(-1);
  const order = [];
  const tris = new Uint32Array(gt.length);
  let overTin = 0;  // triangles with a grid node in the TIN
  const node = (v) => gv[2 * v + 1] * n + gv[2 * v];
  for (let t = 0; t < gt.length; t += 3) {
    let a = gt[t], b = gt[t + 1], c = gt[t + 2];
    if (inside[node(a)] || inside[node(b)] || inside[node(c)]) ++overTin;
    const cross = (gv[2 * b] - gv[2 * a]) * (gv[2 * c + 1] - gv[2 * a + 1]) -
        (gv[2 * b + 1] - gv[2 * a + 1]) * (gv[2 * c] - gv[2 * a]);
    if (cross < 0) [b, c] = [c, b];
    [a, b, c].forEach((v, i) => {
      if (newIndex[v] < 0) {
        newIndex[v] = order.length;
        order.push(v);
      }
      tris[t + i] = newIndex[v];
    });
  }
  const count = order.length;
  const cells = n - 1;
  const us = new Uint16Array(count), vs = new Uint16Array(count), hs = new Uint16Array(count);
  let lo = Infinity, hi = -Infinity;
  const zs = new Float64Array(count);
  for (let i = 0; i < count; ++i) {
    zs[i] = heights[gv[2 * order[i] + 1] * n + gv[2 * order[i]]];
    lo = Math.min(lo, zs[i]);
    hi = Math.max(hi, zs[i]);
  }
  const minH = Math.fround(lo), maxH = Math.fround(hi);
  const lons = new Float64Array(count), lats = new Float64Array(count),
        hts = new Float64Array(count);
  for (let i = 0; i < count; ++i) {
    us[i] = Math.round((gv[2 * order[i]] / cells) * 32767);
    vs[i] = Math.round((gv[2 * order[i] + 1] / cells) * 32767);
    hs[i] = maxH > minH ?
        Math.min(32767, Math.max(0, Math.round(((zs[i] - minH) / (maxH - minH)) * 32767))) :
        0;
    // As a client decodes them.
    lons[i] = west + (east - west) * (us[i] / 32767);
    lats[i] = south + (north - south) * (vs[i] / 32767);
    hts[i] = minH + (maxH - minH) * (hs[i] / 32767);
  }
  const pos = [];
  const boxLo = [Infinity, Infinity, Infinity], boxHi = [-Infinity, -Infinity, -Infinity];
  for (let i = 0; i < count; ++i) {
    const p = ecef(lons[i], lats[i], hts[i]);
    pos.push(p);
    for (let c = 0; c < 3; ++c) {
      boxLo[c] = Math.min(boxLo[c], p[c]);
      boxHi[c] = Math.max(boxHi[c], p[c]);
    }
  }
  const centre = [0, 1, 2].map((c) => 0.5 * (boxLo[c] + boxHi[c]));
  let radius = 0;
  for (const p of pos)
    radius = Math.max(radius, Math.hypot(p[0] - centre[0], p[1] - centre[1], p[2] - centre[2]));
  const horizon = horizonOcclusionPoint(pos, centre);

  // Area-weighted normals in ECEF.
  const normals = new Float64Array(3 * count);
  for (let t = 0; t < tris.length; t += 3) {
    const [a, b, c] = [pos[tris[t]], pos[tris[t + 1]], pos[tris[t + 2]]];
    const u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]], w = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
    const nx = u[1] * w[2] - u[2] * w[1], ny = u[2] * w[0] - u[0] * w[2],
          nz = u[0] * w[1] - u[1] * w[0];
    for (let k = 0; k < 3; ++k) {
      const v = tris[t + k];
      normals[3 * v] += nx;
      normals[3 * v + 1] += ny;
      normals[3 * v + 2] += nz;
    }
  }

  const wide = count > 65536;
  const iw = wide ? 4 : 2;
  const edges = [[], [], [], []];  // west, south, east, north
  for (let i = 0; i < count; ++i) {
    if (us[i] === 0) edges[0].push(i);
    if (vs[i] === 0) edges[1].push(i);
    if (us[i] === 32767) edges[2].push(i);
    if (vs[i] === 32767) edges[3].push(i);
  }
  let size = 88 + 4 + 6 * count;
  size += (iw - (size % iw)) % iw;
  size += 4 + iw * tris.length;
  for (const e of edges) size += 4 + iw * e.length;
  size += 5 + 2 * count + 5 + 1;
  const b = Buffer.alloc(size);
  let o = 0;
  const f64 = (v) => {
    b.writeDoubleLE(v, o);
    o += 8;
  };
  const u32 = (v) => {
    b.writeUInt32LE(v, o);
    o += 4;
  };
  const idx = (v) => {
    if (wide)
      u32(v);
    else {
      b.writeUInt16LE(v, o);
      o += 2;
    }
  };
  centre.forEach(f64);
  b.writeFloatLE(minH, o);
  b.writeFloatLE(maxH, o + 4);
  o += 8;
  centre.forEach(f64);
  f64(radius);
  horizon.forEach(f64);
  u32(count);
  for (const arr of [us, vs, hs]) {
    let prev = 0;
    for (let i = 0; i < count; ++i) {
      b.writeUInt16LE(zig(arr[i] - prev), o);
      o += 2;
      prev = arr[i];
    }
  }
  o += (iw - (o % iw)) % iw;
  u32(tris.length / 3);
  let highest = 0;
  for (const v of tris) {
    idx(highest - v);
    if (v === highest) ++highest;
  }
  for (const e of edges) {
    u32(e.length);
    e.forEach(idx);
  }
  b.writeUInt8(1, o);
  o += 1;
  u32(2 * count);
  for (let i = 0; i < count; ++i) {
    const l = Math.hypot(normals[3 * i], normals[3 * i + 1], normals[3 * i + 2]);
    const [x, y] = l > 0 ?
        octEncode(normals[3 * i] / l, normals[3 * i + 1] / l, normals[3 * i + 2] / l) :
        octEncode(...pos[i].map((c) => c / Math.hypot(...pos[i])));
    b.writeUInt8(x, o);
    b.writeUInt8(y, o + 1);
    o += 2;
  }
  b.writeUInt8(2, o);
  o += 1;
  u32(1);
  b.writeUInt8(0, o);
  o += 1;
  if (o !== size) throw new Error(`encoder size mismatch ${o} != ${size}`);
  return {bytes: b, vertices: count, triangles: tris.length / 3, overTin};
}

const martinis = new Map();
const grids = fs.readFileSync(gridsPath);
const levels = new Map();
let totalSeconds = 0;
for (let at = 0; at < grids.length;) {
  const z = grids.readInt32LE(at), x = grids.readInt32LE(at + 4), y = grids.readInt32LE(at + 8);
  const n = grids.readInt32LE(at + 12);
  const [west, south, east, north] = [0, 1, 2, 3].map((i) => grids.readDoubleLE(at + 16 + 8 * i));
  at += 48;
  const heights = new Float32Array(n * n);
  for (let k = 0; k < n * n; ++k) heights[k] = grids.readDoubleLE(at + 8 * k);
  at += 8 * n * n;
  const inside = grids.subarray(at, at + n * n);
  at += n * n;
  if (!tolerances.has(z)) throw new Error(`no tolerance for level ${z}`);

  const start = performance.now();
  const tile = encodeTile({n, west, south, east, north, heights, inside}, tolerances.get(z));
  const seconds = (performance.now() - start) / 1000;
  totalSeconds += seconds;
  const file = path.join(outDir, 'terrain', String(z), String(x), `${y}.terrain`);
  fs.mkdirSync(path.dirname(file), {recursive: true});
  fs.writeFileSync(file, tile.bytes);
  if (!levels.has(z)) {
    levels.set(z, {
      level: z,
      tolerance: tolerances.get(z),
      grid: n,
      tiles: 0,
      vertices: 0,
      triangles: 0,
      overTin: 0,
      bytes: 0,
      gzip: 0,
      seconds: 0
    });
  }
  const row = levels.get(z);
  row.tiles += 1;
  row.grid = Math.max(row.grid, n);
  row.vertices += tile.vertices;
  row.triangles += tile.triangles;
  row.overTin += tile.overTin;
  row.bytes += tile.bytes.length;
  row.gzip += zlib.gzipSync(tile.bytes, {level: 6}).length;
  row.seconds += seconds;
}
for (const row of [...levels.values()].sort((a, b) => a.level - b.level))
  console.log(JSON.stringify(row));
console.log(JSON.stringify({seconds: totalSeconds}));
