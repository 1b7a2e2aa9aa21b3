// Runs in the page (view.mjs serves it). Reads the view from the query string, loads /scene.glb,
// renders once to the canvas (what a viewer shows: linear tone mapping with the given exposure,
// sRGB output) and once to a float target (linear radiance, no tone mapping), and compares the
// float image with gcr's per-pixel EXR (/reference.exr) when given.
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { EXRLoader } from 'three/addons/loaders/EXRLoader.js';

// MOZ_lightmap (Mozilla Hubs): {index, texCoord, intensity} on a material → lightMap on uv1.
class MozLightmap {
  constructor(parser) { this.parser = parser; this.name = 'MOZ_lightmap'; }
  extendMaterialParams(materialIndex, params) {
    const def = this.parser.json.materials[materialIndex];
    const ext = def.extensions && def.extensions[this.name];
    if (!ext) return Promise.resolve();
    params.lightMapIntensity = ext.intensity ?? 1;
    return this.parser.assignTexture(params, 'lightMap',
      { index: ext.index, texCoord: ext.texCoord ?? 1 }, THREE.SRGBColorSpace);
  }
}

const q = new URLSearchParams(location.search);
const vec = (s) => new THREE.Vector3(...s.split(',').map(Number));
const [w, h] = q.get('size').split('x').map(Number);

async function main() {
  const renderer = new THREE.WebGLRenderer({ antialias: false, preserveDrawingBuffer: true });
  renderer.setPixelRatio(1);
  renderer.setSize(w, h);
  renderer.outputColorSpace = THREE.SRGBColorSpace;
  renderer.toneMapping = THREE.LinearToneMapping;
  renderer.toneMappingExposure = Number(q.get('exposure'));
  document.body.appendChild(renderer.domElement);

  const loader = new GLTFLoader();
  loader.register((parser) => new MozLightmap(parser));
  const gltf = await loader.loadAsync('/scene.glb');
  const scene = gltf.scene;
  let lightmapped = 0;
  scene.traverse((o) => { if (o.isMesh && o.material.lightMap) lightmapped += 1; });

  const camera = new THREE.PerspectiveCamera(Number(q.get('fov')), w / h, 1e-3, 1e4);
  camera.position.copy(vec(q.get('eye')));
  camera.up.copy(vec(q.get('up')));
  camera.lookAt(vec(q.get('target')));

  renderer.render(scene, camera);

  // Linear radiance: a float target gets neither tone mapping nor the sRGB encoding.
  const target = new THREE.WebGLRenderTarget(w, h, { type: THREE.FloatType });
  renderer.setRenderTarget(target);
  renderer.render(scene, camera);
  const rgba = new Float32Array(w * h * 4);
  renderer.readRenderTargetPixels(target, 0, 0, w, h, rgba);
  renderer.setRenderTarget(null);

  const out = { lightmapped, meshes: 0 };
  scene.traverse((o) => { if (o.isMesh) out.meshes += 1; });
  if (q.get('reference')) {
    const exr = await new EXRLoader().setDataType(THREE.FloatType).loadAsync('/reference.exr');
    out.compare = compare(rgba, exr.image, w, h);
  }
  window.result = out;
}

// Luminance of three.js' float image (rows bottom-up) against the EXR's (rows top-down as
// EXRLoader gives them flipped: its data is bottom-up too, flipY is for the texture).
function compare(rgba, ref, w, h) {
  const lum = (r, g, b) => 0.2126 * r + 0.7152 * g + 0.0722 * b;
  const rc = ref.data.length / (ref.width * ref.height);
  if (ref.width !== w || ref.height !== h) throw new Error(`reference is ${ref.width}x${ref.height}, view ${w}x${h}`);
  const a = new Float64Array(w * h), b = new Float64Array(w * h);
  for (let i = 0; i < w * h; i++) {
    a[i] = lum(rgba[4 * i], rgba[4 * i + 1], rgba[4 * i + 2]);
    b[i] = lum(ref.data[rc * i], ref.data[rc * i + 1], ref.data[rc * i + 2]);
  }
  return { three: Array.from(a), gcr: Array.from(b) };
}

main().catch((e) => { window.result = { error: String(e && e.stack || e) }; });
