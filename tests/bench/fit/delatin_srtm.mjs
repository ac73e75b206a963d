// Reference for the fitter benchmark: delatin (greedy-insertion Delaunay TIN,
// Garland–Heckbert) on an SRTM .hgt grid, for each target — a max error in
// metres, or "nCOUNT" for a vertex count (refined point by point until it has
// COUNT vertices: the comparison at equal vertex count); prints vertices, max
// error and RMSE over every grid point (measured here by rasterizing the mesh,
// not delatin's own getRMSD), and the time of the refinement.
//
//   npm install delatin@0.2.0   (in this folder or a scratch folder holding a copy of this script)
//   node delatin_srtm.mjs N44W072.hgt 10 5 2 n232539
import { readFileSync } from 'node:fs';
import Delatin from 'delatin';

const [file, ...targets] = process.argv.slice(2);
const buf = readFileSync(file);
const size = Math.round(Math.sqrt(buf.length / 2));
const data = new Float64Array(size * size);
for (let i = 0; i < size * size; i++) data[i] = buf.readInt16BE(2 * i);

for (const target of targets) {
  const t0 = process.hrtime.bigint();
  const tin = new Delatin(data, size, size);
  if (target.startsWith('n')) {
    const count = Number(target.slice(1));
    while (tin.coords.length / 2 < count && tin.getMaxError() > 0) tin.refine();
  } else {
    tin.run(Number(target));
  }
  const seconds = Number(process.hrtime.bigint() - t0) / 1e9;
  const { coords, triangles } = tin;
  const seen = new Uint8Array(size * size);
  let maxErr = 0, sumSq = 0, count = 0;
  for (let t = 0; t < triangles.length; t += 3) {
    const [a, b, c] = [triangles[t], triangles[t + 1], triangles[t + 2]];
    const ax = coords[2 * a], ay = coords[2 * a + 1], bx = coords[2 * b], by = coords[2 * b + 1];
    const cx = coords[2 * c], cy = coords[2 * c + 1];
    const za = data[ay * size + ax], zb = data[by * size + bx], zc = data[cy * size + cx];
    const det = (bx - ax) * (cy - ay) - (cx - ax) * (by - ay);
    for (let y = Math.min(ay, by, cy); y <= Math.max(ay, by, cy); y++) {
      for (let x = Math.min(ax, bx, cx); x <= Math.max(ax, bx, cx); x++) {
        if (seen[y * size + x]) continue;
        const l1 = ((bx - x) * (cy - y) - (cx - x) * (by - y)) / det;
        const l2 = ((cx - x) * (ay - y) - (ax - x) * (cy - y)) / det;
        const l3 = 1 - l1 - l2;
        if (l1 < -1e-12 || l2 < -1e-12 || l3 < -1e-12) continue;
        seen[y * size + x] = 1;
        const e = Math.abs(l1 * za + l2 * zb + l3 * zc - data[y * size + x]);
        maxErr = Math.max(maxErr, e);
        sumSq += e * e;
        count++;
      }
    }
  }
  const what = target.startsWith('n') ? `${target.slice(1)} vertices` : `${target} m`;
  console.log(`delatin target ${what}: ${coords.length / 2} vertices, ${triangles.length / 3} triangles, ` +
    `max error ${maxErr.toFixed(3)} m, RMSE ${Math.sqrt(sumSq / count).toFixed(3)} m over ${count} points, ${seconds.toFixed(2)} s`);
}
