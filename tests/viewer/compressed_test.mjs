// `ibl view` on compressed bakes (run by tests/viewer/run.sh through CTest): forest baked on a
// 32 cube in rgba16f, bc6h, astc4x4 and rgbm, each made into a page, each page opened in
// headless Debian chromium (software WebGL2), the same view of the sphere grid read back as
// linear radiance, and every compressed page compared with the rgba16f one over the sphere
// pixels. Usage:
//   node compressed_test.mjs IBL WORKDIR
//
// The measure and the bounds are those of the OpenGL test of the same bakes
// (tests/test_shaders_compressed.c, docs/SHADERS.md "Measured: compressed bakes drawn on the
// GPU"): relative luminance error per sphere pixel, mean and 99th percentile, under 1.5% / 8%
// for BC6H and ASTC (measured there on llvmpipe: 0.87% / 4.9% and 0.70% / 4.3%) and 0.5% / 1%
// for RGBM (0.10% / 0.16%). The page draws what ibl_bake_load decodes; the OpenGL test lets
// the driver decode BC6H and decodes RGBM in a shader; the same figures should hold.
//
// Controls, which must fail the same bounds: the BC6H page with red and blue swapped in its
// chain and irradiance (a wrong channel order), and the RGBM page whose chain holds the RGBM
// codes as they are in the file (code / 255, as an upload without the decode would show).
import { execFileSync } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { pathToFileURL } from 'node:url';
import { makeChecker, CHROMIUM, importChromium } from './common.mjs';

const [ibl, work] = process.argv.slice(2);
const chromium = await importChromium('compressed viewer test');
const { check, finish } = makeChecker();
const here = path.dirname(new URL(import.meta.url).pathname);
const forest = path.join(here, '..', 'data', 'forest_128x64.exr');

// ---- the bakes and their pages ---------------------------------------------------------------
fs.rmSync(work, { recursive: true, force: true });
fs.mkdirSync(work, { recursive: true });
const FORMATS = ['rgba16f', 'bc6h', 'astc4x4', 'rgbm'];
const pages = {};
for (const f of FORMATS) {
  const dir = path.join(work, f), html = path.join(work, f + '.html');
  execFileSync(ibl, ['bake', '-q', forest, '--size', '32', '--format', f, '-o', dir]);
  execFileSync(ibl, ['view', '-q', dir, '-o', html]);
  pages[f] = html;
}

// ---- editing a page's embedded textures (for the controls) ------------------------------------
// The page's data block holds each texture as {"...", "bytes": N, "fnv": H, "data": "base64"}
// (cli/viewer_html.c); an edited texture gets its checksum recomputed so that the page takes it.
function fnv1a(bytes) {
  let h = 0x811c9dc5;
  for (let i = 0; i < bytes.length; i++) h = Math.imul(h ^ bytes[i], 16777619) >>> 0;
  return h;
}
function editTexture(page, name, edit) {
  const start = page.indexOf('"' + name + '": {"target"');
  if (start < 0) throw new Error('no texture ' + name + ' in the page');
  const fnvAt = page.indexOf('"fnv": ', start), dataAt = page.indexOf('"data": "', start) + 9;
  const dataEnd = page.indexOf('"', dataAt);
  const bytes = Buffer.from(page.slice(dataAt, dataEnd), 'base64');
  const halves = new Uint16Array(bytes.buffer, bytes.byteOffset, bytes.length / 2);
  edit(halves);
  const fnvEnd = page.indexOf(',', fnvAt);
  return page.slice(0, fnvAt) + '"fnv": ' + fnv1a(bytes) + page.slice(fnvEnd, dataAt) +
         bytes.toString('base64') + page.slice(dataEnd);
}
// IEEE 754 binary16 <-> number (round to nearest even; the codes here are small and finite)
const f32 = new Float32Array(1), u32 = new Uint32Array(f32.buffer);
function toHalf(v) {
  f32[0] = v;
  const x = u32[0], sign = (x >>> 16) & 0x8000, e = ((x >>> 23) & 255) - 127 + 15, m = x & 0x7fffff;
  if (e <= 0) return sign; // (no subnormal codes below: every value is k / 255 or 0)
  let h = sign | (e << 10) | (m >>> 13);
  const rest = m & 0x1fff;
  if (rest > 0x1000 || (rest === 0x1000 && (h & 1))) h++;
  return h;
}

// Swapped red and blue in the chain and the irradiance cube (RGBA texels).
const swapped = path.join(work, 'control-bc6h-swapped.html');
{
  let page = fs.readFileSync(pages.bc6h, 'utf8');
  const swap = (h) => { for (let i = 0; i < h.length; i += 4) [h[i], h[i + 2]] = [h[i + 2], h[i]]; };
  page = editTexture(page, 'specular', swap);
  page = editTexture(page, 'irradiance', swap);
  fs.writeFileSync(swapped, page);
}
// The RGBM chain's codes, undecoded: specular.ktx2's level data (no supercompression: the
// level index at byte 80, 24 bytes a level: offset, length), faces in the page's order.
const undecoded = path.join(work, 'control-rgbm-undecoded.html');
{
  const ktx = fs.readFileSync(path.join(work, 'rgbm', 'specular.ktx2'));
  const levels = ktx.readUInt32LE(40), codes = [];
  for (let l = 0; l < levels; l++) {
    const at = Number(ktx.readBigUInt64LE(80 + 24 * l)), len = Number(ktx.readBigUInt64LE(80 + 24 * l + 8));
    codes.push(ktx.subarray(at, at + len));
  }
  const all = Buffer.concat(codes);
  const page = editTexture(fs.readFileSync(pages.rgbm, 'utf8'), 'specular', (h) => {
    if (h.length !== all.length) throw new Error('RGBM codes: ' + all.length + ' for ' + h.length + ' halves');
    for (let i = 0; i < h.length; i++) h[i] = i % 4 === 3 ? toHalf(1) : toHalf(all[i] / 255);
  });
  fs.writeFileSync(undecoded, page);
}

// ---- the browser: linear radiance of the sphere grid ------------------------------------------
if (!fs.existsSync(CHROMIUM)) {
  console.error('compressed viewer test: ' + CHROMIUM + ' is missing (Debian package chromium; scripts/install-deps.sh installs it)');
  process.exit(1);
}
const browser = await chromium.launch({
  executablePath: CHROMIUM,
  args: ['--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist'],
});
const W = 256, H = 128;

// The page's sphere grid at the default camera as linear RGB floats (top row first) and the
// sphere mask. scene.frag writes its radiance before exposure and display table when its
// u_linear uniform is set; the page's API reads 8-bit display values only, so the draw is
// made into an RGBA32F framebuffer with u_linear set just before the page's own draw calls.
async function radiance(file) {
  const p = await browser.newPage({ viewport: { width: 600, height: 400 }, deviceScaleFactor: 1 });
  const errors = [];
  p.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
  p.on('pageerror', (e) => errors.push(e.message));
  await p.goto(pathToFileURL(file).href);
  await p.waitForFunction(() => window.iblViewer && (window.iblViewer.ready || window.iblViewer.error), null,
                          { timeout: 20000 });
  const status = await p.evaluate(() => ({ ready: iblViewer.ready, error: iblViewer.error }));
  if (!status.ready) {
    await p.close();
    return { error: status.error || 'not ready' };
  }
  await p.evaluate(([w, h]) => { iblViewer.set({ scene: 0, sphere_ao: 0, split: false }); iblViewer.setSize(w, h); }, [W, H]);
  const mask = Buffer.from((await p.evaluate(() => iblViewer.pixels(true))).data, 'base64');
  const linear = await p.evaluate(([w, h]) => {
    const gl = document.getElementById('canvas').getContext('webgl2');
    if (!gl.getExtension('EXT_color_buffer_float')) return { error: 'no EXT_color_buffer_float' };
    const rb = gl.createRenderbuffer(), fb = gl.createFramebuffer();
    gl.bindRenderbuffer(gl.RENDERBUFFER, rb);
    gl.renderbufferStorage(gl.RENDERBUFFER, gl.RGBA32F, w, h);
    gl.bindFramebuffer(gl.FRAMEBUFFER, fb);
    gl.framebufferRenderbuffer(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.RENDERBUFFER, rb);
    const draw = gl.drawArrays;
    gl.drawArrays = function (...args) {
      gl.bindFramebuffer(gl.FRAMEBUFFER, fb);
      gl.uniform1i(gl.getUniformLocation(gl.getParameter(gl.CURRENT_PROGRAM), 'u_linear'), 1);
      return draw.apply(gl, args);
    };
    iblViewer.render();
    gl.drawArrays = draw;
    gl.bindFramebuffer(gl.FRAMEBUFFER, fb);
    const px = new Float32Array(w * h * 4);
    gl.readPixels(0, 0, w, h, gl.RGBA, gl.FLOAT, px);
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    const rows = [];
    for (let y = h - 1; y >= 0; y--) rows.push(...px.subarray(y * w * 4, (y + 1) * w * 4));
    return { data: rows };
  }, [W, H]);
  await p.close();
  if (linear.error) return { error: linear.error };
  return { data: Float32Array.from(linear.data), mask, errors };
}

// Relative luminance error per sphere pixel (docs/SHADERS.md's measure): mean, p99, max.
const lum = (d, i) => 0.2126 * d[i] + 0.7152 * d[i + 1] + 0.0722 * d[i + 2];
function compare(test, ref) {
  const e = [];
  for (let i = 0; i < W * H * 4; i += 4) {
    if (ref.mask[i] < 128) continue;
    const r = lum(ref.data, i);
    if (r > 0) e.push(Math.abs(lum(test.data, i) - r) / r);
  }
  const sorted = Float64Array.from(e).sort();
  return {
    pixels: e.length,
    mean: e.reduce((s, v) => s + v, 0) / Math.max(e.length, 1),
    p99: sorted[Math.floor(0.99 * (sorted.length - 1))],
    max: sorted[sorted.length - 1],
  };
}
const pct = (v) => (100 * v).toFixed(2) + '%';
const show = (m) => 'mean ' + pct(m.mean) + ', p99 ' + pct(m.p99) + ', max ' + pct(m.max) + ' over ' + m.pixels + ' sphere pixels';

const reference = await radiance(pages.rgba16f);
check('the rgba16f page draws', !reference.error && reference.errors.length === 0, reference.error || reference.errors.join('; '));
if (reference.error) {
  await browser.close();
  finish('compressed viewer');
}
const spheres = compare(reference, reference).pixels;
check('the sphere mask covers the grid', spheres > 0.15 * W * H, spheres + ' of ' + W * H + ' pixels');

// bounds: the OpenGL test's for the same bakes; a floor on the mean shows that the page draws
// the compressed chain, not a float one (a tenth of what the OpenGL test measured)
const BOUNDS = {
  bc6h: { mean: 0.015, p99: 0.08, floor: 0.000087 },
  astc4x4: { mean: 0.015, p99: 0.08, floor: 0.00007 },
  rgbm: { mean: 0.005, p99: 0.01, floor: 0.00001 },
};
for (const f of ['bc6h', 'astc4x4', 'rgbm']) {
  const r = await radiance(pages[f]);
  if (r.error) {
    check('the ' + f + ' page draws', false, r.error);
    continue;
  }
  check('the ' + f + ' page loads with no console error', r.errors.length === 0, r.errors.join('; '));
  const m = compare(r, reference), b = BOUNDS[f];
  check(f + ' bake looks like the rgba16f bake (mean < ' + pct(b.mean) + ', p99 < ' + pct(b.p99) + ')',
        m.mean < b.mean && m.p99 < b.p99 && m.mean > b.floor, show(m));
}
for (const [name, file, b] of [['bc6h with red and blue swapped', swapped, BOUNDS.bc6h],
                               ['rgbm with its codes undecoded', undecoded, BOUNDS.rgbm]]) {
  const r = await radiance(file);
  const m = r.error ? null : compare(r, reference);
  check('control: ' + name + ' fails the bounds', m && !(m.mean < b.mean && m.p99 < b.p99), m ? show(m) : r.error);
}
await browser.close();
finish('compressed viewer');
