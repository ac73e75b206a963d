// tinsmith's three.js viewer (GET /three): 3d-tiles-renderer streams the
// tileset, GLTFExtensionsPlugin decodes Draco with the decoder served under
// viewer/lib/three/examples/jsm/libs/draco/, ReorientationPlugin puts the
// tileset's centre at the origin with +y up (three's convention), north -z; orbit controls around it.
// window.tinsmithViewer.ready resolves once the first view has loaded;
// colours.sky is the background, to measure renders.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { DRACOLoader } from 'three/addons/loaders/DRACOLoader.js';
import { TilesRenderer } from '3d-tiles-renderer/three';
import { GLTFExtensionsPlugin, ReorientationPlugin } from '3d-tiles-renderer/three/plugins';

const SKY = [12, 14, 20];
const TERRAIN = 0xd9c7a3;
const $ = (id) => document.getElementById(id);
const url = (path) => new URL(path, document.baseURI).href;
const params = new URLSearchParams(location.search);

let resolveReady, rejectReady;
const api = window.tinsmithViewer = {
  ready: new Promise((resolve, reject) => { resolveReady = resolve; rejectReady = reject; }),
  colours: { sky: SKY }, tiles: null, loadedModels: 0, errors: [],
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

let tiles = null;
function load(id) {
  if (tiles) { scene.remove(tiles.group); tiles.dispose(); }
  status(`Loading ${id}…`);
  tiles = new TilesRenderer(url(`tilesets/${encodeURIComponent(id)}/tileset.json`));
  tiles.registerPlugin(new GLTFExtensionsPlugin({ dracoLoader }));
  tiles.registerPlugin(new ReorientationPlugin({ up: '+y', recenter: true }));
  tiles.setCamera(camera);
  tiles.setResolutionFromRenderer(camera, renderer);
  // Ready once framed, at least one tile drawn and nothing loading: checked
  // on both events, as a tile's 'load-model' can come after the queue's
  // 'tiles-load-end' (which also fires between the root tileset and its
  // first content).
  let framed = false;
  let idle = false;
  const maybeReady = () => {
    if (!framed || !idle || api.loadedModels === 0) return;
    status(`${id}: ${api.loadedModels} tile${api.loadedModels === 1 ? "" : "s"} loaded. Drag to orbit, right-drag to pan, wheel to zoom.`);
    // Two more frames so the last tiles are drawn before anyone looks.
    requestAnimationFrame(() => requestAnimationFrame(() => resolveReady(api)));
  };
  tiles.addEventListener('load-model', ({ scene: model }) => {
    api.loadedModels += 1;
    model.traverse((o) => { if (o.isMesh) o.material = material; });
    maybeReady();
  });
  tiles.addEventListener('tiles-load-start', () => { idle = false; });
  tiles.addEventListener('load-error', ({ error, url: where }) => {
    api.errors.push(`${where}: ${error && error.message}`);
    status(`Failed to load ${where}: ${error && error.message}`, true);
  });
  tiles.addEventListener('load-root-tileset', () => {
    const sphere = new THREE.Sphere();
    if (!tiles.getBoundingSphere(sphere)) return;
    tiles.group.updateMatrixWorld(true);
    sphere.applyMatrix4(tiles.group.matrixWorld);  // the sphere is in the group's frame
    const r = sphere.radius;
    controls.target.copy(sphere.center);
    camera.position.copy(sphere.center).add(new THREE.Vector3(0.3 * r, 0.95 * r, 1.0 * r));
    camera.near = r / 100;
    camera.far = r * 100;
    camera.updateProjectionMatrix();
    controls.update();
    framed = true;
  });
  tiles.addEventListener('tiles-load-end', () => {
    idle = true;
    maybeReady();
  });
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
  select.addEventListener('change', () => load(select.value));
  load(select.value);
})().catch((e) => { status(e.message, true); rejectReady(e); });
