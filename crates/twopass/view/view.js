// The page of `twopass view`: the lightmap .glb of a twopass bake, from the scene's camera.
//
// The lightmap PNG in the .glb holds sRGB(min(1, exposure * L)) (L the radiance, exposure in
// asset.extras.twopass). It is shown unlit on UV set 1 (MeshBasicMaterial, map.channel = 1),
// decoded to linear on sampling and sRGB-encoded on output with no tone curve, so a pixel is
// sRGB(min(1, exposure * L)): the tone map of `twopass render --exposure log2(exposure)`.
// The camera (position, target, up, vertical field of view, metres) is the scene's, from
// asset.extras.twopass.camera. OrbitControls look around; document.title says when the first
// frame is drawn ("twopass view: ready") or what failed ("twopass view: error ...").
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

// For automated screenshots (crates/twopass/tests/view.rs): with `?hold` in the URL the page
// keeps a request to ./hold open until it has drawn (or failed), then requests ./ready. A
// headless browser's virtual-time budget does not run out while a request is pending, so its
// screenshot is taken after the frame even when a busy machine slows the load.
const hold = new URLSearchParams(window.location.search).has('hold');
if (hold) fetch('./hold').catch(() => {});
const settled = () => { if (hold) fetch('./ready').catch(() => {}); };

const status = document.getElementById('status');
const fail = (message) => {
  status.textContent = `twopass view: ${message}`;
  document.title = `twopass view: error: ${message}`;
  settled();
};
status.textContent = 'Loading the bake...';

const file = document.querySelector('meta[name="twopass-glb"]').content;
const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
renderer.outputColorSpace = THREE.SRGBColorSpace;
renderer.toneMapping = THREE.NoToneMapping;
renderer.setPixelRatio(window.devicePixelRatio);
renderer.setSize(window.innerWidth, window.innerHeight);
document.body.appendChild(renderer.domElement);

new GLTFLoader().load(file, (gltf) => {
  const extras = gltf.asset?.extras?.twopass;
  const cam = extras?.camera;
  if (!cam) {
    fail(`${file} has no asset.extras.twopass.camera: bake again with this twopass`);
    return;
  }
  let lightmaps = 0;
  gltf.scene.traverse((o) => {
    if (!o.isMesh) return;
    const map = o.material.emissiveMap;
    if (!map) return;
    map.channel = 1;
    o.material = new THREE.MeshBasicMaterial({ map, side: o.material.side });
    lightmaps += 1;
  });
  if (lightmaps === 0) {
    fail(`${file} has no lightmap (emissiveTexture on TEXCOORD_1)`);
    return;
  }
  const scene = new THREE.Scene();
  scene.add(gltf.scene);
  const aspect = () => window.innerWidth / window.innerHeight;
  const camera = new THREE.PerspectiveCamera(cam.vertical_fov_degrees, aspect(), 0.001, 1000);
  camera.position.fromArray(cam.position);
  camera.up.fromArray(cam.up);
  const target = new THREE.Vector3().fromArray(cam.target);
  camera.lookAt(target);
  const controls = new OrbitControls(camera, renderer.domElement);
  controls.target.copy(target);
  controls.update();
  const draw = () => renderer.render(scene, camera);
  controls.addEventListener('change', draw);
  window.addEventListener('resize', () => {
    camera.aspect = aspect();
    camera.updateProjectionMatrix();
    renderer.setSize(window.innerWidth, window.innerHeight);
    draw();
  });
  draw();
  status.remove();
  document.title = 'twopass view: ready';
  settled();
}, undefined, (e) => fail(`cannot load ${file}: ${e?.message ?? e}`));
