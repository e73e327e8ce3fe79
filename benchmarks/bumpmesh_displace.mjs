// Headless driver for BumpMesh (CNCKitchen/stlTexturizer) used by
// benchmarks/bench_displace.py (issue #23). This file is geotex's own code:
// it only *calls* BumpMesh's export pipeline (js/exportPipeline.js, the module
// the web app's Export button and export worker run) from an external checkout
// given with --bumpmesh DIR. Nothing of BumpMesh (AGPL-3.0-only) is copied here
// or anywhere in geotex.
//
// Setup of the external checkout (once, outside the geotex tree):
//   git -C <mirror> archive HEAD | tar -x -C /tmp/bumpmesh
//   cd /tmp/bumpmesh && npm install three@0.170.0 fflate@0.8.2 pngjs && npm pkg set type=module
// (three 0.170.0 and fflate 0.8.2 are the versions of the app's import map.)
//
// What one run does, as the web app does on Export -> STL:
//   read the binary STL, centre it on its bounding-box centre (the app's loader
//   does this), run runExportPipeline (subdivide -> regularize -> re-subdivide ->
//   displace -> decimate to maxTriangles with flat-face harvesting -> bottom
//   snap -> T-junction repair), move the result back to the file's pose, write a
//   binary STL (80-byte header, count, 50 bytes per facet).
// Settings are the app's defaults (js/main.js `settings`, v1.2.0) except the
// ones given on the command line: mapping, tile size, amplitude, refine length,
// triangle target, bottom angle mask.
//
// Usage:
//   node benchmarks/bumpmesh_displace.mjs --bumpmesh DIR --stl IN.stl --image H.png
//        --out OUT.stl [--tile-mm 20] [--depth-mm 1] [--mapping 5]
//        [--refine-mm L | --refine-mm default] [--max-triangles N | default]
//        [--bottom-angle 0]
// Prints one JSON line: triangles, refine length used, stage seconds, repair stats.
// Exit 3 with a note on stderr when --bumpmesh is missing or not a checkout.

import { existsSync, readFileSync, writeFileSync } from 'node:fs';
import { createRequire } from 'node:module';
import { join, resolve } from 'node:path';
import { pathToFileURL } from 'node:url';

function parseArgs(argv) {
  const out = {};
  for (let i = 0; i < argv.length; i++) {
    const a = argv[i];
    if (!a.startsWith('--')) throw new Error(`unexpected argument ${a}`);
    out[a.slice(2)] = argv[i + 1];
    i++;
  }
  return out;
}

const args = parseArgs(process.argv.slice(2));
const dir = args.bumpmesh ? resolve(args.bumpmesh) : null;
if (!dir || !existsSync(join(dir, 'js', 'exportPipeline.js'))) {
  process.stderr.write(`BumpMesh skipped: --bumpmesh DIR must be a stlTexturizer checkout with `
    + `js/exportPipeline.js and node_modules (three, fflate, pngjs); got ${dir}\n`);
  process.exit(3);
}
for (const k of ['stl', 'image', 'out']) {
  if (!args[k]) { process.stderr.write(`missing --${k}\n`); process.exit(2); }
}

const req = createRequire(join(dir, 'package.json'));
const { PNG } = req('pngjs');
const { runExportPipeline } = await import(pathToFileURL(join(dir, 'js', 'exportPipeline.js')).href);

// The app's default settings (v1.2.0), as plain data.
const DEFAULTS = {
  mappingMode: 5, scaleU: 25, scaleV: 25, amplitude: 0.5, textureHeight: 0.5,
  invertDisplacement: false, offsetU: 0, offsetV: 0, rotation: 0,
  refineLength: 1.0, maxTriangles: 750_000, lockScale: true,
  bottomAngleLimit: 5, topAngleLimit: 0, mappingBlend: 1, seamBandWidth: 0.5,
  textureSmoothing: 0, blendNormalSmoothing: 32, capAngle: 20, boundaryFalloff: 0,
  boundaryFalloffCurve: 'ease', symmetricDisplacement: false, noDownwardZ: false,
  smoothBottom: true, harvestFlatFaces: true, harvestTol: 0.005, preserveUntextured: true,
  useDisplacement: false, snapSeamlessWrap: true,
  cylinderCenterX: null, cylinderCenterY: null, cylinderRadius: null,
  regularizeEnabled: true, regularizeAspectThreshold: 5, regularizeSlack: 3.0,
  regularizeAggressiveSlack: 8.0, regularizeExtremeAspect: 8, regularizeNormalDeg: 15,
  regularizeAggressiveNormalDeg: 25, regularizeSecondPassMul: 1.1,
};

const t0 = performance.now();
const stages = {};
let mark = t0;
const lap = (name) => {
  const now = performance.now();
  stages[name] = +(((now - mark) / 1000).toFixed(3));
  mark = now;
};

// --- read the binary STL into a triangle soup ------------------------------
const buf = readFileSync(args.stl);
const nTri = buf.readUInt32LE(80);
if (buf.length < 84 + 50 * nTri) throw new Error(`${args.stl}: not a binary STL`);
const pos = new Float32Array(nTri * 9);
for (let t = 0; t < nTri; t++) {
  const base = 84 + 50 * t + 12;           // skip the facet normal
  for (let k = 0; k < 9; k++) pos[t * 9 + k] = buf.readFloatLE(base + 4 * k);
}
const lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
for (let i = 0; i < pos.length; i++) {
  const a = i % 3;
  if (pos[i] < lo[a]) lo[a] = pos[i];
  if (pos[i] > hi[a]) hi[a] = pos[i];
}
const centre = [0, 1, 2].map((a) => 0.5 * (lo[a] + hi[a]));
for (let i = 0; i < pos.length; i++) pos[i] -= centre[i % 3];
const vec = (a) => ({ x: a[0], y: a[1], z: a[2] });
const bmin = [0, 1, 2].map((a) => lo[a] - centre[a]);
const bmax = [0, 1, 2].map((a) => hi[a] - centre[a]);
const bounds = {
  min: vec(bmin), max: vec(bmax),
  size: vec([0, 1, 2].map((a) => bmax[a] - bmin[a])), center: vec([0, 0, 0]),
};

// --- height map: RGBA bytes, like a canvas getImageData ---------------------
const png = PNG.sync.read(readFileSync(args.image));
const imageData = { data: new Uint8ClampedArray(png.data.buffer, png.data.byteOffset, png.data.length),
  width: png.width, height: png.height };
lap('read');

// --- settings ---------------------------------------------------------------
const s = { ...DEFAULTS };
const tile = +(args['tile-mm'] ?? 20);
s.scaleU = tile; s.scaleV = tile;
s.amplitude = +(args['depth-mm'] ?? 1);
s.mappingMode = +(args.mapping ?? 5);
s.bottomAngleLimit = +(args['bottom-angle'] ?? 0);
const diag = Math.hypot(bounds.size.x, bounds.size.y, bounds.size.z);
// The app's initial refine length on model load: diagonal / 250, 2 decimals, in [0.05, 5].
s.refineLength = (!args['refine-mm'] || args['refine-mm'] === 'default')
  ? Math.max(0.05, Math.min(5.0, +(diag / 250).toFixed(2))) : +args['refine-mm'];
if (args['max-triangles'] && args['max-triangles'] !== 'default') s.maxTriangles = +args['max-triangles'];
const tmax = Math.max(png.width, png.height, 1);
s.textureAspectU = tmax / Math.max(png.width, 1);
s.textureAspectV = tmax / Math.max(png.height, 1);
if (s.bottomAngleLimit > 0) {
  throw new Error('--bottom-angle > 0 needs the app\'s angle mask, which this driver does not build');
}
const regularizeOpts = {
  aspectThreshold: s.regularizeAspectThreshold, slack: s.regularizeSlack,
  aggressiveSlack: s.regularizeAggressiveSlack, extremeSliverAspect: s.regularizeExtremeAspect,
  maxNormalDeltaCos: Math.cos(s.regularizeNormalDeg * Math.PI / 180),
  aggressiveNormalDeltaCos: Math.cos(s.regularizeAggressiveNormalDeg * Math.PI / 180),
  preserveExcluded: s.preserveUntextured,
};

// --- the pipeline -------------------------------------------------------------
let current = null;
const counts = {};
const onEvent = (stage, p, info) => {
  if (stage !== current) {
    if (current !== null) lap(current);
    current = stage;
  }
  if (info && info.triCount) counts[stage] = info.triCount;
};
const result = await runExportPipeline({
  positions: pos, faceWeights: null, imageData, imgWidth: png.width, imgHeight: png.height,
  settings: s, bounds, regularizeOpts, mode: 'export',
}, onEvent);
if (current !== null) lap(current);

// --- back to the file's pose, binary STL ------------------------------------------
const P = result.positions, N = result.normals;
for (let i = 0; i < P.length; i++) P[i] += centre[i % 3];
const m = (P.length / 9) | 0;
const out = Buffer.alloc(84 + 50 * m);
out.writeUInt32LE(m, 80);
for (let t = 0; t < m; t++) {
  const o = 84 + 50 * t, b = 9 * t;
  let nx, ny, nz;
  if (N) {
    nx = N[b]; ny = N[b + 1]; nz = N[b + 2];
  } else {
    const ux = P[b + 3] - P[b], uy = P[b + 4] - P[b + 1], uz = P[b + 5] - P[b + 2];
    const vx = P[b + 6] - P[b], vy = P[b + 7] - P[b + 1], vz = P[b + 8] - P[b + 2];
    nx = uy * vz - uz * vy; ny = uz * vx - ux * vz; nz = ux * vy - uy * vx;
    const len = Math.hypot(nx, ny, nz) || 1;
    nx /= len; ny /= len; nz /= len;
  }
  out.writeFloatLE(nx, o); out.writeFloatLE(ny, o + 4); out.writeFloatLE(nz, o + 8);
  for (let k = 0; k < 9; k++) out.writeFloatLE(P[b + k], o + 12 + 4 * k);
}
writeFileSync(args.out, out);
lap('write');

process.stdout.write(JSON.stringify({
  triangles: m, input_triangles: nTri, refine_mm: s.refineLength, max_triangles: s.maxTriangles,
  safety_cap_hit: !!result.safetyCapHit, decimated: !!result.runDecimation,
  stage_triangles: counts, stages, repair: result.repairStats,
  seconds_in_process: +(((performance.now() - t0) / 1000).toFixed(3)),
}) + '\n');
