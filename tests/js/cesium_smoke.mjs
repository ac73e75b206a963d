#!/usr/bin/env node
// Renders a tileset directory in CesiumJS in headless Chromium (SwiftShader,
// no GPU, no network) and checks that it loads and covers the view:
//
//   node tests/js/cesium_smoke.mjs DIR --out SCREENSHOT.png [--timeout 120] [--min-share 0.30] [--verbose]
//
// A node http server on 127.0.0.1 (ephemeral port) serves DIR under
// /tileset/, Cesium's built files under /cesium/ and the page below. The
// page has no imagery, no ion, no widget that reaches the network; the
// background and the globe get two saturated colours no lit terrain has,
// the light is fixed (not the clock's sun). The camera looks straight down
// on the root region, the page waits for allTilesLoaded and three more frames.
// Fails on a console error, a page error, a failed or non-2xx request (404s
// are listed), a request to any other host, a tile that fails to load,
// or the timeout; then measures the share of screenshot pixels that are
// neither background nor globe nor black, which must reach --min-share.
// Exit status 0 on success, 1 on failure, 2 on bad usage.
import fs from 'node:fs';
import http from 'node:http';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { chromium } from 'playwright-core';
import { decodePng } from './png.mjs';

const HERE = path.dirname(fileURLToPath(import.meta.url));
const CESIUM_DIR = path.join(HERE, 'node_modules', 'cesium', 'Build', 'Cesium');
const CHROMIUM = '/usr/bin/chromium';
const BACKGROUND = [0, 64, 255]; // sky (space) colour
const GLOBE = [255, 0, 255]; // globe base colour
const COLOUR_DISTANCE = 48; // RGB Euclidean: closer than this = that colour
const DARK = 16; // max channel below this = black
const VIEWPORT = { width: 1024, height: 768 };

function usage(message) {
  if (message) console.error(`cesium_smoke: ${message}`);
  console.error('usage: node cesium_smoke.mjs DIR --out SCREENSHOT.png [--timeout SECONDS] [--min-share FRACTION] [--verbose]');
  process.exit(2);
}

function parseArgs(argv) {
  const opts = { dir: null, out: null, timeout: 120, minShare: 0.3, verbose: false };
  for (let i = 0; i < argv.length; ++i) {
    const a = argv[i];
    const value = () => { const v = argv[++i]; if (v === undefined) usage(`${a} needs a value`); return v; };
    if (a === '--out') opts.out = value();
    else if (a === '--timeout') opts.timeout = Number(value());
    else if (a === '--min-share') opts.minShare = Number(value());
    else if (a === '--verbose') opts.verbose = true;
    else if (a.startsWith('-')) usage(`unknown option '${a}'`);
    else if (opts.dir === null) opts.dir = a;
    else usage(`unexpected argument '${a}'`);
  }
  if (!opts.dir || !opts.out) usage('DIR and --out are required');
  if (!(opts.timeout > 0)) usage('--timeout must be a positive number of seconds');
  if (!(opts.minShare >= 0 && opts.minShare <= 1)) usage('--min-share must be within [0, 1]');
  return opts;
}

const PAGE = `<!doctype html>
<html><head><meta charset="utf-8"><title>tinsmith smoke</title>
<link rel="stylesheet" href="/cesium/Widgets/widgets.css">
<style>html, body, #view { margin: 0; width: 100%; height: 100%; overflow: hidden; }</style>
<script>window.CESIUM_BASE_URL = '/cesium/';</script>
<script src="/cesium/Cesium.js"></script>
</head><body><div id="view"></div>
<script>
(async () => {
  const smoke = window.smoke = { done: false, error: null, tilesLoaded: 0, allTilesLoadedEvents: 0, maxVisited: 0 };
  try {
    Cesium.Ion.defaultAccessToken = '';
    const viewer = new Cesium.Viewer('view', {
      baseLayer: false, terrainProvider: new Cesium.EllipsoidTerrainProvider(),
      geocoder: false, baseLayerPicker: false, homeButton: false, sceneModePicker: false,
      navigationHelpButton: false, animation: false, timeline: false, fullscreenButton: false,
      infoBox: false, selectionIndicator: false, projectionPicker: false, vrButton: false,
      skyBox: false, skyAtmosphere: false, shouldAnimate: false,
    });
    viewer.targetFrameRate = 10; // SwiftShader renders on the CPU the compilers share
    const scene = viewer.scene;
    scene.backgroundColor = Cesium.Color.fromBytes(${BACKGROUND.join(', ')}, 255);
    scene.globe.baseColor = Cesium.Color.fromBytes(${GLOBE.join(', ')}, 255);
    scene.globe.showGroundAtmosphere = false;
    scene.globe.enableLighting = false;
    scene.fog.enabled = false;
    if (scene.sun) scene.sun.show = false;
    if (scene.moon) scene.moon.show = false;

    const tilesetJson = await (await fetch('/tileset/tileset.json')).json();
    const region = tilesetJson.root && tilesetJson.root.boundingVolume && tilesetJson.root.boundingVolume.region;
    const tileset = await Cesium.Cesium3DTileset.fromUrl('/tileset/tileset.json');
    tileset.tileFailed.addEventListener((e) => { smoke.error = 'tile failed: ' + e.url + ': ' + e.message; });
    tileset.tileLoad.addEventListener(() => { smoke.tilesLoaded += 1; });
    if (new URLSearchParams(location.search).has('verbose'))
      setInterval(() => {
        const st = tileset.statistics || {};
        console.log('frame ' + scene.frameState.frameNumber + ': tilesLoaded ' + tileset.tilesLoaded + ', visited ' + st.visited +
          ', selected ' + st.selected + ', pending requests ' + st.numberOfPendingRequests + ', content ready ' + st.numberOfTilesWithContentReady);
      }, 5000);
    if (region) {
      const rect = new Cesium.Rectangle(region[0], region[1], region[2], region[3]);
      viewer.camera.setView({ destination: rect });
      // Light from the west, 50 degrees off the vertical, so relief shades.
      const centre = Cesium.Cartesian3.fromRadians((region[0] + region[2]) / 2, (region[1] + region[3]) / 2, 0);
      const up = Cesium.Cartesian3.normalize(centre, new Cesium.Cartesian3());
      const east = Cesium.Cartesian3.normalize(Cesium.Cartesian3.cross(Cesium.Cartesian3.UNIT_Z, up, new Cesium.Cartesian3()), new Cesium.Cartesian3());
      const dir = Cesium.Cartesian3.add(Cesium.Cartesian3.negate(up, new Cesium.Cartesian3()), Cesium.Cartesian3.multiplyByScalar(east, 1.2, new Cesium.Cartesian3()), new Cesium.Cartesian3());
      scene.light = new Cesium.DirectionalLight({ direction: Cesium.Cartesian3.normalize(dir, dir), intensity: 2.0 });
    }
    scene.primitives.add(tileset);
    if (!region) {
      await viewer.zoomTo(tileset);
      scene.light = new Cesium.DirectionalLight({ direction: Cesium.Cartesian3.clone(viewer.camera.directionWC) });
    }
    scene.postRender.addEventListener(() => {
      const st = tileset.statistics;
      if (st) smoke.maxVisited = Math.max(smoke.maxVisited, st.visited);
    });
    tileset.allTilesLoaded.addEventListener(() => {
      smoke.allTilesLoadedEvents += 1;
      let frames = 0;
      const remove = scene.postRender.addEventListener(() => {
        if (++frames < 3) return;
        remove();
        if (tileset.tilesLoaded) smoke.done = true;
      });
    });
  } catch (e) {
    smoke.error = String((e && e.stack) || e);
  }
})();
</script></body></html>
`;

const MIME = {
  '.html': 'text/html; charset=utf-8', '.js': 'text/javascript; charset=utf-8', '.mjs': 'text/javascript; charset=utf-8',
  '.css': 'text/css; charset=utf-8', '.json': 'application/json', '.glb': 'model/gltf-binary', '.wasm': 'application/wasm',
  '.png': 'image/png', '.jpg': 'image/jpeg', '.svg': 'image/svg+xml', '.xml': 'application/xml', '.ktx2': 'image/ktx2',
};

// The server: / -> PAGE, /cesium/... and /tileset/... from disk. Records
// every 4xx/5xx it sends.
function startServer(tilesetDir, log) {
  const roots = { '/cesium/': CESIUM_DIR, '/tileset/': path.resolve(tilesetDir) };
  const server = http.createServer((req, res) => {
    const url = new URL(req.url, 'http://127.0.0.1');
    const send = (status, body, type = 'text/plain; charset=utf-8') => {
      if (status >= 400) log.failures.push(`${status} ${req.method} ${url.pathname}`);
      res.writeHead(status, { 'Content-Type': type, 'Cache-Control': 'no-store' });
      res.end(body);
    };
    if (req.method !== 'GET' && req.method !== 'HEAD') return send(405, 'method not allowed');
    if (url.pathname === '/' || url.pathname === '/index.html') return send(200, PAGE, MIME['.html']);
    if (url.pathname === '/favicon.ico') { res.writeHead(204); return res.end(); }
    for (const [prefix, root] of Object.entries(roots)) {
      if (!url.pathname.startsWith(prefix)) continue;
      const rel = decodeURIComponent(url.pathname.slice(prefix.length));
      const file = path.resolve(root, rel);
      if (file !== root && !file.startsWith(root + path.sep)) return send(403, 'outside the served directory');
      fs.stat(file, (err, st) => {
        if (err || !st.isFile()) return send(404, 'not found');
        if (prefix === '/tileset/') log.tilesetRequests += 1;
        res.writeHead(200, { 'Content-Type': MIME[path.extname(file).toLowerCase()] ?? 'application/octet-stream', 'Content-Length': st.size });
        if (req.method === 'HEAD') return res.end();
        fs.createReadStream(file).pipe(res);
      });
      return;
    }
    send(404, 'not found');
  });
  return new Promise((resolve, reject) => {
    server.on('error', reject);
    server.listen(0, '127.0.0.1', () => resolve(server));
  });
}

// Share of pixels that are neither background nor globe colour nor black.
function terrainShare(png) {
  const dist = (d, i, c) => Math.hypot(d[i] - c[0], d[i + 1] - c[1], d[i + 2] - c[2]);
  let terrain = 0, background = 0, globe = 0, black = 0;
  const n = png.width * png.height;
  for (let p = 0; p < n; ++p) {
    const i = p * png.channels;
    const d = png.data;
    if (dist(d, i, BACKGROUND) < COLOUR_DISTANCE) ++background;
    else if (dist(d, i, GLOBE) < COLOUR_DISTANCE) ++globe;
    else if (Math.max(d[i], d[i + 1], d[i + 2]) < DARK) ++black;
    else ++terrain;
  }
  return { terrain: terrain / n, background: background / n, globe: globe / n, black: black / n, pixels: n };
}

async function main() {
  const opts = parseArgs(process.argv.slice(2));
  if (!fs.existsSync(path.join(opts.dir, 'tileset.json'))) usage(`${opts.dir}/tileset.json does not exist`);
  if (!fs.existsSync(path.join(CESIUM_DIR, 'Cesium.js'))) usage(`${CESIUM_DIR}/Cesium.js is missing: run tools/setup.sh`);
  if (!fs.existsSync(CHROMIUM)) usage(`${CHROMIUM} is missing: run tools/setup.sh (Debian package chromium)`);

  const started = Date.now();
  const deadline = started + opts.timeout * 1000;
  const log = { failures: [], tilesetRequests: 0 };
  const problems = [];
  const server = await startServer(opts.dir, log);
  const origin = `http://127.0.0.1:${server.address().port}`;
  let browser = null;
  let share = null;
  let timedOut = false;
  // A hard stop in case the browser hangs past the deadline.
  const watchdog = setTimeout(() => {
    console.log(`ERROR: cesium_smoke: still running ${opts.timeout + 30} s after the start; giving up`);
    process.exit(1);
  }, (opts.timeout + 30) * 1000);
  watchdog.unref();
  try {
    browser = await chromium.launch({
      executablePath: CHROMIUM,
      args: ['--headless=new', '--no-sandbox', '--enable-unsafe-swiftshader', '--use-angle=swiftshader', '--disable-dev-shm-usage'],
      timeout: 60_000,
    });
    const page = await browser.newPage({ viewport: VIEWPORT, deviceScaleFactor: 1 });
    page.on('console', (msg) => {
      if (msg.type() === 'error') problems.push(`console error: ${msg.text()}`);
      else if (opts.verbose) console.log(`console ${msg.type()}: ${msg.text()}`);
    });
    page.on('pageerror', (err) => problems.push(`page error: ${err.message}`));
    page.on('requestfailed', (req) => problems.push(`request failed: ${req.url()} (${req.failure()?.errorText})`));
    page.on('response', (res) => { if (res.status() >= 400) problems.push(`HTTP ${res.status()}: ${res.url()}`); });
    await page.route('**/*', (route) => {
      const url = route.request().url();
      if (url.startsWith(origin + '/') || url.startsWith('data:') || url.startsWith('blob:')) return route.continue();
      problems.push(`request to another host blocked: ${url}`);
      return route.abort('blockedbyclient');
    });
    await page.goto(origin + (opts.verbose ? '/?verbose' : '/'), { timeout: Math.max(1000, deadline - Date.now()) });
    try {
      await page.waitForFunction(() => window.smoke && (window.smoke.done || window.smoke.error), null,
        { timeout: Math.max(1000, deadline - Date.now()), polling: 500 });
    } catch {
      timedOut = true;
    }
    const state = await page.evaluate(() => window.smoke ?? null);
    if (timedOut)
      problems.push(`tiles not loaded within ${opts.timeout} s` + (state && state.maxVisited === 0
        ? ": Cesium never traversed the tileset (it skips one whose geometricError projects below 16 px at this view)" : ''));
    if (state?.error) problems.push(`page: ${state.error}`);
    const shot = await page.screenshot({ path: opts.out, timeout: 30_000 });
    share = terrainShare(decodePng(shot));
    console.log(`cesium_smoke: ${state?.tilesLoaded ?? 0} tiles loaded, ${log.tilesetRequests} tileset requests, ` +
      `allTilesLoaded ${state?.allTilesLoadedEvents ?? 0}x, ${((Date.now() - started) / 1000).toFixed(1)} s; screenshot ${opts.out}`);
    console.log(`cesium_smoke: terrain share ${(share.terrain * 100).toFixed(1)} % ` +
      `(background ${(share.background * 100).toFixed(1)} %, globe ${(share.globe * 100).toFixed(1)} %, black ${(share.black * 100).toFixed(1)} %; ` +
      `${share.pixels} pixels), required ${(opts.minShare * 100).toFixed(1)} %`);
    if (share.terrain < opts.minShare) problems.push(`terrain covers ${(share.terrain * 100).toFixed(1)} % of the view, less than ${(opts.minShare * 100).toFixed(1)} %`);
  } catch (e) {
    problems.push(`${e.message ?? e}`);
  } finally {
    if (browser) await browser.close().catch(() => {});
    server.close();
    clearTimeout(watchdog);
  }
  for (const f of log.failures) console.log(`server: ${f}`);
  for (const p of problems) console.log(`ERROR: cesium_smoke: ${p}`);
  console.log(`cesium_smoke: ${problems.length ? 'FAILED' : 'ok'}`);
  process.exitCode = problems.length ? 1 : 0;
}

main().catch((e) => { console.error(`ERROR: cesium_smoke: ${e.stack ?? e}`); process.exit(1); });
