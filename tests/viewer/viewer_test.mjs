// Browser tests of `ibl view` (run by tests/viewer/run.sh through CTest): headless Debian
// chromium driven by playwright-core, software WebGL2 (SwiftShader). Usage:
//   node viewer_test.mjs IBL WORKDIR
// IBL_VIEWER_SCREENSHOTS=DIR also writes the screenshots of docs/VIEWER.md there.
import { execFileSync, spawnSync } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { pathToFileURL } from 'node:url';
import { makeChecker, readPng, CHROMIUM, importChromium } from './common.mjs';

const [ibl, work] = process.argv.slice(2);
const chromium = await importChromium('viewer test');

const { check, finish } = makeChecker();

// ---- image measures ------------------------------------------------------------------------
const luma = (d, i) => 0.2126 * d[i] + 0.7152 * d[i + 1] + 0.0722 * d[i + 2];
function mean(img) {
  let s = 0;
  for (let i = 0; i < img.data.length; i += 4) s += luma(img.data, i);
  return s / (img.data.length / 4);
}
// Mean |Laplacian| of the luminance over the pixels where mask(x, y) holds with all four
// neighbours: high frequencies, which a blur removes (smooth ramps have none).
function sharpness(img, mask) {
  const { width: w, height: h, data: d } = img;
  const m = (x, y) => !mask || mask(x, y);
  let s = 0, n = 0;
  for (let y = 1; y + 1 < h; y++)
    for (let x = 1; x + 1 < w; x++) {
      if (!(m(x, y) && m(x - 1, y) && m(x + 1, y) && m(x, y - 1) && m(x, y + 1))) continue;
      const i = (y * w + x) * 4;
      s += Math.abs(4 * luma(d, i) - luma(d, i - 4) - luma(d, i + 4) - luma(d, i - 4 * w) - luma(d, i + 4 * w));
      n++;
    }
  return s / Math.max(n, 1);
}
// The brightest luminance where mask(x, y): the sun's highlight, which a wider lobe spreads.
function peak(img, mask) {
  let m = 0;
  for (let y = 0; y < img.height; y++)
    for (let x = 0; x < img.width; x++)
      if (!mask || mask(x, y)) m = Math.max(m, luma(img.data, (y * img.width + x) * 4));
  return m;
}
function diff(a, b, x0 = 0, x1 = a.width) {
  const per = [];
  for (let y = 0; y < a.height; y++)
    for (let x = x0; x < x1; x++) {
      const i = (y * a.width + x) * 4;
      per.push(Math.max(Math.abs(a.data[i] - b.data[i]), Math.abs(a.data[i + 1] - b.data[i + 1]),
                        Math.abs(a.data[i + 2] - b.data[i + 2])));
    }
  const sorted = Float64Array.from(per).sort();
  return {
    mean: per.reduce((s, v) => s + v, 0) / per.length,
    p99: sorted[Math.floor(0.99 * (sorted.length - 1))],
    max: sorted[sorted.length - 1],
    over16: per.filter((v) => v > 16).length / per.length,
  };
}

// ---- the command line part ------------------------------------------------------------------
function run(args) {
  return spawnSync(ibl, args, { encoding: 'utf8' });
}

fs.rmSync(work, { recursive: true, force: true });
fs.mkdirSync(work, { recursive: true });
const bake = path.join(work, 'bake'), html = path.join(work, 'viewer.html');
execFileSync(ibl, ['bake', '-q', '--size', '64', '-o', bake]);
{
  const r = run(['view', '-q', bake, '-o', html]);
  check('ibl view writes the page', r.status === 0 && fs.existsSync(html), r.stderr.trim());
}

function refusal(name, prepare, fileName) {
  const dir = path.join(work, 'bad-' + name), out = path.join(work, 'bad-' + name + '.html');
  fs.cpSync(bake, dir, { recursive: true });
  prepare(dir);
  const r = run(['view', '-q', dir, '-o', out]);
  const lines = r.stderr.trim().split('\n');
  check('ibl view refuses a bake with ' + name,
        r.status === 1 && lines.length === 1 && lines[0].includes(fileName) && !fs.existsSync(out),
        'exit ' + r.status + ': ' + r.stderr.trim());
}
refusal('no specular.ktx2', (d) => { fs.rmSync(path.join(d, 'specular.ktx2')); fs.rmSync(path.join(d, 'specular.dds')); }, 'specular');
refusal('a truncated brdf_lut.ktx2', (d) => {
  const f = path.join(d, 'brdf_lut.ktx2');
  fs.writeFileSync(f, fs.readFileSync(f).subarray(0, 300));
}, 'brdf_lut.ktx2');
refusal('a broken manifest.json', (d) => {
  const f = path.join(d, 'manifest.json');
  fs.writeFileSync(f, fs.readFileSync(f, 'utf8').slice(0, 200));
}, 'manifest.json');
refusal('no manifest.json', (d) => fs.rmSync(path.join(d, 'manifest.json')), 'manifest.json');

// A copy of the page with one embedded texture damaged.
const page = fs.readFileSync(html, 'utf8');
const at = page.indexOf('"data": "', page.indexOf('"irradiance": {')) + 9 + 1000;
const corrupted = path.join(work, 'corrupted.html');
fs.writeFileSync(corrupted, page.slice(0, at) + (page[at] === 'A' ? 'B' : 'A') + page.slice(at + 1));

// ---- the browser part -------------------------------------------------------------------------
if (!fs.existsSync(CHROMIUM)) {
  console.error('viewer test: ' + CHROMIUM + ' is missing (Debian package chromium; scripts/install-deps.sh installs it)');
  process.exit(1);
}
const browser = await chromium.launch({
  executablePath: CHROMIUM,
  args: ['--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist'],
});

async function open(file, viewport = { width: 900, height: 520 }) {
  const p = await browser.newPage({ viewport, deviceScaleFactor: 1 });
  const errors = [];
  p.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
  p.on('pageerror', (e) => errors.push(e.message));
  await p.goto(pathToFileURL(file).href);
  await p.waitForFunction(() => window.iblViewer && (window.iblViewer.ready || window.iblViewer.error), null,
                          { timeout: 20000 });
  return { p, errors };
}

const { p, errors } = await open(html);
const status = await p.evaluate(() => ({ ready: iblViewer.ready, error: iblViewer.error }));
check('the page loads from file:// with no console error', status.ready && !status.error && errors.length === 0,
      status.error || errors.join('; '));

// The default camera against `ibl render` of the same view, both tone-mapped 8-bit sRGB.
const W = 256, H = 128;
await p.evaluate(([w, h]) => iblViewer.setSize(w, h), [W, H]);
const exposure = await p.evaluate(() => iblViewer.state.exposure);
const shot = readPng(await p.locator('#canvas').screenshot());
const refPng = path.join(work, 'render.png');
execFileSync(ibl, ['render', '-q', bake, '--width', String(W), '--height', String(H), '--exposure', String(exposure), '-o', refPng]);
const ref = readPng(fs.readFileSync(refPng));
const d = diff(shot, ref);
// bound: mean <= 0.5 of an 8-bit step, 99th percentile <= 2 steps, at most 0.5% of the pixels
// (sphere silhouettes, hit differently by float rounding) more than 16 steps apart
check('the screenshot matches ibl render of the same view',
      shot.width === W && shot.height === H && d.mean <= 0.5 && d.p99 <= 2 && d.over16 <= 0.005,
      'mean ' + d.mean.toFixed(3) + ', p99 ' + d.p99 + ', max ' + d.max + ', >16: ' + (100 * d.over16).toFixed(2) + '%');

async function pixels(patch, mask) {
  const r = await p.evaluate(([pt, m]) => { iblViewer.set(pt); return iblViewer.pixels(m); }, [patch, !!mask]);
  return { width: r.width, height: r.height, data: Buffer.from(r.data, 'base64') };
}
// Where an object is (inside: 2 pixels from its outline), or the background.
async function region(patch, inside) {
  const m = await pixels(patch, true);
  const at = (x, y) => m.data[(y * m.width + x) * 4] > 127;
  return (x, y) => {
    for (let dy = -2; dy <= 2; dy++)
      for (let dx = -2; dx <= 2; dx++) {
        const u = Math.min(Math.max(x + dx, 0), m.width - 1), v = Math.min(Math.max(y + dy, 0), m.height - 1);
        if (at(u, v) !== inside) return false;
      }
    return true;
  };
}

// Controls on the shader ball: a metal, camera fixed.
const metal = { scene: 1, model: 0, metallic: 1, roughness: 0.05, base: '#ffffff', ball_ao: 0 };
// the sun's highlight at 8 EV below the default exposure, where the sharp one is not clipped
const ball = await region(metal, true);
const sharp = await pixels({ exposure: exposure - 8 });
const rough = await pixels({ roughness: 0.6 });
check('roughness up blurs the reflection (the sun\'s highlight spreads)', peak(sharp, ball) > 1.5 * peak(rough, ball),
      'highlight peak ' + peak(sharp, ball).toFixed(1) + ' -> ' + peak(rough, ball).toFixed(1));
await pixels({ exposure });
const dielectric = await pixels({ metallic: 0, roughness: 0.8, base: '#3060c0' });
check('metalness changes the ball', diff(rough, dielectric).mean > 2, 'mean diff ' + diff(rough, dielectric).mean.toFixed(2));
const noEnergy = await pixels({ metallic: 1, roughness: 1, base: '#ffffff', A: { energy: 0 } });
const turquin = await pixels({ A: { energy: 2 } });
const fdez = await pixels({ A: { energy: 1 } });
check('energy compensation brightens a rough metal', mean(turquin) > mean(noEnergy) && mean(fdez) > mean(noEnergy),
      'mean ' + mean(noEnergy).toFixed(2) + ' -> turquin ' + mean(turquin).toFixed(2) + ', fdez-aguera ' + mean(fdez).toFixed(2));
const bpLow = await pixels({ A: { energy: 0 }, model: 1, base: '#101010', f0: 0.5, shininess: 1, exposure: exposure - 8 });
const bpHigh = await pixels({ shininess: 3.5 });
check('Blinn-Phong shininess up sharpens (the sun\'s highlight narrows)', peak(bpHigh, ball) > 1.5 * peak(bpLow, ball),
      'highlight peak ' + peak(bpLow, ball).toFixed(1) + ' -> ' + peak(bpHigh, ball).toFixed(1));
const bpF0 = await pixels({ f0: 0.1 });
check('Blinn-Phong F0 down darkens the reflection', peak(bpF0, ball) < 0.5 * peak(bpHigh, ball),
      'highlight peak ' + peak(bpHigh, ball).toFixed(1) + ' -> ' + peak(bpF0, ball).toFixed(1));
const ballOcc = await pixels({ exposure, model: 0, metallic: 1, roughness: 0.3, ball_ao: 1, A: { so: 2 } });
const ballNoSo = await pixels({ A: { so: 0 } });
check('SO off brightens the occluded ball', mean(ballNoSo) > mean(ballOcc),
      'mean ' + mean(ballOcc).toFixed(2) + ' -> ' + mean(ballNoSo).toFixed(2));

// Sphere grid with render.c's synthetic AO: each SO formula darkens the occluded balls.
const soNone = await pixels({ scene: 0, sphere_ao: 0.2, A: { so: 0 } });
const soNames = ['ao', 'triace', 'triace-shininess', 'triace-fast', 'frostbite', 'cone'];
const soMeans = [];
for (let f = 1; f <= 6; f++) soMeans.push(mean(await pixels({ A: { so: f } })));
check('each SO formula darkens the occluded spheres; off is brightest', soMeans.every((m) => m < mean(soNone)),
      'none ' + mean(soNone).toFixed(2) + ', ' + soNames.map((n, i) => n + ' ' + soMeans[i].toFixed(2)).join(', '));
const mixDiffs = [];
for (let m = 1; m <= 5; m++) mixDiffs.push(diff(soNone, await pixels({ A: { so: 2, mix: m } })).mean);
const base2 = await pixels({ A: { so: 2, mix: 0 } });
const mixVsMultiply = [];
for (let m = 1; m <= 5; m++) mixVsMultiply.push(diff(base2, await pixels({ A: { mix: m } })).mean);
check('each composition changes the occluded spheres', mixVsMultiply.every((v) => v > 0.05),
      'mean diff vs multiply: ' + mixVsMultiply.map((v) => v.toFixed(2)).join(', '));
const irrMap = await pixels({ A: { so: 0, mix: 0, irradiance: 0 }, sphere_ao: 0 });
const irrSh = await pixels({ A: { irradiance: 1 } });
const dIrr = diff(irrMap, irrSh);
check('SH vs irradiance map changes the diffuse spheres slightly', dIrr.mean > 0 && dIrr.mean < 8,
      'mean diff ' + dIrr.mean.toFixed(3));
const brighter = await pixels({ A: { irradiance: 0 }, exposure: exposure + 1 });
check('exposure +1 EV brightens', mean(brighter) > mean(irrMap) + 5,
      'mean ' + mean(irrMap).toFixed(2) + ' -> ' + mean(brighter).toFixed(2));
const clampTm = await pixels({ exposure, tonemap: 1 });
check('tone mapping none (clamp) differs from filmic', diff(irrMap, clampTm).mean > 2,
      'mean diff ' + diff(irrMap, clampTm).mean.toFixed(2));
const levels = await p.evaluate(() => document.getElementById('bg').options.length);
const bgSharp = await pixels({ tonemap: 0, bg: 0 });
const sky = await region({}, false);
const bgBlur = await pixels({ bg: levels - 1 });
check('a blurrier background level is smoother', sharpness(bgBlur, sky) < 0.7 * sharpness(bgSharp, sky),
      'background sharpness ' + sharpness(bgSharp, sky).toFixed(3) + ' -> ' + sharpness(bgBlur, sky).toFixed(3));

// A/B split: each side is its own setting.
const a = await pixels({ bg: 0, sphere_ao: 0.2, A: { so: 0 }, B: { so: 4 }, split: false });
const bOnly = await pixels({ A: { so: 4 } });
const split = await pixels({ A: { so: 0 }, split: true, split_at: 0.5 });
const half = W / 2;
const left = diff(split, a, 0, half), right = diff(split, bOnly, half, W);
check('the A/B split shows A left and B right', left.max === 0 && right.max === 0 && diff(a, bOnly).mean > 0,
      'left max ' + left.max + ', right max ' + right.max);

// Camera: keyboard and wheel move it; R resets to the view of ibl render.
await p.evaluate(() => iblViewer.set({ split: false, sphere_ao: 0, camera: null }));
const home = await pixels({});
await p.locator('#canvas').focus();
await p.keyboard.press('ArrowLeft');
const turned = await pixels({});
await p.mouse.move(100, 60);
await p.mouse.wheel(0, 300);
const zoomed = await pixels({});
await p.keyboard.press('r');
const reset = await pixels({});
check('arrow keys and the wheel move the camera; R resets it',
      diff(home, turned).mean > 1 && diff(turned, zoomed).mean > 1 && diff(home, reset).max === 0);

const facts = await p.evaluate(() => document.getElementById('facts').textContent);
check('the side panel shows the manifest\'s facts', /ggx/.test(facts) && /64/.test(facts), facts.slice(0, 120));

// Frame time: synced draws of the sphere grid (software rendering: no GPU here).
const ms256 = await p.evaluate(() => { iblViewer.set({ scene: 0 }); return iblViewer.benchmark(5); });
const ms960 = await p.evaluate(() => { iblViewer.setSize(960, 540); return iblViewer.benchmark(2); });
console.log('frame time (SwiftShader, synced): ' + ms256.toFixed(1) + ' ms at 256x128, ' + ms960.toFixed(1) + ' ms at 960x540');

if (process.env.IBL_VIEWER_SCREENSHOTS) {
  const dir = process.env.IBL_VIEWER_SCREENSHOTS;
  const shots = [
    ['viewer_grid.png', { scene: 0, sphere_ao: 0, split: false }],
    ['viewer_ball.png', { scene: 1, model: 0, metallic: 1, roughness: 0.25, base: '#e6c27a', ball_ao: 1, A: { so: 0 } }],
    ['viewer_split.png', { scene: 0, sphere_ao: 0.2, A: { so: 0 }, B: { so: 4 }, split: true, split_at: 0.5 }],
  ];
  await p.setViewportSize({ width: 1000, height: 430 });
  await p.evaluate(() => iblViewer.setSize(null));
  for (const [name, patch] of shots) {
    await p.evaluate((pt) => { iblViewer.set(pt); iblViewer.render(); }, patch);
    await p.screenshot({ path: path.join(dir, name) });
  }
}
await p.close();

// A probe bake (the sample scene's set with every cube edge cut to 8): the global probe is
// drawn and the side panel lists the local probes in layer order.
{
  const rooms = path.join(path.dirname(new URL(import.meta.url).pathname), '..', '..', 'examples', 'rooms');
  const set = path.join(work, 'probes.json'), pbake = path.join(work, 'probe-bake'), phtml = path.join(work, 'probes.html');
  fs.writeFileSync(set, fs.readFileSync(path.join(rooms, 'probes.json'), 'utf8').replace(/"size": \d+/g, '"size": 8'));
  execFileSync(ibl, ['capture', '-q', path.join(rooms, 'scene.gltf'), '--probes', set, '-o', path.join(work, 'caps'),
                     '--samples', '1', '--bounces', '1']);
  execFileSync(ibl, ['bake', '-q', '--probes', set, '--captures', path.join(work, 'caps'), '-o', pbake]);
  const r = run(['view', '-q', pbake, '-o', phtml]);
  check('ibl view takes a probe bake', r.status === 0 && fs.existsSync(phtml), r.stderr.trim());
  const want = JSON.parse(fs.readFileSync(path.join(pbake, 'manifest.json'), 'utf8')).probes.probes;
  const q = await open(phtml);
  const got = await q.p.evaluate(() => ({ ready: iblViewer.ready, facts: document.getElementById('facts').textContent }));
  check('its page draws the global probe and lists the local probes in layer order',
        got.ready && q.errors.length === 0 && want.length === 8 &&
        want.every((w, i) => got.facts.includes('layer ' + i + w.name)),
        got.facts.slice(0, 200));
  await q.p.close();
}

// A damaged texture: a message in the page, no drawing.
const bad = await open(corrupted);
const shown = await bad.p.evaluate(() => {
  const e = document.getElementById('error');
  return { visible: !e.hidden && e.offsetHeight > 0, text: e.textContent, ready: iblViewer.ready };
});
check('a corrupted embedded texture shows an error in the page',
      shown.visible && !shown.ready && /irradiance/.test(shown.text) && /corrupted/.test(shown.text), shown.text);
await bad.p.close();
await browser.close();

finish();
