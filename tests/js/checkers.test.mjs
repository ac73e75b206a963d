// Tests of the checkers themselves: the sample passes every one, and each
// planted fault is caught (a corrupted Draco payload that the glTF validator
// accepts, a child region outside its parent, a missing content file, ...).
//
//   node --test tests/js/checkers.test.mjs
//
// The Cesium render runs when /usr/bin/chromium exists, unless
// TINSMITH_SKIP_BROWSER=1.
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { spawnSync } from 'node:child_process';
import { fileURLToPath } from 'node:url';
import { parseGlb } from './glb.mjs';
import { readMedia, writeMedia } from './media_db.mjs';

const HERE = path.dirname(fileURLToPath(import.meta.url));
let tmp;
let sample;

function run(script, args, timeout = 300_000) {
  const r = spawnSync(process.execPath, [path.join(HERE, script), ...args], { encoding: 'utf8', timeout, maxBuffer: 64 << 20 });
  if (r.error) throw r.error;
  return r;
}

// check_tiles --json: { status, report }.
function checkTiles(dir, ...more) {
  const r = run('check_tiles.mjs', [dir, ...more, '--json']);
  assert.ok(r.stdout.trim(), `check_tiles printed no JSON; stderr:\n${r.stderr}`);
  return { status: r.status, report: JSON.parse(r.stdout), text: r.stderr };
}

function copySample(name) {
  const dir = path.join(tmp, name);
  fs.cpSync(path.join(sample, 'draco'), dir, { recursive: true });
  return dir;
}

function editJson(file, edit) {
  const json = JSON.parse(fs.readFileSync(file, 'utf8'));
  edit(json);
  fs.writeFileSync(file, JSON.stringify(json, null, 1));
}

// XORs `count` bytes of the Draco bufferView of `file`, starting at the
// given fraction of its length.
function flipDracoBytes(file, fraction, count = 8) {
  const bytes = fs.readFileSync(file);
  const { json } = parseGlb(new Uint8Array(bytes));
  const binStart = 20 + bytes.readUInt32LE(12) + 8;
  const view = json.bufferViews[json.meshes[0].primitives[0].extensions.KHR_draco_mesh_compression.bufferView];
  const start = binStart + (view.byteOffset ?? 0) + Math.floor(view.byteLength * fraction);
  for (let i = 0; i < count && start + i < binStart + view.byteLength; ++i) bytes[start + i] ^= 0xff;
  fs.writeFileSync(file, bytes);
}

before(() => {
  tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'tinsmith-js-'));
  sample = path.join(tmp, 'sample');
  const r = run('make_sample_tileset.mjs', [sample]);
  assert.equal(r.status, 0, r.stderr);
});

after(() => fs.rmSync(tmp, { recursive: true, force: true }));

test('the sample passes check_tiles, compared with its plain twin', () => {
  const { status, report, text } = checkTiles(path.join(sample, 'draco'), '--plain', path.join(sample, 'plain'));
  assert.equal(status, 0, text);
  assert.equal(report.glbFiles, 21);
  assert.equal(report.comparedWithPlain, 21);
  assert.equal(report.tilesetFiles, 2);
  assert.equal(report.validator.errors, 0);
});

test('the plain twin passes check_tiles on its own', () => {
  const { status, text } = checkTiles(path.join(sample, 'plain'));
  assert.equal(status, 0, text);
});

for (const fraction of [0, 0.3, 0.5, 0.9]) {
  test(`Draco bytes flipped at ${fraction * 100} % of the payload: the validator accepts the tile, the checker does not`, () => {
    const dir = copySample(`flip-${fraction}`);
    flipDracoBytes(path.join(dir, 'tiles/1/0/0.glb'), fraction);
    const { status, report, text } = checkTiles(dir, '--plain', path.join(sample, 'plain'));
    assert.equal(report.validator.errors, 0, 'the validator does not decode Draco');
    assert.equal(status, 1, text);
    assert.ok(report.errors.length > 0);
    assert.ok(report.errors.every((e) => e.file === 'tiles/1/0/0.glb'), text);
  });
}

test('a flipped Draco payload is caught without the plain twin too', () => {
  const dir = copySample('flip-alone');
  flipDracoBytes(path.join(dir, 'tiles/1/0/0.glb'), 0.5);
  const { status, report, text } = checkTiles(dir);
  assert.equal(status, 1, text);
  assert.ok(report.errors.some((e) => /outside the region|min\/max|Draco/.test(e.message)), text);
});

test('a child region outside its parent is caught', () => {
  const dir = copySample('child-outside');
  // Widen one z2 tile (in the external tileset) 1e-6 rad (~4 m) past its
  // parent's east edge; its content still fits, so nothing else fails.
  editJson(path.join(dir, 'tilesets/1/1/1.json'), (t) => { t.root.children[3].boundingVolume.region[2] += 1e-6; });
  const { status, report, text } = checkTiles(dir);
  assert.equal(status, 1, text);
  assert.equal(report.errors.length, 1, text);
  assert.match(report.errors[0].message, /root\.children\[3\]: region is not inside its parent's .*east/);
});

test('a child region above its parent is caught', () => {
  const dir = copySample('child-above');
  editJson(path.join(dir, 'tileset.json'), (t) => { t.root.children[0].boundingVolume.region[5] = t.root.boundingVolume.region[5] + 0.01; });
  const { status, report, text } = checkTiles(dir);
  assert.equal(status, 1, text);
  assert.equal(report.errors.length, 1, text);
  assert.match(report.errors[0].message, /root\.children\[0\]: region is not inside its parent's .*maximum height/);
});

test('a missing content file is caught', () => {
  const dir = copySample('missing');
  fs.rmSync(path.join(dir, 'tiles/2/3/3.glb'));
  const { status, report, text } = checkTiles(dir);
  assert.equal(status, 1, text);
  assert.equal(report.errors.length, 1, text);
  assert.match(report.errors[0].message, /content uri '..\/..\/..\/tiles\/2\/3\/3.glb' does not exist/);
});

test('a missing plain twin is caught', () => {
  const plain = path.join(tmp, 'plain-missing');
  fs.cpSync(path.join(sample, 'plain'), plain, { recursive: true });
  fs.rmSync(path.join(plain, 'tiles/2/0/0.glb'));
  const { status, report, text } = checkTiles(path.join(sample, 'draco'), '--plain', plain);
  assert.equal(status, 1, text);
  assert.ok(report.errors.some((e) => /no plain twin/.test(e.message)), text);
});

test('geometric error growing down the tree is caught', () => {
  const dir = copySample('error-grows');
  editJson(path.join(dir, 'tilesets/1/1/1.json'), (t) => { t.root.children[0].geometricError = 300; });
  const { status, report, text } = checkTiles(dir);
  assert.equal(status, 1, text);
  assert.ok(report.errors.some((e) => /geometricError 300 > parent's 256/.test(e.message)), text);
});

test('content outside its own region is caught', () => {
  const dir = copySample('region-low');
  editJson(path.join(dir, 'tileset.json'), (t) => {
    const r = t.root.children[0].boundingVolume.region;
    r[5] = r[4] + 1; // the z1 tile's region 1 m tall
    for (const c of t.root.children[0].children ?? []) c.boundingVolume.region[5] = r[5];
  });
  const { status, report, text } = checkTiles(dir);
  assert.equal(status, 1, text);
  assert.ok(report.errors.some((e) => e.file === 'tiles/1/0/0.glb' && /lie outside the region/.test(e.message)), text);
});

test('a malformed region, a bad version and a missing refine are caught', () => {
  const dir = copySample('malformed');
  editJson(path.join(dir, 'tileset.json'), (t) => {
    t.asset.version = '2.0';
    delete t.root.refine;
    const r = t.root.children[1].boundingVolume.region;
    [r[0], r[2]] = [r[2], r[0]];
  });
  const { status, report, text } = checkTiles(dir);
  assert.equal(status, 1, text);
  for (const pattern of [/asset.version is "2.0"/, /no refine/, /west .* > east/])
    assert.ok(report.errors.some((e) => pattern.test(e.message)), `${pattern} not reported:\n${text}`);
});

test('the archive agrees with the directory and with 3d-tiles-tools', () => {
  const r = run('check_archive.mjs', [path.join(sample, 'sample.3dtiles'), path.join(sample, 'draco')]);
  assert.equal(r.status, 0, r.stdout + r.stderr);
  assert.match(r.stdout, /23 media rows/);
});

test('a changed archive row and an extra file in the directory are caught', () => {
  const { entries } = readMedia(path.join(sample, 'sample.3dtiles'));
  const changed = new Map(entries);
  const glb = Buffer.from(changed.get('tiles/2/1/1.glb'));
  glb[glb.length - 5] ^= 0x01;
  changed.set('tiles/2/1/1.glb', glb);
  const archive = path.join(tmp, 'changed.3dtiles');
  writeMedia(archive, [...changed]);
  const dir = copySample('extra-file');
  fs.writeFileSync(path.join(dir, 'stray.txt'), 'not in the archive\n');
  const r = run('check_archive.mjs', [archive, dir]);
  assert.equal(r.status, 1, r.stdout + r.stderr);
  assert.match(r.stdout, /'tiles\/2\/1\/1.glb' differs/);
  assert.match(r.stdout, /keys in .* but not in the archive: stray.txt/);
});

test('the sqlite3 shell reads the archive as better-sqlite3 does', () => {
  const archive = path.join(sample, 'sample.3dtiles');
  const viaModule = readMedia(archive);
  process.env.TINSMITH_SQLITE_READER = 'cli';
  try {
    const viaShell = readMedia(archive);
    assert.equal(viaShell.reader, 'sqlite3 CLI');
    assert.deepEqual([...viaShell.entries.keys()], [...viaModule.entries.keys()]);
    for (const [k, v] of viaModule.entries) assert.ok(viaShell.entries.get(k).equals(v), k);
  } finally {
    delete process.env.TINSMITH_SQLITE_READER;
  }
});

const noBrowser = !fs.existsSync('/usr/bin/chromium') || process.env.TINSMITH_SKIP_BROWSER === '1';
test('Cesium loads and renders the sample', { skip: noBrowser && 'no /usr/bin/chromium or TINSMITH_SKIP_BROWSER=1' }, () => {
  const shot = path.join(tmp, 'smoke.png');
  const r = run('cesium_smoke.mjs', [path.join(sample, 'draco'), '--out', shot, '--timeout', '150'], 200_000);
  assert.equal(r.status, 0, r.stdout + r.stderr);
  const share = Number(/terrain share ([\d.]+) %/.exec(r.stdout)?.[1]);
  assert.ok(share >= 30, r.stdout);
  assert.ok(fs.statSync(shot).size > 1000);
});
