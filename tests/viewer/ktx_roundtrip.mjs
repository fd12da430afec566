// Every kind of KTX2 file ibl writes, read and written again by ktx-parse (the KTX2 library
// of three.js and glTF-Transform, written to the KTX 2.0 specification by another hand): the
// bytes must come back identical, so the header, level index, data format descriptor,
// key/value data (sorted, padded), supercompression and level alignment are what the
// specification says. A control makes sure the comparison sees a one-byte change.
// Usage: node ktx_roundtrip.mjs IBL WORKDIR
import { spawnSync } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { makeChecker } from './common.mjs';

const [ibl, work] = process.argv.slice(2);
const here = path.dirname(fileURLToPath(import.meta.url));
const repo = path.resolve(here, '..', '..');
const { read, write } = await import('ktx-parse');

const { check, finish } = makeChecker();
function run(args) {
  const r = spawnSync(ibl, [...args, '-q'], { encoding: 'utf8' });
  if (r.status !== 0) throw new Error(`ibl ${args.join(' ')}: ${r.stderr}`);
}
function roundTrip(bytes) {
  // keepWriter: ktx-parse would otherwise put its own name in KTXwriter
  return write(read(bytes), { keepWriter: true });
}
function firstDifference(a, b) {
  const n = Math.max(a.length, b.length);
  for (let i = 0; i < n; i++) if (a[i] !== b[i]) return i;
  return -1;
}

fs.rmSync(work, { recursive: true, force: true });
fs.mkdirSync(work, { recursive: true });
const hdr = path.join(repo, 'tests/data/uffizi_latlong_256x128.hdr');
const out = (f) => path.join(work, f);
// cube textures in every pixel format and supercompression ibl writes
const formats = ['rgba16f', 'rgba32f', 'rg11b10f', 'rgb9e5', 'rg16f', 'rg32f', 'bc6h', 'bc6h-signed',
                 'astc4x4', 'astc6x6', 'rgbm', 'rgbd', 'rgbe'];
for (const f of formats) run(['convert', hdr, '-o', out(`cube_${f}.ktx2`), '--format', f]);
run(['convert', hdr, '-o', out('cube_zstd.ktx2'), '--zstd', '5']);
run(['convert', hdr, '-o', out('cube_bc6h_zstd.ktx2'), '--format', 'bc6h', '--zstd']);
// a prefiltered chain with its metadata, BRDF tables (2D, 3D volume), a bake folder's files
run(['prefilter', hdr, '-o', out('chain.ktx2'), '--size', '32']);
run(['lut', '-o', out('lut.ktx2'), '--size', '32']);
run(['bake', hdr, '--target', 'three', '--size', '32', '-o', out('bake')]);
const files = fs.readdirSync(work).filter((f) => f.endsWith('.ktx2')).map(out)
  .concat(fs.readdirSync(out('bake')).filter((f) => f.endsWith('.ktx2')).map((f) => path.join(out('bake'), f)));
for (const file of files) {
  const a = new Uint8Array(fs.readFileSync(file));
  let b, error = '';
  try { b = roundTrip(a); } catch (e) { error = String(e); }
  const at = b ? firstDifference(a, b) : 0;
  check(`ktx-parse round trip of ${path.relative(work, file)} is byte-identical`, b && at < 0,
    error || (at >= 0 ? `first difference at byte ${at} of ${a.length}` : `${a.length} bytes`));
}
check('at least 20 KTX2 files were checked', files.length >= 20, `${files.length}`);
// control: a key/value entry whose padding is left out of kvdByteLength does not survive
{
  const a = new Uint8Array(fs.readFileSync(out('cube_rgba16f.ktx2')));
  const bad = a.slice();
  const view = new DataView(bad.buffer);
  view.setUint32(60, view.getUint32(60, true) - 2, true);
  let b = null;
  try { b = roundTrip(bad); } catch (e) { b = null; }
  check('control: a changed kvdByteLength is caught', b === null || firstDifference(bad, b) >= 0);
}
finish('ktx round trip');
