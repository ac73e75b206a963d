#!/usr/bin/env node
// The viewer pages in headless Chromium (SwiftShader WebGL, no network) on a
// real `tinsmith serve` (ctest Viewer.Browser):
//
//   node tests/js/viewer_browser.mjs TINSMITH STORE OUT_DIR [--timeout 170]
//
// Two servers on ephemeral loopback ports: the first as `tinsmith serve
// STORE` (the viewer found by itself, in the source tree), the second with
// --base-path /terrain/demo and --viewer given. On each, `/` (CesiumJS) and
// `/three` (three.js) must load with no console error, no page error, no
// failed or ≥ 400 request and no request to another host, and fill the map
// with terrain: at least MIN_TERRAIN_SHARE of the map's pixels (the window
// less the side panel) terrain-coloured — farther than COLOUR_DISTANCE from
// both flat colours the page paints where there is no terrain (its sky and
// its plain globe, tinsmithViewer.colours) and not near-black. On the first
// server, `/` also:
//   - probe(centre): the height the panel shows is the elevation route's z
//     for the same lon, lat (asked by this script: equal doubles), and the
//     rendered mesh's picked height is within the tileset's root
//     geometricError (the loosest tile's measured error) + PICK_SLACK of
//     the route's ellipsoidalHeight;
//   - a profile between two screen points: the profile request answers 200
//     and the chart canvas is drawn (≥ MIN_CHART_SHARE of it not background);
//   - real input: the panel follows the mouse, a drag in profile mode draws
//     a profile;
//   - the break lines (lines.geojson) and the Draco decoder (on /three) are
//     fetched from the server.
// Screenshots go to OUT_DIR (viewer.png, viewer-profile.png,
// viewer-tiles.png, three.png, prefix-viewer.png, prefix-three.png). Exit 0 on success, 1 on a failure.
//
// The harness (arguments, deadline, servers, pages, pixel measures) is
// exported for terrain_browser.mjs; the checks run only when this file is
// the script node was given.
import { spawn } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { chromium } from 'playwright-core';
import { decodePng } from './png.mjs';

export const CHROMIUM = '/usr/bin/chromium';
export const VIEWPORT = { width: 1280, height: 800 };
export const MIN_TERRAIN_SHARE = 0.25;  // of the map's pixels; measured about 0.5-0.6 on Red Butte
const MIN_CHART_SHARE = 0.05;
const COLOUR_DISTANCE = 40;  // RGB distance under which a pixel is the sky's or the globe's colour
const PICK_SLACK = 1.0;  // metres: depth-buffer precision of the pick at this range
const PREFIX = '/terrain/demo';

const [bin, store, outDir, ...rest] = process.argv.slice(2);
const script = path.basename(process.argv[1] ?? 'viewer_browser.mjs', '.mjs');
if (!bin || !store || !outDir) {
  console.error(`usage: node ${script}.mjs TINSMITH STORE OUT_DIR [--timeout SECONDS]`);
  process.exit(2);
}
export { bin, store, outDir };
const timeoutSeconds = rest[0] === '--timeout' ? Number(rest[1]) : 170;
export const started = Date.now();
const deadline = started + timeoutSeconds * 1000;
export const left = () => Math.max(1000, deadline - Date.now());
export const root = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '..', '..');
fs.mkdirSync(outDir, { recursive: true });

export const problems = [];
let onFailure = () => {};
export const fail = (what) => { problems.push(what); console.log(`ERROR: ${script}: ${what}`); onFailure(); };
export const note = (what) => console.log(`${script}: ${what}`);

// A hard stop whatever hangs.
const watchdog = setTimeout(() => {
  console.log(`ERROR: ${script}: still running ${timeoutSeconds + 20} s after the start; giving up`);
  process.exit(1);
}, (timeoutSeconds + 20) * 1000);
watchdog.unref();

/// `tinsmith serve` on 127.0.0.1, port 0; resolves with its origin once it says where it listens.
export function startServer(args) {
  const child = spawn(bin, ['serve', store, '--host', '127.0.0.1', '--port', '0', '--reload', '0', ...args],
    { stdio: ['ignore', 'ignore', 'pipe'] });
  let text = '';
  return new Promise((resolve, reject) => {
    const timer = setTimeout(() => {
      child.kill('SIGKILL');  // never left running behind a failed test
      reject(new Error(`tinsmith serve did not start: ${text}`));
    }, 20_000);
    child.stderr.on('data', (chunk) => {
      text += chunk;
      const m = /on (http:\/\/127\.0\.0\.1:\d+)/.exec(text);
      if (m && /(viewer from|viewer is not installed)[^\n]*\n/.test(text)) {
        clearTimeout(timer);
        resolve({ child, origin: m[1], log: () => text });
      }
    });
    child.on('exit', (code) => reject(new Error(`tinsmith serve exited ${code}: ${text}`)));
  });
}

/// Headless Chromium with software WebGL.
export function launchBrowser() {
  if (!fs.existsSync(CHROMIUM)) throw new Error(`${CHROMIUM} is missing: run tools/setup.sh`);
  return chromium.launch({
    executablePath: CHROMIUM,
    args: ['--headless=new', '--no-sandbox', '--enable-unsafe-swiftshader', '--use-angle=swiftshader', '--disable-dev-shm-usage'],
    timeout: 60_000,
  });
}

/// Closes the browser, stops the servers and exits 0, or 1 after any problem.
export async function finish(browser, servers) {
  if (browser) await browser.close().catch(() => {});
  for (const s of servers) s.child.kill('SIGTERM');
  clearTimeout(watchdog);
  note(`${problems.length ? 'FAILED' : 'ok'} in ${((Date.now() - started) / 1000).toFixed(1)} s; screenshots in ${outDir}`);
  process.exit(problems.length ? 1 : 0);
}

/// A page whose every console error, page error, failed request and
/// response ≥ 400 is a problem; requests leaving the origin are blocked.
export async function openPage(browser, origin, label) {
  const page = await browser.newPage({ viewport: VIEWPORT, deviceScaleFactor: 1 });
  const requests = [];
  page.on('console', (msg) => { if (msg.type() === 'error') fail(`${label}: console error: ${msg.text()}`); });
  page.on('pageerror', (err) => fail(`${label}: page error: ${err.message}`));
  page.on('requestfailed', (req) => fail(`${label}: request failed: ${req.url()} (${req.failure()?.errorText})`));
  page.on('response', (res) => {
    requests.push({ url: res.url(), status: res.status() });
    if (res.status() >= 400) fail(`${label}: HTTP ${res.status()} for ${res.url()}`);
  });
  await page.route('**/*', (route) => {
    const u = route.request().url();
    if (u.startsWith(origin + '/') || u.startsWith('data:') || u.startsWith('blob:')) return route.continue();
    fail(`${label}: request to another host: ${u}`);
    return route.abort('blockedbyclient');
  });
  return { page, requests };
}

/// Share of the map's pixels (outside the panel) that are terrain-coloured,
/// and, over the pixels of the page's terrain colour (colours.terrain) lit
/// more or less — its chromaticity within SHADE_CHROMA — how their
/// brightness (0–255) spreads: its standard deviation, near 0 for a flat
/// colour, larger for shaded relief.
const SHADE_CHROMA = 0.03;
const near = (c, ref) => ref && Math.hypot(c[0] - ref[0], c[1] - ref[1], c[2] - ref[2]) < COLOUR_DISTANCE;
const chroma = ([r, g, b]) => { const sum = r + g + b || 1; return [r / sum, g / sum]; };
const hexColour = (hex) => [1, 3, 5].map((i) => parseInt(hex.slice(i, i + 2), 16));
export async function terrainPixels(page, file) {
  const colours = await page.evaluate(() => window.tinsmithViewer.colours);
  const shot = await page.screenshot({ path: file, timeout: 30_000 });
  const png = decodePng(shot);
  const panel = await page.evaluate(() => {
    const r = document.getElementById('panel').getBoundingClientRect();
    return { x0: r.left, y0: r.top, x1: r.right, y1: r.bottom };
  });
  const sand = colours.terrain ? chroma(hexColour(colours.terrain)) : null;
  let terrain = 0, counted = 0, shaded = 0, brightness = 0, brightnessSquared = 0;
  for (let y = 0; y < png.height; ++y)
    for (let x = 0; x < png.width; ++x) {
      if (x >= panel.x0 && x < panel.x1 && y >= panel.y0 && y < panel.y1) continue;
      const i = (y * png.width + x) * png.channels;
      const [r, g, b] = [png.data[i], png.data[i + 1], png.data[i + 2]];
      ++counted;
      if (near([r, g, b], colours.sky) || near([r, g, b], colours.globe) || Math.max(r, g, b) < 16) continue;
      ++terrain;
      const [cr, cg] = chroma([r, g, b]);
      if (!sand || Math.hypot(cr - sand[0], cg - sand[1]) > SHADE_CHROMA) continue;
      ++shaded;
      const luma = 0.299 * r + 0.587 * g + 0.114 * b;
      brightness += luma;
      brightnessSquared += luma * luma;
    }
  const mean = shaded ? brightness / shaded : 0;
  return {
    share: terrain / counted, shadedShare: shaded / counted,
    brightnessSpread: shaded ? Math.sqrt(Math.max(0, brightnessSquared / shaded - mean * mean)) : 0,
  };
}
const terrainShare = async (page, file) => (await terrainPixels(page, file)).share;

/// Waits for tinsmithViewer.ready; gives up at the first problem reported.
export async function waitReady(page, label) {
  const failed = new Promise((_, reject) => { onFailure = () => reject(new Error(`${label}: not ready (see above)`)); });
  failed.catch(() => {});
  await Promise.race([failed, (async () => {
    await page.waitForFunction(() => window.tinsmithViewer && window.tinsmithViewer.ready, null, { timeout: left() });
    await page.evaluate(() => window.tinsmithViewer.ready.then(() => true), null, { timeout: left() });
  })()]);
  onFailure = () => {};
  note(`${label}: ready after ${((Date.now() - started) / 1000).toFixed(1)} s`);
}

export function checkShare(label, share) {
  note(`${label}: terrain-coloured ${(share * 100).toFixed(1)} % of the map (required ${(MIN_TERRAIN_SHARE * 100).toFixed(0)} %)`);
  if (!(share >= MIN_TERRAIN_SHARE)) fail(`${label}: terrain covers ${(share * 100).toFixed(1)} % of the map`);
}

async function checkCesium(browser, origin, base, label, full) {
  const { page, requests } = await openPage(browser, origin, label);
  await page.goto(`${origin}${base}/`, { timeout: left() });
  await waitReady(page, label);
  checkShare(label, await terrainShare(page, path.join(outDir, `${full ? '' : 'prefix-'}viewer.png`)));
  const id = await page.evaluate(() => window.tinsmithViewer.id);
  // 3D Tiles on the ellipsoid unless asked otherwise; the Globe choice
  // offered exactly when the tileset has Cesium terrain.
  const summary = (await (await fetch(`${origin}${base}/tilesets`)).json()).tilesets.find((s) => s.id === id);
  const globe = await page.evaluate(() => ({ mode: window.tinsmithViewer.mode, offered: !document.getElementById('globe-choice').hidden }));
  if (globe.mode !== 'tiles') fail(`${label}: the globe is '${globe.mode}' by default, not 3D Tiles on the ellipsoid`);
  if (globe.offered !== Boolean(summary?.links?.terrain))
    fail(`${label}: the Globe choice is ${globe.offered ? '' : 'not '}offered for a tileset ${summary?.links?.terrain ? 'with' : 'without'} terrain`);
  const p = await page.evaluate(([x, y]) => window.tinsmithViewer.probe(x, y), [VIEWPORT.width / 2 - 180, VIEWPORT.height / 2]);
  if (!p || p.z === null) { fail(`${label}: the probe found no height at the map's centre`); await page.close(); return; }
  const shown = await page.evaluate(() => document.getElementById('c-z').textContent);
  if (shown !== `${p.z.toFixed(2)} m`) fail(`${label}: the panel shows '${shown}', the probe ${p.z}`);
  if (!full) { await page.close(); return; }

  const answer = await (await fetch(`${origin}${base}/tilesets/${id}/elevation?lon=${p.lon}&lat=${p.lat}`)).json();
  const tileset = await (await fetch(`${origin}${base}/tilesets/${id}/tileset.json`)).json();
  const tolerance = tileset.root.geometricError + PICK_SLACK;
  const pickDiff = p.pickHeight === null ? Infinity : Math.abs(p.pickHeight - answer.ellipsoidalHeight);
  note(`${label}: probe at (${p.screen}) lon ${p.lon.toFixed(6)} lat ${p.lat.toFixed(6)}: page z ${p.z}, route z ${answer.z}; ` +
    `slope ${p.slope?.toFixed(2)}°, aspect ${p.aspect?.toFixed(1)}°; picked mesh height ${p.pickHeight?.toFixed(2)} m vs route ` +
    `ellipsoidal ${answer.ellipsoidalHeight?.toFixed(2)} m: ${pickDiff.toFixed(2)} m (allowed ${tolerance.toFixed(2)} m)`);
  if (p.z !== answer.z) fail(`${label}: the page's height ${p.z} is not the elevation route's ${answer.z}`);
  if (!(pickDiff <= tolerance)) fail(`${label}: the rendered mesh is ${pickDiff.toFixed(2)} m from the TIN there`);

  const profile = await page.evaluate(([ax, ay, bx, by]) => window.tinsmithViewer.profileScreen(ax, ay, bx, by),
    [VIEWPORT.width * 0.36, VIEWPORT.height * 0.45, VIEWPORT.width * 0.5, VIEWPORT.height * 0.68]);
  const chart = await page.evaluate(() => {
    const c = document.getElementById('chart');
    const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
    let drawn = 0;
    for (let i = 0; i < d.length; i += 4) if (Math.abs(d[i] - 0x11) + Math.abs(d[i + 1] - 0x15) + Math.abs(d[i + 2] - 0x1a) > 30) ++drawn;
    return drawn / (d.length / 4);
  });
  const profileOk = requests.some((r) => r.url.includes('/profile?') && r.status === 200);
  note(`${label}: profile: ${profile.samples} samples over ${profile.length.toFixed(0)} m, chart ${(chart * 100).toFixed(1)} % drawn ` +
    `(required ${(MIN_CHART_SHARE * 100).toFixed(0)} %)`);
  if (!profileOk) fail(`${label}: no profile request answered 200`);
  if (!(profile.inside >= 2 && chart >= MIN_CHART_SHARE)) fail(`${label}: the profile chart is blank`);
  if (!requests.some((r) => r.url.endsWith('/lines.geojson') && r.status === 200)) fail(`${label}: lines.geojson was not loaded`);

  // Real input: the panel follows the mouse; a drag in profile mode draws a profile.
  await page.mouse.move(480, 440, { steps: 3 });
  try {
    await page.waitForFunction(() => { const p = window.tinsmithViewer.lastProbe; return p && p.screen[0] === 480 && p.screen[1] === 440; },
      null, { timeout: 20_000 });
    note(`${label}: the mouse at (480,440): panel height ${await page.evaluate(() => document.getElementById('c-z').textContent)}`);
  } catch { fail(`${label}: the cursor panel did not follow the mouse`); }
  const profiles = await page.evaluate(() => window.tinsmithViewer.profiles);
  await page.click('#profile-mode');
  await page.mouse.move(470, 420);
  await page.mouse.down();
  await page.mouse.move(610, 520, { steps: 4 });
  await page.mouse.up();
  try {
    await page.waitForFunction((n) => window.tinsmithViewer.profiles > n, profiles, { timeout: 20_000 });
    const dragged = await page.evaluate(() => window.tinsmithViewer.lastProfile);
    note(`${label}: dragged profile: ${dragged.samples} samples over ${dragged.length.toFixed(0)} m`);
  } catch { fail(`${label}: a drag in profile mode drew no profile`); }

  // The README's pictures: the cursor panel and the profile, then the tile
  // wireframe, boxes and labels.
  await page.waitForTimeout(500);
  await page.screenshot({ path: path.join(outDir, 'viewer-profile.png'), timeout: 30_000 });

  await page.evaluate(() => {
    for (const id of ['show-wireframe', 'show-tiles']) document.getElementById(id).click();
  });
  await page.waitForTimeout(1500);
  await page.screenshot({ path: path.join(outDir, 'viewer-tiles.png'), timeout: 30_000 });
  await page.close();
}

async function checkThree(browser, origin, base, label, full) {
  const { page, requests } = await openPage(browser, origin, label);
  await page.goto(`${origin}${base}/three`, { timeout: left() });
  await waitReady(page, label);
  const state = await page.evaluate(() => ({ models: window.tinsmithViewer.loadedModels, errors: window.tinsmithViewer.errors }));
  note(`${label}: ${state.models} tiles loaded`);
  for (const e of state.errors) fail(`${label}: ${e}`);
  if (!(state.models > 0)) fail(`${label}: no tile loaded`);
  checkShare(label, await terrainShare(page, path.join(outDir, `${full ? '' : 'prefix-'}three.png`)));
  if (!requests.some((r) => /libs\/draco\/gltf\/draco_(decoder\.wasm|decoder\.js)$/.test(r.url) && r.status === 200))
    fail(`${label}: the Draco decoder was not fetched from the server`);
  await page.close();
}

async function main() {
  const servers = [];
  let browser = null;
  try {
    const plain = await startServer(['-q']);
    servers.push(plain);
    if (!plain.log().includes(path.join(root, 'server', 'viewer')))
      fail(`tinsmith serve did not find the source tree's viewer by itself: ${plain.log().trim()}`);
    const prefixed = await startServer(['-q', '--base-path', PREFIX, '--viewer', path.join(root, 'server', 'viewer')]);
    servers.push(prefixed);
    browser = await launchBrowser();
    await checkCesium(browser, plain.origin, '', 'cesium', true);
    await checkThree(browser, plain.origin, '', 'three', true);
    const redirect = await fetch(`${prefixed.origin}${PREFIX}`, { redirect: 'manual' });
    if (redirect.status !== 301 || redirect.headers.get('location') !== `${PREFIX}/`)
      fail(`${PREFIX} answered ${redirect.status} to ${redirect.headers.get('location')}, not 301 to ${PREFIX}/`);
    await checkCesium(browser, prefixed.origin, PREFIX, 'cesium under a prefix', false);
    await checkThree(browser, prefixed.origin, PREFIX, 'three under a prefix', false);
  } catch (e) {
    fail(e.stack ?? String(e));
  }
  await finish(browser, servers);
}

if (process.argv[1] && path.resolve(process.argv[1]) === fileURLToPath(import.meta.url)) await main();
