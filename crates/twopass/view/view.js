// The page of `twopass view`: a twopass lightmap bake, from the scene's camera.
//
// Mode `lightmap` (meta twopass-mode; the user's glTF asset with an irradiance lightmap): the
// asset's own materials and textures are kept, and each material's extras.lightMap (three.js
// puts extras in material.userData) becomes material.lightMap on UV channel 1 with
// lightMapIntensity = intensity x exposure (x multiplier for RGBM, whose texel is read as
// rgb * a by the shader chunk below), so three.js multiplies the irradiance by the base
// colour and its texture; emission is scaled by the exposure too.
// Mode `unlit` (a radiance lightmap, or a scene that is not glTF): the lightmap PNG in the
// .glb holds sRGB(min(1, exposure * L)) (L the radiance, exposure in asset.extras.twopass). It
// is shown unlit on UV set 1 (MeshBasicMaterial, map.channel = 1), decoded to linear on
// sampling and sRGB-encoded on output with no tone curve.
// Either way a pixel is sRGB(min(1, exposure * L)): the tone map of `twopass render
// --exposure log2(exposure)`.
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
const mode = document.querySelector('meta[name="twopass-mode"]')?.content ?? 'unlit';

// RGBM: value = multiplier * a * rgb, the 8-bit values read linearly (the texture has no
// colour space). The multiplier is in lightMapIntensity; the chunk multiplies by alpha.
const RGBM_TEXEL = 'lightMapTexel.rgb * lightMapTexel.a * lightMapIntensity';
const rgbmDecode = (shader) => {
  shader.fragmentShader = shader.fragmentShader
    .replace('#include <lights_fragment_maps>', THREE.ShaderChunk.lights_fragment_maps)
    .replaceAll('lightMapTexel.rgb * lightMapIntensity', RGBM_TEXEL);
};

// Mode `lightmap`: every material with extras.lightMap gets its texture as material.lightMap.
// Returns how many materials were wired.
const wireLightMaps = async (gltf, exposure) => {
  const done = new Set();
  const meshes = [];
  // The lightmap holds the lamps' light already: the asset's own lights (KHR_lights_punctual)
  // are switched off, as an engine does with lights marked baked.
  gltf.scene.traverse((o) => {
    if (o.isMesh) meshes.push(o);
    if (o.isLight) o.visible = false;
  });
  for (const o of meshes) {
    for (const material of Array.isArray(o.material) ? o.material : [o.material]) {
      const entry = material.userData?.lightMap;
      if (!entry || done.has(material)) continue;
      done.add(material);
      const texture = await gltf.parser.getDependency('texture', entry.index);
      texture.channel = entry.texCoord;
      const rgbm = entry.encoding === 'rgbm';
      texture.colorSpace = rgbm ? THREE.NoColorSpace : THREE.SRGBColorSpace;
      texture.needsUpdate = true;
      material.lightMap = texture;
      material.lightMapIntensity = entry.intensity * exposure * (rgbm ? entry.multiplier : 1);
      if (material.emissive) material.emissiveIntensity *= exposure;
      if (rgbm) {
        material.onBeforeCompile = rgbmDecode;
        material.customProgramCacheKey = () => 'twopass-rgbm';
      }
      material.needsUpdate = true;
    }
  }
  return done.size;
};
const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
renderer.outputColorSpace = THREE.SRGBColorSpace;
renderer.toneMapping = THREE.NoToneMapping;
renderer.setPixelRatio(window.devicePixelRatio);
renderer.setSize(window.innerWidth, window.innerHeight);
document.body.appendChild(renderer.domElement);

new GLTFLoader().load(file, async (gltf) => {
  const extras = gltf.asset?.extras?.twopass;
  const cam = extras?.camera;
  if (!cam) {
    fail(`${file} has no asset.extras.twopass.camera: bake again with this twopass`);
    return;
  }
  let lightmaps = 0;
  if (mode === 'lightmap') {
    try {
      lightmaps = await wireLightMaps(gltf, extras.exposure);
    } catch (e) {
      fail(`cannot read the lightmap of ${file}: ${e?.message ?? e}`);
      return;
    }
    if (lightmaps === 0) {
      fail(`${file} has no material with extras.lightMap`);
      return;
    }
  } else {
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
