// `ibl bake --target gltf` rendered by an engine: Babylon.js's glTF loader (npm
// @babylonjs/loaders, the EXT_lights_image_based implementation by the extension's authors)
// in headless Debian chromium. A glTF scene is made from the bake's engine_gltf.gltf (its
// light, RGBD faces and irradiance coefficients as written) plus a grid of ten spheres with
// glTF metallic-roughness materials; Babylon loads it, renders it, and renders the same loaded
// spheres again lit by a DDS of the same environment with the babylon row's chain (the form
// tests/viewer/engines_test.mjs checks against Babylon's own import of the HDRI). The two
// renders must agree when the glTF's chain is in the level mapping Babylon's loader assumes.
// Negative controls, each must fail the bound: the glTF with two cube faces exchanged, and with
// the irradiance coefficients in the unsigned basis (the Condon-Shortley signs dropped).
// The last column has roughness 0.95: the loader's materials at roughness exactly 1 render
// black in SwiftShader under any light, the DDS too.
// Usage: node gltf_test.mjs IBL WORKDIR [SCREENSHOT_DIR]
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

const W = 320, H = 128, SIZE = 128;
const ROUGHNESS = [0, 0.25, 0.5, 0.75, 0.95];

// ---- the sphere grid as glTF: one UV sphere (positions, normals, indices in a data URI) and
// ten materials; metal row above, dielectric below, roughness rising to the right as Babylon
// shows it (its glTF loader mirrors x: glTF is right-handed, Babylon's scene left-handed) ----
function sphereGltfParts() {
  const rings = 32, segments = 64, radius = 0.9, pos = [], nrm = [], idx = [];
  for (let r = 0; r <= rings; r++)
    for (let s = 0; s <= segments; s++) {
      const th = Math.PI * r / rings, ph = 2 * Math.PI * s / segments;
      const n = [Math.sin(th) * Math.cos(ph), Math.cos(th), -Math.sin(th) * Math.sin(ph)];
      nrm.push(...n);
      pos.push(...n.map((v) => v * radius));
    }
  for (let r = 0; r < rings; r++)
    for (let s = 0; s < segments; s++) {
      const a = r * (segments + 1) + s, b = a + segments + 1;
      idx.push(a, b, a + 1, a + 1, b, b + 1);
    }
  const p = Buffer.from(new Float32Array(pos).buffer), n = Buffer.from(new Float32Array(nrm).buffer);
  const i = Buffer.from(new Uint16Array(idx).buffer);
  const data = Buffer.concat([p, n, i]);
  const parts = {
    buffers: [{ byteLength: data.length, uri: 'data:application/octet-stream;base64,' + data.toString('base64') }],
    bufferViews: [
      { buffer: 0, byteOffset: 0, byteLength: p.length, target: 34962 },
      { buffer: 0, byteOffset: p.length, byteLength: n.length, target: 34962 },
      { buffer: 0, byteOffset: p.length + n.length, byteLength: i.length, target: 34963 }],
    accessors: [
      { bufferView: 0, componentType: 5126, count: pos.length / 3, type: 'VEC3',
        min: [-radius, -radius, -radius], max: [radius, radius, radius] },
      { bufferView: 1, componentType: 5126, count: nrm.length / 3, type: 'VEC3' },
      { bufferView: 2, componentType: 5123, count: idx.length, type: 'SCALAR' }],
    materials: [], meshes: [], nodes: [],
  };
  ROUGHNESS.forEach((r, col) => [1, 0].forEach((metal, row) => {
    const k = parts.materials.length;
    parts.materials.push({ name: `r${r}_m${metal}`,
      pbrMetallicRoughness: { baseColorFactor: [1, 1, 1, 1], metallicFactor: metal, roughnessFactor: r } });
    parts.meshes.push({ primitives: [{ attributes: { POSITION: 0, NORMAL: 1 }, indices: 2, material: k }] });
    parts.nodes.push({ mesh: k, translation: [4 - 2 * col, row ? -1 : 1, 0] });
  }));
  return parts;
}

// The bake's engine_gltf.gltf with the spheres added; `corrupt` changes the light.
function writeScene(bakeDir, file, corrupt = null) {
  const g = JSON.parse(fs.readFileSync(path.join(bakeDir, 'engine_gltf.gltf'), 'utf8'));
  Object.assign(g, sphereGltfParts());
  g.scenes[0].nodes = g.nodes.map((_, i) => i);
  const light = g.extensions.EXT_lights_image_based.lights[0];
  if (corrupt === 'faces') // +Z and -Z exchanged in every mip: a face order that is wrong
    light.specularImages = light.specularImages.map((f) => [f[0], f[1], f[2], f[3], f[5], f[4]]);
  if (corrupt === 'sh-sign') // the unsigned basis: Condon-Shortley signs (y, x, yz, xz) dropped
    for (const i of [1, 3, 5, 7]) light.irradianceCoefficients[i] = light.irradianceCoefficients[i].map((v) => -v);
  fs.writeFileSync(path.join(bakeDir, file), JSON.stringify(g));
}

const page = `<!doctype html><body style="margin:0;background:#000">
<canvas id="c" width="${W}" height="${H}"></canvas>
<script type="importmap">{"imports":{"@babylonjs/core/":"/nm/@babylonjs/core/","@babylonjs/loaders/":"/nm/@babylonjs/loaders/"}}</script>
<script type="module">
const mods = await Promise.all(['@babylonjs/core/Engines/engine.js', '@babylonjs/core/scene.js',
  '@babylonjs/core/Cameras/freeCamera.js', '@babylonjs/core/Cameras/camera.js',
  '@babylonjs/core/Materials/PBR/pbrMaterial.js', '@babylonjs/core/Materials/Textures/cubeTexture.js',
  '@babylonjs/core/Materials/Textures/baseTexture.polynomial.js',
  '@babylonjs/core/Maths/math.vector.js', '@babylonjs/core/Maths/math.color.js',
  '@babylonjs/core/Materials/Textures/Loaders/ddsTextureLoader.js', '@babylonjs/core/Loading/sceneLoader.js', '@babylonjs/core/Loading/loadingScreen.js',
  '@babylonjs/loaders/glTF/2.0/glTFLoader.js', '@babylonjs/loaders/glTF/2.0/Extensions/EXT_lights_image_based.js']
  .map((m) => import(m)));
const B = Object.assign({}, ...mods);
const engine = new B.Engine(document.getElementById('c'), false, { preserveDrawingBuffer: true, premultipliedAlpha: false });
function newScene() {
  const scene = new B.Scene(engine);
  scene.clearColor = new B.Color4(0, 0, 0, 0);
  scene.imageProcessingConfiguration.toneMappingEnabled = false;
  const camera = new B.FreeCamera('c', new B.Vector3(0, 0, -10), scene);
  camera.mode = B.Camera.ORTHOGRAPHIC_CAMERA;
  camera.orthoLeft = -5; camera.orthoRight = 5; camera.orthoTop = 2; camera.orthoBottom = -2;
  camera.setTarget(B.Vector3.Zero());
  return scene;
}
function whenReady(tex) { return new Promise((res) => { const t = () => tex.isReady() ? res() : setTimeout(t, 20); t(); }); }
async function grab(scene) {
  await whenReady(scene.environmentTexture);
  await scene.whenReadyAsync();
  scene.render();
  scene.render();
  const px = await engine.readPixels(0, 0, ${W}, ${H});
  return Array.from(new Uint8Array(px.buffer));
}
// Each glTF scene in turn; asLoaded keeps the light's gammaSpace flag as Babylon's loader left
// it, the others clear it before the first render (see the bound below); the last one's
// spheres are then lit by the DDS.
window.run = async (scenes, ddsUrl) => {
  const out = { renders: [], dds: null };
  for (const [i, [url, asLoaded]] of scenes.entries()) {
    const scene = newScene();
    await B.AppendSceneAsync(url, scene);
    const env = scene.environmentTexture;
    out.lodGenerationScale = env.lodGenerationScale;
    out.gammaSpace = env.gammaSpace;
    if (!asLoaded) env.gammaSpace = false;
    out.renders.push(await grab(scene));
    if (i === scenes.length - 1) {
      const d = B.CubeTexture.CreateFromPrefilteredData(ddsUrl, scene);
      d.gammaSpace = false;
      scene.environmentTexture = d;
      out.dds = await grab(scene);
    }
    scene.dispose();
  }
  return out;
};
window.ready = true;
</script>`;


freshWorkWithEnvironments(work, repo);
const { server, base } = await startServer(here, work, { 'gltf.html': page });
const { browser, open } = await launchChromium();
const opened = open(`${base}/page/gltf.html`);

// Three bakes of each environment at 128 texels, run while chromium loads Babylon's modules:
//  - gltf: `--target gltf` as it is (levels 128..16, roughness linear in the level, as the
//    extension asks: "the various mip levels evenly map to roughness values from 0 to 1");
//  - gltf-babylon: the same light with the chain in the mapping Babylon's loader assumes: it
//    sets lodGenerationScale = (levels - 1) / log2(specularImageSize), so level l holds
//    GGX alpha = 2^(l / scale) / size (Babylon's HDRFiltering); 3/7 for 4 levels at 128;
//  - ref: the DDS Babylon reads directly, Babylon's mapping at its default scale 0.8 and the
//    whole chain, in ibl's frame (the babylon row's chain without its mirror and turn: Babylon's
//    loader puts the light's cube in Babylon's world as the file has it, measured below).
const LEVELS = 4, SCALE = (LEVELS - 1) / Math.log2(SIZE);
const bakeArgs = {
  gltf: ['--target', 'gltf'],
  'gltf-babylon': ['--target', 'gltf', '--mapping', 'babylon', '--babylon-lod-scale', String(SCALE), '--levels', String(LEVELS)],
  ref: ['--mapping', 'babylon', '--levels', String(Math.log2(SIZE) + 1)],
};
const ENVS = ['uffizi', 'axes'];
await Promise.all(ENVS.flatMap((env) => Object.entries(bakeArgs).map(([kind, args]) =>
  runIbl(ibl, ['bake', path.join(work, env + '.hdr'), ...args, '--size', String(SIZE), '-o', path.join(work, `${env}-${kind}`), '-q']))));
for (const env of ENVS) {
  writeScene(path.join(work, `${env}-gltf`), 'scene.gltf');
  const dir = path.join(work, `${env}-gltf-babylon`);
  writeScene(dir, 'scene.gltf');
  writeScene(dir, 'scene_faces.gltf', 'faces');
  writeScene(dir, 'scene_sh.gltf', 'sh-sign');
}
const { p, errors } = await opened;
console.log('Babylon.js loaded after ' + ((Date.now() - t0) / 1000).toFixed(1) + ' s');

// Bound: mean |difference| over the sphere pixels (8-bit sRGB, no tone mapping) between the
// glTF light with the chain in Babylon's mapping and the DDS: both are ibl's GGX filter of the
// same cube; they differ by the glTF's 8-bit RGBD (half a gamma-2.2 code over D), by the two
// chains' level spacing under trilinear filtering (4 levels 5x apart in alpha against 8 levels
// 2.4x apart) and by the 9 SH terms of the file against the polynomial Babylon fits to the DDS
// cube: measured 0.7-0.8/255 (docs/ENGINES.md). 2/255 holds that with room. The light's
// gammaSpace flag is cleared first: Babylon's loader leaves it true on the RGBD-decoded (linear)
// radiance, so its shader raises the radiance to the power 2.2 (measured below, not bounded).
// Negative controls on the axes environment, each at least 4x the bound away on the row it
// reaches: +Z and -Z faces exchanged (the metal row: specular only), the irradiance
// coefficients without the Condon-Shortley signs (the dielectric row: the SH give its diffuse).
const BOUND = 2.0;
const columns = (a, b) => ROUGHNESS.map((_, c) => compareRenders(a, b, W, [c * W / 5, (c + 1) * W / 5]).mean.toFixed(2)).join(' ');
const metalRow = (img) => img.slice(W * (H / 2) * 4); // readPixels rows run bottom first
const dielectricRow = (img) => img.slice(0, W * (H / 2) * 4);
for (const env of ENVS) {
  const scenes = [[`/w/${env}-gltf/scene.gltf`, true], [`/w/${env}-gltf/scene.gltf`, false],
    [`/w/${env}-gltf-babylon/scene_faces.gltf`, false], [`/w/${env}-gltf-babylon/scene_sh.gltf`, false],
    [`/w/${env}-gltf-babylon/scene.gltf`, false]];
  const r = await p.evaluate(([s, d]) => window.run(s, d), [scenes, `/w/${env}-ref/specular.dds`]);
  const [asLoaded, linear, faces, sh, matched] = r.renders;
  check(`${env}: Babylon's loader sets lodGenerationScale (levels - 1) / log2(size)`,
    Math.abs(r.lodGenerationScale - SCALE) < 1e-9, String(r.lodGenerationScale));
  const c = compareRenders(matched, r.dds, W);
  check(`${env}: glTF light (chain in Babylon's mapping) vs the DDS, same spheres`, c.mean < BOUND && c.pixels > 5000,
    `mean ${c.mean.toFixed(3)}/255, worst ${c.worst}/255 over ${c.pixels} px; by roughness ${columns(matched, r.dds)}`);
  if (env === 'axes') {
    const f = compareRenders(metalRow(faces), metalRow(r.dds), W), fm = compareRenders(metalRow(matched), metalRow(r.dds), W);
    check('axes: +Z and -Z faces exchanged in the glTF fail the bound (metal row)', f.mean > 4 * BOUND,
      `mean ${f.mean.toFixed(3)}/255; the file's own faces ${fm.mean.toFixed(3)}`);
    const s = compareRenders(dielectricRow(sh), dielectricRow(r.dds), W), sm = compareRenders(dielectricRow(matched), dielectricRow(r.dds), W);
    check('axes: irradiance coefficients without the Condon-Shortley signs fail the bound (dielectric row)',
      s.mean > 4 * BOUND, `mean ${s.mean.toFixed(3)}/255; the file's own SH ${sm.mean.toFixed(3)}`);
  }
  // measured, not bounded: the file as the extension defines it (levels linear in roughness)
  // read through Babylon's mapping, and Babylon's loader as it is (gammaSpace left true)
  const l = compareRenders(linear, r.dds, W), g = compareRenders(asLoaded, r.dds, W);
  console.log(`     ${env}: --target gltf as it is (levels linear in roughness) vs the DDS: mean ${l.mean.toFixed(3)}/255, by roughness ${columns(linear, r.dds)}`);
  console.log(`     ${env}: the same with the loader's gammaSpace (${r.gammaSpace}) left: mean ${g.mean.toFixed(3)}/255`);
  if (shots && env === 'uffizi') writeStackedPng(path.join(shots, 'engines_gltf.png'), W, H, [matched, r.dds, linear]);
}
check('no page errors', errors.length === 0, errors.join('; '));
await browser.close();
server.close();
finish(`glTF test (${((Date.now() - t0) / 1000).toFixed(1)} s)`);
