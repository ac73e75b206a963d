#!/usr/bin/env node
// Checks a whole-TIN glb from `tinsmith export --format glb` independently of
// the exporter:
//
//   node tests/js/check_glb.mjs FILE.glb [--plain PLAIN.glb]
//
// The Khronos glTF validator reports no error; the one primitive decodes
// (Draco with draco3dgltf); asset.extras.tinsmith names the frame and counts
// that agree with the decoded data (vertices, triangles). An ecef export,
// taken to ECEF (node matrix, then the y-up -> z-up turn), lies on the Earth
// (heights -500 to 9000 m above the WGS84 ellipsoid); a local one carries a
// whole-metre offset. With --plain, the file is compared with its
// uncompressed twin (same frame): same triangle count, positions within
// extras.tinsmith.positionErrorBound (+ float32 slack) both ways, triangles
// matched by centroid and winding, normals within 2 degrees.
// Exit status 0 when nothing is wrong, 1 on any error, 2 on bad usage.
import fs from 'node:fs';
import validator from 'gltf-validator';
import { parseGlb, primitiveGeometry, scenePrimitives } from './glb.mjs';
import { ecefToGeodetic, multiply, normalMatrix, transformPoint, Y_UP_TO_Z_UP } from './geodesy.mjs';
import { comparePrimitives } from './compare_meshes.mjs';

function usage(message) {
  if (message) console.error(`check_glb: ${message}`);
  console.error('usage: node check_glb.mjs FILE.glb [--plain PLAIN.glb]');
  process.exit(2);
}

const args = process.argv.slice(2);
let file = null, plain = null;
for (let i = 0; i < args.length; ++i) {
  if (args[i] === '--plain') { plain = args[++i]; if (!plain) usage('--plain needs a file'); }
  else if (args[i].startsWith('-')) usage(`unknown option '${args[i]}'`);
  else if (file === null) file = args[i];
  else usage(`unexpected argument '${args[i]}'`);
}
if (!file) usage('FILE.glb is required');

const errors = [];
const error = (where, message) => errors.push(`${where}: ${message}`);

async function load(name) {
  const bytes = new Uint8Array(fs.readFileSync(name));
  const result = await validator.validateBytes(bytes, {
    uri: name, maxIssues: 0,
    externalResourceFunction: (uri) => Promise.reject(new Error(`external resource '${uri}' (the glb must be self-contained)`)),
  });
  for (const msg of result.issues.messages) {
    if (msg.severity === 0) error(name, `glTF validator ${msg.code} at ${msg.pointer ?? msg.offset ?? '?'}: ${msg.message}`);
  }
  const { json: gltf, bin } = parseGlb(bytes);
  const prims = scenePrimitives(gltf);
  if (prims.length !== 1) { error(name, `${prims.length} primitives, expected one`); return null; }
  const geometry = await primitiveGeometry(gltf, bin, prims[0].primitive);
  const gltfToZUp = multiply(Y_UP_TO_Z_UP, prims[0].matrix);
  const extras = gltf.asset?.extras?.tinsmith;
  if (!extras) { error(name, 'asset.extras.tinsmith is missing'); return null; }
  const vertices = geometry.positions.length / 3, triangles = geometry.indices.length / 3;
  if (vertices !== extras.vertices) error(name, `${vertices} positions decoded, extras say ${extras.vertices} vertices`);
  if (triangles !== extras.triangles) error(name, `${triangles} triangles decoded, extras say ${extras.triangles}`);
  if (!(extras.positionErrorBound > 0)) error(name, `positionErrorBound ${extras.positionErrorBound} is not positive`);
  if (extras.frame === 'ecef') {
    let lo = Infinity, hi = -Infinity;
    for (let i = 0; i < geometry.positions.length; i += 3) {
      const p = transformPoint(gltfToZUp, geometry.positions[i], geometry.positions[i + 1], geometry.positions[i + 2]);
      const h = ecefToGeodetic(p[0], p[1], p[2]).h;
      lo = Math.min(lo, h); hi = Math.max(hi, h);
    }
    if (!(lo > -500 && hi < 9000)) error(name, `heights ${lo.toFixed(1)} to ${hi.toFixed(1)} m: not on the Earth`);
  } else if (extras.frame === 'local') {
    if (!Array.isArray(extras.offset) || extras.offset.length !== 3 || !extras.offset.every(Number.isInteger))
      error(name, `offset ${JSON.stringify(extras.offset)} is not three whole metres`);
  } else {
    error(name, `frame '${extras.frame}' is neither ecef nor local`);
  }
  return { name, extras, draco: Boolean(geometry.draco), bytes: bytes.length, vertices, triangles,
           prim: { geometry, gltfToZUp, normalToZUp: normalMatrix(gltfToZUp) } };
}

const main = await load(file);
let summary = main ? `${main.vertices} vertices, ${main.triangles} triangles, ${main.draco ? 'Draco' : 'plain'}, ${main.bytes} bytes` : '';
if (main && plain) {
  const twin = await load(plain);
  if (twin) {
    if (twin.draco) error(plain, 'the --plain twin is Draco-compressed');
    if (twin.extras.frame !== main.extras.frame) error(plain, `frame ${twin.extras.frame}, not ${main.extras.frame}`);
    const { messages, positionError, normalAngle } = comparePrimitives(main.prim, twin.prim, main.extras.positionErrorBound);
    for (const m of messages) error(file, `against ${plain}: ${m}`);
    summary += `; against the plain twin: positions within ${positionError.toExponential(2)} m (bound ${main.extras.positionErrorBound}), normals within ${normalAngle.toFixed(2)}°`;
  }
}
for (const e of errors) console.log(`ERROR: ${e}`);
console.log(`check_glb: ${file}: ${summary}; ${errors.length} errors`);
process.exit(errors.length ? 1 : 0);
