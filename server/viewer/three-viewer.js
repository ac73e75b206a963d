// tinsmith's three.js viewer (GET /three): 3d-tiles-renderer streams the
// tileset, GLTFExtensionsPlugin decodes Draco with the decoder served under
// viewer/lib/three/examples/jsm/libs/draco/, ReorientationPlugin puts the
// tileset's centre at the origin with +y up (three's convention), north -z; orbit controls around it.
// With ?terrain=1 (or the panel's choice), for a tileset whose store holds
// Cesium terrain, QuantizedMeshPlugin streams that terrain (terrain/layer.json)
// instead, placed and framed the same way.
// window.tinsmithViewer.ready resolves once the first view has loaded;
// colours (sky: the background, globe: the terrain's plain ellipsoid outside
// the TIN, terrain: the ground's colour before shading) are to measure
// renders; mode is 'tiles' or 'terrain'.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { DRACOLoader } from 'three/addons/loaders/DRACOLoader.js';
import { TilesRenderer } from '3d-tiles-renderer/three';
import { GLTFExtensionsPlugin, QuantizedMeshPlugin, ReorientationPlugin } from '3d-tiles-renderer/three/plugins';

const SKY = [12, 14, 20];
const GLOBE = [38, 58, 92];  // the CesiumJS page's plain globe
const TERRAIN = 0xd9c7a3;
const $ = (id) => document.getElementById(id);
const url = (path) => new URL(path, document.baseURI).href;
const params = new URLSearchParams(location.search);

let resolveReady, rejectReady;
const api = window.tinsmithViewer = {
  ready: new Promise((resolve, reject) => { resolveReady = resolve; rejectReady = reject; }),
  colours: { sky: SKY, globe: GLOBE, terrain: `#${TERRAIN.toString(16).padStart(6, '0')}` }, tiles: null, loadedModels: 0, errors: [], mode: 'tiles', hasTerrain: false,
};
api.ready.catch(() => {});
const status = (text, error = false) => { $('status').textContent = text; $('status').classList.toggle('error', error); };

const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(window.devicePixelRatio);
renderer.setSize(window.innerWidth, window.innerHeight);
renderer.setClearColor(new THREE.Color(`rgb(${SKY.join(',')})`));
$('view').appendChild(renderer.domElement);

const scene = new THREE.Scene();
const camera = new THREE.PerspectiveCamera(50, window.innerWidth / window.innerHeight, 1, 1e6);
const controls = new OrbitControls(camera, renderer.domElement);
controls.enableDamping = true;
scene.add(new THREE.HemisphereLight(0xffffff, 0x404040, 1.2));
const sun = new THREE.DirectionalLight(0xffffff, 2.0);
sun.position.set(-1, 0.9, 0.35);  // from the west-south-west, as the CesiumJS page lights it
scene.add(sun);

const dracoLoader = new DRACOLoader();
dracoLoader.setDecoderPath(url('viewer/lib/three/examples/jsm/libs/draco/gltf/'));
const material = new THREE.MeshStandardMaterial({ color: TERRAIN, roughness: 0.95, metalness: 0, side: THREE.DoubleSide });
const terrainMaterial = new THREE.MeshStandardMaterial({ vertexColors: true, roughness: 0.95, metalness: 0, side: THREE.DoubleSide });

// The terrain tiles fill the world outside the TIN with the ellipsoid
// itself (height 0): those vertices get the plain globe colour, the TIN's
// the terrain colour. A tile model's positions are float32 in its own frame
// (a coarse tile's origin can be thousands of km from its vertices), placed
// in the earth-centred frame by its matrix (relative to tiles.group), so a
// height counts as 0 within half a metre plus eight float32 steps of the
// vertex's offset. A split tile (QuantizedMeshPlugin's stand-in for a child
// the layer does not list) is its parent's triangles cut in that frame: a
// vertex made on a cut edge lies on the edge's chord, below the ellipsoid by
// up to (the parent's diagonal)² / 8R.
const EARTH_RADIUS = 6371008.8;  // metres, the mean radius: for bounds on sags and framing only
const groundColour = new THREE.Color(TERRAIN);
const globeColour = new THREE.Color(`rgb(${GLOBE.join(',')})`);
function colourByHeight(model, tile) {
  let sag = 0;
  if (tile.internal && tile.internal.isVirtual && tile.parent && tile.parent.boundingVolume.region) {
    const [west, south, east, north] = tile.parent.boundingVolume.region;
    const diagonal = Math.hypot((east - west) * Math.cos((south + north) / 2), north - south) * EARTH_RADIUS;
    sag = diagonal * diagonal / (8 * EARTH_RADIUS);
  }
  const local = new THREE.Vector3();
  const position = new THREE.Vector3();
  const cartographic = {};
  model.traverse((o) => {
    if (!o.isMesh) return;
    const toEarth = new THREE.Matrix4();
    for (let node = o; node; node = node === model ? null : node.parent) {
      node.updateMatrix();
      toEarth.premultiply(node.matrix);
    }
    const positions = o.geometry.getAttribute('position');
    const colours = new Float32Array(positions.count * 3);
    for (let i = 0; i < positions.count; ++i) {
      local.fromBufferAttribute(positions, i);
      position.copy(local).applyMatrix4(toEarth);
      tiles.ellipsoid.getPositionToCartographic(position, cartographic);
      const zero = 0.5 + 8 * local.length() * 2 ** -23;
      const onEllipsoid = cartographic.height < zero && cartographic.height > -zero - sag;
      (onEllipsoid ? globeColour : groundColour).toArray(colours, 3 * i);
    }
    o.geometry.setAttribute('color', new THREE.BufferAttribute(colours, 3));
    o.material = terrainMaterial;
  });
}

// Looks down on a sphere (in the scene's frame) from above and to one side.
function frame(sphere) {
  const r = sphere.radius;
  controls.target.copy(sphere.center);
  camera.position.copy(sphere.center).add(new THREE.Vector3(0.3 * r, 0.95 * r, 1.0 * r));
  camera.near = r / 100;
  camera.far = r * 100;
  camera.updateProjectionMatrix();
  controls.update();
}

// The sphere around a tileset's bounds (summary.bounds.lonlat in degrees,
// summary.heights in metres) once ReorientationPlugin has put their centre
// at the origin: the terrain's own root is the whole globe.
function boundsSphere(summary) {
  const [west, south, east, north] = summary.bounds.lonlat;
  const [low, high] = summary.heights || [0, 0];
  const across = THREE.MathUtils.degToRad(east - west) * Math.cos(THREE.MathUtils.degToRad((south + north) / 2)) * EARTH_RADIUS;
  const along = THREE.MathUtils.degToRad(north - south) * EARTH_RADIUS;
  return new THREE.Sphere(new THREE.Vector3(), 0.5 * Math.hypot(across, along, high - low));
}

let tiles = null;
function load(id, summary) {
  if (tiles) { scene.remove(tiles.group); tiles.dispose(); }
  status(`Loading ${id}…`);
  api.hasTerrain = Boolean(summary && summary.links && summary.links.terrain && summary.bounds && summary.bounds.lonlat);
  api.mode = api.hasTerrain && params.get('terrain') === '1' ? 'terrain' : 'tiles';
  api.loadedModels = 0;
  $('terrain-choice').hidden = !api.hasTerrain;
  $(api.mode === 'terrain' ? 'show-terrain' : 'show-tiles').checked = true;
  let terrainSphere = null;
  if (api.mode === 'terrain') {
    const [west, south, east, north] = summary.bounds.lonlat;
    const [low, high] = summary.heights || [0, 0];
    terrainSphere = boundsSphere(summary);
    tiles = new TilesRenderer(url(`tilesets/${encodeURIComponent(id)}/terrain/layer.json`));
    tiles.registerPlugin(new QuantizedMeshPlugin({}));
    tiles.registerPlugin(new ReorientationPlugin({
      lat: THREE.MathUtils.degToRad((south + north) / 2), lon: THREE.MathUtils.degToRad((west + east) / 2),
      height: (low + high) / 2, recenter: true,
    }));
  } else {
    tiles = new TilesRenderer(url(`tilesets/${encodeURIComponent(id)}/tileset.json`));
    tiles.registerPlugin(new GLTFExtensionsPlugin({ dracoLoader }));
    tiles.registerPlugin(new ReorientationPlugin({ up: '+y', recenter: true }));
  }
  tiles.setCamera(camera);
  tiles.setResolutionFromRenderer(camera, renderer);
  // Ready once framed, at least one tile drawn and nothing loading for
  // QUIET_UPDATES updates in a row: 'tiles-load-end' also fires between the
  // root tileset and its first content, and between a terrain tile and its
  // children (QuantizedMeshPlugin adds them once the tile is parsed), and a
  // tile's 'load-model' can come after it.
  const QUIET_UPDATES = 10;
  let framed = false;
  let idle = false;
  let quiet = 0;
  tiles.addEventListener('update-after', () => {
    quiet = framed && idle && api.loadedModels > 0 ? quiet + 1 : 0;
    if (quiet !== QUIET_UPDATES) return;
    const what = api.mode === 'terrain' ? 'terrain tile' : 'tile';
    status(`${id}: ${api.loadedModels} ${what}${api.loadedModels === 1 ? "" : "s"} loaded. Drag to orbit, right-drag to pan, wheel to zoom.`);
    // Two more frames so the last tiles are drawn before anyone looks.
    requestAnimationFrame(() => requestAnimationFrame(() => resolveReady(api)));
  });
  tiles.addEventListener('load-model', ({ scene: model, tile }) => {
    api.loadedModels += 1;
    if (api.mode === 'terrain') colourByHeight(model, tile);
    else model.traverse((o) => { if (o.isMesh) o.material = material; });
  });
  tiles.addEventListener('tiles-load-start', () => { idle = false; });
  tiles.addEventListener('load-error', ({ error, url: where }) => {
    api.errors.push(`${where}: ${error && error.message}`);
    status(`Failed to load ${where}: ${error && error.message}`, true);
  });
  tiles.addEventListener('load-root-tileset', () => {
    const sphere = terrainSphere || new THREE.Sphere();
    if (!terrainSphere) {
      if (!tiles.getBoundingSphere(sphere)) return;
      tiles.group.updateMatrixWorld(true);
      sphere.applyMatrix4(tiles.group.matrixWorld);  // the sphere is in the group's frame
    }
    frame(sphere);
    framed = true;
  });
  tiles.addEventListener('tiles-load-end', () => { idle = true; });
  scene.add(tiles.group);
  api.tiles = tiles;
}

window.addEventListener('resize', () => {
  camera.aspect = window.innerWidth / window.innerHeight;
  camera.updateProjectionMatrix();
  renderer.setSize(window.innerWidth, window.innerHeight);
  if (tiles) tiles.setResolutionFromRenderer(camera, renderer);
});

renderer.setAnimationLoop(() => {
  controls.update();
  camera.updateMatrixWorld();
  if (tiles) tiles.update();
  renderer.render(scene, camera);
});

(async () => {
  const response = await fetch(url('tilesets'));
  if (!response.ok) throw new Error(`${response.status} for tilesets`);
  const list = (await response.json()).tilesets;
  if (!list.length) throw new Error('the server holds no tileset');
  const select = $('tileset');
  for (const s of list) select.add(new Option(s.id, s.id));
  const wanted = params.get('tileset');
  select.value = list.some((s) => s.id === wanted) ? wanted : list[0].id;
  select.disabled = list.length < 2;
  const summary = () => list.find((s) => s.id === select.value);
  select.addEventListener('change', () => load(select.value, summary()));
  for (const id of ['show-tiles', 'show-terrain'])
    $(id).addEventListener('change', (e) => {
      const terrain = e.target.value === 'terrain';
      const next = new URL(location.href);
      if (terrain) next.searchParams.set('terrain', '1'); else next.searchParams.delete('terrain');
      history.replaceState(null, '', next);
      params.set('terrain', terrain ? '1' : '0');
      load(select.value, summary());
    });
  load(select.value, summary());
})().catch((e) => { status(e.message, true); rejectReady(e); });
