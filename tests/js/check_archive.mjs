#!/usr/bin/env node
// Checks a tinsmith `.3dtiles` archive against the directory store of the
// same tiles, with 3d-tiles-tools (the Cesium reference implementation of
// the format) in both directions:
//
//   node tests/js/check_archive.mjs ARCHIVE.3dtiles DIR [--keep]
//
// 1. The archive's media(key TEXT PRIMARY KEY, content BLOB) rows are read
//    directly (better-sqlite3 from 3d-tiles-tools, or the sqlite3 shell).
// 2. `3d-tiles-tools convert -i ARCHIVE -o TMP/unpacked` unpacks it; every
//    unpacked file must equal its media row, byte for byte, same key set.
// 3. DIR's files (every regular file, keys are '/'-separated relative paths)
//    must be the same key set with the same bytes.
// 4. `3d-tiles-tools convert -i DIR -o TMP/from-dir.3dtiles` packs DIR; its
//    media rows must equal the archive's (keys and bytes).
// Exit status 0 when all agree, 1 otherwise, 2 on bad usage. --keep leaves
// the temporary directory and prints where it is.
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { spawnSync } from 'node:child_process';
import { fileURLToPath } from 'node:url';
import { readMedia } from './media_db.mjs';

const HERE = path.dirname(fileURLToPath(import.meta.url));

function usage(message) {
  if (message) console.error(`check_archive: ${message}`);
  console.error('usage: node check_archive.mjs ARCHIVE.3dtiles DIR [--keep]');
  process.exit(2);
}

// Runs the 3d-tiles-tools CLI from tests/js (its local install) via npx.
function tilesTools(args) {
  const r = spawnSync('npx', ['--no', '3d-tiles-tools', ...args], {
    cwd: HERE, encoding: 'utf8', timeout: 300_000, maxBuffer: 64 << 20,
  });
  if (r.error) throw new Error(`npx 3d-tiles-tools ${args.join(' ')}: ${r.error.message}`);
  if (r.status !== 0)
    throw new Error(`npx 3d-tiles-tools ${args.join(' ')} exited ${r.status}:\n${(r.stdout + r.stderr).trim()}`);
  return r;
}

// Every regular file under dir -> Map(relative posix path -> Buffer).
function readTree(dir) {
  const out = new Map();
  const walk = (abs, rel) => {
    for (const e of fs.readdirSync(abs, { withFileTypes: true })) {
      const r = rel ? `${rel}/${e.name}` : e.name;
      if (e.isDirectory()) walk(path.join(abs, e.name), r);
      else if (e.isFile()) out.set(r, fs.readFileSync(path.join(abs, e.name)));
      else throw new Error(`${path.join(abs, e.name)} is neither a file nor a directory`);
    }
  };
  walk(dir, '');
  return out;
}

// Differences between two key -> bytes maps, as messages (at most `limit`
// listed per kind, then a count).
function compare(nameA, a, nameB, b, limit = 10) {
  const onlyA = [...a.keys()].filter((k) => !b.has(k)).sort();
  const onlyB = [...b.keys()].filter((k) => !a.has(k)).sort();
  const differ = [...a.keys()].filter((k) => b.has(k) && !a.get(k).equals(b.get(k))).sort();
  const out = [];
  const list = (keys, what) => {
    if (!keys.length) return;
    const shown = keys.slice(0, limit).join(', ');
    out.push(`${keys.length} ${what}: ${shown}${keys.length > limit ? ', ...' : ''}`);
  };
  list(onlyA, `keys in ${nameA} but not in ${nameB}`);
  list(onlyB, `keys in ${nameB} but not in ${nameA}`);
  for (const k of differ.slice(0, limit))
    out.push(`'${k}' differs: ${a.get(k).length} bytes in ${nameA}, ${b.get(k).length} in ${nameB}${a.get(k).length === b.get(k).length ? ` (first difference at byte ${firstDifference(a.get(k), b.get(k))})` : ''}`);
  if (differ.length > limit) out.push(`... and ${differ.length - limit} more keys differ`);
  return out;
}

function firstDifference(x, y) {
  for (let i = 0; i < x.length; ++i) if (x[i] !== y[i]) return i;
  return -1;
}

function main() {
  const args = process.argv.slice(2);
  const keep = args.includes('--keep');
  const positional = args.filter((a) => a !== '--keep');
  if (positional.some((a) => a.startsWith('-'))) usage(`unknown option '${positional.find((a) => a.startsWith('-'))}'`);
  if (positional.length !== 2) usage();
  const [archive, dir] = positional.map((p) => path.resolve(p));
  if (!fs.existsSync(archive) || !fs.statSync(archive).isFile()) usage(`'${archive}' is not a file`);
  if (!fs.existsSync(dir) || !fs.statSync(dir).isDirectory()) usage(`'${dir}' is not a directory`);

  const errors = [];
  const tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'check_archive-'));
  try {
    const { entries: media, reader } = readMedia(archive);
    if (!media.has('tileset.json')) errors.push("the archive has no 'tileset.json' row");
    for (const k of media.keys())
      if (k.startsWith('/') || k.startsWith('./') || k.includes('\\') || k.split('/').includes('..'))
        errors.push(`archive key '${k}' is not a plain relative '/' path`);

    const unpackedDir = path.join(tmp, 'unpacked');
    tilesTools(['convert', '-i', archive, '-o', unpackedDir]);
    const unpacked = readTree(unpackedDir);
    for (const m of compare('the archive', media, '3d-tiles-tools unpacked', unpacked)) errors.push(`unpack: ${m}`);

    const tree = readTree(dir);
    for (const m of compare('the archive', media, dir, tree)) errors.push(`directory: ${m}`);

    const repacked = path.join(tmp, 'from-dir.3dtiles');
    tilesTools(['convert', '-i', dir, '-o', repacked]);
    const { entries: repackedMedia } = readMedia(repacked);
    for (const m of compare('the archive', media, '3d-tiles-tools packed DIR', repackedMedia)) errors.push(`pack: ${m}`);

    const bytes = [...media.values()].reduce((s, b) => s + b.length, 0);
    for (const e of errors) console.log(`ERROR: ${path.basename(archive)}: ${e}`);
    console.log(`check_archive: ${media.size} media rows (${bytes} bytes, read with ${reader}) against 3d-tiles-tools unpack, ${tree.size} files of ${dir}, 3d-tiles-tools pack: ${errors.length} errors`);
  } catch (e) {
    console.log(`ERROR: ${path.basename(archive)}: ${e.message}`);
    errors.push(e.message);
  } finally {
    if (keep) console.log(`check_archive: kept ${tmp}`);
    else fs.rmSync(tmp, { recursive: true, force: true });
  }
  process.exitCode = errors.length ? 1 : 0;
}

main();
