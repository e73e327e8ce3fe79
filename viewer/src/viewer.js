// The geotex 3D viewer: three.js + GLTFLoader + OrbitControls, bundled into one
// script that works from file:// (no server, no network).  A page holds one or
// more <div class="geotex-viewer" data-model="ID" data-up="y|z"> elements, each
// naming a <script type="application/octet-stream" id="ID"> holding a base64
// GLB.  State is reported on the element (data-state="loading|loaded|error")
// and errors go to console.error.
import {
  AmbientLight, Box3, Color, DirectionalLight, HemisphereLight, MathUtils,
  PerspectiveCamera, Scene, SRGBColorSpace, Vector3, WebGLRenderer,
} from "three";
import { GLTFLoader } from "three/examples/jsm/loaders/GLTFLoader.js";
import { OrbitControls } from "three/examples/jsm/controls/OrbitControls.js";

const PLAIN = new Color("#d9c7a3");   // the colour of geotex render pictures

function decodeBase64(text) {
  const bin = atob(text.replace(/\s+/g, ""));
  const bytes = new Uint8Array(bin.length);
  for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
  return bytes.buffer;
}

function fail(el, message) {
  el.dataset.state = "error";
  el.textContent = "geotex viewer: " + message;
  console.error("geotex viewer: " + message);
}

function fitCamera(camera, controls, object) {
  const box = new Box3().setFromObject(object);
  const center = box.getCenter(new Vector3());
  const radius = box.getSize(new Vector3()).length() / 2 || 1;
  // front three-quarter view from above (front = +z, right = +x, up = +y),
  // the view geotex render uses
  const dir = new Vector3(0.75, 0.58, 1.0).normalize();
  const fit = Math.tan(MathUtils.degToRad(camera.fov / 2)) * Math.min(1, camera.aspect);
  const dist = (radius / fit) * 0.9;
  camera.position.copy(center).addScaledVector(dir, dist);
  camera.near = dist / 1000;
  camera.far = dist * 100;
  camera.updateProjectionMatrix();
  controls.target.copy(center);
  controls.update();
}

export function mount(el) {
  const script = document.getElementById(el.dataset.model || "");
  if (!script) return fail(el, "no model data (data-model names no script element)");
  el.dataset.state = "loading";
  let renderer;
  try {
    renderer = new WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  } catch (err) {
    return fail(el, "WebGL is not available in this browser (" + err.message + ")");
  }
  const width = el.clientWidth || 640;
  const height = el.clientHeight || 480;
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  renderer.setSize(width, height);
  renderer.outputColorSpace = SRGBColorSpace;
  el.appendChild(renderer.domElement);

  const scene = new Scene();
  scene.background = new Color("#eef1f5");
  scene.add(new HemisphereLight(0xffffff, 0x6d6a66, 0.9));
  scene.add(new AmbientLight(0xffffff, 0.15));
  const key = new DirectionalLight(0xffffff, 2.4);
  key.position.set(3, 5, 4);
  scene.add(key);
  const fill = new DirectionalLight(0xffffff, 0.6);
  fill.position.set(-4, 2, -3);
  scene.add(fill);
  const camera = new PerspectiveCamera(35, width / height, 0.01, 1000);
  const controls = new OrbitControls(camera, renderer.domElement);
  const render = () => renderer.render(scene, camera);
  controls.addEventListener("change", render);

  new GLTFLoader().parse(decodeBase64(script.textContent), "", (gltf) => {
    const root = gltf.scene;
    const up = el.dataset.up || "y";
    if (up === "z") root.rotation.x = -Math.PI / 2;       // z-up -> y-up
    else if (up === "x") root.rotation.z = Math.PI / 2;   // x-up -> y-up
    root.updateMatrixWorld(true);
    let triangles = 0;
    root.traverse((o) => {
      if (!o.isMesh) return;
      const m = o.material;
      if (m && !m.map && m.color) m.color.copy(PLAIN);
      if (m) m.flatShading = !o.geometry.attributes.normal;
      const index = o.geometry.index;
      triangles += (index ? index.count : o.geometry.attributes.position.count) / 3;
    });
    scene.add(root);
    fitCamera(camera, controls, root);
    render();
    el.dataset.triangles = String(Math.round(triangles));
    el.dataset.state = "loaded";
  }, (err) => fail(el, "the model could not be read (" + (err && err.message) + ")"));

  window.addEventListener("resize", () => {
    const w = el.clientWidth || width, h = el.clientHeight || height;
    camera.aspect = w / h;
    camera.updateProjectionMatrix();
    renderer.setSize(w, h);
    render();
  });
}

export function mountAll() {
  document.querySelectorAll(".geotex-viewer").forEach((el) => {
    if (!el.dataset.state) mount(el);
  });
}

window.GeotexViewer = { mount, mountAll };
if (document.readyState === "loading") {
  document.addEventListener("DOMContentLoaded", mountAll);
} else {
  mountAll();
}
