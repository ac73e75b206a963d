#!/usr/bin/env node
// Draws each zoom of a tinsmith directory store as a plan view of its mesh:
//
//   node tests/js/draw_zooms.mjs STORE_DIR OUT_PREFIX [--width 700] [--detail E,N,SIZE] [--svg] [--rgb]
//
// Reads STORE_DIR/tileset.json (and any external tileset below it) and every
// .glb it names (plain accessors or Draco, decoded with draco3dgltf), takes
// the positions to ECEF as the checkers do (node matrices, the y-up -> z-up
// turn, tile transforms) and then to a local east/north plane tangent at the
// centre of the root region. One picture per zoom, all of that zoom's tiles:
// triangles filled by height (a hypsometric ramp times a hillshade lit from
// the north-west, one flat colour per triangle so the facets show), their
// edges as thin dark lines, tile sides in red (the top edges of the skirts),
// the data's own boundary in black. Skirt triangles (vertical, hanging below
// the tile sides) are left out of the fill and the edges. The caption gives
// the zoom, its tolerance (from STORE_DIR/tinsmith/build.json when present),
// the tiles, the surface and skirt triangles and the measured max error
// (asset.extras.tinsmith.geometricError of the tiles). An inset enlarges a
// square (--detail E,N,SIZE in metres from the root region's centre; by
// default the seventh of the width with the most triangles of the finest
// zoom), the same square in every zoom, placed where no zoom has data.
// The SVG is rasterized by Debian's Chromium (headless, playwright-core) and
// written as a 256-colour PNG, OUT_PREFIX{z}.png (--rgb: Chromium's own PNG);
// --svg keeps OUT_PREFIX{z}.svg as well. A drawing tool, not a checker.
// Exit status 0 on success, 1 on failure, 2 on bad usage.
import fs from 'node:fs';
import path from 'node:path';
import zlib from 'node:zlib';
import { chromium } from 'playwright-core';
import { parseGlb, primitiveGeometry, scenePrimitives } from './glb.mjs';
import { decodePng } from './png.mjs';
import {
  ecefToGeodetic, geodeticToEcef, IDENTITY, multiply, transformPoint, Y_UP_TO_Z_UP,
} from './geodesy.mjs';

const CHROMIUM = '/usr/bin/chromium';
const SKIRT_RATIO = 1e-3; // plan area / 3D area below this: a vertical (skirt) triangle
const LIGHT = (() => { // from the north-west, 45 degrees up
  const az = (315 * Math.PI) / 180, alt = (45 * Math.PI) / 180;
  return [Math.cos(alt) * Math.sin(az), Math.cos(alt) * Math.cos(az), Math.sin(alt)];
})();
// Hypsometric ramp over the store's height range: valley green to rock to snow.
const RAMP = [
  [0.0, [92, 145, 88]], [0.25, [160, 180, 112]], [0.5, [204, 178, 120]],
  [0.75, [168, 128, 96]], [1.0, [236, 232, 226]],
];
const HEIGHT_BINS = 48;
const SHADE_BINS = 24;

function usage(message) {
  if (message) console.error(`draw_zooms: ${message}`);
  console.error('usage: node draw_zooms.mjs STORE_DIR OUT_PREFIX [--width PIXELS] [--detail E,N,SIZE] [--svg] [--rgb]');
  process.exit(2);
}

function parseArgs(argv) {
  const opts = { dir: null, prefix: null, width: 700, svg: false, detail: null, rgb: false };
  for (let i = 0; i < argv.length; ++i) {
    const a = argv[i];
    if (a === '--width') opts.width = Number(argv[++i]);
    else if (a === '--svg') opts.svg = true;
    else if (a === '--rgb') opts.rgb = true;
    else if (a === '--detail') {
      opts.detail = String(argv[++i]).split(',').map(Number);
      if (opts.detail.length !== 3 || !opts.detail.every(Number.isFinite) || !(opts.detail[2] > 0))
        usage('--detail needs E,N,SIZE in metres (east and north of the centre of the root region)');
    }
    else if (a === '-h' || a === '--help') usage();
    else if (a.startsWith('-')) usage(`unknown option '${a}'`);
    else if (opts.dir === null) opts.dir = a;
    else if (opts.prefix === null) opts.prefix = a;
    else usage(`unexpected argument '${a}'`);
  }
  if (!opts.dir || !opts.prefix) usage('STORE_DIR and OUT_PREFIX are required');
  if (!(opts.width >= 200 && opts.width <= 4000)) usage('--width must be within [200, 4000]');
  return opts;
}

// Every .glb content reached from tileset.json: [{ rel, transform }].
function collectContents(dir) {
  const out = [];
  const load = (relFile, transform) => {
    const tileset = JSON.parse(fs.readFileSync(path.join(dir, relFile), 'utf8'));
    const visit = (tile, parentTransform) => {
      const t = tile.transform ? multiply(parentTransform, tile.transform) : parentTransform;
      const contents = [tile.content, ...(tile.contents ?? [])].filter(Boolean);
      for (const c of contents) {
        const rel = path.posix.normalize(path.posix.join(path.posix.dirname(relFile), decodeURIComponent(c.uri ?? c.url)));
        if (rel.endsWith('.json')) load(rel, t);
        else if (rel.endsWith('.glb')) out.push({ rel, transform: t });
      }
      for (const child of tile.children ?? []) visit(child, t);
    };
    visit(tileset.root, transform);
    return tileset;
  };
  const top = load('tileset.json', IDENTITY);
  return { top, contents: out };
}

// The local frame: east/north/up at a geodetic point (h = 0).
function enuFrame(lon, lat) {
  const o = geodeticToEcef(lon, lat, 0);
  const sl = Math.sin(lon), cl = Math.cos(lon), sp = Math.sin(lat), cp = Math.cos(lat);
  return (x, y, z) => {
    const dx = x - o[0], dy = y - o[1], dz = z - o[2];
    return [-sl * dx + cl * dy, -sp * cl * dx - sp * sl * dy + cp * dz, cp * cl * dx + cp * sl * dy + sp * dz];
  };
}

const key = (p) => `${Math.round(p[0] * 1000)},${Math.round(p[1] * 1000)},${Math.round(p[2] * 1000)}`;

// One tile: its surface triangles (plan coordinates, height, shade), edges,
// tile-side edges and data-boundary edges.
async function readTile(dir, content, toEnu) {
  const { json, bin } = parseGlb(fs.readFileSync(path.join(dir, content.rel)));
  const record = json.asset?.extras?.tinsmith ?? {};
  let zoom = Array.isArray(record.tile) ? record.tile[0] : null;
  if (zoom === null) {
    const m = /(?:^|\/)tiles\/(\d+)\/\d+\/\d+\.glb$/.exec(content.rel);
    if (!m) throw new Error(`${content.rel}: no asset.extras.tinsmith.tile and not a tiles/z/x/y.glb path`);
    zoom = Number(m[1]);
  }
  const tile = { rel: content.rel, zoom, record, surface: [], edges: [], sides: [], boundary: [], skirts: 0 };
  for (const prim of scenePrimitives(json)) {
    const g = await primitiveGeometry(json, bin, prim.primitive);
    const toEcef = multiply(content.transform, multiply(Y_UP_TO_Z_UP, prim.matrix));
    const n = g.positions.length / 3;
    const enu = new Array(n);
    const height = new Float64Array(n);
    for (let i = 0; i < n; ++i) {
      const p = transformPoint(toEcef, g.positions[3 * i], g.positions[3 * i + 1], g.positions[3 * i + 2]);
      enu[i] = toEnu(p[0], p[1], p[2]);
      height[i] = ecefToGeodetic(p[0], p[1], p[2]).h;
    }
    const surfaceTriangles = [];
    const skirtTriangles = [];
    for (let t = 0; t < g.indices.length; t += 3) {
      const [a, b, c] = [g.indices[t], g.indices[t + 1], g.indices[t + 2]];
      const [pa, pb, pc] = [enu[a], enu[b], enu[c]];
      const u = [pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]];
      const v = [pc[0] - pa[0], pc[1] - pa[1], pc[2] - pa[2]];
      const nx = u[1] * v[2] - u[2] * v[1], ny = u[2] * v[0] - u[0] * v[2], nz = u[0] * v[1] - u[1] * v[0];
      const area3 = Math.hypot(nx, ny, nz);
      if (!(Math.abs(nz) > SKIRT_RATIO * area3)) { skirtTriangles.push([a, b, c]); continue; }
      const s = nz > 0 ? 1 : -1; // upward normal
      const shade = Math.max(0, (s * (nx * LIGHT[0] + ny * LIGHT[1] + nz * LIGHT[2])) / area3);
      surfaceTriangles.push([a, b, c]);
      tile.surface.push({
        pts: [pa[0], pa[1], pb[0], pb[1], pc[0], pc[1]],
        h: (height[a] + height[b] + height[c]) / 3, shade,
      });
    }
    tile.skirts += skirtTriangles.length;
    // Surface edges by vertex position (Draco may split vertices), with
    // their use counts; the top edges of skirts are the tile sides.
    const edgeUses = new Map();
    const top = new Set();
    for (const tri of surfaceTriangles) {
      for (let i = 0; i < 3; ++i) {
        const a = tri[i], b = tri[(i + 1) % 3];
        const ka = key(enu[a]), kb = key(enu[b]);
        top.add(ka);
        const k = ka < kb ? `${ka}|${kb}` : `${kb}|${ka}`;
        const e = edgeUses.get(k);
        if (e) e.uses += 1;
        else edgeUses.set(k, { a: enu[a], b: enu[b], uses: 1 });
      }
    }
    const sideKeys = new Set();
    for (const tri of skirtTriangles) {
      for (let i = 0; i < 3; ++i) {
        const ka = key(enu[tri[i]]), kb = key(enu[tri[(i + 1) % 3]]);
        if (top.has(ka) && top.has(kb) && ka !== kb) sideKeys.add(ka < kb ? `${ka}|${kb}` : `${kb}|${ka}`);
      }
    }
    for (const [k, e] of edgeUses) {
      const seg = [e.a[0], e.a[1], e.b[0], e.b[1]];
      if (sideKeys.has(k)) tile.sides.push(seg);
      else if (e.uses === 1) tile.boundary.push(seg);
      else tile.edges.push(seg);
    }
  }
  return tile;
}

function rampColour(f) {
  f = Math.min(1, Math.max(0, f));
  for (let i = 1; i < RAMP.length; ++i) {
    const [f1, c1] = RAMP[i];
    const [f0, c0] = RAMP[i - 1];
    if (f <= f1) {
      const t = (f - f0) / (f1 - f0);
      return c0.map((v, j) => v + t * (c1[j] - v));
    }
  }
  return RAMP[RAMP.length - 1][1];
}

const hex = (c) => '#' + c.map((v) => Math.round(Math.min(255, Math.max(0, v))).toString(16).padStart(2, '0')).join('');
const fmt = (n, digits = 0) => n.toLocaleString('en-GB', { minimumFractionDigits: digits, maximumFractionDigits: digits }).replace(/,/g, '\u2009');

// One zoom's SVG: the overview, and the detail square enlarged in the inset
// (an empty place on the map, or below it).
function zoomSvg(zoom, tiles, view, info) {
  const { width, scale, e0, n1, mapHeight, hMin, hMax, detail } = view;
  const X = (e) => ((e - e0) * scale).toFixed(1);
  const Y = (n) => ((n1 - n) * scale + view.top).toFixed(1);
  // Fills grouped by quantized colour: one path per colour.
  const groups = new Map();
  let surface = 0, skirts = 0, maxError = -Infinity, inDetail = 0;
  const [de0, dn0, de1, dn1] = [detail.e - detail.size / 2, detail.n - detail.size / 2, detail.e + detail.size / 2, detail.n + detail.size / 2];
  for (const t of tiles) {
    surface += t.surface.length;
    skirts += t.skirts;
    if (Number.isFinite(t.record.geometricError)) maxError = Math.max(maxError, t.record.geometricError);
    for (const tri of t.surface) {
      const hb = Math.min(HEIGHT_BINS - 1, Math.floor(((tri.h - hMin) / (hMax - hMin || 1)) * HEIGHT_BINS));
      const sb = Math.min(SHADE_BINS - 1, Math.floor(tri.shade * SHADE_BINS));
      const k = hb * SHADE_BINS + sb;
      let d = groups.get(k);
      if (!d) groups.set(k, (d = []));
      const p = tri.pts;
      d.push(`M${X(p[0])} ${Y(p[1])}L${X(p[2])} ${Y(p[3])}L${X(p[4])} ${Y(p[5])}Z`);
      const ce = (p[0] + p[2] + p[4]) / 3, cn = (p[1] + p[3] + p[5]) / 3;
      if (ce >= de0 && ce < de1 && cn >= dn0 && cn < dn1) ++inDetail;
    }
  }
  const fills = [];
  for (const [k, d] of groups) {
    const hb = Math.floor(k / SHADE_BINS), sb = k % SHADE_BINS;
    const base = rampColour((hb + 0.5) / HEIGHT_BINS);
    const light = 0.45 + 0.8 * ((sb + 0.5) / SHADE_BINS);
    const c = hex(base.map((v) => v * light));
    fills.push(`<path fill="${c}" stroke="${c}" d="${d.join('')}"/>`);
  }
  const segs = (list) => list.map((s) => `M${X(s[0])} ${Y(s[1])}L${X(s[2])} ${Y(s[3])}`).join('');
  const edges = tiles.map((t) => segs(t.edges)).join('');
  const boundary = tiles.map((t) => segs(t.boundary)).join('');
  const sides = tiles.map((t) => segs(t.sides)).join('');
  // Edge width: thinner as triangles get denser (mean edge length in pixels).
  const meanEdgePx = Math.sqrt((view.areaM2 * scale * scale) / Math.max(1, surface)) * 1.5;
  const edgeWidth = Math.max(0.25, Math.min(0.6, meanEdgePx / 25));
  const edgeOpacity = Math.max(0.35, Math.min(0.7, meanEdgePx / 20));
  const tol = info.tolerance !== null ? `tolerance ${fmt(info.tolerance * 2 ** (info.finestZoom - zoom), info.tolerance < 1 ? 2 : 1)} m · ` : '';
  const line1 = `zoom ${zoom} · ${tol}${tiles.length} tile${tiles.length === 1 ? '' : 's'} · ` +
    `${fmt(surface)} triangles (+ ${fmt(skirts)} in skirts) · max error ${Number.isFinite(maxError) ? fmt(maxError, 3) : '?'} m`;
  const line2 = `${info.name}: red tile sides, black data boundary, fill by height ${fmt(hMin)}–${fmt(hMax)} m (WGS84), lit from the NW`;
  // Scale bar: the largest of 1, 2, 5 × 10^k metres under a quarter of the width.
  const bar = (px, s) => {
    const target = px / s;
    const pow = 10 ** Math.floor(Math.log10(target));
    const m = [5, 2, 1].map((v) => v * pow).find((v) => v <= target);
    return { px: m * s, label: m >= 1000 ? `${m / 1000} km` : `${m} m` };
  };
  const main = bar(width / 4, scale);
  const inset = view.inset;
  const by = Math.max(view.top + mapHeight, inset.below ? inset.y + inset.size : 0) + 18;
  const height = by + 22;
  // The detail square in overview pixels, and the inset's magnification.
  const dx = Number(X(de0)), dy = Number(Y(dn1)), dpx = detail.size * scale;
  const mag = inset.size / dpx;
  const ibar = bar(inset.size / 3, scale * mag);
  const defs = `<defs>
<g id="fills" stroke-width="0.3">${fills.join('\n')}</g>
<path id="edges" fill="none" vector-effect="non-scaling-stroke" d="${edges}"/>
<path id="boundary" fill="none" vector-effect="non-scaling-stroke" d="${boundary}"/>
<path id="sides" fill="none" stroke-linecap="round" vector-effect="non-scaling-stroke" d="${sides}"/>
<clipPath id="insetClip"><rect x="${dx}" y="${dy}" width="${dpx.toFixed(1)}" height="${dpx.toFixed(1)}"/></clipPath>
</defs>`;
  const layers = (ew, eo) => `<use href="#fills" shape-rendering="crispEdges"/>
<use href="#edges" stroke="#202020" stroke-opacity="${eo.toFixed(2)}" stroke-width="${ew.toFixed(2)}"/>
<use href="#boundary" stroke="#000000" stroke-width="1.1"/>
<use href="#sides" stroke="#d01c1c" stroke-width="1.6"/>`;
  return {
    height,
    svg: `<svg xmlns="http://www.w3.org/2000/svg" width="${width}" height="${height}" viewBox="0 0 ${width} ${height}" font-family="DejaVu Sans, sans-serif">
${defs}
<rect width="${width}" height="${height}" fill="#ffffff"/>
<text x="8" y="18" font-size="13" font-weight="bold" fill="#202020">${line1}</text>
<text x="8" y="36" font-size="11" fill="#404040">${line2}</text>
${layers(edgeWidth, edgeOpacity)}
<rect x="${dx}" y="${dy}" width="${dpx.toFixed(1)}" height="${dpx.toFixed(1)}" fill="none" stroke="#1a4fd0" stroke-width="1.5"/>
<svg x="${inset.x}" y="${inset.y}" width="${inset.size}" height="${inset.size}" viewBox="${dx} ${dy} ${dpx.toFixed(2)} ${dpx.toFixed(2)}">
<rect x="${dx}" y="${dy}" width="${dpx.toFixed(1)}" height="${dpx.toFixed(1)}" fill="#ffffff"/>
<g clip-path="url(#insetClip)">${layers(0.5, 0.75)}</g>
</svg>
<rect x="${inset.x}" y="${inset.y}" width="${inset.size}" height="${inset.size}" fill="none" stroke="#1a4fd0" stroke-width="2"/>
<g fill="#202020" font-size="11">
<text x="${inset.x}" y="${inset.y - 5}">detail ×${mag.toFixed(1)}: ${fmt(inDetail)} triangles</text>
<rect x="${inset.x + 6}" y="${inset.y + inset.size - 12}" width="${ibar.px.toFixed(1)}" height="4" fill="#ffffff" stroke="#202020" stroke-width="0.8"/>
<text x="${(inset.x + 10 + ibar.px).toFixed(1)}" y="${inset.y + inset.size - 6}" stroke="#ffffff" stroke-width="3" paint-order="stroke">${ibar.label}</text>
<rect x="8" y="${by}" width="${main.px.toFixed(1)}" height="4"/>
<text x="${(8 + main.px + 6).toFixed(1)}" y="${by + 6}">${main.label}</text>
<text x="${width - 34}" y="${by + 8}">N</text>
<path d="M${width - 20} ${by + 10}L${width - 20} ${by - 8}M${width - 25} ${by - 2}L${width - 20} ${by - 10}L${width - 15} ${by - 2}" fill="none" stroke="#202020" stroke-width="1.5"/>
</g>
</svg>`,
    stats: { zoom, tiles: tiles.length, surface, skirts, maxError, inDetail },
  };
}

// A screenshot (png.mjs decoded) -> an 8-bit palette PNG: 256 colours by
// variance splits of the pixel histogram, nearest colour per pixel, no dithering
// (flat fills and thin lines need none), zlib level 9. About a third of the
// size of Chromium's RGB PNG for these pictures.
function palettePng(img) {
  const { width, height, channels, data } = img;
  const n = width * height;
  const rgb = new Uint32Array(n);
  const counts = new Map();
  for (let i = 0; i < n; ++i) {
    const o = i * channels;
    const c = (data[o] << 16) | (data[o + 1] << 8) | data[o + 2];
    rgb[i] = c;
    counts.set(c, (counts.get(c) ?? 0) + 1);
  }
  const colours = [...counts.entries()].map(([c, w]) => [(c >> 16) & 255, (c >> 8) & 255, c & 255, w]);
  // Split the box with the largest weighted squared error along its widest
  // channel (by variance) at the weighted mean.
  const stats = (box) => {
    let w = 0; const m = [0, 0, 0], q = [0, 0, 0];
    for (const c of box) { w += c[3]; for (let ch = 0; ch < 3; ++ch) { m[ch] += c[ch] * c[3]; q[ch] += c[ch] * c[ch] * c[3]; } }
    const mean = m.map((v) => v / w), vari = q.map((v, ch) => v - w * mean[ch] * mean[ch]);
    const ch = vari.indexOf(Math.max(...vari));
    return { box, mean, ch, sse: box.length < 2 ? 0 : vari[0] + vari[1] + vari[2] };
  };
  const boxes = [stats(colours)];
  while (boxes.length < 256) {
    let bi = 0;
    boxes.forEach((b, i) => { if (b.sse > boxes[bi].sse) bi = i; });
    const { box, mean, ch, sse } = boxes[bi];
    if (!(sse > 0)) break;
    const lo = box.filter((c) => c[ch] <= mean[ch]), hi = box.filter((c) => c[ch] > mean[ch]);
    if (!lo.length || !hi.length) { boxes[bi].sse = 0; continue; }
    boxes.splice(bi, 1, stats(lo), stats(hi));
  }
  const palette = boxes.map((b) => b.mean.map(Math.round));
  const index = new Map();
  for (const [c] of counts) {
    const r = (c >> 16) & 255, g = (c >> 8) & 255, b = c & 255;
    let best = 0, bd = Infinity;
    palette.forEach((p, i) => { const d = (p[0] - r) ** 2 + (p[1] - g) ** 2 + (p[2] - b) ** 2; if (d < bd) { bd = d; best = i; } });
    index.set(c, best);
  }
  const raw = Buffer.alloc((width + 1) * height);
  for (let y = 0; y < height; ++y) for (let x = 0; x < width; ++x) raw[y * (width + 1) + 1 + x] = index.get(rgb[y * width + x]);
  const crcTable = Array.from({ length: 256 }, (_, k) => { let c = k; for (let i = 0; i < 8; ++i) c = c & 1 ? 0xedb88320 ^ (c >>> 1) : c >>> 1; return c >>> 0; });
  const crc = (buf) => { let c = 0xffffffff; for (const b of buf) c = crcTable[(c ^ b) & 255] ^ (c >>> 8); return (c ^ 0xffffffff) >>> 0; };
  const chunk = (type, body) => {
    const head = Buffer.alloc(8); head.writeUInt32BE(body.length, 0); head.write(type, 4, 'latin1');
    const tail = Buffer.alloc(4); tail.writeUInt32BE(crc(Buffer.concat([head.subarray(4), body])), 0);
    return Buffer.concat([head, body, tail]);
  };
  const ihdr = Buffer.alloc(13);
  ihdr.writeUInt32BE(width, 0); ihdr.writeUInt32BE(height, 4); ihdr[8] = 8; ihdr[9] = 3;
  return Buffer.concat([
    Buffer.from([0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a]), chunk('IHDR', ihdr),
    chunk('PLTE', Buffer.from(palette.flat())), chunk('IDAT', zlib.deflateSync(raw, { level: 9 })), chunk('IEND', Buffer.alloc(0)),
  ]);
}

async function main() {
  const opts = parseArgs(process.argv.slice(2));
  if (!fs.existsSync(path.join(opts.dir, 'tileset.json'))) usage(`${opts.dir}/tileset.json does not exist`);
  if (!fs.existsSync(CHROMIUM)) usage(`${CHROMIUM} is missing: run tools/setup.sh (Debian package chromium)`);
  const started = Date.now();
  const { top, contents } = collectContents(opts.dir);
  const region = top.root?.boundingVolume?.region;
  if (!region) throw new Error('the root tile has no region');
  const toEnu = enuFrame((region[0] + region[2]) / 2, (region[1] + region[3]) / 2);
  let buildInfo = null;
  try { buildInfo = JSON.parse(fs.readFileSync(path.join(opts.dir, 'tinsmith', 'build.json'), 'utf8')); } catch { /* optional */ }
  const info = {
    name: path.basename(path.resolve(opts.dir)),
    tolerance: Number.isFinite(buildInfo?.options?.tolerance) ? buildInfo.options.tolerance : null,
    finestZoom: buildInfo?.pyramid?.finestZoom ?? 0,
  };

  const byZoom = new Map();
  let e0 = Infinity, e1 = -Infinity, n0 = Infinity, n1 = -Infinity, hMin = Infinity, hMax = -Infinity;
  for (const c of contents) {
    const t = await readTile(opts.dir, c, toEnu);
    if (!byZoom.has(t.zoom)) byZoom.set(t.zoom, []);
    byZoom.get(t.zoom).push(t);
    for (const tri of t.surface) {
      const p = tri.pts;
      for (let i = 0; i < 6; i += 2) {
        e0 = Math.min(e0, p[i]); e1 = Math.max(e1, p[i]);
        n0 = Math.min(n0, p[i + 1]); n1 = Math.max(n1, p[i + 1]);
      }
      hMin = Math.min(hMin, tri.h); hMax = Math.max(hMax, tri.h);
    }
  }
  if (!byZoom.size) throw new Error('no tiles with triangles');
  const margin = 8;
  const inner = opts.width - 2 * margin;
  const scale = inner / (e1 - e0);
  const view = {
    width: opts.width, scale, e0: e0 - margin / scale, n1, top: 46,
    mapHeight: (n1 - n0) * scale, hMin, hMax, areaM2: (e1 - e0) * (n1 - n0),
  };
  // The detail square: --detail, else the square of a seventh of the width
  // holding the most triangles of the finest zoom.
  const finest = byZoom.get(Math.max(...byZoom.keys()));
  if (opts.detail) {
    view.detail = { e: opts.detail[0], n: opts.detail[1], size: opts.detail[2] };
  } else {
    const size = (e1 - e0) / 7;
    const cells = new Map();
    const cellOf = (e, n) => `${Math.floor((e - e0) / (size / 2))},${Math.floor((n - n0) / (size / 2))}`;
    for (const t of finest) for (const tri of t.surface) {
      const k = cellOf((tri.pts[0] + tri.pts[2] + tri.pts[4]) / 3, (tri.pts[1] + tri.pts[3] + tri.pts[5]) / 3);
      cells.set(k, (cells.get(k) ?? 0) + 1);
    }
    // Squares of 2 x 2 half-size cells.
    let best = null;
    for (const k of cells.keys()) {
      const [i, j] = k.split(',').map(Number);
      const count = [[0, 0], [1, 0], [0, 1], [1, 1]].reduce((s, [a, b]) => s + (cells.get(`${i + a},${j + b}`) ?? 0), 0);
      if (!best || count > best.count) best = { count, e: e0 + (i + 1) * (size / 2), n: n0 + (j + 1) * (size / 2) };
    }
    view.detail = { e: best.e, n: best.n, size };
  }
  // The inset: the first place, from the bottom right, where a square of
  // its size (and its label) meets no triangle of any zoom; else below the map.
  const cell = 4;
  const cols = Math.ceil(opts.width / cell), rows = Math.ceil((view.top + view.mapHeight + 1) / cell);
  const used = new Uint8Array(cols * rows);
  for (const list of byZoom.values()) for (const t of list) for (const tri of t.surface) {
    const p = tri.pts;
    const xs = [p[0], p[2], p[4]].map((e) => (e - view.e0) * scale), ys = [p[1], p[3], p[5]].map((n) => (n1 - n) * scale + view.top);
    const c0 = Math.max(0, Math.floor(Math.min(...xs) / cell)), c1 = Math.min(cols - 1, Math.floor(Math.max(...xs) / cell));
    const r0 = Math.max(0, Math.floor(Math.min(...ys) / cell)), r1 = Math.min(rows - 1, Math.floor(Math.max(...ys) / cell));
    for (let r = r0; r <= r1; ++r) used.fill(1, r * cols + c0, r * cols + c1 + 1);
  }
  const freeAt = (x, y, size) => {
    for (let r = Math.floor((y - 20) / cell); r <= Math.floor((y + size + 4) / cell); ++r)
      for (let c = Math.floor((x - 4) / cell); c <= Math.floor((x + size + 4) / cell); ++c)
        if (r < 0 || c < 0 || r >= rows || c >= cols || used[r * cols + c]) return false;
    return true;
  };
  view.inset = null;
  for (let size = Math.round(Math.min(opts.width * 0.45, 320)); size >= 200 && !view.inset; size -= 20)
    for (let y = Math.floor(view.top + view.mapHeight - size); y >= view.top + 20 && !view.inset; y -= cell)
      for (let x = opts.width - margin - size; x >= margin && !view.inset; x -= cell)
        if (freeAt(x, y, size)) view.inset = { x, y, size, below: false };
  if (!view.inset) view.inset = { x: margin, y: view.top + view.mapHeight + 24, size: Math.round(Math.min(opts.width * 0.45, 320)), below: true };
  console.log(`draw_zooms: detail square ${view.detail.size.toFixed(0)} m at ${view.detail.e.toFixed(0)} m east, ${view.detail.n.toFixed(0)} m north of the root region's centre`);

  const browser = await chromium.launch({
    executablePath: CHROMIUM,
    args: ['--headless=new', '--no-sandbox', '--disable-gpu', '--disable-dev-shm-usage'],
    timeout: 60_000,
  });
  try {
    for (const zoom of [...byZoom.keys()].sort((a, b) => a - b)) {
      const { svg, height, stats } = zoomSvg(zoom, byZoom.get(zoom), view, info);
      if (opts.svg) fs.writeFileSync(`${opts.prefix}${zoom}.svg`, svg);
      const page = await browser.newPage({ viewport: { width: opts.width, height: Math.ceil(height) }, deviceScaleFactor: 1 });
      await page.setContent(`<!doctype html><html><body style="margin:0;background:#fff">${svg}</body></html>`);
      const out = `${opts.prefix}${zoom}.png`;
      const shot = await page.screenshot({ clip: { x: 0, y: 0, width: opts.width, height: Math.ceil(height) }, timeout: 60_000 });
      fs.writeFileSync(out, opts.rgb ? shot : palettePng(decodePng(shot)));
      await page.close();
      console.log(`draw_zooms: zoom ${zoom}: ${stats.tiles} tiles, ${stats.surface} triangles + ${stats.skirts} skirt, ` +
        `max error ${stats.maxError.toFixed(3)} m, ${stats.inDetail} in the detail square -> ${out} (${fs.statSync(out).size} bytes)`);
    }
  } finally {
    await browser.close().catch(() => {});
  }
  console.log(`draw_zooms: ${byZoom.size} zooms, ${contents.length} tiles, ${((Date.now() - started) / 1000).toFixed(1)} s`);
}

main().catch((e) => { console.error(`ERROR: draw_zooms: ${e.stack ?? e}`); process.exit(1); });
