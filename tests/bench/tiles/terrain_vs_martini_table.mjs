// The table of terrain_vs_martini.sh, in markdown, from the files of its
// work directory: per level of the grid, tiles, bytes and triangles per tile
// and the max measured error (decoded, against the geographic DEM-TIN) of
// tinsmith, martini at the level's CesiumJS error ("martini C") and martini
// at the error tinsmith's records declare for the level ("martini T"), then
// times and peak memory.
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
const runs = ['cesium', 'equal'].map((k) => ({
  mesh: byLevel(lines(`martini_${k}.jsonl`)),
  total: lines(`martini_${k}.jsonl`).find((r) => r.level === undefined),
  error: byLevel(lines(`martini_${k}_error.jsonl`)),
  time: time(`martini_${k}.time`),
}));
const grids = JSON.parse(read('grids.json'));

const n0 = (v) => Math.round(v).toLocaleString('en-US').replace(/,/g, ' ');
const e2 = (v) => (v >= 100 ? v.toFixed(0) : v >= 10 ? v.toFixed(1) : v.toFixed(2));
const over = (e, limit) => (e > limit * (1 + 1e-9) ? '**' + e2(e) + '**' : e2(e));

console.log('| level | Cesium error m | tiles | bytes/tile: tinsmith (no metadata) / martini C / martini T | triangles/tile: tinsmith / martini C / martini T | max error m: tinsmith declared / tinsmith measured / martini C / martini T | martini tolerance T m | grid |');
console.log('|---|---|---|---|---|---|---|---|');
const total = { tiles: 0, tb: 0, tm: 0, tt: 0, mb: [0, 0], mt: [0, 0], tg: 0, mg: [0, 0], over: [0, 0, 0, 0] };
for (const lv of summary.terrain.levels) {
  const z = lv.level, s = tStore.get(z), e = tError.get(z);
  const [c, q] = runs.map((r) => ({ m: r.mesh.get(z), e: r.error.get(z) }));
  const tiles = s.tiles;
  const limit = lv.cesiumError;
  const errs = [s.recordError, e.maxError, c.e.maxError, q.e.maxError];
  errs.forEach((v, i) => { if (v > limit * (1 + 1e-9)) total.over[i]++; });
  console.log(`| ${z} | ${e2(limit)} | ${tiles} | ${n0(s.bytes / tiles)} (${n0((s.bytes - s.metadata) / tiles)}) / ${n0(c.m.bytes / tiles)} / ${n0(q.m.bytes / tiles)} | ` +
    `${n0(s.triangles / tiles)} / ${n0(c.m.triangles / tiles)} / ${n0(q.m.triangles / tiles)} | ` +
    `${over(errs[0], limit)} / ${over(errs[1], limit)} / ${over(errs[2], limit)} / ${over(errs[3], limit)} | ${e2(q.m.tolerance)} | ${grids.grid[z]}² |`);
  total.tiles += tiles; total.tb += s.bytes; total.tm += s.metadata; total.tt += s.triangles; total.tg += s.gzip;
  [c, q].forEach((r, i) => { total.mb[i] += r.m.bytes; total.mt[i] += r.m.triangles; total.mg[i] += r.m.gzip; });
}
const t = total;
console.log(`| all | | ${t.tiles} | ${n0(t.tb / t.tiles)} (${n0((t.tb - t.tm) / t.tiles)}) / ${n0(t.mb[0] / t.tiles)} / ${n0(t.mb[1] / t.tiles)} | ` +
  `${n0(t.tt / t.tiles)} / ${n0(t.mt[0] / t.tiles)} / ${n0(t.mt[1] / t.tiles)} | levels over the Cesium error: ${t.over.join(' / ')} | | |`);
console.log('');
console.log(`Totals: tinsmith ${n0(t.tb)} B (${n0(t.tb - t.tm)} B without its metadata; gzip -6 ${n0(t.tg)} B), ` +
  `martini C ${n0(t.mb[0])} B (gzip ${n0(t.mg[0])} B), martini T ${n0(t.mb[1])} B (gzip ${n0(t.mg[1])} B); ` +
  `triangles ${n0(t.tt)} / ${n0(t.mt[0])} / ${n0(t.mt[1])}.`);
const tt = time('tile.time'), tin = time('tin.time'), g = time('grids.time');
console.log(`Time, one thread: tinsmith tile ${tt.wall.toFixed(2)} s wall, ${tt.cpu.toFixed(2)} s CPU, ${n0(tt.mb)} MB peak ` +
  `(tinsmith tin: ${tin.wall.toFixed(2)} s, ${n0(tin.mb)} MB); ` +
  runs.map((r, i) => `martini ${'CT'[i]} (node) ${r.time.wall.toFixed(2)} s wall, ${r.time.cpu.toFixed(2)} s CPU, ${n0(r.time.mb)} MB peak, ` +
    `${r.total.seconds.toFixed(2)} s meshing + encoding`).join('; ') +
  `; resampling the DEM-TIN onto martini's grids (C++) ${g.wall.toFixed(2)} s, ${n0(g.mb)} MB peak, ${n0(grids.nodes)} nodes.`);
const fillOver = [...tError.values()].reduce((m, r) => Math.max(m, r.fillOverTin), 0);
const collapsed = [...tError.values()].reduce((m, r) => m + r.collapsed, 0);
console.log(`tinsmith's fill and walls (corners at height 0, not counted above): ${[...tError.values()].reduce((m, r) => m + r.fillTriangles, 0)} triangles, ` +
  `largest difference over the TIN ${e2(fillOver)} m; surface triangles left without area by quantization: tinsmith ${collapsed}, ` +
  `martini C ${[...runs[0].error.values()].reduce((m, r) => m + r.collapsed, 0)}, martini T ${[...runs[1].error.values()].reduce((m, r) => m + r.collapsed, 0)}.`);
