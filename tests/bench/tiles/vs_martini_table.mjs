// The table of vs_martini.sh, from the files it wrote: tinsmith's summary and
// store records, martini's per-zoom sums, both measured errors, the timings
// (/usr/bin/time -f '%e %M %U %S': wall seconds, peak RSS in KB, user and
// system CPU seconds).
import fs from 'node:fs';

const [tinsmithJson, storeJsonl, tileTime, gridsJson, gridsTime, martiniJsonl, martiniTime, errorJsonl] =
  process.argv.slice(2);
const lines = (path) => fs.readFileSync(path, 'utf8').trim().split('\n').map((l) => JSON.parse(l));
const time = (path) => {
  const [wall, kb, user, sys] = fs.readFileSync(path, 'utf8').trim().split('\n').pop().split(' ').map(Number);
  return { wall, mb: kb / 1024, cpu: user + sys };
};
const summary = JSON.parse(fs.readFileSync(tinsmithJson, 'utf8'));
const store = new Map(lines(storeJsonl).map((r) => [r.zoom, r]));
const martiniRows = lines(martiniJsonl);
const martiniWork = martiniRows.pop().seconds;
const martini = new Map(martiniRows.map((r) => [r.zoom, r]));
const errorRows = lines(errorJsonl);
const errorSeconds = errorRows.pop().seconds;
const measured = new Map(errorRows.map((r) => [r.zoom, r]));
const grids = JSON.parse(fs.readFileSync(gridsJson, 'utf8'));
const [tile, gridT, martiniT] = [time(tileTime), time(gridsTime), time(martiniTime)];

const n = (v) => Math.round(v).toLocaleString('en-US').replace(/,/g, ' ');
const m = (v, tol) => `${v.toFixed(2)}${v > tol + 1e-9 ? ' (over)' : ''}`;
const out = [];
out.push('| zoom | tolerance m | tiles | triangles: tinsmith / martini | .glb bytes: tinsmith / martini | ' +
         'max error m: tinsmith / martini | martini at DEM cells m | martini grid |');
out.push('|---|---|---|---|---|---|---|---|');
const total = { tiles: 0, t: 0, mt: 0, b: 0, mb: 0, p: 0, mp: 0, over: [0, 0] };
for (const z of summary.zooms) {
  const mr = martini.get(z.zoom), me = measured.get(z.zoom), s = store.get(z.zoom);
  if (!mr || !me || !s) throw new Error(`zoom ${z.zoom} is missing from martini's or the store's rows`);
  if (mr.tiles !== z.tiles || me.tiles !== z.tiles || s.tiles !== z.tiles)
    throw new Error(`zoom ${z.zoom}: tile counts differ (${z.tiles}, ${s.tiles}, ${mr.tiles}, ${me.tiles})`);
  out.push(`| ${z.zoom} | ${z.tolerance} | ${z.tiles} | ${n(z.triangles)} / ${n(mr.triangles)} | ` +
           `${n(z.bytes)} / ${n(mr.bytes)} | ${m(z.maxError, z.tolerance)} / ${m(me.maxError, z.tolerance)} | ` +
           `${m(me.maxAtDemPoints, z.tolerance)} | ${mr.grid}² |`);
  total.tiles += z.tiles;
  total.t += z.triangles;
  total.mt += mr.triangles;
  total.b += z.bytes;
  total.mb += mr.bytes;
  total.p += s.payload;
  total.mp += mr.payload;
  if (z.maxError > z.tolerance + 1e-9) total.over[0]++;
  if (me.maxError > z.tolerance + 1e-9) total.over[1]++;
}
out.push(`| all | | ${total.tiles} | ${n(total.t)} / ${n(total.mt)} | ${n(total.b)} / ${n(total.mb)} | ` +
         `zooms over: ${total.over[0]} / ${total.over[1]} | | |`);
out.push('');
out.push(`- Draco payload bytes (the .glb's binary chunk): tinsmith ${n(total.p)} ` +
         `(${(total.p / total.t).toFixed(2)} B/triangle), martini ${n(total.mp)} ` +
         `(${(total.mp / total.mt).toFixed(2)} B/triangle); triangles include skirts on both.`);
out.push(`- tinsmith tile, 1 thread, whole process (read .tin, fits, meshes, Draco, archive): ` +
         `${tile.wall.toFixed(2)} s wall (${tile.cpu.toFixed(2)} s CPU), ${tile.mb.toFixed(0)} MB peak.`);
out.push(`- martini + draco3d, node (1 thread): meshing, skirts, normals and Draco ${martiniWork.toFixed(2)} s wall; ` +
         `whole node process ${martiniT.wall.toFixed(2)} s wall (${martiniT.cpu.toFixed(2)} s CPU), ` +
         `${martiniT.mb.toFixed(0)} MB peak; ` +
         `plus the DEM-TIN resampled onto its ${n(grids.nodes)} grid nodes (C++, ${n(grids.outside)} outside the TIN) ` +
         `${gridT.wall.toFixed(2)} s wall (${gridT.cpu.toFixed(2)} s CPU).`);
const martiniTotal = martiniT.wall + gridT.wall, martiniCpu = martiniT.cpu + gridT.cpu;
out.push(`- time ratio tinsmith / martini: ${(tile.wall / martiniTotal).toFixed(2)} wall ` +
         `(${(tile.cpu / martiniCpu).toFixed(2)} CPU) against node + resampling ` +
         `(${martiniTotal.toFixed(2)} s wall, ${martiniCpu.toFixed(2)} s CPU), ` +
         `${(tile.wall / martiniWork).toFixed(2)} wall against martini's work alone.`);
out.push(`- martini's error measured in ${errorSeconds.toFixed(2)} s (2 threads); its worst point per zoom: ` +
         errorRows.map((r) => `z${r.zoom} ${r.worst} at (${r.at[0].toFixed(0)}, ${r.at[1].toFixed(0)}): ` +
                              `mesh ${r.meshZ.toFixed(1)}, TIN ${r.tinZ.toFixed(1)}`).join('; ') + '.');
out.push(`- pyramid square: origin (${grids.x0.toFixed(3)}, ${grids.y0.toFixed(3)}), side ${grids.size.toFixed(3)} m.`);
console.log(out.join('\n'));
