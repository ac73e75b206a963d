// The table of terrain_vs_martini.sh, in markdown, from the files of its
// work directory: per level of the grid, tiles, bytes and triangles per tile
// and the max measured error (decoded, against the geographic DEM-TIN) of
// tinsmith and of martini at the level's CesiumJS error (C), at the error
// tinsmith's records declare for the level (T) and at T scaled by how far
// martini overshot it (E); then totals, times and peak memory.
//
//   node terrain_vs_martini_table.mjs WORKDIR
import fs from 'node:fs';
import path from 'node:path';

const dir = process.argv[2] ?? '.';
const read = (name) => fs.readFileSync(path.join(dir, name), 'utf8');
const lines = (name) => read(name).trim().split('\n').filter(Boolean).map((l) => JSON.parse(l));
const byLevel = (rows) => new Map(rows.filter((r) => r.level !== undefined).map((r) => [r.level, r]));
const time = (name) => {
  const [wall, rss, user, sys] = read(name).trim().split('\n').pop().split(' ').map(Number);
  return { wall, mb: rss / 1024, cpu: user + sys };
};

const summary = JSON.parse(read('tinsmith.json'));
const tStore = byLevel(lines('tinsmith_store.jsonl'));
const tError = byLevel(lines('tinsmith_error.jsonl'));
const names = ['cesium', 'declared', 'equalised'];
const runs = names.map((k) => ({
  mesh: byLevel(lines(`martini_${k}.jsonl`)),
  total: lines(`martini_${k}.jsonl`).find((r) => r.level === undefined),
  error: byLevel(lines(`martini_${k}_error.jsonl`)),
  time: time(`martini_${k}.time`),
}));
const grids = JSON.parse(read('grids.json'));

const n0 = (v) => Math.round(v).toLocaleString('en-US').replace(/,/g, ' ');
const e2 = (v) => (v >= 100 ? v.toFixed(0) : v >= 10 ? v.toFixed(1) : v.toFixed(2));
const over = (e, limit) => (e > limit * (1 + 1e-9) ? '**' + e2(e) + '**' : e2(e));

console.log('| level | Cesium error m | tiles | bytes/tile: tinsmith (no metadata) / martini C / T / E | ' +
  'triangles/tile: tinsmith / martini C / T / E | max error m: tinsmith declared / tinsmith measured / martini C / T / E | ' +
  'martini tolerance T / E m | martini grid |');
console.log('|---|---|---|---|---|---|---|---|');
const total = { tiles: 0, tb: 0, tm: 0, tt: 0, tg: 0, tf: 0, mb: [0, 0, 0], mt: [0, 0, 0], mg: [0, 0, 0], mo: [0, 0, 0],
                over: [0, 0, 0, 0, 0] };
for (const lv of summary.terrain.levels) {
  const z = lv.level, s = tStore.get(z), e = tError.get(z);
  const m = runs.map((r) => ({ m: r.mesh.get(z), e: r.error.get(z) }));
  const tiles = s.tiles;
  const limit = lv.cesiumError;
  const errs = [s.recordError, e.maxError, ...m.map((r) => r.e.maxError)];
  errs.forEach((v, i) => { if (v > limit * (1 + 1e-9)) total.over[i]++; });
  console.log(`| ${z} | ${e2(limit)} | ${tiles} | ${n0(s.bytes / tiles)} (${n0((s.bytes - s.metadata) / tiles)}) / ` +
    `${m.map((r) => n0(r.m.bytes / tiles)).join(' / ')} | ` +
    `${n0(s.triangles / tiles)} / ${m.map((r) => n0(r.m.triangles / tiles)).join(' / ')} | ` +
    `${errs.map((v) => over(v, limit)).join(' / ')} | ${e2(m[1].m.tolerance)} / ${e2(m[2].m.tolerance)} | ${grids.grid[z]}² |`);
  total.tiles += tiles; total.tb += s.bytes; total.tm += s.metadata; total.tt += s.triangles; total.tg += s.gzip;
  total.tf += e.fillTriangles;
  m.forEach((r, i) => { total.mb[i] += r.m.bytes; total.mt[i] += r.m.triangles; total.mg[i] += r.m.gzip; total.mo[i] += r.m.overTin; });
}
const t = total;
console.log(`| all | | ${t.tiles} | ${n0(t.tb / t.tiles)} (${n0((t.tb - t.tm) / t.tiles)}) / ${t.mb.map((b) => n0(b / t.tiles)).join(' / ')} | ` +
  `${n0(t.tt / t.tiles)} / ${t.mt.map((b) => n0(b / t.tiles)).join(' / ')} | levels over the Cesium error: ${t.over.join(' / ')} | | |`);
console.log('');
console.log(`Totals: tinsmith ${n0(t.tb)} B (${n0(t.tb - t.tm)} B without its metadata; gzip -6 ${n0(t.tg)} B); ` +
  t.mb.map((b, i) => `martini ${'CTE'[i]} ${n0(b)} B (gzip ${n0(t.mg[i])} B)`).join(', ') + '. ' +
  `Triangles: tinsmith ${n0(t.tt)}, of them ${n0(t.tf)} fill and walls (corners at height 0); ` +
  t.mt.map((b, i) => `martini ${'CTE'[i]} ${n0(b)}, of them ${n0(t.mo[i])} with a grid node in the TIN`).join('; ') + '.');
const tt = time('tile.time'), tin = time('tin.time'), g = time('grids.time');
console.log(`Time, one thread: tinsmith tile ${tt.wall.toFixed(2)} s wall, ${tt.cpu.toFixed(2)} s CPU, ${n0(tt.mb)} MB peak ` +
  `(tinsmith tin: ${tin.wall.toFixed(2)} s, ${n0(tin.mb)} MB); ` +
  runs.map((r, i) => `martini ${'CTE'[i]} (node) ${r.time.wall.toFixed(2)} s wall, ${r.time.cpu.toFixed(2)} s CPU, ` +
    `${n0(r.time.mb)} MB peak, ${r.total.seconds.toFixed(2)} s of it meshing + encoding`).join('; ') +
  `; resampling the DEM-TIN onto martini's grids (C++, not in martini's times) ${g.wall.toFixed(2)} s, ${n0(g.mb)} MB peak, ` +
  `${n0(grids.nodes)} nodes.`);
const fillOver = [...tError.values()].reduce((m, r) => Math.max(m, r.fillOverTin), 0);
const collapsed = (rows) => [...rows.values()].reduce((m, r) => m + r.collapsed, 0);
const under = [...tError.values()].filter((r) => r.underFill > 0)
  .map((r) => `${r.level}: ${r.underFill} (${e2(r.underFillDepth)} m, ${r.underFillWorst})`).join(', ');
console.log(`tinsmith's fill over the TIN (not counted above): largest difference ${e2(fillOver)} m; ` +
  `TIN vertices off the TIN's edge under the fill, per level (deepest from the edge, in the working frame; tile): ` +
  `${under || 'none'}. Surface triangles quantization left without area: tinsmith ${collapsed(tError)}, ` +
  `martini ${runs.map((r) => collapsed(r.error)).join(' / ')}.`);
