// Shared by the browser render tests of the engine outputs (engines_test.mjs, gltf_test.mjs, lightprobe_test.mjs):
// the axes environment, a local HTTP server of node_modules and the work folder, headless
// chromium, the comparison of two renders over the sphere pixels and a PNG of stacked renders.
import { execFile } from 'node:child_process';
import fs from 'node:fs';
import http from 'node:http';
import path from 'node:path';
import zlib from 'node:zlib';

// The axes environment as a Radiance .hdr (flat RGBE scanlines) in ibl's equirect layout
// (centre column -Z, right quarter +X, top row +Y; docs/CONVENTIONS.md): one colour per axis
// direction, brightest on the axis, and white dots 25 degrees to the right of +X, +Z and -Z
// (seen from inside) and 20 up, so that a mirror image puts a dot on the other side. Every
// colour differs from its opposite's, so a wrong face order or a wrong sign moves whole
// colours across the spheres.
export function writeAxesHdr(file, W = 256, H = 128) {
  const axes = [
    [[1, 0, 0], [3.0, 0.15, 0.1]], [[-1, 0, 0], [0.1, 0.9, 1.2]],
    [[0, 1, 0], [0.2, 2.0, 0.2]], [[0, -1, 0], [0.6, 0.1, 0.9]],
    [[0, 0, 1], [0.15, 0.3, 3.0]], [[0, 0, -1], [1.6, 1.4, 0.1]]];
  const dots = [[-Math.PI / 2 + 0.44, 0.35], [Math.PI + 0.44, 0.35], [0.44, 0.35], [0.44 - Math.PI, 0.35]]
    .map(([phi, up]) => [Math.cos(up) * Math.sin(phi), Math.sin(up), -Math.cos(up) * Math.cos(phi)]);
  const head = Buffer.from(`#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y ${H} +X ${W}\n`, 'latin1');
  const body = Buffer.alloc(W * H * 4);
  for (let y = 0; y < H; y++)
    for (let x = 0; x < W; x++) {
      const phi = 2 * Math.PI * ((x + 0.5) / W - 0.5), theta = Math.PI * (y + 0.5) / H;
      const d = [Math.sin(theta) * Math.sin(phi), Math.cos(theta), -Math.sin(theta) * Math.cos(phi)];
      const dot = (a) => a[0] * d[0] + a[1] * d[1] + a[2] * d[2];
      let best = 0;
      axes.forEach(([a], i) => { if (dot(a) > dot(axes[best][0])) best = i; });
      let c = axes[best][1].map((v) => v * (0.35 + 0.65 * dot(axes[best][0])));
      if (dots.some((p) => dot(p) > Math.cos(0.16))) c = [8, 8, 8];
      const e = Math.ceil(Math.log2(Math.max(...c)) + 1e-9), scale = 256 / 2 ** e, i = (y * W + x) * 4;
      for (let k = 0; k < 3; k++) body[i + k] = Math.min(255, Math.floor(c[k] * scale));
      body[i + 3] = e + 128;
    }
  fs.writeFileSync(file, Buffer.concat([head, body]));
}

// A fresh work folder `work` holding the two test environments, axes.hdr (writeAxesHdr) and
// uffizi.hdr (tests/data/uffizi_latlong_256x128.hdr of the repository at `repo`); returns
// their paths.
export function freshWorkWithEnvironments(work, repo) {
  fs.rmSync(work, { recursive: true, force: true });
  fs.mkdirSync(work, { recursive: true });
  const axes = path.join(work, 'axes.hdr'), uffizi = path.join(work, 'uffizi.hdr');
  writeAxesHdr(axes);
  fs.copyFileSync(path.join(repo, 'tests/data/uffizi_latlong_256x128.hdr'), uffizi);
  return { axes, uffizi };
}

// A server on 127.0.0.1: /nm/ -> tests/viewer/node_modules, /w/ -> the work folder,
// /page/NAME -> pages[NAME].
export async function startServer(here, work, pages) {
  const types = { '.js': 'text/javascript', '.mjs': 'text/javascript', '.html': 'text/html',
    '.gltf': 'model/gltf+json', '.png': 'image/png' };
  const server = http.createServer((req, res) => {
    const url = decodeURIComponent(req.url.split('?')[0]);
    if (url === '/favicon.ico') {
      res.writeHead(204);
      return res.end();
    }
    if (url.startsWith('/page/')) {
      res.writeHead(200, { 'content-type': 'text/html' });
      return res.end(pages[url.slice(6)] || '');
    }
    let file = null;
    if (url.startsWith('/nm/')) file = path.join(here, 'node_modules', url.slice(4));
    else if (url.startsWith('/w/')) file = path.join(work, url.slice(3));
    if (!file || !fs.existsSync(file) || !fs.statSync(file).isFile()) {
      res.writeHead(404);
      return res.end();
    }
    res.writeHead(200, { 'content-type': types[path.extname(file)] || 'application/octet-stream' });
    fs.createReadStream(file).pipe(res);
  });
  await new Promise((r) => server.listen(0, '127.0.0.1', r));
  return { server, base: `http://127.0.0.1:${server.address().port}` };
}

// Headless Debian chromium with software WebGL2 (SwiftShader); open(url) resolves once the
// page sets window.ready, with the page's uncaught errors collected.
export async function launchChromium() {
  const { chromium } = await import('playwright-core');
  const browser = await chromium.launch({
    executablePath: process.env.IBL_CHROMIUM || '/usr/bin/chromium',
    args: ['--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist'],
  });
  const open = async (url) => {
    const p = await browser.newPage();
    const errors = [];
    p.on('pageerror', (e) => errors.push(String(e)));
    p.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
    p.on('response', (r) => { if (r.status() >= 400) errors.push(r.status() + ' ' + r.url()); });
    await p.goto(url);
    await p.waitForFunction(() => window.ready === true, null, { timeout: 150000 });
    return { p, errors };
  };
  return { browser, open };
}

// `ibl ARGS...` as a promise (the bakes run while chromium loads the engine's modules)
export function runIbl(ibl, args) {
  return new Promise((resolve, reject) => execFile(ibl, args, (e, out, err) =>
    e ? reject(new Error(`ibl ${args.join(' ')}: ${err}`)) : resolve(out)));
}

// Mean and worst |difference| (0..255 per channel) over the pixels where either render drew
// a sphere (alpha > 0: both pages clear to transparent black); `columns` restricts it to a
// range of x (one column of spheres).
export function compareRenders(a, b, width, columns = null) {
  let sum = 0, n = 0, worst = 0;
  for (let i = 0; i < a.length; i += 4) {
    const x = (i / 4) % width;
    if (columns && (x < columns[0] || x >= columns[1])) continue;
    if (a[i + 3] === 0 && b[i + 3] === 0) continue;
    for (let k = 0; k < 3; k++) {
      const d = Math.abs(a[i + k] - b[i + k]);
      sum += d;
      if (d > worst) worst = d;
    }
    n += 3;
  }
  return { mean: n ? sum / n : Infinity, worst, pixels: n / 3 };
}

// A PNG of RGBA renders (readPixels order: rows bottom first) stacked top to bottom.
export function writeStackedPng(file, w, h, images) {
  const rows = [];
  for (const img of images)
    for (let y = h - 1; y >= 0; y--) {
      const row = Buffer.alloc(1 + w * 3);
      for (let x = 0; x < w; x++)
        for (let k = 0; k < 3; k++) row[1 + x * 3 + k] = img[(y * w + x) * 4 + k];
      rows.push(row);
    }
  const chunk = (type, data) => {
    const len = Buffer.alloc(4), crc = Buffer.alloc(4), body = Buffer.concat([Buffer.from(type, 'latin1'), data]);
    len.writeUInt32BE(data.length);
    crc.writeUInt32BE(zlib.crc32(body) >>> 0);
    return Buffer.concat([len, body, crc]);
  };
  const ihdr = Buffer.alloc(13);
  ihdr.writeUInt32BE(w, 0);
  ihdr.writeUInt32BE(h * images.length, 4);
  ihdr[8] = 8;
  ihdr[9] = 2;
  fs.writeFileSync(file, Buffer.concat([Buffer.from([137, 80, 78, 71, 13, 10, 26, 10]), chunk('IHDR', ihdr),
    chunk('IDAT', zlib.deflateSync(Buffer.concat(rows))), chunk('IEND', Buffer.alloc(0))]));
}
