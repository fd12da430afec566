// sh.json's engines.three (`ibl bake --target three`) in three.js's LightProbe, in headless
// Debian chromium: a white diffuse sphere lit only by a LightProbe whose coefficients are
// ibl's, against the same sphere lit only by the LightProbe three makes itself from the same
// HDRI (WebGLCubeRenderTarget.fromEquirectangularTexture, then
// LightProbeGenerator.fromCubeRenderTarget: three's own equirect import and SH projection).
// The sphere is seen from +Z and from -Z, so every SH term shows. Negative controls, each must
// fail the bound: the coefficients without the x flip (c3, c4, c7 with the cube frame's sign)
// and the bake a quarter turn off.
// Usage: node lightprobe_test.mjs IBL WORKDIR [SCREENSHOT_DIR]
import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { makeChecker } from './common.mjs';
import { freshWorkWithEnvironments, startServer, launchChromium, runIbl, compareRenders, writeStackedPng } from './render_common.mjs';

const [ibl, work, shots] = process.argv.slice(2);
const here = path.dirname(fileURLToPath(import.meta.url));
const repo = path.resolve(here, '..', '..');
const { check, finish } = makeChecker();
const t0 = Date.now();
const W = 256, H = 128, SIZE = 128;

const page = `<!doctype html><body style="margin:0;background:#000">
<canvas id="c" width="${W}" height="${H}"></canvas>
<script type="importmap">{"imports":{"three":"/nm/three/build/three.module.js"}}</script>
<script type="module">
import * as THREE from 'three';
import { HDRLoader } from '/nm/three/examples/jsm/loaders/HDRLoader.js';
import { LightProbeGenerator } from '/nm/three/examples/jsm/lights/LightProbeGenerator.js';
const renderer = new THREE.WebGLRenderer({ canvas: document.getElementById('c'), preserveDrawingBuffer: true, alpha: true });
renderer.toneMapping = THREE.NoToneMapping;
renderer.setClearColor(0x000000, 0);
renderer.autoClear = false;
const scene = new THREE.Scene();
const probe = new THREE.LightProbe();
scene.add(probe);
scene.add(new THREE.Mesh(new THREE.SphereGeometry(1, 96, 48),
  new THREE.MeshStandardMaterial({ color: 0xffffff, roughness: 1, metalness: 0 })));
const cameras = [10, -10].map((z) => {
  const c = new THREE.OrthographicCamera(-1.05, 1.05, 1.05, -1.05, 0.1, 100);
  c.position.set(0, 0, z);
  c.lookAt(0, 0, 0);
  return c;
});
// the sphere seen from +Z (left half) and from -Z (right half)
function grab() {
  renderer.setScissorTest(true);
  renderer.clear();
  cameras.forEach((c, i) => {
    renderer.setViewport(i * ${H}, 0, ${H}, ${H});
    renderer.setScissor(i * ${H}, 0, ${H}, ${H});
    renderer.render(scene, c);
  });
  const gl = renderer.getContext(), px = new Uint8Array(${W} * ${H} * 4);
  gl.readPixels(0, 0, ${W}, ${H}, gl.RGBA, gl.UNSIGNED_BYTE, px);
  return Array.from(px);
}
window.run = async (hdrUrl, shArrays) => {
  const eq = await new HDRLoader().loadAsync(hdrUrl);
  const target = new THREE.WebGLCubeRenderTarget(${SIZE}, { type: THREE.HalfFloatType });
  target.fromEquirectangularTexture(renderer, eq);
  const own = await LightProbeGenerator.fromCubeRenderTarget(renderer, target);
  probe.sh.copy(own.sh);
  const out = { own: grab(), ibl: [], ownSh: own.sh.toArray() };
  for (const values of shArrays) {
    probe.sh.fromArray(values);
    out.ibl.push(grab());
  }
  return out;
};
window.ready = true;
</script>`;

freshWorkWithEnvironments(work, repo);
const { server, base } = await startServer(here, work, { 'probe.html': page });
const { browser, open } = await launchChromium();
const opened = open(`${base}/page/probe.html`);
const ENVS = ['uffizi', 'axes'];
const bake = (env, dir, extra = []) => runIbl(ibl, ['bake', path.join(work, env + '.hdr'), '--target', 'three',
  ...extra, '--size', String(SIZE), '-o', path.join(work, dir), '-q']);
await Promise.all([...ENVS.map((env) => bake(env, env)), bake('axes', 'axes-turned', ['--yaw', '0'])]);
const shOf = (dir) => JSON.parse(fs.readFileSync(path.join(work, dir, 'sh.json'), 'utf8')).engines.three.values.flat();
const { p, errors } = await opened;
console.log('three.js loaded after ' + ((Date.now() - t0) / 1000).toFixed(1) + ' s');

// Bound: mean |difference| over the sphere pixels (8-bit sRGB). Both probes are 9-term SH of the
// same HDRI in three's frame; they differ by the two equirect-to-cube resamplings (ibl's
// 128-texel cube against three's 128-texel render target) and the projection weights (ibl's
// exact texel solid angles, three's approximation 4 / (1 + u^2 + v^2)^1.5): a few tenths of a
// percent of the light, measured 0.2-0.4/255 (docs/ENGINES.md). 1.5/255 holds that; the
// negative controls (x unflipped, a quarter turn) move the light across the sphere by far more.
const BOUND = 1.5;
for (const env of ENVS) {
  const values = shOf(env);
  const unflipped = values.map((v, i) => ([3, 4, 7].includes(Math.floor(i / 3)) ? -v : v));
  const arrays = env === 'axes' ? [values, unflipped, shOf('axes-turned')] : [values];
  const r = await p.evaluate(([h, a]) => window.run(h, a), [`/w/${env}.hdr`, arrays]);
  const c = compareRenders(r.own, r.ibl[0], W);
  const worstCoefficient = Math.max(...values.map((v, i) => Math.abs(v - r.ownSh[i])));
  check(`${env}: LightProbe from sh.json engines.three vs three's LightProbeGenerator of the HDRI`,
    c.mean < BOUND && c.pixels > 15000,
    `mean ${c.mean.toFixed(3)}/255, worst ${c.worst}/255 over ${c.pixels} px; largest coefficient difference ${worstCoefficient.toFixed(4)} (c0 ${values[0].toFixed(3)})`);
  if (env === 'axes') {
    const u = compareRenders(r.own, r.ibl[1], W), t = compareRenders(r.own, r.ibl[2], W);
    check('axes: c3, c4, c7 without the flip fail the bound', u.mean > 4 * BOUND, `mean ${u.mean.toFixed(3)}/255`);
    check('axes: the bake a quarter turn off fails the bound', t.mean > 4 * BOUND, `mean ${t.mean.toFixed(3)}/255`);
  }
  if (shots && env === 'axes') writeStackedPng(path.join(shots, 'engines_three_lightprobe.png'), W, H, [r.own, r.ibl[0]]);
}
check('no page errors', errors.length === 0, errors.join('; '));
await browser.close();
server.close();
finish(`LightProbe test (${((Date.now() - t0) / 1000).toFixed(1)} s)`);
