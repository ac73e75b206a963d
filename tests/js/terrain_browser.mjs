#!/usr/bin/env node
// tinsmith's Cesium terrain (quantized-mesh) in the viewer pages, in headless
// Chromium (SwiftShader WebGL, no network) on a real `tinsmith serve` (ctest
// Viewer.Terrain):
//
//   node tests/js/terrain_browser.mjs TINSMITH STORE OUT_DIR [--timeout 170]
//
// STORE's first tileset must have Cesium terrain (links.terrain in
// /tilesets: built with scheme both). Every page loads with no console
// error, no page error, no failed or ≥ 400 request and no request to another
// host (viewer_browser.mjs's harness). Checked:
//   - `/?terrain=1`: the globe is CesiumTerrainProvider on terrain/ and no
//     terrain tile failed (its errorEvent); the view is drawn from tiles
//     down to within one level of the deepest layer.json lists; every tile
//     layer.json lists is fetched and decoded into a mesh by CesiumJS
//     itself; terrain fills at least MIN_TERRAIN_SHARE of the map and is
//     shaded (the brightness of those pixels spreads by at least
//     MIN_BRIGHTNESS_SPREAD);
//   - at the map's centre, sampleTerrainMostDetailed samples the deepest
//     level layer.json lists there and its height is within that level's
//     error (CesiumJS's: LEVEL_ZERO_ERROR / 2^level) of the elevation
//     route's ellipsoidalHeight; the panel shows it;
//   - seen from 1.5 km, a CLAMP_TO_GROUND point there is clamped to within
//     the same error of the route's ellipsoidalHeight;
//   - the panel's Globe choice switches back to 3D Tiles on the ellipsoid;
//   - `/three?terrain=1`: QuantizedMeshPlugin loads terrain tiles with no load
//     error, down to within one level of the deepest, and they fill and
//     shade the map as above.
// Screenshots: OUT_DIR/terrain.png, terrain-clamped.png, three-terrain.png.
// Exit 0 on success, 1 on a failure.
import path from 'node:path';
import {
  VIEWPORT, checkShare, fail, finish, launchBrowser, left, note, openPage, outDir, started,
  startServer, terrainPixels, waitReady,
} from './viewer_browser.mjs';

// CesiumJS's geometric error of a level-0 tile of the geographic tiling
// scheme (two root tiles, 65-sample heightmap estimate), metres:
// TerrainProvider.getEstimatedLevelZeroGeometricErrorForAHeightmap.
const LEVEL_ZERO_ERROR = 6378137 * 2 * Math.PI * 0.25 / (65 * 2);
const levelError = (level) => LEVEL_ZERO_ERROR / 2 ** level;
const MIN_BRIGHTNESS_SPREAD = 10;  // of terrain pixels' brightness (0–255): a flat colour ~0, Red Butte's relief 30–46
const CLOSE_RANGE = 1500;  // metres from the camera to the clamped point: the deepest level is drawn there

const elapsed = () => `${((Date.now() - started) / 1000).toFixed(1)} s`;

/// The deepest level whose layer.json ranges hold the tile under lon, lat (degrees); -1 if none.
function deepestLevel(layer, lon, lat) {
  let deepest = -1;
  layer.available.forEach((ranges, level) => {
    const x = Math.floor((lon + 180) / 360 * 2 ** (level + 1));
    const y = Math.floor((lat + 90) / 180 * 2 ** level);  // TMS: rows counted from the south
    if (ranges.some((r) => x >= r.startX && x <= r.endX && y >= r.startY && y <= r.endY)) deepest = level;
  });
  return deepest;
}

/// Every tile layer.json lists, as [level, x, y] with y in TMS order.
function listedTiles(layer) {
  const tiles = [];
  layer.available.forEach((ranges, level) => {
    for (const r of ranges)
      for (let x = r.startX; x <= r.endX; ++x)
        for (let y = r.startY; y <= r.endY; ++y) tiles.push([level, x, y]);
  });
  return tiles;
}

/// One line per distinct error, naming the first few tiles it hit.
function failGrouped(label, what, failures) {
  const byMessage = new Map();
  for (const { tile, message } of failures) byMessage.set(message, [...(byMessage.get(message) ?? []), tile]);
  for (const [message, tiles] of byMessage)
    fail(`${label}: ${what} ${tiles.length} tile${tiles.length === 1 ? '' : 's'} (${tiles.slice(0, 4).join(', ')}${tiles.length > 4 ? ', …' : ''}): ${message}`);
}

function checkShaded(label, measured) {
  checkShare(label, measured.share);
  note(`${label}: ${(measured.shadedShare * 100).toFixed(1)} % of the map in the terrain colour, its brightness spread ${measured.brightnessSpread.toFixed(1)} (required ${MIN_BRIGHTNESS_SPREAD})`);
  if (!(measured.brightnessSpread >= MIN_BRIGHTNESS_SPREAD))
    fail(`${label}: the terrain is not shaded (brightness spread ${measured.brightnessSpread.toFixed(1)})`);
}

/// layer.json and terrain tiles were loaded, down to within one level of
/// the deepest layer.json lists: the pages frame the whole TIN, whose
/// deepest level the server chose to meet its tolerance, so both clients'
/// screen-space rules reach that level or the one above it.
function checkTerrainRequests(label, requests, layer) {
  if (!requests.some((r) => r.url.endsWith('/terrain/layer.json') && r.status === 200)) fail(`${label}: terrain/layer.json was not loaded`);
  const levels = requests.map((r) => /\/terrain\/(\d+)\/\d+\/\d+\.terrain$/.exec(r.url)?.[1]).filter(Boolean).map(Number);
  const deepest = levels.length ? Math.max(...levels) : -1;
  const listed = layer.available.length - 1;
  note(`${label}: ${levels.length} terrain tiles loaded, levels ${levels.length ? Math.min(...levels) : '–'}–${deepest} (layer.json: 0–${listed})`);
  if (deepest < listed - 1) fail(`${label}: the view was drawn from levels down to ${deepest} only; layer.json lists levels down to ${listed}`);
}

async function checkCesiumTerrain(browser, origin, summary, layer) {
  const label = 'cesium terrain';
  const { page, requests } = await openPage(browser, origin, label);
  await page.goto(`${origin}/?terrain=1`, { timeout: left() });
  await waitReady(page, label);
  const globe = await page.evaluate(() => {
    const v = window.tinsmithViewer;
    return { mode: v.mode, cesiumTerrain: v.viewer.terrainProvider instanceof Cesium.CesiumTerrainProvider, errors: v.errors };
  });
  note(`${label}: mode ${globe.mode}, CesiumTerrainProvider ${globe.cesiumTerrain}`);
  if (globe.mode !== 'terrain' || !globe.cesiumTerrain) { fail(`${label}: ?terrain=1 did not make the globe tinsmith's terrain`); await page.close(); return; }
  for (const e of globe.errors) fail(`${label}: the globe: ${e}`);
  checkShaded(label, await terrainPixels(page, path.join(outDir, 'terrain.png')));
  checkTerrainRequests(label, requests, layer);

  // CesiumJS decodes every tile the layer lists.
  const tiles = listedTiles(layer);
  const decoded = await page.evaluate(async (list) => {
    const provider = window.tinsmithViewer.viewer.terrainProvider;
    const scheme = provider.tilingScheme;
    const failures = [];
    let meshes = 0;
    await Promise.all(list.map(async ([level, x, tmsY]) => {
      const y = scheme.getNumberOfYTilesAtLevel(level) - 1 - tmsY;
      try {
        const data = await provider.requestTileGeometry(x, y, level);
        await data.createMesh({ tilingScheme: scheme, x, y, level, throttle: false });
        ++meshes;
      } catch (e) {
        failures.push({ tile: `${level}/${x}/${tmsY}.terrain`, message: String(e && e.message ? e.message : e) });
      }
    }));
    return { meshes, failures };
  }, tiles);
  note(`${label}: CesiumJS decoded ${decoded.meshes} of the ${tiles.length} tiles layer.json lists (${elapsed()})`);
  failGrouped(label, 'CesiumJS cannot decode', decoded.failures.sort((a, b) => a.tile.localeCompare(b.tile, 'en', { numeric: true })));

  // The map's centre: the terrain's own height against the elevation route's.
  const p = await page.evaluate(([x, y]) => window.tinsmithViewer.probe(x, y), [VIEWPORT.width / 2 - 180, VIEWPORT.height / 2]);
  const route = await (await fetch(`${origin}/tilesets/${summary.id}/elevation?lon=${p.lon}&lat=${p.lat}`)).json();
  if (typeof route.ellipsoidalHeight !== 'number') { fail(`${label}: the elevation route has no ellipsoidalHeight at the map's centre`); await page.close(); return; }
  const level = deepestLevel(layer, p.lon, p.lat);
  const tolerance = levelError(level);
  const sampled = await page.evaluate(([lon, lat]) => window.tinsmithViewer.terrainHeightAt(lon, lat), [p.lon, p.lat]);
  const sampleDiff = Math.abs(sampled.terrainHeight - route.ellipsoidalHeight);
  note(`${label}: at lon ${p.lon.toFixed(6)} lat ${p.lat.toFixed(6)}: sampleTerrainMostDetailed ${sampled.terrainHeight.toFixed(2)} m ` +
    `at level ${sampled.level} (layer.json's deepest there: ${level}), route ellipsoidal ${route.ellipsoidalHeight.toFixed(2)} m: ` +
    `${sampleDiff.toFixed(2)} m (allowed ${tolerance.toFixed(2)} m); drawn surface picked at ${p.pickHeight?.toFixed(2)} m`);
  if (sampled.level !== level) fail(`${label}: CesiumJS samples level ${sampled.level} there, layer.json lists level ${level}`);
  if (!(sampleDiff <= tolerance)) fail(`${label}: the terrain is ${sampleDiff.toFixed(2)} m from the TIN at the map's centre`);
  const shown = await page.evaluate(() => document.getElementById('c-terrain').textContent);
  if (!shown.startsWith(`${p.terrainHeight.toFixed(2)} m`)) fail(`${label}: the panel shows terrain '${shown}', the probe ${p.terrainHeight}`);

  // Close up, a point clamped to the ground sits on the deepest level's surface.
  await page.evaluate(async ([lon, lat, height, range]) => {
    const camera = window.tinsmithViewer.viewer.camera;
    camera.lookAt(Cesium.Cartesian3.fromDegrees(lon, lat, height), new Cesium.HeadingPitchRange(0.3, -0.7, range));
    camera.lookAtTransform(Cesium.Matrix4.IDENTITY);
    await window.tinsmithViewer.settled();
  }, [p.lon, p.lat, sampled.terrainHeight, CLOSE_RANGE]);
  const clamped = await page.evaluate(([lon, lat]) => window.tinsmithViewer.clampedEntity(lon, lat), [p.lon, p.lat]);
  const clampDiff = Math.abs(clamped.clampedHeight - route.ellipsoidalHeight);
  note(`${label}: a CLAMP_TO_GROUND point there is clamped to ${clamped.clampedHeight.toFixed(2)} m ` +
    `(globe ${clamped.globeHeight?.toFixed(2)} m): ${clampDiff.toFixed(2)} m from the route's (allowed ${tolerance.toFixed(2)} m)`);
  if (!(clampDiff <= tolerance)) fail(`${label}: the clamped point is ${clampDiff.toFixed(2)} m from the TIN`);
  await page.screenshot({ path: path.join(outDir, 'terrain-clamped.png'), timeout: 30_000 });

  // The panel's choice goes back to the tileset on the ellipsoid.
  await page.click('#globe-ellipsoid');
  try {
    await page.waitForFunction(() => window.tinsmithViewer.mode === 'tiles', null, { timeout: 20_000 });
    const back = await page.evaluate(async () => {
      const v = window.tinsmithViewer;
      await v.settled();
      return { shown: v.tileset.show, ellipsoid: v.viewer.terrainProvider instanceof Cesium.EllipsoidTerrainProvider, url: location.search };
    });
    note(`${label}: Globe: ellipsoid: tileset shown ${back.shown}, ellipsoid ${back.ellipsoid}, URL '${back.url}'`);
    if (!back.shown || !back.ellipsoid || back.url.includes('terrain=1')) fail(`${label}: the Globe choice did not go back to the ellipsoid and the tileset`);
  } catch { fail(`${label}: the Globe choice did not switch to the ellipsoid`); }
  await page.close();
}

async function checkThreeTerrain(browser, origin, layer) {
  const label = 'three terrain';
  const { page, requests } = await openPage(browser, origin, label);
  await page.goto(`${origin}/three?terrain=1`, { timeout: left() });
  await waitReady(page, label);
  const state = await page.evaluate(() => ({ mode: window.tinsmithViewer.mode, models: window.tinsmithViewer.loadedModels, errors: window.tinsmithViewer.errors }));
  note(`${label}: mode ${state.mode}, ${state.models} terrain tiles loaded`);
  if (state.mode !== 'terrain') fail(`${label}: ?terrain=1 did not load the terrain`);
  for (const e of state.errors) fail(`${label}: ${e}`);
  if (!(state.models > 0)) fail(`${label}: no terrain tile loaded`);
  checkShaded(label, await terrainPixels(page, path.join(outDir, 'three-terrain.png')));
  checkTerrainRequests(label, requests, layer);
  await page.close();
}

const servers = [];
let browser = null;
try {
  const server = await startServer(['-q']);
  servers.push(server);
  const summary = (await (await fetch(`${server.origin}/tilesets`)).json()).tilesets[0];
  if (!summary?.links?.terrain) {
    fail(`${summary ? `tileset ${summary.id}` : 'the store'} has no Cesium terrain (no links.terrain in /tilesets): build it with --scheme both`);
  } else {
    const layer = await (await fetch(`${server.origin}${summary.links.terrain}`)).json();
    note(`${summary.id}: layer.json lists levels 0–${layer.available.length - 1}, ${listedTiles(layer).length} tiles, extensions ${layer.extensions}`);
    browser = await launchBrowser();
    // Each page on its own: a failure on one still lets the other be checked.
    await checkCesiumTerrain(browser, server.origin, summary, layer).catch((e) => fail(`cesium terrain: ${e.stack ?? e}`));
    await checkThreeTerrain(browser, server.origin, layer).catch((e) => fail(`three terrain: ${e.stack ?? e}`));
  }
} catch (e) {
  fail(e.stack ?? String(e));
}
await finish(browser, servers);
