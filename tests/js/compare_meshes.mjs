// Compares a decoded (Draco) primitive with its uncompressed twin, allowing
// for Draco's vertex reordering: vertices and triangle centroids are matched
// through a spatial hash, within the position error bound plus float32 slack.
//
// Both inputs: { geometry: { positions, normals, indices }, gltfToZUp,
// normalToZUp } as check_tiles builds them. Positions are compared after
// each file's own node matrices, so a tile may move its origin between the
// two and still compare equal.
import { transformPoint } from './geodesy.mjs';

const FLOAT32_REL = 2 ** -23;
const NORMAL_TOLERANCE_DEG = 2;

class SpatialHash {
  constructor(cell) { this.cell = cell; this.map = new Map(); }
  key(i, j, k) { return `${i},${j},${k}`; }
  add(p, id) {
    const k = this.key(Math.floor(p[0] / this.cell), Math.floor(p[1] / this.cell), Math.floor(p[2] / this.cell));
    let list = this.map.get(k);
    if (!list) this.map.set(k, (list = []));
    list.push(id);
  }
  // ids of the points stored within `radius` (<= cell) of p, via `points`.
  near(p, radius, points) {
    const out = [];
    const ci = Math.floor(p[0] / this.cell), cj = Math.floor(p[1] / this.cell), ck = Math.floor(p[2] / this.cell);
    for (let di = -1; di <= 1; ++di)
      for (let dj = -1; dj <= 1; ++dj)
        for (let dk = -1; dk <= 1; ++dk) {
          const list = this.map.get(this.key(ci + di, cj + dj, ck + dk));
          if (!list) continue;
          for (const id of list) {
            const q = points[id];
            if (Math.hypot(q[0] - p[0], q[1] - p[1], q[2] - p[2]) <= radius) out.push(id);
          }
        }
    return out;
  }
}

function worldPoints(prim) {
  const g = prim.geometry;
  const out = [];
  for (let i = 0; i < g.positions.length; i += 3) out.push(transformPoint(prim.gltfToZUp, g.positions[i], g.positions[i + 1], g.positions[i + 2]));
  return out;
}

function worldNormals(prim) {
  const g = prim.geometry;
  if (!g.normals || !prim.normalToZUp) return null;
  const out = [];
  for (let i = 0; i < g.normals.length; i += 3) {
    const n = transformPoint(prim.normalToZUp, g.normals[i], g.normals[i + 1], g.normals[i + 2]);
    const l = Math.hypot(...n) || 1;
    out.push([n[0] / l, n[1] / l, n[2] / l]);
  }
  return out;
}

// Triangles as { centroid, normal (area-weighted, unnormalised) }.
function triangles(points, indices) {
  const out = [];
  for (let t = 0; t < indices.length; t += 3) {
    const [a, b, c] = [points[indices[t]], points[indices[t + 1]], points[indices[t + 2]]];
    if (!a || !b || !c) continue;
    const u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    const v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
    const w = [c[0] - b[0], c[1] - b[1], c[2] - b[2]];
    const normal = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
    out.push({
      centroid: [(a[0] + b[0] + c[0]) / 3, (a[1] + b[1] + c[1]) / 3, (a[2] + b[2] + c[2]) / 3],
      normal,
      // The distance of the vertex farthest from the opposite edge's line.
      height: Math.hypot(...normal) / Math.max(Math.hypot(...u), Math.hypot(...v), Math.hypot(...w)),
    });
  }
  return out;
}

function maxAbs(values) {
  let m = 0;
  for (const v of values) m = Math.max(m, Math.abs(v));
  return m;
}

// Every point of `from` within `tol` of some point of `to`; returns
// { missing, worst, worstAt, matchedWorst } (worst: distance from a missing
// point to its nearest; matchedWorst: the largest nearest distance among the
// points that matched).
function coverage(from, to, tol) {
  const hash = new SpatialHash(tol);
  to.forEach((p, i) => hash.add(p, i));
  let missing = 0, worst = 0, worstAt = -1, matchedWorst = 0;
  from.forEach((p, i) => {
    const near = hash.near(p, tol, to);
    if (near.length) {
      let best = Infinity;
      for (const j of near) best = Math.min(best, Math.hypot(to[j][0] - p[0], to[j][1] - p[1], to[j][2] - p[2]));
      matchedWorst = Math.max(matchedWorst, best);
    } else {
      ++missing;
      let best = Infinity;
      for (const q of to) best = Math.min(best, Math.hypot(q[0] - p[0], q[1] - p[1], q[2] - p[2]));
      if (best > worst) { worst = best; worstAt = i; }
    }
  });
  return { missing, worst, worstAt, matchedWorst };
}

// Decoded (a) against plain (b); `bound` from a's extras. Returns
// { messages, positionError (m), normalAngle (degrees) }: the findings, and
// the largest matched vertex distance and normal angle (the headroom).
export function comparePrimitives(a, b, bound) {
  const messages = [];
  let normalAngle = 0;
  const ga = a.geometry, gb = b.geometry;
  const ta = ga.indices.length / 3, tb = gb.indices.length / 3;
  if (ta !== tb) messages.push(`${ta} triangles, the plain twin ${tb}`);
  const tol = bound + 1e-4 + FLOAT32_REL * Math.max(maxAbs(ga.positions), maxAbs(gb.positions));
  const pa = worldPoints(a), pb = worldPoints(b);

  const ab = coverage(pa, pb, tol);
  if (ab.missing)
    messages.push(`${ab.missing} of ${pa.length} decoded positions are farther than ${tol.toExponential(3)} m from every plain position (worst: vertex ${ab.worstAt}, ${ab.worst.toPrecision(4)} m)`);
  const ba = coverage(pb, pa, tol);
  if (ba.missing)
    messages.push(`${ba.missing} of ${pb.length} plain positions are farther than ${tol.toExponential(3)} m from every decoded position (worst: vertex ${ba.worstAt}, ${ba.worst.toPrecision(4)} m)`);

  // Triangles: a centroid within tol of a twin's centroid with the same winding.
  const tra = triangles(pa, ga.indices), trb = triangles(pb, gb.indices);
  const matchTriangles = (from, to) => {
    const hash = new SpatialHash(tol);
    to.forEach((t, i) => hash.add(t.centroid, i));
    const centroids = to.map((t) => t.centroid);
    let unmatched = 0, flipped = 0;
    for (const t of from) {
      const near = hash.near(t.centroid, tol, centroids);
      if (near.length === 0) { ++unmatched; continue; }
      const same = near.some((j) => {
        const n = to[j].normal;
        // A triangle thinner than twice the bound may turn over when its
        // vertices move within the bound: its winding is not the encoder's.
        return n[0] * t.normal[0] + n[1] * t.normal[1] + n[2] * t.normal[2] > 0 ||
          Math.hypot(...n) < tol * tol || Math.hypot(...t.normal) < tol * tol ||
          t.height < 2 * tol || to[j].height < 2 * tol;
      });
      if (!same) ++flipped;
    }
    return { unmatched, flipped };
  };
  const mab = matchTriangles(tra, trb);
  if (mab.unmatched) messages.push(`${mab.unmatched} of ${tra.length} decoded triangles match no plain triangle (centroids within ${tol.toExponential(3)} m)`);
  if (mab.flipped) messages.push(`${mab.flipped} decoded triangles have the opposite winding of their plain twin`);
  const mba = matchTriangles(trb, tra);
  if (mba.unmatched) messages.push(`${mba.unmatched} of ${trb.length} plain triangles match no decoded triangle`);

  // Normals: at each decoded vertex, the closest-in-angle plain normal among
  // the plain vertices within tol (a vertex may be split along a seam).
  const na = worldNormals(a), nb = worldNormals(b);
  if (!!na !== !!nb) messages.push(`normals: ${na ? 'decoded has them, the plain twin not' : 'the plain twin has them, decoded not'}`);
  if (na && nb) {
    const hash = new SpatialHash(tol);
    pb.forEach((p, i) => hash.add(p, i));
    const cosTol = Math.cos((NORMAL_TOLERANCE_DEG * Math.PI) / 180);
    let bad = 0, worst = 0;
    pa.forEach((p, i) => {
      const near = hash.near(p, tol, pb);
      if (near.length === 0) return; // already reported as a position mismatch
      let best = -1;
      for (const j of near) best = Math.max(best, na[i][0] * nb[j][0] + na[i][1] * nb[j][1] + na[i][2] * nb[j][2]);
      const angle = (Math.acos(Math.max(-1, Math.min(1, best))) * 180) / Math.PI;
      normalAngle = Math.max(normalAngle, angle);
      if (best < cosTol) { ++bad; worst = Math.max(worst, angle); }
    });
    if (bad) messages.push(`${bad} of ${pa.length} decoded normals differ from the plain twin's by more than ${NORMAL_TOLERANCE_DEG}° (worst ${worst.toFixed(2)}°)`);
  }
  return { messages, positionError: Math.max(ab.matchedWorst, ba.matchedWorst), normalAngle };
}
