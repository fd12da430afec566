// The DDS files ibl writes, read by an independent reader: Babylon.js's DDSTools (npm
// @babylonjs/core, Misc/dds.pure.js), the whole path its engine takes (header, FourCC or DX10,
// faces, mip offsets, half or float texels), with a stand-in engine that keeps what would be
// uploaded. Each face of level 0 must equal the PFM faces ibl wrote from the same cube.
// Usage: node dds_test.mjs IBL WORKDIR
import { execFileSync } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { makeChecker } from './common.mjs';

const [ibl, work] = process.argv.slice(2);
let DDSTools;
try {
  ({ DDSTools } = await import('@babylonjs/core/Misc/dds.pure.js'));
} catch (e) {
  console.error('dds test: the npm package @babylonjs/core is missing (scripts/install-deps.sh runs npm ci in tests/viewer): ' + e.message);
  process.exit(1);
}
const { check, finish } = makeChecker();
fs.rmSync(work, { recursive: true, force: true });
fs.mkdirSync(work, { recursive: true });
const run = (args) => execFileSync(ibl, args, { cwd: work, stdio: ['ignore', 'pipe', 'pipe'] });

// the reference: six float faces of a 16-texel cube of the built-in sky
run(['sky', '-o', 'sky.exr', '-q', '--size', '128']);
run(['convert', 'sky.exr', '--size', '16', '--out-layout', 'faces', '-o', 'face.pfm', '-q']);
const FACES = ['px', 'nx', 'py', 'ny', 'pz', 'nz'];
function readPfm(file) {
  const b = fs.readFileSync(file);
  const lines = b.toString('latin1', 0, 64).split('\n');
  const [w, h] = lines[1].split(/\s+/).map(Number), scale = Number(lines[2]);
  const at = lines[0].length + lines[1].length + lines[2].length + 3, ch = lines[0] === 'PF' ? 3 : 1;
  const out = new Float32Array(w * h * 4);
  for (let y = 0; y < h; y++) // PFM rows run bottom to top
    for (let x = 0; x < w; x++)
      for (let k = 0; k < 3; k++) {
        const o = at + (((h - 1 - y) * w + x) * ch + (ch === 3 ? k : 0)) * 4;
        out[(y * w + x) * 4 + k] = scale < 0 ? b.readFloatLE(o) : b.readFloatBE(o);
      }
  return { w, h, data: out };
}
const faces = FACES.map((f) => readPfm(path.join(work, `face_${f}.pfm`)));

// Babylon's reader with a stand-in engine: float textures available, half floats not, so
// every texel arrives as a Float32 (the path of _GetHalfFloatAsFloatRGBAArrayBuffer and
// _GetFloatRGBAArrayBuffer)
function babylonRead(file) {
  const bytes = new Uint8Array(fs.readFileSync(file));
  const info = DDSTools.GetDDSInfo(bytes);
  const uploads = {};
  const engine = {
    getCaps: () => ({ s3tc: null, textureFloat: true, textureFloatLinearFiltering: true,
                      textureHalfFloat: false, textureHalfFloatLinearFiltering: false }),
    _getRGBABufferInternalSizedFormat: () => 0,
    _uploadDataToTextureDirectly: (texture, data, face, lod) => { uploads[`${face}/${lod}`] = Float32Array.from(data); },
    _uploadCompressedDataToTextureDirectly: () => { throw new Error('compressed'); },
  };
  DDSTools.UploadDDSLevels(engine, {}, bytes, info, true, info.isCube ? 6 : 1);
  return { info, uploads };
}

const cases = [
  { name: 'rgba16f, legacy header (FourCC 113)', format: 'rgba16f', header: 'legacy', fourcc: 113, tol: 2 ** -11 },
  { name: 'rgba32f, legacy header (FourCC 116)', format: 'rgba32f', header: 'legacy', fourcc: 116, tol: 0 },
  { name: 'rgba16f, the default header', format: 'rgba16f', header: null, fourcc: 113, tol: 2 ** -11 },
  { name: 'rgba16f, DX10 header', format: 'rgba16f', header: 'dx10', fourcc: 0x30315844, tol: 2 ** -11 },
];
for (const c of cases) {
  const out = `cube_${c.format}_${c.header || 'default'}.dds`;
  run(['convert', 'face.pfm'.replace('.pfm', '_px.pfm'), ...FACES.slice(1).map((f) => `face_${f}.pfm`),
       '--format', c.format, '--mips', ...(c.header ? ['--dds-header', c.header] : []), '-o', out, '-q']);
  const fourcc = fs.readFileSync(path.join(work, out)).readUInt32LE(84);
  const { info, uploads } = babylonRead(path.join(work, out));
  // bound: a half float keeps 11 significant bits (relative rounding <= 2^-11); float is exact
  let worst = 0, count = 0;
  for (let f = 0; f < 6; f++) {
    const got = uploads[`${f}/0`];
    if (!got) { worst = Infinity; break; }
    for (let i = 0; i < faces[f].data.length; i++) {
      if (i % 4 === 3) continue;
      const want = faces[f].data[i];
      worst = Math.max(worst, Math.abs(got[i] - want) / Math.max(Math.abs(want), 1e-30));
      count++;
    }
  }
  check(`${c.name}: Babylon.js reads the cube, its mips and every texel`,
        fourcc === c.fourcc && info.isCube && info.mipmapCount === 5 && Object.keys(uploads).length === 30 &&
        count === 6 * 16 * 16 * 3 && worst <= c.tol,
        `FourCC ${fourcc}, cube ${info.isCube}, ${info.mipmapCount} levels, ${Object.keys(uploads).length} uploads, ` +
        `worst relative difference ${worst.toExponential(2)} (bound ${c.tol})`);
}
finish();
