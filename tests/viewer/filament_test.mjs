// `ibl bake --target filament` loaded by Filament's own WebAssembly build (npm package filament,
// the version in package-lock.json), rendered in headless Debian chromium (software WebGL2)
// and compared with an independent reference inside the same renderer. Usage:
//   node filament_test.mjs IBL WORKDIR
//
// The environment is an "axes" picture: one colour per major axis (+X red, -X cyan, +Y green,
// -Y magenta, +Z blue, -Z yellow: a mirror of any axis swaps two complementary colours) and a
// white dot on the -Z face up and to the right of its centre (a face flipped in itself moves
// it). The reference is what cmgen's frame means for ibl (the brief's measurement): the
// environment turned by 180 degrees about +Y, filtered by `ibl prefilter --preset filament`
// (rgba16f KTX1, the form known to load and render correctly) with the irradiance map of
// `ibl irradiance`, none of them going through the target's code. The target bake's chain,
// its SH (KTX1 "sh" key) and its skybox must render like the reference, and the skybox must
// show each axis where the turned frame puts it.
import { execFileSync } from 'node:child_process';
import fs from 'node:fs';
import http from 'node:http';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { makeChecker, readPng, CHROMIUM, importChromium } from './common.mjs';

const [ibl, work] = process.argv.slice(2);
const here = path.dirname(fileURLToPath(import.meta.url));
const filamentDir = path.join(here, 'node_modules', 'filament');
const chromium = await importChromium('filament test');
if (!fs.existsSync(path.join(filamentDir, 'filament.wasm'))) {
  console.error('filament test: the npm package filament is missing (scripts/install-deps.sh runs npm ci in tests/viewer)');
  process.exit(1);
}

const { check, finish } = makeChecker();

fs.rmSync(work, { recursive: true, force: true });
fs.mkdirSync(work, { recursive: true });

// ---- the axes environment, a 256x128 equirect PFM in ibl's layout (docs/CONVENTIONS.md) -------
const AXIS_COLOURS = {
  '+x': [1, 0.1, 0.1], '-x': [0.1, 1, 1], '+y': [0.1, 1, 0.1],
  '-y': [1, 0.1, 1], '+z': [0.1, 0.1, 1], '-z': [1, 1, 0.1],
};
const DOT = normalize([0.35, 0.3, -1]);  // on the -Z face, up and right seen from inside
const DOT2 = normalize([0.35, 0.3, 1]);  // on the +Z face
function normalize(v) { const l = Math.hypot(...v); return v.map((x) => x / l); }
function axisOf(d) {
  const a = d.map(Math.abs), i = a[0] >= a[1] && a[0] >= a[2] ? 0 : a[1] >= a[2] ? 1 : 2;
  return (d[i] >= 0 ? '+' : '-') + 'xyz'[i];
}
function envColour(d) {
  const dot = d[0] * DOT[0] + d[1] * DOT[1] + d[2] * DOT[2];
  const dot2 = d[0] * DOT2[0] + d[1] * DOT2[1] + d[2] * DOT2[2];
  return dot > Math.cos(0.12) || dot2 > Math.cos(0.12) ? [1.5, 1.5, 1.5] : AXIS_COLOURS[axisOf(d)];
}
{
  const W = 256, H = 128, header = Buffer.from(`PF\n${W} ${H}\n-1.0\n`, 'latin1');
  const body = Buffer.alloc(W * H * 12);
  for (let row = 0; row < H; row++) { // PFM rows run bottom to top
    const v = 1 - (row + 0.5) / H, theta = Math.PI * v;
    for (let x = 0; x < W; x++) {
      const phi = 2 * Math.PI * ((x + 0.5) / W - 0.5);
      const d = [Math.sin(theta) * Math.sin(phi), Math.cos(theta), -Math.sin(theta) * Math.cos(phi)];
      const c = envColour(d);
      for (let k = 0; k < 3; k++) body.writeFloatLE(c[k], (row * W + x) * 12 + k * 4);
    }
  }
  fs.writeFileSync(path.join(work, 'axes.pfm'), Buffer.concat([header, body]));
}

// ---- the bake and the reference ---------------------------------------------------------------
const run = (args) => execFileSync(ibl, args, { cwd: work, stdio: ['ignore', 'pipe', 'pipe'] });
run(['bake', 'axes.pfm', '-o', 'bake', '--target', 'filament', '--size', '64', '-q']);
run(['prefilter', 'axes.pfm', '--preset', 'filament', '--size', '64', '--levels', '3', '--yaw', '180',
     '--format', 'rgba16f', '-o', 'ref_ibl.ktx', '-q']);
run(['irradiance', 'axes.pfm', '--yaw', '180', '--format', 'rgba16f', '-o', 'ref_irradiance.ktx', '-q']);
run(['convert', 'axes.pfm', '--yaw', '180', '--size', '64', '--format', 'rgba16f', '-o', 'ref_sky.ktx', '-q']);
for (const f of ['engine_filament_ibl.ktx', 'engine_filament_skybox.ktx', 'engine_filament_irradiance.ktx', 'sh.txt'])
  fs.copyFileSync(path.join(work, 'bake', f), path.join(work, f));

// ---- a GLB: one UV sphere, three nodes (mirror metal, rough metal, white diffuse) -------------
function sphereGlb() {
  const SEG = 48, RING = 24, pos = [], idx = [];
  for (let r = 0; r <= RING; r++)
    for (let s = 0; s <= SEG; s++) {
      const t = Math.PI * r / RING, p = 2 * Math.PI * s / SEG;
      pos.push(Math.sin(t) * Math.cos(p), Math.cos(t), -Math.sin(t) * Math.sin(p));
    }
  for (let r = 0; r < RING; r++)
    for (let s = 0; s < SEG; s++) {
      const a = r * (SEG + 1) + s, b = a + SEG + 1;
      idx.push(a, b, a + 1, a + 1, b, b + 1);
    }
  const positions = Buffer.from(new Float32Array(pos).buffer); // unit sphere: normals = positions
  const indices = Buffer.from(new Uint16Array(idx).buffer);
  const bin = Buffer.concat([positions, indices, Buffer.alloc((4 - (indices.length % 4)) % 4)]);
  const mat = (metal, rough) => ({ pbrMetallicRoughness: { baseColorFactor: [1, 1, 1, 1], metallicFactor: metal, roughnessFactor: rough } });
  const json = {
    asset: { version: '2.0' }, scene: 0, scenes: [{ nodes: [0, 1, 2] }],
    nodes: [{ mesh: 0, translation: [-2.5, 0, -4] }, { mesh: 1, translation: [0, 0, -4] }, { mesh: 2, translation: [2.5, 0, -4] }],
    meshes: [0, 1, 2].map((m) => ({ primitives: [{ attributes: { POSITION: 0, NORMAL: 0 }, indices: 1, material: m }] })),
    materials: [mat(1, 0), mat(1, 0.5), mat(0, 1)],
    buffers: [{ byteLength: bin.length }],
    bufferViews: [{ buffer: 0, byteOffset: 0, byteLength: positions.length, target: 34962 },
                  { buffer: 0, byteOffset: positions.length, byteLength: indices.length, target: 34963 }],
    accessors: [{ bufferView: 0, componentType: 5126, count: pos.length / 3, type: 'VEC3', min: [-1, -1, -1], max: [1, 1, 1] },
                { bufferView: 1, componentType: 5123, count: idx.length, type: 'SCALAR' }],
  };
  let text = Buffer.from(JSON.stringify(json));
  text = Buffer.concat([text, Buffer.alloc((4 - (text.length % 4)) % 4, 0x20)]);
  const chunk = (type, data) => { const h = Buffer.alloc(8); h.writeUInt32LE(data.length, 0); h.write(type, 4, 'latin1'); return Buffer.concat([h, data]); };
  const body = Buffer.concat([chunk('JSON', text), chunk('BIN\0', bin)]);
  const h = Buffer.alloc(12); h.write('glTF', 0, 'latin1'); h.writeUInt32LE(2, 4); h.writeUInt32LE(12 + body.length, 8);
  return Buffer.concat([h, body]);
}
fs.writeFileSync(path.join(work, 'spheres.glb'), sphereGlb());

// ---- the page: Filament renders one light set into a 360x160 canvas ----------------------------
const W = 360, H = 160;
fs.writeFileSync(path.join(work, 'index.html'), `<!doctype html><html><head><link rel="icon" href="data:,"></head><body style="margin:0">
<canvas id="c" width="${W}" height="${H}" style="width:${W}px;height:${H}px"></canvas>
<script src="filament.js"></script><script>
const assets = ['spheres.glb', 'engine_filament_ibl.ktx', 'engine_filament_skybox.ktx',
                'ref_ibl.ktx', 'ref_irradiance.ktx', 'ref_sky.ktx'];
window.state = {};
Filament.init(assets, () => {
  try {
    const canvas = document.getElementById('c');
    const engine = Filament.Engine.create(canvas);
    const scene = engine.createScene(), renderer = engine.createRenderer();
    const camera = engine.createCamera(Filament.EntityManager.get().create());
    const view = engine.createView(), swap = engine.createSwapChain();
    view.setCamera(camera); view.setScene(scene); view.setViewport([0, 0, ${W}, ${H}]);
    view.setPostProcessingEnabled(false);             // linear output, no tone mapping
    camera.setProjectionFov(90, ${W} / ${H}, 0.1, 100, Filament.Camera$Fov.VERTICAL);
    camera.lookAt([0, 0, 0], [0, 0, -1], [0, 1, 0]);
    camera.setExposureDirect(1.0);
    const loader = engine.createAssetLoader();
    const asset = loader.createAsset(Filament.assets['spheres.glb']);
    asset.loadResources();
    scene.addEntities(asset.getEntities());
    const ktx = (name) => engine.createTextureFromKtx1(Filament.assets[name]);
    const sets = {
      target: () => {
        const bundle = new Filament.Ktx1Bundle(Filament.Buffer(Filament.assets['engine_filament_ibl.ktx']));
        const sh = bundle.getMetadata('sh').split(/\\s/, 27).map(parseFloat);
        window.state.sh = sh;
        return { ibl: Filament.IndirectLight.Builder().reflections(ktx('engine_filament_ibl.ktx'))
                     .irradianceSh(3, sh).intensity(1).build(engine),
                 sky: engine.createSkyFromKtx1(Filament.assets['engine_filament_skybox.ktx']) };
      },
      reference: () => ({ ibl: Filament.IndirectLight.Builder().reflections(ktx('ref_ibl.ktx'))
                              .irradianceTex(ktx('ref_irradiance.ktx')).intensity(1).build(engine),
                          sky: engine.createSkyFromKtx1(Filament.assets['ref_sky.ktx']) }),
    };
    // a few frames on animation ticks: Filament skips a beginFrame that comes too soon
    window.show = (name) => new Promise((resolve) => {
      let s;
      try { s = sets[name](); } catch (e) { resolve(String(e && e.message || e)); return; }
      scene.setIndirectLight(s.ibl); scene.setSkybox(s.sky);
      let frames = 0;
      const tick = () => {
        if (renderer.beginFrame(swap)) { renderer.render(swap, view); renderer.endFrame(); frames++; }
        engine.execute();
        if (frames < 6) requestAnimationFrame(tick); else resolve(true);
      };
      requestAnimationFrame(tick);
    });
    window.state.ready = true;
  } catch (e) { window.state.error = String(e && e.stack || e); }
});
</script></body></html>`);
for (const f of ['filament.js', 'filament.wasm']) fs.copyFileSync(path.join(filamentDir, f), path.join(work, f));

// ---- serve the folder on a local port (the wasm is fetched; file:// would refuse it) ----------
const types = { '.html': 'text/html', '.js': 'text/javascript', '.wasm': 'application/wasm' };
const server = http.createServer((req, res) => {
  const file = path.join(work, path.normalize(decodeURIComponent(req.url.split('?')[0])).replace(/^(\.\.[/\\])+/, ''));
  if (!file.startsWith(work) || !fs.existsSync(file) || fs.statSync(file).isDirectory()) { res.writeHead(404); res.end(); return; }
  res.writeHead(200, { 'Content-Type': types[path.extname(file)] || 'application/octet-stream' });
  res.end(fs.readFileSync(file));
});
await new Promise((r) => server.listen(0, '127.0.0.1', r));
const url = `http://127.0.0.1:${server.address().port}/index.html`;

// ---- PNG reading (chromium's screenshots: 8-bit RGB(A), not interlaced) ----------------------
// The screenshot as RGB floats 0..255 (the measures below index three channels).
function readRgb(buf) {
  const img = readPng(buf), out = new Float64Array(img.width * img.height * 3);
  for (let i = 0; i < img.width * img.height; i++)
    for (let k = 0; k < 3; k++) out[i * 3 + k] = img.data[i * 4 + k];
  return { width: img.width, height: img.height, data: out };
}

// ---- render both light sets --------------------------------------------------------------------
const browser = await chromium.launch({
  executablePath: CHROMIUM,
  args: ['--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist'],
});
// one fresh page per light set: nothing of one set can linger into the other's frames
const shots = {};
for (const name of ['target', 'reference']) {
  const page = await browser.newPage({ viewport: { width: W, height: H }, deviceScaleFactor: 1 });
  const errors = [];
  page.on('pageerror', (e) => errors.push(e.message));
  page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
  await page.goto(url);
  await page.waitForFunction(() => window.state.ready || window.state.error, null, { timeout: 30000 });
  const status = await page.evaluate(() => window.state);
  const shown = status.ready ? await page.evaluate((n) => window.show(n), name) : status.error;
  check(`${name}: Filament loads and renders it`, shown === true && errors.length === 0,
        shown === true ? errors.join('; ') : shown);
  const png = await page.locator('#c').screenshot();
  fs.writeFileSync(path.join(work, name + '.png'), png);
  shots[name] = readRgb(png);
  await page.close();
}
await browser.close();
server.close();

// ---- measures ------------------------------------------------------------------------------------
// The mean colour (0..255) of the pixels within radius r of (cx, cy).
function disc(img, cx, cy, r) {
  const m = [0, 0, 0];
  let n = 0;
  for (let y = Math.floor(cy - r); y <= cy + r; y++)
    for (let x = Math.floor(cx - r); x <= cx + r; x++) {
      if ((x - cx) ** 2 + (y - cy) ** 2 > r * r) continue;
      for (let k = 0; k < 3; k++) m[k] += img.data[(y * img.width + x) * 3 + k];
      n++;
    }
  return m.map((v) => v / n);
}
// Screen position of a world point for the page's camera (at the origin looking down -Z).
const tanHalf = Math.tan(45 * Math.PI / 180);
function project(p) {
  return [W / 2 + (p[0] / -p[2]) / tanHalf * (H / 2), H / 2 - (p[1] / -p[2]) / tanHalf * (H / 2)];
}
const sphereR = 1 / 4 / tanHalf * (H / 2); // projected radius of a unit sphere 4 units away (approx.)
const SPHERES = [[-2.5, 0, -4], [0, 0, -4], [2.5, 0, -4]];
const centres = SPHERES.map(project);
const names = ['mirror metal', 'rough metal (r 0.5)', 'white diffuse'];
// Per sphere, the target against the reference. Bound: the target stores rg11b10f (6-bit
// mantissas for R and G, 5 for B: at most 1.6% rounding per texel), the reference rgba16f; the
// diffuse sphere is lit by the target's 9 SH terms against the reference's irradiance map,
// which differ by the SH truncation of this hard-edged picture (3 bands: a few percent of
// E/pi); each channel within 6% of the reference's value + 3 8-bit steps.
for (let i = 0; i < 3; i++) {
  const [cx, cy] = centres[i];
  const t = disc(shots.target, cx, cy, sphereR * 0.6), r = disc(shots.reference, cx, cy, sphereR * 0.6);
  const worst = Math.max(...t.map((v, k) => Math.abs(v - r[k]) - (0.06 * r[k] + 3)));
  check(`${names[i]}: the target renders like the reference`, worst <= 0,
        `target ${t.map((v) => v.toFixed(1)).join(' ')}, reference ${r.map((v) => v.toFixed(1)).join(' ')}`);
}

// Orientation: the skybox pixel seen along a world direction d shows the environment's colour
// at (-dx, dy, -dz), the turn of 180 degrees about +Y (cmgen's frame). Background points away
// from the spheres; each must be nearest (in RGB) to the expected axis colour of all six.
// Exact: the colours are 0.9 apart in some channel, far beyond any filtering or rounding.
function nearestAxis(c) {
  let best = null, bestD = Infinity;
  for (const [k, v] of Object.entries(AXIS_COLOURS)) {
    const e = v.map((x) => Math.min(255, 255 * x));
    const dd = e.reduce((s, x, j) => s + (x - c[j]) ** 2, 0);
    if (dd < bestD) { bestD = dd; best = k; }
  }
  return best;
}
const probes = [[0, 0.75, -1], [0, -0.75, -1], [-1.6, 0.6, -1], [1.6, 0.6, -1], [-1.6, -0.6, -1], [1.6, -0.6, -1]];
for (const name of ['target', 'reference']) {
  let ok = true;
  const seen = [];
  for (const p of probes) {
    const [sx, sy] = project(p), d = normalize(p);
    const want = axisOf([-d[0], d[1], -d[2]]), got = nearestAxis(disc(shots[name], sx, sy, 2));
    seen.push(`${p.join(',')}: ${got}${got === want ? '' : ' (want ' + want + ')'}`);
    ok = ok && got === want;
  }
  check(`${name}: the skybox shows each axis where cmgen's frame puts it`, ok, seen.join('; '));
}
// The +Z face's dot, seen straight ahead in the turned frame: up and to the left (x and y
// mirrors would move it right or down).
for (const name of ['target', 'reference']) {
  const w = [-DOT2[0], DOT2[1], -DOT2[2]], at = project(w), mx = project([-w[0], w[1], w[2]]), my = project([w[0], -w[1], w[2]]);
  const c = disc(shots[name], at[0], at[1], 1.5), cx = disc(shots[name], mx[0], mx[1], 1.5), cy = disc(shots[name], my[0], my[1], 1.5);
  check(`${name}: the skybox's dot is up and left of the centre, not mirrored`,
        Math.min(...c) > 200 && Math.min(...cx) < 150 && Math.min(...cy) < 150,
        `dot ${c.map((v) => v.toFixed(0)).join(' ')}, x-mirror ${cx.map((v) => v.toFixed(0)).join(' ')}, y-mirror ${cy.map((v) => v.toFixed(0)).join(' ')}`);
}
// The mirror ball's centre reflects the direction behind the camera (+Z in the world), whose
// colour in the turned frame is the environment's -Z (yellow): a mirrored or unturned chain
// shows blue there.
// The white dot, seen in the mirror ball: the world direction that shows it is
// (-DOT.x, DOT.y, -DOT.z); the ball's point whose normal halves it and the view direction.
const dotWorld = [-DOT[0], DOT[1], -DOT[2]];
for (const name of ['target', 'reference']) {
  const [cx, cy] = centres[0];
  const c = disc(shots[name], cx, cy, 2);
  const s0 = SPHERES[0], v = normalize(s0);
  const n = normalize(dotWorld.map((x, k) => x - v[k]));
  const [dx, dy] = project([s0[0] + n[0], n[1], s0[2] + n[2]]);
  const dot = disc(shots[name], dx, dy, 1), mirrored = (() => {
    const nm = normalize([-dotWorld[0], dotWorld[1], dotWorld[2]].map((x, k) => x - v[k]));
    return disc(shots[name], ...project([s0[0] + nm[0], nm[1], s0[2] + nm[2]]), 1);
  })();
  const want = axisOf([-0, 0, -1]);
  check(`${name}: the mirror ball reflects the turned frame (centre, and the dot where it belongs)`,
        // the dot covers only a few pixels of the ball: its blue (the yellow face has none)
        // must stand out against the same spot mirrored in x
        nearestAxis(c) === want && dot[2] > mirrored[2] + 80,
        `centre ${c.map((x) => x.toFixed(0)).join(' ')} nearest ${nearestAxis(c)} (want ${want}); ` +
        `dot ${dot.map((x) => x.toFixed(0)).join(' ')}, its mirror image ${mirrored.map((x) => x.toFixed(0)).join(' ')}`);
}

finish();
