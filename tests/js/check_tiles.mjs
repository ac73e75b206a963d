#!/usr/bin/env node
// Checks a tinsmith tileset directory (tileset.json + tiles/{z}/{x}/{y}.glb,
// external tilesets anywhere below) independently of the tiler:
//
//   node tests/js/check_tiles.mjs DIR [--plain PLAIN_DIR] [--json]
//
// Tileset JSON (every file reached from DIR/tileset.json): 3D Tiles 1.1 (or
// 1.0) rules, region bounding volumes nested parent > child, geometric error
// not growing downwards, every content uri present.
// Every .glb under DIR: the Khronos glTF validator reports no error; every
// primitive decodes (Draco with draco3dgltf); accessor counts and bounds
// agree with the decoded data; asset.extras.tinsmith names the tile; the
// content, taken to ECEF (node matrices, the y-up -> z-up turn, tile
// transforms), lies in the region of every tile that references it.
// With --plain, each tile is compared with its uncompressed twin: same
// triangle count, positions within extras.tinsmith.positionErrorBound
// (+ float32 slack) both ways, triangles matched by centroid and winding,
// normals within 2 degrees.
// Exit status 0 when nothing is wrong, 1 on any error, 2 on bad usage.
import fs from 'node:fs';
import path from 'node:path';
import validator from 'gltf-validator';
import { parseGlb, primitiveGeometry, scenePrimitives } from './glb.mjs';
import {
  ecefToGeodetic, IDENTITY, multiply, normalMatrix, transformPoint, Y_UP_TO_Z_UP, WGS84_A,
} from './geodesy.mjs';
import { comparePrimitives } from './compare_meshes.mjs';

const EPS_ANGLE = 1e-9; // rad (~6 mm): child region inside its parent
const EPS_HEIGHT = 1e-3; // m
const EPS_CONTENT = 1e-3; // m on top of the position error bound: content inside its region
const FLOAT32_REL = 2 ** -23; // twice float32's relative rounding

function usage(message) {
  if (message) console.error(`check_tiles: ${message}`);
  console.error('usage: node check_tiles.mjs DIR [--plain PLAIN_DIR] [--json]');
  process.exit(2);
}

function parseArgs(argv) {
  const opts = { dir: null, plain: null, json: false };
  for (let i = 0; i < argv.length; ++i) {
    const a = argv[i];
    if (a === '--json') opts.json = true;
    else if (a === '--plain') { opts.plain = argv[++i]; if (!opts.plain) usage('--plain needs a directory'); }
    else if (a === '-h' || a === '--help') usage();
    else if (a.startsWith('-')) usage(`unknown option '${a}'`);
    else if (opts.dir === null) opts.dir = a;
    else usage(`unexpected argument '${a}'`);
  }
  if (!opts.dir) usage('DIR is required');
  return opts;
}

class Report {
  constructor() { this.errors = []; this.warnings = []; }
  error(file, message) { this.errors.push({ file, message }); }
  warn(file, message) { this.warnings.push({ file, message }); }
}

const isNum = (v) => typeof v === 'number' && Number.isFinite(v);

// Region well-formedness; returns the region as an object or null.
function checkRegion(report, file, label, region) {
  if (!Array.isArray(region) || region.length !== 6 || !region.every(isNum)) {
    report.error(file, `${label}: region must be 6 finite numbers, got ${JSON.stringify(region)}`);
    return null;
  }
  const [west, south, east, north, minH, maxH] = region;
  const tiny = 1e-12;
  const problems = [];
  if (west < -Math.PI - tiny || west > Math.PI + tiny || east < -Math.PI - tiny || east > Math.PI + tiny)
    problems.push('west/east outside [-pi, pi] (radians expected)');
  if (south < -Math.PI / 2 - tiny || north > Math.PI / 2 + tiny || north < -Math.PI / 2 - tiny || south > Math.PI / 2 + tiny)
    problems.push('south/north outside [-pi/2, pi/2] (radians expected)');
  if (west > east) problems.push(`west ${west} > east ${east}`);
  if (south > north) problems.push(`south ${south} > north ${north}`);
  if (minH > maxH) problems.push(`minimum height ${minH} > maximum height ${maxH}`);
  if (problems.length) {
    report.error(file, `${label}: region ${JSON.stringify(region)}: ${problems.join('; ')}`);
    return null;
  }
  return { west, south, east, north, minH, maxH };
}

function regionInside(child, parent) {
  const out = [];
  if (child.west < parent.west - EPS_ANGLE) out.push(`west ${child.west} < parent's ${parent.west}`);
  if (child.east > parent.east + EPS_ANGLE) out.push(`east ${child.east} > parent's ${parent.east}`);
  if (child.south < parent.south - EPS_ANGLE) out.push(`south ${child.south} < parent's ${parent.south}`);
  if (child.north > parent.north + EPS_ANGLE) out.push(`north ${child.north} > parent's ${parent.north}`);
  if (child.minH < parent.minH - EPS_HEIGHT) out.push(`minimum height ${child.minH} < parent's ${parent.minH}`);
  if (child.maxH > parent.maxH + EPS_HEIGHT) out.push(`maximum height ${child.maxH} > parent's ${parent.maxH}`);
  return out;
}

// Resolves a content uri against the tileset file that names it; returns a
// path relative to DIR (posix) or throws with the reason.
function resolveUri(fromFile, uri) {
  if (typeof uri !== 'string' || uri === '') throw new Error(`content uri ${JSON.stringify(uri)} is not a non-empty string`);
  if (/^[a-z][a-z0-9+.-]*:/i.test(uri) || uri.startsWith('/')) throw new Error(`content uri '${uri}' is not a relative path`);
  if (/[?#]/.test(uri)) throw new Error(`content uri '${uri}' has a query or fragment`);
  const decoded = decodeURIComponent(uri);
  const rel = path.posix.normalize(path.posix.join(path.posix.dirname(fromFile), decoded));
  if (rel.startsWith('../') || rel === '..') throw new Error(`content uri '${uri}' points outside the tileset directory`);
  return rel;
}

// Walks every tileset JSON from `relFile`, checking the tree and collecting
// the GLB references: Map(rel path -> [{ label, region, transform, geometricError }]).
function walkTilesets(report, dir, stats) {
  const glbRefs = new Map();
  const visitedFiles = new Set();

  const loadTileset = (relFile, parent) => {
    if (visitedFiles.has(relFile)) { report.error(relFile, 'tileset file is referenced more than once (or a cycle)'); return; }
    visitedFiles.add(relFile);
    stats.tilesetFiles += 1;
    let tileset;
    try {
      tileset = JSON.parse(fs.readFileSync(path.join(dir, relFile), 'utf8'));
    } catch (e) {
      report.error(relFile, `cannot read tileset JSON: ${e.message}`);
      return;
    }
    const version = tileset.asset?.version;
    if (version !== '1.1' && version !== '1.0') report.error(relFile, `asset.version is ${JSON.stringify(version)}, expected "1.1" (or "1.0")`);
    if (!isNum(tileset.geometricError) || tileset.geometricError < 0)
      report.error(relFile, `tileset geometricError must be a number >= 0, got ${JSON.stringify(tileset.geometricError)}`);
    if (!tileset.root || typeof tileset.root !== 'object') { report.error(relFile, 'tileset has no root tile'); return; }
    if (isNum(tileset.geometricError) && isNum(tileset.root.geometricError) && tileset.geometricError < tileset.root.geometricError)
      report.error(relFile, `tileset geometricError ${tileset.geometricError} < root tile's ${tileset.root.geometricError}`);
    if (parent === null && tileset.root.refine === undefined) report.error(relFile, 'root: no refine (REPLACE or ADD) on the root tile');
    visitTile(tileset.root, relFile, 'root', parent);
  };

  const visitTile = (tile, relFile, label, parent) => {
    stats.tiles += 1;
    const where = `${label}`;
    if (!tile.boundingVolume) report.error(relFile, `${where}: no boundingVolume`);
    let region = null;
    if (tile.boundingVolume && tile.boundingVolume.region === undefined)
      report.error(relFile, `${where}: boundingVolume is not a region (tinsmith writes regions): ${Object.keys(tile.boundingVolume).join(', ')}`);
    else if (tile.boundingVolume) region = checkRegion(report, relFile, where, tile.boundingVolume.region);
    const ge = tile.geometricError;
    if (!isNum(ge) || ge < 0) report.error(relFile, `${where}: geometricError must be a number >= 0, got ${JSON.stringify(ge)}`);
    if (tile.refine !== undefined && tile.refine !== 'REPLACE' && tile.refine !== 'ADD')
      report.error(relFile, `${where}: refine is ${JSON.stringify(tile.refine)}, expected "REPLACE" or "ADD"`);
    if (parent) {
      if (region && parent.region) {
        const out = regionInside(region, parent.region);
        if (out.length) report.error(relFile, `${where}: region is not inside its parent's (${parent.label}): ${out.join('; ')}`);
      }
      if (isNum(ge) && isNum(parent.geometricError) && ge > parent.geometricError)
        report.error(relFile, `${where}: geometricError ${ge} > parent's ${parent.geometricError} (${parent.label})`);
    }
    let transform = parent ? parent.transform : IDENTITY;
    if (tile.transform !== undefined) {
      if (!Array.isArray(tile.transform) || tile.transform.length !== 16 || !tile.transform.every(isNum))
        report.error(relFile, `${where}: transform must be 16 finite numbers`);
      else transform = multiply(transform, tile.transform);
    }
    const me = { label: `${relFile}:${where}`, region, geometricError: isNum(ge) ? ge : null, transform };

    const contents = [];
    if (tile.content) contents.push(['content', tile.content]);
    if (Array.isArray(tile.contents)) tile.contents.forEach((c, i) => contents.push([`contents[${i}]`, c]));
    for (const [key, content] of contents) {
      const uri = content.uri ?? content.url;
      if (content.uri === undefined && content.url !== undefined) report.error(relFile, `${where}.${key}: uses 'url' (3D Tiles 1.0 pre-release), not 'uri'`);
      let rel;
      try { rel = resolveUri(relFile, uri); } catch (e) { report.error(relFile, `${where}.${key}: ${e.message}`); continue; }
      if (!fs.existsSync(path.join(dir, rel)) || !fs.statSync(path.join(dir, rel)).isFile()) {
        report.error(relFile, `${where}.${key}: content uri '${uri}' does not exist (${rel})`);
        continue;
      }
      if (content.boundingVolume?.region !== undefined && region) {
        const cr = checkRegion(report, relFile, `${where}.${key}.boundingVolume`, content.boundingVolume.region);
        const out = cr ? regionInside(cr, region) : [];
        if (out.length) report.error(relFile, `${where}.${key}: content region is not inside the tile's: ${out.join('; ')}`);
      }
      const ext = path.posix.extname(rel).toLowerCase();
      if (ext === '.json') loadTileset(rel, me);
      else if (ext === '.glb') {
        if (!glbRefs.has(rel)) glbRefs.set(rel, []);
        glbRefs.get(rel).push(me);
      } else report.warn(relFile, `${where}.${key}: content '${uri}' is neither .glb nor .json: not checked`);
    }
    if (tile.children !== undefined && !Array.isArray(tile.children)) report.error(relFile, `${where}: children is not an array`);
    (tile.children ?? []).forEach((child, i) => visitTile(child, relFile, `${label}.children[${i}]`, me));
  };

  if (!fs.existsSync(path.join(dir, 'tileset.json'))) report.error('tileset.json', 'does not exist');
  else loadTileset('tileset.json', null);
  return glbRefs;
}

function listGlbs(dir) {
  const out = [];
  const walk = (abs, rel) => {
    for (const e of fs.readdirSync(abs, { withFileTypes: true }).sort((a, b) => (a.name < b.name ? -1 : 1))) {
      const r = rel ? `${rel}/${e.name}` : e.name;
      if (e.isDirectory()) walk(path.join(abs, e.name), r);
      else if (e.name.toLowerCase().endsWith('.glb')) out.push(r);
    }
  };
  walk(dir, '');
  return out;
}

// Geometry of every primitive of a GLB, in ECEF-ready form: { primitives:
// [{ index, geometry, toWorld, normalToWorld, accessorProblems }] }. Decode
// failures are reported and the primitive skipped.
async function loadPrimitives(report, file, gltf, bin) {
  const out = [];
  let prims;
  try { prims = scenePrimitives(gltf); } catch (e) { report.error(file, e.message); return out; }
  if (prims.length === 0) report.error(file, 'the scene has no mesh primitive');
  for (const p of prims) {
    const label = `mesh ${p.mesh} primitive ${p.primitiveIndex}`;
    let geometry;
    try {
      geometry = await primitiveGeometry(gltf, bin, p.primitive);
    } catch (e) {
      report.error(file, `${label}: ${p.primitive.extensions?.KHR_draco_mesh_compression ? 'Draco: ' : ''}${e.message}`);
      continue;
    }
    const gltfToZUp = multiply(Y_UP_TO_Z_UP, p.matrix);
    out.push({ label, primitive: p.primitive, geometry, gltfToZUp, normalToZUp: normalMatrix(gltfToZUp) });
  }
  return out;
}

// Largest |coordinate| of the positions: sets the float32 rounding slack.
function maxAbs(values) {
  let m = 0;
  for (const v of values) m = Math.max(m, Math.abs(v));
  return m;
}

// Decoded data against the primitive's own accessors and basic sanity.
function checkPrimitiveData(report, file, gltf, prim, bound) {
  const { geometry: g, primitive, label } = prim;
  const nPoints = g.positions.length / 3;
  for (let i = 0; i < g.indices.length; ++i)
    if (g.indices[i] >= nPoints) { report.error(file, `${label}: index ${g.indices[i]} at ${i} >= vertex count ${nPoints}`); break; }
  if (!g.positions.every(Number.isFinite)) report.error(file, `${label}: non-finite positions`);
  const acc = (name) => (primitive.attributes?.[name] !== undefined ? gltf.accessors?.[primitive.attributes[name]] : undefined);
  const pos = acc('POSITION');
  if (pos && pos.count !== nPoints) report.error(file, `${label}: POSITION accessor count ${pos.count} != decoded vertex count ${nPoints}`);
  const nrm = acc('NORMAL');
  if (nrm && g.normals && nrm.count !== g.normals.length / 3) report.error(file, `${label}: NORMAL accessor count ${nrm.count} != decoded ${g.normals.length / 3}`);
  if (primitive.attributes?.NORMAL !== undefined && !g.normals) report.error(file, `${label}: NORMAL is declared but the Draco payload has none`);
  if (primitive.indices !== undefined) {
    const ia = gltf.accessors?.[primitive.indices];
    if (ia && ia.count !== g.indices.length) report.error(file, `${label}: indices accessor count ${ia.count} != decoded index count ${g.indices.length}`);
  }
  if (g.draco && pos && Array.isArray(pos.min) && Array.isArray(pos.max)) {
    const tol = bound + 1e-4 + FLOAT32_REL * maxAbs(g.positions);
    for (let c = 0; c < 3; ++c) {
      let lo = Infinity, hi = -Infinity;
      for (let i = c; i < g.positions.length; i += 3) { lo = Math.min(lo, g.positions[i]); hi = Math.max(hi, g.positions[i]); }
      if (Math.abs(lo - pos.min[c]) > tol || Math.abs(hi - pos.max[c]) > tol)
        report.error(file, `${label}: POSITION accessor min/max [${pos.min[c]}, ${pos.max[c]}] on axis ${c} does not match the decoded [${lo}, ${hi}] (tolerance ${tol.toExponential(2)} m)`);
    }
  }
  if (g.draco && g.normals) {
    let bad = 0;
    for (let i = 0; i < g.normals.length; i += 3)
      if (Math.abs(Math.hypot(g.normals[i], g.normals[i + 1], g.normals[i + 2]) - 1) > 0.01) ++bad;
    if (bad) report.error(file, `${label}: ${bad} decoded normals are not unit length`);
  }
}

// Content positions in ECEF must lie in every referencing tile's region.
function checkContentInRegion(report, file, prim, refs, bound) {
  const g = prim.geometry;
  const eps = bound + EPS_CONTENT + FLOAT32_REL * maxAbs(g.positions);
  for (const ref of refs) {
    if (!ref.region) continue;
    const toEcef = multiply(ref.transform, prim.gltfToZUp);
    const r = ref.region;
    let outside = 0, worst = 0, worstAt = -1, worstWhat = '';
    for (let i = 0; i < g.positions.length; i += 3) {
      const [x, y, z] = transformPoint(toEcef, g.positions[i], g.positions[i + 1], g.positions[i + 2]);
      const { lon, lat, h } = ecefToGeodetic(x, y, z);
      const lonScale = Math.max(WGS84_A * Math.cos(lat), 1); // m per rad of longitude
      const latScale = WGS84_A * 0.99; // m per rad of latitude, a lower bound
      const excess = [
        [(r.west - lon) * lonScale, 'west'], [(lon - r.east) * lonScale, 'east'],
        [(r.south - lat) * latScale, 'south'], [(lat - r.north) * latScale, 'north'],
        [r.minH - h, 'below minimum height'], [h - r.maxH, 'above maximum height'],
      ];
      for (const [e, what] of excess)
        if (e > eps) {
          if (e > worst) { worst = e; worstAt = i / 3; worstWhat = what; }
        }
      if (excess.some(([e]) => e > eps)) ++outside;
    }
    if (outside)
      report.error(file, `${prim.label}: ${outside} of ${g.positions.length / 3} vertices lie outside the region of ${ref.label} (worst: vertex ${worstAt}, ${worst.toFixed(3)} m ${worstWhat}; tolerance ${eps.toFixed(4)} m)`);
  }
}

function checkExtras(report, file, gltf, refs, isDraco) {
  const t = gltf.asset?.extras?.tinsmith;
  if (!t || typeof t !== 'object') { report.error(file, 'asset.extras.tinsmith is missing'); return { bound: null, tile: null }; }
  const m = /^tiles\/(\d+)\/(\d+)\/(\d+)\.glb$/.exec(file);
  if (!Array.isArray(t.tile) || t.tile.length !== 3 || !t.tile.every(Number.isInteger))
    report.error(file, `asset.extras.tinsmith.tile must be [z, x, y] integers, got ${JSON.stringify(t.tile)}`);
  else if (m && (t.tile[0] !== +m[1] || t.tile[1] !== +m[2] || t.tile[2] !== +m[3]))
    report.error(file, `asset.extras.tinsmith.tile ${JSON.stringify(t.tile)} does not match the file's path`);
  if (!isNum(t.geometricError)) report.error(file, `asset.extras.tinsmith.geometricError must be a number, got ${JSON.stringify(t.geometricError)}`);
  else for (const ref of refs)
    // The tile's own measured error; the tileset may declare more (an error
    // never grows down the tree, so a parent declares at least its children's).
    if (ref.geometricError !== null && t.geometricError > ref.geometricError + 1e-9 * Math.max(1, Math.abs(t.geometricError)))
      report.error(file, `asset.extras.tinsmith.geometricError ${t.geometricError} > ${ref.label} geometricError ${ref.geometricError}`);
  let bound = null;
  if (t.positionErrorBound !== undefined) {
    if (!isNum(t.positionErrorBound) || t.positionErrorBound < 0)
      report.error(file, `asset.extras.tinsmith.positionErrorBound must be a number >= 0, got ${JSON.stringify(t.positionErrorBound)}`);
    else bound = t.positionErrorBound;
  } else if (isDraco) report.error(file, 'asset.extras.tinsmith.positionErrorBound is missing (required for Draco tiles)');
  return { bound, tile: t.tile };
}

async function checkGlb(report, opts, file, refs, stats) {
  const bytes = new Uint8Array(fs.readFileSync(path.join(opts.dir, file)));
  const result = await validator.validateBytes(bytes, {
    uri: file, maxIssues: 0,
    externalResourceFunction: (uri) => Promise.reject(new Error(`external resource '${uri}' (tiles must be self-contained)`)),
  });
  const issues = result.issues;
  stats.validator.errors += issues.numErrors; stats.validator.warnings += issues.numWarnings;
  stats.validator.infos += issues.numInfos; stats.validator.hints += issues.numHints;
  for (const msg of issues.messages) {
    const text = `glTF validator ${msg.code} at ${msg.pointer ?? msg.offset ?? '?'}: ${msg.message}`;
    if (msg.severity === 0) report.error(file, text);
    else if (msg.severity === 1) report.warn(file, text);
  }
  let gltf, bin;
  try { ({ json: gltf, bin } = parseGlb(bytes)); } catch (e) { report.error(file, e.message); return; }
  const isDraco = (gltf.extensionsUsed ?? []).includes('KHR_draco_mesh_compression');
  if (refs.length === 0) report.warn(file, 'not referenced by any tile');
  const { bound } = checkExtras(report, file, gltf, refs, isDraco);
  const prims = await loadPrimitives(report, file, gltf, bin);
  for (const prim of prims) {
    const b = prim.geometry.draco ? (bound ?? 0) : 0;
    checkPrimitiveData(report, file, gltf, prim, b);
    checkContentInRegion(report, file, prim, refs, b);
    stats.triangles += prim.geometry.indices.length / 3;
  }
  if (opts.plain) {
    const plainPath = path.join(opts.plain, file);
    if (!fs.existsSync(plainPath)) { report.error(file, `no plain twin ${plainPath}`); return; }
    let plain;
    try { plain = parseGlb(new Uint8Array(fs.readFileSync(plainPath))); } catch (e) { report.error(file, `plain twin: ${e.message}`); return; }
    const pt = plain.json.asset?.extras?.tinsmith?.tile;
    const dt = gltf.asset?.extras?.tinsmith?.tile;
    if (JSON.stringify(pt) !== JSON.stringify(dt)) report.error(file, `plain twin names tile ${JSON.stringify(pt)}, this one ${JSON.stringify(dt)}`);
    const plainReport = new Report();
    const plainPrims = await loadPrimitives(plainReport, file, plain.json, plain.bin);
    for (const e of plainReport.errors) report.error(file, `plain twin: ${e.message}`);
    if (plainPrims.length !== prims.length) {
      report.error(file, `${prims.length} primitives, the plain twin ${plainPrims.length}`);
      return;
    }
    prims.forEach((prim, i) => {
      const b = prim.geometry.draco ? (bound ?? 0) : 0;
      const { messages, positionError, normalAngle } = comparePrimitives(prim, plainPrims[i], b);
      for (const message of messages) report.error(file, `${prim.label} vs plain: ${message}`);
      const h = stats.headroom;
      h.positionError = Math.max(h.positionError, positionError);
      if (b > 0) h.positionErrorOverBound = Math.max(h.positionErrorOverBound, positionError / b);
      h.normalAngle = Math.max(h.normalAngle, normalAngle);
    });
    stats.comparedWithPlain += 1;
  }
}

async function main() {
  const opts = parseArgs(process.argv.slice(2));
  if (!fs.existsSync(opts.dir) || !fs.statSync(opts.dir).isDirectory()) usage(`'${opts.dir}' is not a directory`);
  if (opts.plain && (!fs.existsSync(opts.plain) || !fs.statSync(opts.plain).isDirectory())) usage(`'${opts.plain}' is not a directory`);
  const report = new Report();
  const stats = {
    tilesetFiles: 0, tiles: 0, glbFiles: 0, triangles: 0, comparedWithPlain: 0,
    headroom: { positionError: 0, positionErrorOverBound: 0, normalAngle: 0 }, // worst matched, against the plain twin
    validator: { errors: 0, warnings: 0, infos: 0, hints: 0 },
  };
  const glbRefs = walkTilesets(report, opts.dir, stats);
  const glbs = listGlbs(opts.dir);
  for (const file of glbs) {
    stats.glbFiles += 1;
    await checkGlb(report, opts, file, glbRefs.get(file) ?? [], stats);
  }
  const ok = report.errors.length === 0;
  const log = opts.json ? console.error : console.log;
  for (const w of report.warnings) log(`warning: ${w.file}: ${w.message}`);
  for (const e of report.errors) log(`ERROR: ${e.file}: ${e.message}`);
  if (opts.plain)
    log(`check_tiles: against the plain twin, worst matched position error ${stats.headroom.positionError.toPrecision(3)} m ` +
      `(${(stats.headroom.positionErrorOverBound * 100).toFixed(0)} % of positionErrorBound), worst normal ${stats.headroom.normalAngle.toFixed(2)}°`);
  log(`check_tiles: ${stats.glbFiles} tiles checked (${stats.triangles} triangles; ${stats.tiles} tiles in ${stats.tilesetFiles} tileset files` +
    `${opts.plain ? `; ${stats.comparedWithPlain} compared with ${opts.plain}` : ''}): ${report.errors.length} errors, ${report.warnings.length} warnings; ` +
    `validator: ${stats.validator.errors} errors, ${stats.validator.warnings} warnings, ${stats.validator.infos} infos`);
  if (opts.json)
    console.log(JSON.stringify({ ok, dir: opts.dir, plain: opts.plain, ...stats, errors: report.errors, warnings: report.warnings }, null, 1));
  process.exitCode = ok ? 0 : 1;
}

main().catch((e) => { console.error(`ERROR: check_tiles: ${e.stack ?? e}`); process.exit(1); });
