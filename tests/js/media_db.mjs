// The `.3dtiles` archive's table, media(key TEXT PRIMARY KEY, content BLOB),
// read and written with the better-sqlite3 module that 3d-tiles-tools depends
// on (resolved from 3d-tiles-tools' own location), or, when that native
// module does not load, read through the sqlite3 command-line shell.
import { createRequire } from 'node:module';
import { spawnSync } from 'node:child_process';

const require = createRequire(import.meta.url);

let loadError = null;
function betterSqlite() {
  try {
    // resolve() finds 3d-tiles-tools' entry point without running it.
    const toolsRequire = createRequire(require.resolve('3d-tiles-tools'));
    return toolsRequire('better-sqlite3');
  } catch (e) {
    loadError = e;
    return null;
  }
}

// Column layout of `media`, as PRAGMA table_info reports it.
function checkSchema(columns, path) {
  const byName = Object.fromEntries(columns.map((c) => [c.name, c]));
  const problems = [];
  if (!byName.key || String(byName.key.type).toUpperCase() !== 'TEXT' || Number(byName.key.pk) !== 1)
    problems.push('column key must be TEXT PRIMARY KEY');
  if (!byName.content || String(byName.content.type).toUpperCase() !== 'BLOB')
    problems.push('column content must be BLOB');
  if (columns.length !== 2) problems.push(`table has ${columns.length} columns, expected 2`);
  if (problems.length) throw new Error(`${path}: media table: ${problems.join('; ')}`);
}

// ARCHIVE -> { entries: Map(key -> Buffer), reader: 'better-sqlite3' | 'sqlite3 CLI' }.
// Throws when the file is not an SQLite database with the media table.
// TINSMITH_SQLITE_READER=cli forces the shell (to test that path).
export function readMedia(path) {
  const Database = process.env.TINSMITH_SQLITE_READER === 'cli' ? null : betterSqlite();
  if (Database) {
    const db = new Database(path, { readonly: true, fileMustExist: true });
    try {
      const columns = db.prepare("PRAGMA table_info('media')").all();
      if (columns.length === 0) throw new Error(`${path}: no table 'media'`);
      checkSchema(columns, path);
      const entries = new Map();
      for (const row of db.prepare('SELECT key, content FROM media ORDER BY key').iterate()) {
        if (typeof row.key !== 'string') throw new Error(`${path}: a media key is not TEXT (${typeof row.key})`);
        if (!(row.content instanceof Uint8Array))
          throw new Error(`${path}: media row '${row.key}' has no BLOB content`);
        entries.set(row.key, Buffer.from(row.content));
      }
      return { entries, reader: 'better-sqlite3' };
    } finally {
      db.close();
    }
  }
  const run = (sql) => {
    const r = spawnSync('sqlite3', ['-readonly', '-json', path, sql], { encoding: 'utf8', maxBuffer: 1 << 30 });
    if (r.error) throw new Error(`neither better-sqlite3 nor the sqlite3 shell is available: ${r.error.message}`);
    if (r.status !== 0) throw new Error(`${path}: sqlite3: ${r.stderr.trim()}`);
    return r.stdout.trim() ? JSON.parse(r.stdout) : [];
  };
  const columns = run("PRAGMA table_info('media')");
  if (columns.length === 0) throw new Error(`${path}: no table 'media'`);
  checkSchema(columns, path);
  const entries = new Map();
  for (const row of run("SELECT key, typeof(key) AS kt, typeof(content) AS ct, hex(content) AS hex FROM media ORDER BY key")) {
    if (row.kt !== 'text') throw new Error(`${path}: a media key is not TEXT (${row.kt})`);
    if (row.ct !== 'blob') throw new Error(`${path}: media row '${row.key}' has no BLOB content (${row.ct})`);
    entries.set(row.key, Buffer.from(row.hex, 'hex'));
  }
  return { entries, reader: 'sqlite3 CLI' };
}

// Writes a new archive with `entries` ([key, Buffer] pairs, written in the
// order given). Needs better-sqlite3.
export function writeMedia(path, entries) {
  const Database = betterSqlite();
  if (!Database) throw new Error(`better-sqlite3 (from 3d-tiles-tools) does not load (${loadError?.message}); run tools/setup.sh`);
  const db = new Database(path);
  try {
    db.exec('CREATE TABLE media (key TEXT PRIMARY KEY, content BLOB)');
    const insert = db.prepare('INSERT INTO media VALUES (?, ?)');
    db.transaction(() => { for (const [k, v] of entries) insert.run(k, v); })();
  } finally {
    db.close();
  }
}
