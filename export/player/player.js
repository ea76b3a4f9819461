// confluent's web player: plays scene.glb (one glTF node per frame, export/gltf_writer.h) with
// the atlas video as its texture, the active frame following the video's current frame.
//
// config.json beside this page (written by WritePlayer) gives {"scene": URL, "video": URL};
// the query parameters scene= and video= override it.
//
// Fixed-camera mode, for tests and screenshots: with fx, fy, cx, cy, width, height (pixels,
// OpenCV intrinsics as in calib/camera.h), R (9 numbers, row-major) and t (3 numbers):
// x_cam = R * X_world + t in OpenCV axes (x right, y down, z forward), metres, and frame=N
// (optionally near, far in metres), the page renders frame N from exactly that camera at
// width x height pixels (pixel (x, y) of the canvas is the OpenCV pixel centred at (x, y)),
// pauses, hides its controls and sets window.playerReady = true once that frame is drawn with
// the video's frame N as texture. window.playerError is set when something failed.
//
// Without a camera the page plays: orbit controls, play/pause and a timeline; each presented
// video frame (requestVideoFrameCallback's mediaTime) selects its mesh frame. window.playerFrame
// is the mesh frame shown, window.playerFps the scene's frame rate.
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { MeshoptDecoder } from 'three/addons/libs/meshopt_decoder.module.js';

const params = new URLSearchParams(location.search);
const statusText = document.getElementById('status');
const playButton = document.getElementById('play');
const timeline = document.getElementById('timeline');
const frameText = document.getElementById('frame');
const video = document.getElementById('atlas');

window.playerReady = false;
window.playerError = null;

function fail(message) {
  window.playerError = String(message);
  statusText.textContent = 'error: ' + message;
  console.error(message);
}

function numbers(name, count) {
  const text = params.get(name);
  if (text === null) return null;
  const values = text.split(',').map(Number);
  if (values.length !== count || values.some((v) => !Number.isFinite(v))) {
    throw new Error(`query parameter ${name}: expected ${count} numbers, got '${text}'`);
  }
  return values;
}

// The fixed camera of the query, or null.
function queryCamera() {
  const intrinsics = ['fx', 'fy', 'cx', 'cy', 'width', 'height'].map((name) => numbers(name, 1));
  if (intrinsics.every((v) => v === null)) return null;
  if (intrinsics.some((v) => v === null)) throw new Error('a fixed camera needs fx, fy, cx, cy, width and height');
  const [fx, fy, cx, cy, width, height] = intrinsics.map((v) => v[0]);
  const R = numbers('R', 9) || [1, 0, 0, 0, 1, 0, 0, 0, 1];
  const t = numbers('t', 3) || [0, 0, 0];
  const near = numbers('near', 1)?.[0] ?? 0.02;
  const far = numbers('far', 1)?.[0] ?? 1000;
  return { fx, fy, cx, cy, width: Math.round(width), height: Math.round(height), R, t, near, far };
}

// A three.js camera that sees exactly what the OpenCV camera `c` sees. OpenCV looks down +z with
// y down; three.js down -z with y up: camera axes (x, y, z)_three = (x, -y, -z)_cv. The image
// spans [-0.5, W - 0.5] x [-0.5, H - 0.5] in OpenCV pixels.
function fixedCamera(c) {
  const camera = new THREE.PerspectiveCamera();
  const { fx, fy, cx, cy, width: W, height: H, near: n, far: f } = c;
  camera.projectionMatrix.set(
    2 * fx / W, 0, 1 - 2 * (cx + 0.5) / W, 0,
    0, 2 * fy / H, 2 * (cy + 0.5) / H - 1, 0,
    0, 0, -(f + n) / (f - n), -2 * f * n / (f - n),
    0, 0, -1, 0);
  camera.projectionMatrixInverse.copy(camera.projectionMatrix).invert();
  // world_from_camera = [R^T, -R^T t] * diag(1, -1, -1, 1)
  const [r00, r01, r02, r10, r11, r12, r20, r21, r22] = c.R;
  const [tx, ty, tz] = c.t;
  const px = -(r00 * tx + r10 * ty + r20 * tz);
  const py = -(r01 * tx + r11 * ty + r21 * tz);
  const pz = -(r02 * tx + r12 * ty + r22 * tz);
  camera.matrixAutoUpdate = false;
  camera.matrix.set(
    r00, -r10, -r20, px,
    r01, -r11, -r21, py,
    r02, -r12, -r22, pz,
    0, 0, 0, 1);
  camera.matrixWorldNeedsUpdate = true;
  camera.updateMatrixWorld(true);
  // Keep three.js from recomputing the projection from fov/aspect.
  camera.updateProjectionMatrix = () => {};
  return camera;
}

async function loadConfig() {
  let config = { scene: '../scene.glb', video: '../atlas.mp4' };
  try {
    const response = await fetch('config.json');
    if (response.ok) config = { ...config, ...(await response.json()) };
  } catch (error) { /* defaults */ }
  if (params.get('scene')) config.scene = params.get('scene');
  if (params.get('video')) config.video = params.get('video');
  return config;
}

// Resolves when the video can show a frame, or rejects when it cannot be loaded or decoded.
function loadVideo(url) {
  return new Promise((resolve, reject) => {
    video.addEventListener('loadeddata', () => resolve(video), { once: true });
    video.addEventListener('error', () => reject(new Error(`${url}: cannot be played (${video.error?.message || 'no decoder?'})`)), { once: true });
    video.src = url;
    video.load();
  });
}

function seek(time) {
  return new Promise((resolve) => {
    video.addEventListener('seeked', () => resolve(), { once: true });
    video.currentTime = time;
  });
}

function nextAnimationFrame() {
  return new Promise((resolve) => requestAnimationFrame(() => resolve()));
}

async function main() {
  const config = await loadConfig();
  const fixed = queryCamera();
  if (fixed) document.body.classList.add('fixed');

  const renderer = new THREE.WebGLRenderer({ antialias: !fixed, preserveDrawingBuffer: !!fixed });
  renderer.setPixelRatio(fixed ? 1 : window.devicePixelRatio);
  renderer.outputColorSpace = THREE.SRGBColorSpace;
  renderer.setClearColor(0x000000, 1);
  document.getElementById('view').appendChild(renderer.domElement);

  const loader = new GLTFLoader();
  loader.setMeshoptDecoder(MeshoptDecoder);
  const gltf = await loader.loadAsync(config.scene);
  const scene = new THREE.Scene();
  // The file's root rotates confluent's Z-up world to glTF's Y-up; undo it so that the query's
  // cameras (confluent world) apply as they are, and orbit about z.
  const world = new THREE.Group();
  world.rotation.x = Math.PI / 2;
  world.add(gltf.scene);
  scene.add(world);
  scene.updateMatrixWorld(true);

  const extras = gltf.scene.userData || {};
  const fps = Number(extras.fps) || 25;
  window.playerFps = fps;
  const frames = [];
  gltf.scene.traverse((node) => { if (/^frame_\d+$/.test(node.name)) frames.push(node); });
  frames.sort((a, b) => a.name.localeCompare(b.name));
  if (frames.length === 0) throw new Error(`${config.scene}: no frame_NNNNNN nodes`);
  const materials = new Set();
  for (const node of frames) {
    node.scale.set(1, 1, 1);
    node.visible = false;
    node.traverse((o) => { if (o.material) { materials.add(o.material); o.frustumCulled = false; } });
  }
  let current = -1;
  function showFrame(k) {
    k = Math.max(0, Math.min(frames.length - 1, k));
    if (k === current) return;
    if (current >= 0) frames[current].visible = false;
    frames[k].visible = true;
    current = k;
    window.playerFrame = k;
    timeline.value = String(k);
    frameText.textContent = `${k} / ${frames.length - 1}`;
  }
  showFrame(fixed ? Math.round(numbers('frame', 1)?.[0] ?? 0) : 0);

  // The atlas video as the texture (glTF convention: no vertical flip); without it, the
  // file's own base colour (the first atlas frame) stays.
  let texture = null;
  try {
    await loadVideo(config.video);
    texture = new THREE.VideoTexture(video);
    texture.colorSpace = THREE.SRGBColorSpace;
    texture.flipY = false;
    // Mipmapped like confluent's renderer (render/renderer.h), regenerated per video frame.
    texture.generateMipmaps = true;
    texture.minFilter = THREE.LinearMipmapLinearFilter;
    texture.magFilter = THREE.LinearFilter;
    for (const material of materials) { material.map = texture; material.needsUpdate = true; }
  } catch (error) {
    console.warn(String(error));
    window.playerVideoError = String(error);
    if (fixed) throw error;
  }

  if (fixed) {
    renderer.setSize(fixed.width, fixed.height);
    const camera = fixedCamera(fixed);
    await seek((current + 0.5) / fps);
    // The seeked frame is presented at the next composition; a paused video may already have
    // presented it, so wait for its callback at most a second.
    if (video.requestVideoFrameCallback) {
      await Promise.race([new Promise((resolve) => video.requestVideoFrameCallback(() => resolve())),
                          new Promise((resolve) => setTimeout(resolve, 1000))]);
    }
    for (let i = 0; i < 3; ++i) { renderer.render(scene, camera); await nextAnimationFrame(); }
    renderer.render(scene, camera);
    window.playerReady = true;
    return;
  }

  // Interactive mode: orbit about z around the first frame's bounds.
  const camera = new THREE.PerspectiveCamera(40, 1, 0.02, 1000);
  camera.up.set(0, 0, 1);
  const box = new THREE.Box3().setFromObject(frames[current]);
  const centre = box.getCenter(new THREE.Vector3());
  const radius = Math.max(box.getSize(new THREE.Vector3()).length() / 2, 0.1);
  camera.position.copy(centre).add(new THREE.Vector3(0, -3.2 * radius, 0.4 * radius));
  const controls = new OrbitControls(camera, renderer.domElement);
  controls.target.copy(centre);
  controls.update();
  function resize() {
    renderer.setSize(window.innerWidth, window.innerHeight);
    camera.aspect = window.innerWidth / Math.max(window.innerHeight, 1);
    camera.updateProjectionMatrix();
  }
  window.addEventListener('resize', resize);
  resize();

  timeline.max = String(frames.length - 1);
  timeline.disabled = false;
  playButton.disabled = false;
  statusText.textContent = '';
  let playing = false;
  let clockStart = 0;
  function setPlaying(on) {
    playing = on;
    playButton.textContent = on ? 'pause' : 'play';
    if (texture && on) video.play();
    // The paused clock may lag the frame last presented; park the video in the middle of the
    // frame shown, so video, texture and mesh agree.
    if (texture && !on) { video.pause(); video.currentTime = (current + 0.5) / fps; }
    clockStart = performance.now() / 1000 - current / fps;
  }
  playButton.addEventListener('click', () => setPlaying(!playing));
  timeline.addEventListener('input', () => {
    const k = Number(timeline.value);
    showFrame(k);
    if (texture) video.currentTime = (k + 0.5) / fps;
    clockStart = performance.now() / 1000 - k / fps;
  });
  // The video drives the frame: each presented video frame selects its mesh frame.
  if (texture && video.requestVideoFrameCallback) {
    const onVideoFrame = (now, metadata) => {
      showFrame(Math.round(metadata.mediaTime * fps));
      video.requestVideoFrameCallback(onVideoFrame);
    };
    video.requestVideoFrameCallback(onVideoFrame);
  }
  renderer.setAnimationLoop(() => {
    if (texture && !video.requestVideoFrameCallback) showFrame(Math.floor(video.currentTime * fps + 1e-3));
    if (!texture && playing) showFrame(Math.floor((performance.now() / 1000 - clockStart) * fps) % frames.length);
    controls.update();
    renderer.render(scene, camera);
  });
  setPlaying(true);
  window.playerReady = true;
}

main().catch((error) => fail(error && error.message ? error.message : error));
