// tinsmith's CesiumJS viewer (GET /). Offline: no Ion, no imagery unless the
// page is given ?imagery=XYZ-URL-TEMPLATE, a plain globe colour. Everything
// it asks the server for is relative to the page (tilesets, …/tileset.json,
// …/elevation, …/profile, …/lines.geojson, …/terrain/…), so any port and any
// --base-path prefix work.
//
// Two globes: the ellipsoid with the 3D Tiles tileset on it (the default),
// or, for a tileset whose store holds Cesium terrain (links.terrain in
// /tilesets), tinsmith's quantized-mesh terrain as the globe itself
// (?terrain=1 or the panel's Globe choice), the tileset hidden.
//
// What the cursor panel shows comes from the elevation route (the TIN), not
// from the rendered mesh: the mesh only says where on the ground the cursor
// is (lon, lat). In terrain mode it also shows the terrain tiles' own height
// there (sampleTerrainMostDetailed), beside the route's ellipsoidal height.
// window.tinsmithViewer is for tests and scripts:
//   ready                 resolves when the first tileset is in view and loaded
//   mode                  'tiles' (3D Tiles on the ellipsoid) or 'terrain'
//   hasTerrain            whether the tileset shown has Cesium terrain
//   setMode(mode)         switches the globe; resolves once the view is loaded
//   settled()             resolves once what the view needs is loaded and drawn
//   probe(x, y)           what the panel shows for the screen point (CSS px)
//   profileScreen(ax, ay, bx, by)  a profile between two screen points
//   terrainHeightAt(lon, lat)  (terrain mode) the terrain tiles' height there,
//                         the deepest level available there, and the elevation
//                         route's z and ellipsoidalHeight
//   clampedEntity(lon, lat)  (terrain mode) adds a point clamped to the ground;
//                         resolves with the height CesiumJS clamped it to
//   errors                terrain tiles CesiumJS failed to load
//   colours               the page's flat colours (sky, globe), to measure renders
//   viewer                the Cesium.Viewer
(() => {
  'use strict';

  const SKY = [12, 14, 20];        // background (space) colour
  const GLOBE = [38, 58, 92];      // the plain globe colour: no lit terrain is this blue
  const TERRAIN = '#d9c7a3';       // the tiles' colour, shaded by the fixed light
  const WATER = '#3d6f9e';         // the terrain's water mask (lakes), terrain mode
  const PROFILE_COLOUR = '#ff5ad2';
  const LINE_COLOURS = {
    road: '#ff7a1a', river: '#1f8fff', lake: '#2fd0ff', boundary: '#f2f2f2',
    hole: '#f2f2f2', contour: '#7a5a3a', breakline: '#ffe14d', other: '#ffe14d',
  };

  const $ = (id) => document.getElementById(id);
  const params = new URLSearchParams(location.search);
  const url = (path) => new URL(path, document.baseURI).href;
  const fmt = (v, digits) => (v === null || v === undefined ? '–' : Number(v).toFixed(digits));

  let resolveReady, rejectReady;
  const api = window.tinsmithViewer = {
    ready: new Promise((resolve, reject) => { resolveReady = resolve; rejectReady = reject; }),
    colours: { sky: SKY, globe: GLOBE, terrain: TERRAIN },
    tileset: null, id: null, summary: null, lastProbe: null, lastProfile: null, profiles: 0,
    mode: 'tiles', hasTerrain: false, errors: [],
  };
  api.ready.catch(() => {});

  function status(text, error = false) {
    $('status').textContent = text;
    $('status').classList.toggle('error', error);
  }

  async function getJson(path) {
    const response = await fetch(url(path));
    if (!response.ok) {
      let message = `${response.status} for ${path}`;
      try { message = (await response.json()).error.message; } catch { /* not JSON */ }
      const e = new Error(message);
      e.status = response.status;
      throw e;
    }
    return response.json();
  }

  // The elevation route's answer for one lon, lat; z null off the TIN. The
  // batch form (POST) answers a point off the TIN with z null, not a 404.
  async function elevationAt(lon, lat) {
    const response = await fetch(url(`tilesets/${encodeURIComponent(api.id)}/elevation`), {
      method: 'POST', headers: { 'Content-Type': 'application/json' },
      body: JSON.stringify({ crs: 'lonlat', points: [[lon, lat]] }),
    });
    if (!response.ok) throw new Error(`${response.status} for the elevation at ${lon}, ${lat}`);
    return (await response.json()).points[0];
  }

  // --- the scene -----------------------------------------------------------
  Cesium.Ion.defaultAccessToken = '';  // nothing here reaches Ion
  const viewer = new Cesium.Viewer('view', {
    baseLayer: false, terrainProvider: new Cesium.EllipsoidTerrainProvider(),
    geocoder: false, baseLayerPicker: false, homeButton: false, sceneModePicker: false,
    navigationHelpButton: false, animation: false, timeline: false, fullscreenButton: false,
    infoBox: false, selectionIndicator: false, projectionPicker: false, vrButton: false,
    skyBox: false, skyAtmosphere: false, shouldAnimate: false,
    requestRenderMode: true, maximumRenderTimeChange: Infinity,
  });
  const scene = viewer.scene;
  api.viewer = viewer;
  scene.backgroundColor = Cesium.Color.fromBytes(...SKY, 255);
  scene.globe.baseColor = Cesium.Color.fromBytes(...GLOBE, 255);
  scene.globe.showGroundAtmosphere = false;
  scene.globe.enableLighting = false;
  scene.fog.enabled = false;
  if (scene.sun) scene.sun.show = false;
  if (scene.moon) scene.moon.show = false;

  let wantTerrain = params.get('terrain') === '1';  // the globe asked for, kept across tilesets
  const imagery = params.get('imagery');
  let imageryProvider = null;
  if (imagery) {
    imageryProvider = new Cesium.UrlTemplateImageryProvider({ url: imagery, credit: 'imagery: ' + imagery });
    viewer.imageryLayers.addImageryProvider(imageryProvider);
  }

  // A light from the west-south-west, 50° off the vertical at the tileset's
  // centre, so relief shades the same at any hour.
  function lightFrom(centre) {
    const up = Cesium.Cartesian3.normalize(centre, new Cesium.Cartesian3());
    const east = Cesium.Cartesian3.normalize(Cesium.Cartesian3.cross(Cesium.Cartesian3.UNIT_Z, up, new Cesium.Cartesian3()), new Cesium.Cartesian3());
    const north = Cesium.Cartesian3.cross(up, east, new Cesium.Cartesian3());
    const dir = Cesium.Cartesian3.negate(up, new Cesium.Cartesian3());
    Cesium.Cartesian3.add(dir, Cesium.Cartesian3.multiplyByScalar(east, 1.1, new Cesium.Cartesian3()), dir);
    Cesium.Cartesian3.add(dir, Cesium.Cartesian3.multiplyByScalar(north, 0.4, new Cesium.Cartesian3()), dir);
    scene.light = new Cesium.DirectionalLight({ direction: Cesium.Cartesian3.normalize(dir, dir), intensity: 2.2 });
  }

  // --- the globe: the ellipsoid, or tinsmith's terrain ----------------------
  // The terrain tiles fill the world outside the TIN with the ellipsoid
  // itself (height 0), so a height within half a metre of 0 keeps the plain
  // globe colour and only the TIN's ground is sandy; the water mask paints
  // the lakes. Lit by the fixed light through the tiles' vertex normals.
  // With ?imagery= the imagery colours the globe instead.
  const groundMaterial = new Cesium.Material({
    fabric: {
      type: 'TinsmithGround',
      uniforms: {
        ground: Cesium.Color.fromCssColorString(TERRAIN),
        ellipsoid: Cesium.Color.fromBytes(...GLOBE, 255),
        water: Cesium.Color.fromCssColorString(WATER),
      },
      source: `czm_material czm_getMaterial(czm_materialInput materialInput) {
        czm_material material = czm_getDefaultMaterial(materialInput);
        material.diffuse = abs(materialInput.height) < 0.5 ? ellipsoid.rgb : ground.rgb;
#ifdef HAS_WATER_MASK
        material.diffuse = mix(material.diffuse, water.rgb, materialInput.waterMask);
#endif
        material.alpha = 1.0;
        return material;
      }`,
    },
  });
  const terrainProviders = new Map();  // tileset id → Promise<CesiumTerrainProvider>
  function terrainProviderFor(id) {
    if (!terrainProviders.has(id)) {
      const provider = Cesium.CesiumTerrainProvider.fromUrl(url(`tilesets/${encodeURIComponent(id)}/terrain/`), {
        requestVertexNormals: true, requestWaterMask: true,
      }).then((p) => {
        p.errorEvent.addEventListener((e) => {
          api.errors.push(e.message);
          status(`A terrain tile failed: ${e.message}`, true);
        });
        return p;
      });
      provider.catch(() => terrainProviders.delete(id));
      terrainProviders.set(id, provider);
    }
    return terrainProviders.get(id);
  }

  // Resolves once the globe has no tile left to load, drawn three times over.
  function globeLoaded() {
    return new Promise((resolve) => {
      let frames = 0;
      const remove = scene.postRender.addEventListener(() => {
        frames = scene.globe.tilesLoaded ? frames + 1 : 0;
        if (frames < 3) { scene.requestRender(); return; }
        remove();
        resolve();
      });
      scene.requestRender();
    });
  }

  // mode 'terrain' needs the tileset's terrain (api.hasTerrain).
  async function setGlobe(mode) {
    const terrain = mode === 'terrain';
    const id = api.id;
    const provider = terrain ? await terrainProviderFor(id) : new Cesium.EllipsoidTerrainProvider();
    if (id !== api.id) return;
    viewer.terrainProvider = provider;
    scene.globe.enableLighting = terrain;
    scene.globe.material = terrain && !imageryProvider ? groundMaterial : undefined;
    scene.globe.depthTestAgainstTerrain = terrain;
    api.mode = mode;
    if (api.tileset) api.tileset.show = !terrain;
    $(terrain ? 'globe-terrain' : 'globe-ellipsoid').checked = true;
    // The tile controls act on the 3D Tiles tileset, hidden in terrain mode.
    for (const control of ['show-wireframe', 'show-tiles', 'sse']) $(control).disabled = terrain;
    $('c-terrain-name').hidden = $('c-terrain').hidden = !terrain;
    scene.requestRender();
  }

  function settled() {
    if (api.mode === 'terrain') return globeLoaded();
    return api.tileset ? allLoaded(api.tileset) : Promise.resolve();
  }
  api.settled = settled;

  let lineCount = 0;
  function loadedStatus() {
    if (api.errors.length) return;  // the failure stays in view
    const s = api.summary;
    const what = api.mode === 'terrain'
      ? 'Cesium terrain (quantized-mesh), '
      : s ? `${s.tileCount} tiles, zooms ${s.zooms.min}–${s.zooms.max}, ` : '';
    status(`${api.id}: ${what}${lineCount} break lines. Drag to orbit; right-drag or wheel to zoom.`);
  }

  async function switchGlobe(mode) {
    if (mode === 'terrain' && !api.hasTerrain) throw new Error(`${api.id} has no Cesium terrain`);
    wantTerrain = mode === 'terrain';
    const next = new URL(location.href);
    if (wantTerrain) next.searchParams.set('terrain', '1'); else next.searchParams.delete('terrain');
    history.replaceState(null, '', next);
    status(wantTerrain ? 'Loading the terrain…' : 'Loading the tiles…');
    await setGlobe(mode);
    if (api.tileset) applyDebug(api.tileset);
    await settled();
    loadedStatus();
  }
  api.setMode = switchGlobe;

  // --- tile labels: zoom, x/y and measured error of each tile drawn ---------
  const labels = scene.primitives.add(new Cesium.LabelCollection());
  let visible = new Map(), shownKey = '';
  function tileName(tile) {
    const m = /tiles\/(\d+)\/(\d+)\/(\d+)\.glb/.exec(tile.content && tile.content.url ? tile.content.url : '');
    return m ? { z: +m[1], x: +m[2], y: +m[3] } : null;
  }
  scene.preUpdate.addEventListener(() => { visible = new Map(); });
  scene.postRender.addEventListener(() => {
    if (!$('show-tiles').checked) {
      if (shownKey) { labels.removeAll(); shownKey = ''; }
      return;
    }
    const key = [...visible.keys()].sort().join(',');
    if (key === shownKey) return;
    shownKey = key;
    labels.removeAll();
    for (const [, { tile, name }] of visible) {
      labels.add({
        position: tile.boundingSphere.center,
        text: `z${name.z} ${name.x}/${name.y}\nerror ${tile.geometricError.toFixed(2)} m`,
        font: '13px sans-serif', fillColor: Cesium.Color.WHITE, outlineColor: Cesium.Color.BLACK,
        outlineWidth: 3, style: Cesium.LabelStyle.FILL_AND_OUTLINE, showBackground: false,
        disableDepthTestDistance: Number.POSITIVE_INFINITY,
      });
    }
    scene.requestRender();
  });
  function watchTiles(tileset) {
    tileset.tileVisible.addEventListener((tile) => {
      const name = tileName(tile);
      if (name) visible.set(`${name.z}/${name.x}/${name.y}`, { tile, name });
    });
  }

  // --- break lines: lines.geojson as polylines over the terrain ------------
  let lineLayers = [];
  function lineLayer(features, contours) {
    const instances = [];
    for (const f of features) {
      const kind = f.properties.kind;
      if ((kind === 'contour') !== contours || f.geometry.type !== 'LineString') continue;
      const flat = [];
      for (const [lon, lat, h] of f.geometry.coordinates) flat.push(lon, lat, h + 0.5);
      const colour = Cesium.Color.fromCssColorString(LINE_COLOURS[kind] || LINE_COLOURS.other);
      instances.push(new Cesium.GeometryInstance({
        geometry: new Cesium.PolylineGeometry({
          positions: Cesium.Cartesian3.fromDegreesArrayHeights(flat), width: kind === 'contour' ? 1.5 : 3,
          arcType: Cesium.ArcType.NONE, vertexFormat: Cesium.PolylineColorAppearance.VERTEX_FORMAT,
        }),
        attributes: {
          color: Cesium.ColorGeometryInstanceAttribute.fromColor(colour),
          depthFailColor: Cesium.ColorGeometryInstanceAttribute.fromColor(colour.withAlpha(0.35)),
        },
      }));
    }
    if (!instances.length) return null;
    // Drawn dimmed where a coarser tile hides them.
    return scene.primitives.add(new Cesium.Primitive({
      geometryInstances: instances, appearance: new Cesium.PolylineColorAppearance(),
      depthFailAppearance: new Cesium.PolylineColorAppearance({ translucent: true }),
      asynchronous: false,
    }));
  }
  async function loadLines(id) {
    for (const p of lineLayers) if (p) scene.primitives.remove(p);
    lineLayers = [];
    if (!api.summary || !api.summary.elevation) return 0;
    const collection = await getJson(`tilesets/${encodeURIComponent(id)}/lines.geojson`);
    if (id !== api.id) return 0;
    lineLayers = [lineLayer(collection.features, false), lineLayer(collection.features, true)];
    showLines();
    return collection.features.length;
  }
  function showLines() {
    if (lineLayers[0]) lineLayers[0].show = $('show-lines').checked;
    if (lineLayers[1]) lineLayers[1].show = $('show-contours').checked;
    scene.requestRender();
  }

  // --- loading a tileset ---------------------------------------------------
  function allLoaded(tileset) {
    return new Promise((resolve) => {
      const done = () => {
        let frames = 0;
        const remove = scene.postRender.addEventListener(() => {
          if (++frames < 3) { scene.requestRender(); return; }
          remove();
          resolve();
        });
        scene.requestRender();
      };
      if (tileset.tilesLoaded) done();
      else {
        const remove = tileset.allTilesLoaded.addEventListener(() => { remove(); done(); });
        scene.requestRender();
      }
    });
  }

  function flyTo(tileset, duration) {
    const sphere = tileset.boundingSphere;
    return new Promise((resolve) => {
      viewer.camera.flyToBoundingSphere(sphere, {
        offset: new Cesium.HeadingPitchRange(Cesium.Math.toRadians(20), Cesium.Math.toRadians(-50), sphere.radius * 1.55),
        duration, complete: resolve, cancel: resolve,
      });
    });
  }

  async function load(id, summaries) {
    api.id = id;
    api.summary = summaries.find((s) => s.id === id) || null;
    api.hasTerrain = Boolean(api.summary && api.summary.links && api.summary.links.terrain);
    $('globe-choice').hidden = !api.hasTerrain;
    const mode = api.hasTerrain && wantTerrain ? 'terrain' : 'tiles';
    status(`Loading ${id}…`);
    if (api.tileset) scene.primitives.remove(api.tileset);
    api.tileset = null;
    const tileset = await Cesium.Cesium3DTileset.fromUrl(url(`tilesets/${encodeURIComponent(id)}/tileset.json`), {
      enableDebugWireframe: true, maximumScreenSpaceError: Number($('sse').value),
    });
    if (id !== api.id) { tileset.destroy(); return; }
    // Sandy tiles on their own; the imagery's own colours when there is one.
    tileset.style = new Cesium.Cesium3DTileStyle({ color: `color('${imageryProvider ? '#ffffff' : TERRAIN}')` });
    tileset.tileFailed.addEventListener((e) => status(`A tile failed to load: ${e.url}: ${e.message}`, true));
    if (imageryProvider && tileset.imageryLayers) tileset.imageryLayers.addImageryProvider(imageryProvider);
    watchTiles(tileset);
    applyDebug(tileset);
    lightFrom(tileset.boundingSphere.center);
    scene.primitives.add(tileset);
    api.tileset = tileset;
    await setGlobe(mode);
    if (id !== api.id) return;
    const lines = loadLines(id).catch((e) => { status(`Break lines: ${e.message}`, true); return 0; });
    await flyTo(tileset, params.has('instant') ? 0 : 1.5);
    await settled();
    lineCount = await lines;
    loadedStatus();
  }

  function applyDebug(tileset) {
    tileset.debugWireframe = $('show-wireframe').checked;
    tileset.debugShowBoundingVolume = $('show-tiles').checked;
    tileset.maximumScreenSpaceError = Number($('sse').value);
    scene.requestRender();
  }

  // --- under the cursor: the elevation route at the picked lon, lat --------
  function pickLonLat(x, y) {
    const at = new Cesium.Cartesian2(x, y);
    let position = scene.pickPositionSupported ? scene.pickPosition(at) : undefined;
    let onMesh = Cesium.defined(position);
    if (!onMesh) position = viewer.camera.pickEllipsoid(at, scene.globe.ellipsoid);
    if (!Cesium.defined(position)) return null;
    const c = Cesium.Cartographic.fromCartesian(position);
    if (!c) return null;
    return { lon: Cesium.Math.toDegrees(c.longitude), lat: Cesium.Math.toDegrees(c.latitude), pickHeight: onMesh ? c.height : null };
  }

  function showProbe(p) {
    const crs = api.summary && api.summary.crs ? api.summary.crs : 'x, y';
    $('c-crs-name').textContent = crs;
    if (!p) { for (const k of ['c-z', 'c-lonlat', 'c-xy', 'c-slope', 'c-terrain']) $(k).textContent = '–'; return; }
    $('c-lonlat').textContent = `${p.lon.toFixed(6)}°, ${p.lat.toFixed(6)}°`;
    $('c-terrain').textContent = p.terrainHeight === undefined ? '–'
      : `${fmt(p.terrainHeight, 2)} m ellipsoidal (level ${p.terrainLevel})` +
        (p.ellipsoidalHeight === undefined || p.ellipsoidalHeight === null ? '' : `, TIN ${fmt(p.ellipsoidalHeight, 2)} m`);
    if (p.z === null || p.z === undefined) {
      $('c-z').textContent = 'off the TIN'; $('c-xy').textContent = '–'; $('c-slope').textContent = '–';
      return;
    }
    $('c-z').textContent = `${p.z.toFixed(2)} m`;
    $('c-xy').textContent = `${p.x.toFixed(2)}, ${p.y.toFixed(2)} m`;
    $('c-slope').textContent = `${fmt(p.slope, 1)}°` + (p.aspect === null || p.aspect === undefined ? ', level' : `, facing ${fmt(p.aspect, 0)}°`);
  }

  let probeSerial = 0;
  async function probe(x, y) {
    const serial = ++probeSerial;
    const where = pickLonLat(x, y);
    if (!where || !api.id) { showProbe(null); return null; }
    const result = { screen: [x, y], lon: where.lon, lat: where.lat, pickHeight: where.pickHeight, z: null };
    const [e, t] = await Promise.all([
      api.summary && api.summary.elevation ? elevationAt(where.lon, where.lat) : null,
      api.mode === 'terrain' ? terrainSample(where.lon, where.lat) : null,
    ]);
    if (e) Object.assign(result, { x: e.x, y: e.y, z: e.z, slope: e.slope, aspect: e.aspect, ellipsoidalHeight: e.ellipsoidalHeight });
    if (t) Object.assign(result, { terrainHeight: t.height, terrainLevel: t.level });
    result.crs = api.summary ? api.summary.crs : '';
    if (serial === probeSerial) showProbe(result);
    api.lastProbe = result;
    return result;
  }
  api.probe = probe;

  // --- the terrain tiles' own height ---------------------------------------
  // The height of the terrain mesh at lon, lat (degrees), in metres above
  // the ellipsoid, from the deepest level layer.json (and the tiles'
  // metadata) make available there; rejects when a tile fails to load.
  async function terrainSample(lon, lat) {
    const provider = viewer.terrainProvider;
    const at = Cesium.Cartographic.fromDegrees(lon, lat);
    const level = provider.availability ? provider.availability.computeMaximumLevelAtPosition(at) : null;
    const [sampled] = await Cesium.sampleTerrainMostDetailed(provider, [at], true);
    return { height: sampled.height, level };
  }

  function needTerrain(what) {
    if (api.mode !== 'terrain') throw new Error(`${what}: the globe is not tinsmith terrain (?terrain=1)`);
  }

  api.terrainHeightAt = async (lon, lat) => {
    needTerrain('terrainHeightAt');
    const [t, e] = await Promise.all([terrainSample(lon, lat), elevationAt(lon, lat)]);
    return { lon, lat, terrainHeight: t.height, level: t.level, z: e.z, ellipsoidalHeight: e.ellipsoidalHeight ?? null };
  };

  // A point entity clamped to the ground (HeightReference.CLAMP_TO_GROUND)
  // at lon, lat; resolves, once the view has settled, with the height of
  // the position CesiumJS clamped it to (it follows the most detailed
  // terrain tile drawn there), beside the globe's height there
  // (Globe.getHeight) and the elevation route's answer. The clamped position
  // is read through DataSourceDisplay.getBoundingSphere, which
  // viewer.flyTo(entity) uses: marked private in CesiumJS, the only way to
  // it; the version is pinned (package.json).
  api.clampedEntity = async (lon, lat) => {
    needTerrain('clampedEntity');
    const entity = viewer.entities.add({
      position: Cesium.Cartesian3.fromDegrees(lon, lat, 0),
      point: {
        pixelSize: 11, color: Cesium.Color.fromCssColorString(PROFILE_COLOUR), outlineColor: Cesium.Color.WHITE,
        outlineWidth: 2, heightReference: Cesium.HeightReference.CLAMP_TO_GROUND,
        disableDepthTestDistance: Number.POSITIVE_INFINITY,
      },
    });
    await settled();
    const sphere = new Cesium.BoundingSphere();
    for (let frame = 0; ; ++frame) {
      const state = viewer.dataSourceDisplay.getBoundingSphere(entity, false, sphere);
      if (state === Cesium.BoundingSphereState.DONE) break;
      if (state === Cesium.BoundingSphereState.FAILED || frame > 200) throw new Error(`clampedEntity: no clamped position at ${lon}, ${lat}`);
      await new Promise((resolve) => { const remove = scene.postRender.addEventListener(() => { remove(); resolve(); }); scene.requestRender(); });
    }
    const clamped = Cesium.Cartographic.fromCartesian(sphere.center);
    const e = await elevationAt(lon, lat);
    return {
      lon, lat, clampedHeight: clamped.height, globeHeight: scene.globe.getHeight(Cesium.Cartographic.fromDegrees(lon, lat)) ?? null,
      z: e.z, ellipsoidalHeight: e.ellipsoidalHeight ?? null,
    };
  };

  // --- profile: drag a line, the profile route, a chart ---------------------
  const profileLine = scene.primitives.add(new Cesium.PolylineCollection());
  let profileMode = false, dragStart = null;

  function drawChart(answer) {
    const canvas = $('chart');
    const ctx = canvas.getContext('2d');
    const W = canvas.width, H = canvas.height, L = 44, R = 8, T = 10, B = 22;
    ctx.fillStyle = '#11151a';
    ctx.fillRect(0, 0, W, H);
    const samples = answer.samples.filter((s) => s.z !== null);
    if (samples.length < 2) return false;
    let lo = Math.min(...samples.map((s) => s.z)), hi = Math.max(...samples.map((s) => s.z));
    if (hi - lo < 1) { lo -= 0.5; hi += 0.5; }
    const sx = (d) => L + (d / answer.length) * (W - L - R);
    const sy = (z) => T + (1 - (z - lo) / (hi - lo)) * (H - T - B);
    ctx.beginPath();
    ctx.moveTo(sx(samples[0].distance), H - B);
    for (const s of samples) ctx.lineTo(sx(s.distance), sy(s.z));
    ctx.lineTo(sx(samples[samples.length - 1].distance), H - B);
    ctx.closePath();
    ctx.fillStyle = 'rgba(217, 199, 163, 0.55)';
    ctx.fill();
    ctx.beginPath();
    samples.forEach((s, i) => (i ? ctx.lineTo(sx(s.distance), sy(s.z)) : ctx.moveTo(sx(s.distance), sy(s.z))));
    ctx.strokeStyle = PROFILE_COLOUR;
    ctx.lineWidth = 2;
    ctx.stroke();
    ctx.fillStyle = '#c8d0da';
    ctx.font = '11px sans-serif';
    ctx.fillText(`${hi.toFixed(0)} m`, 2, T + 8);
    ctx.fillText(`${lo.toFixed(0)} m`, 2, H - B);
    ctx.fillText('0', L, H - 6);
    const total = `${answer.length.toFixed(0)} m`;
    ctx.fillText(total, W - R - ctx.measureText(total).width, H - 6);
    return true;
  }

  async function profileBetween(a, b) {
    const line = `${a.lon},${a.lat};${b.lon},${b.lat}`;
    const answer = await getJson(`tilesets/${encodeURIComponent(api.id)}/profile?lonlat=${line}`);
    const drawn = drawChart(answer);
    const inside = answer.samples.filter((s) => s.z !== null);
    const zs = inside.map((s) => s.z);
    $('profile-info').textContent = inside.length
      ? `${answer.length.toFixed(0)} m, ${answer.samples.length} samples every ${answer.spacing.toFixed(1)} m; ` +
        `${Math.min(...zs).toFixed(1)}–${Math.max(...zs).toFixed(1)} m`
      : 'the line misses the TIN';
    // The line on the ground: the samples' heights, lifted by the geoid
    // undulation the tiles carry (from one elevation answer).
    let undulation = 0;
    for (const s of [inside[0], inside[inside.length - 1]]) {
      if (!s || undulation) continue;
      const t = answer.length > 0 ? s.distance / answer.length : 0;
      const e = await elevationAt(a.lon + t * (b.lon - a.lon), a.lat + t * (b.lat - a.lat));
      if (e.z !== null && e.ellipsoidalHeight !== undefined) undulation = e.ellipsoidalHeight - e.z;
    }
    profileLine.removeAll();
    const flat = [];
    for (const s of inside) {
      const t = answer.length > 0 ? s.distance / answer.length : 0;
      flat.push(a.lon + t * (b.lon - a.lon), a.lat + t * (b.lat - a.lat), s.z + undulation + 1);
    }
    if (flat.length >= 6)
      profileLine.add({ positions: Cesium.Cartesian3.fromDegreesArrayHeights(flat), width: 3,
        material: Cesium.Material.fromType('Color', { color: Cesium.Color.fromCssColorString(PROFILE_COLOUR) }) });
    scene.requestRender();
    api.lastProfile = { samples: answer.samples.length, inside: inside.length, length: answer.length, drawn };
    api.profiles += 1;
    return api.lastProfile;
  }

  api.profileScreen = async (ax, ay, bx, by) => {
    const a = pickLonLat(ax, ay), b = pickLonLat(bx, by);
    if (!a || !b) throw new Error('a profile end is off the globe');
    return profileBetween(a, b);
  };

  function setProfileMode(on) {
    profileMode = on;
    $('profile-mode').classList.toggle('active', on);
    scene.screenSpaceCameraController.enableInputs = !on;
  }
  $('profile-mode').addEventListener('click', () => setProfileMode(!profileMode));

  const handler = new Cesium.ScreenSpaceEventHandler(scene.canvas);
  let pending = null;
  handler.setInputAction((m) => {
    const p = m.endPosition;
    if (profileMode && dragStart) {
      const b = pickLonLat(p.x, p.y);
      if (b) {
        profileLine.removeAll();
        profileLine.add({ positions: Cesium.Cartesian3.fromDegreesArray([dragStart.lon, dragStart.lat, b.lon, b.lat]).map((c, i) => {
          const h = (i === 0 ? dragStart.pickHeight : b.pickHeight) || 0;
          const g = Cesium.Cartographic.fromCartesian(c);
          return Cesium.Cartesian3.fromRadians(g.longitude, g.latitude, h + 2);
        }), width: 2 });
        scene.requestRender();
      }
    }
    // One elevation request at a time; the last position wins.
    if (pending) { pending.next = [p.x, p.y]; return; }
    pending = { next: null };
    const run = (x, y) => probe(x, y).catch((e) => status(e.message, true)).finally(() => {
      const next = pending && pending.next;
      if (next) { pending.next = null; run(...next); } else pending = null;
    });
    run(p.x, p.y);
  }, Cesium.ScreenSpaceEventType.MOUSE_MOVE);
  handler.setInputAction((m) => {
    if (profileMode) dragStart = pickLonLat(m.position.x, m.position.y);
  }, Cesium.ScreenSpaceEventType.LEFT_DOWN);
  handler.setInputAction((m) => {
    if (!profileMode || !dragStart) return;
    const a = dragStart, b = pickLonLat(m.position.x, m.position.y);
    dragStart = null;
    setProfileMode(false);
    if (b) profileBetween(a, b).catch((e) => status(`Profile: ${e.message}`, true));
  }, Cesium.ScreenSpaceEventType.LEFT_UP);

  // --- controls ------------------------------------------------------------
  for (const id of ['globe-ellipsoid', 'globe-terrain'])
    $(id).addEventListener('change', (e) => switchGlobe(e.target.value).catch((err) => status(err.message, true)));
  $('show-lines').addEventListener('change', showLines);
  $('show-contours').addEventListener('change', showLines);
  for (const id of ['show-wireframe', 'show-tiles']) $(id).addEventListener('change', () => api.tileset && applyDebug(api.tileset));
  $('sse').addEventListener('input', () => {
    $('sse-value').textContent = $('sse').value;
    if (api.tileset) applyDebug(api.tileset);
  });

  // --- start ---------------------------------------------------------------
  (async () => {
    const list = (await getJson('tilesets')).tilesets;
    if (!list.length) throw new Error('the server holds no tileset');
    const select = $('tileset');
    for (const s of list) select.add(new Option(s.id, s.id));
    const wanted = params.get('tileset');
    const first = list.some((s) => s.id === wanted) ? wanted : list[0].id;
    select.value = first;
    select.disabled = list.length < 2;
    select.addEventListener('change', () => {
      const next = new URL(location.href);
      next.searchParams.set('tileset', select.value);
      history.replaceState(null, '', next);
      load(select.value, list).catch((e) => status(e.message, true));
    });
    await load(first, list);
    resolveReady(api);
  })().catch((e) => {
    status(e.message, true);
    rejectReady(e);
  });
})();
