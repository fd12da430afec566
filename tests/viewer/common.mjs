// Shared by the browser tests: the pass/fail tally and a small PNG reader.
import zlib from 'node:zlib';

// check(name, ok, detail) prints one line per check; finish(label) prints the tally and exits
// non-zero when any check failed.
export function makeChecker() {
  const tally = { passed: 0, failed: 0 };
  tally.check = (name, ok, detail) => {
    if (ok) tally.passed++;
    else tally.failed++;
    console.log((ok ? 'ok   ' : 'FAIL ') + name + (detail ? '  (' + detail + ')' : ''));
  };
  tally.finish = (label) => {
    console.log(`${label ? label + ': ' : ''}${tally.passed} passed, ${tally.failed} failed`);
    process.exit(tally.failed ? 1 : 0);
  };
  return tally;
}

// The system chromium (Debian's, never a download) and playwright-core's driver for it; a missing
// npm package ends the test with one line naming what installs it.
export const CHROMIUM = process.env.IBL_CHROMIUM || '/usr/bin/chromium';
export async function importChromium(label) {
  try {
    return (await import('playwright-core')).chromium;
  } catch (e) {
    console.error(label + ': the npm package playwright-core is missing (scripts/install-deps.sh runs npm ci in tests/viewer)');
    process.exit(1);
  }
}

// ---- a small PNG reader (8-bit grey/RGB/RGBA, not interlaced): ibl's and chromium's PNGs ----
export function readPng(buf) {
  let pos = 8, width = 0, height = 0, type = 0;
  const idat = [];
  while (pos < buf.length) {
    const len = buf.readUInt32BE(pos), kind = buf.toString('latin1', pos + 4, pos + 8);
    const body = buf.subarray(pos + 8, pos + 8 + len);
    if (kind === 'IHDR') {
      width = body.readUInt32BE(0);
      height = body.readUInt32BE(4);
      if (body[8] !== 8 || body[12] !== 0) throw new Error('PNG: only 8-bit, not interlaced');
      type = body[9];
    } else if (kind === 'IDAT') idat.push(body);
    pos += 12 + len;
  }
  const bpp = { 0: 1, 2: 3, 6: 4 }[type];
  if (!bpp) throw new Error('PNG: colour type ' + type);
  const raw = zlib.inflateSync(Buffer.concat(idat));
  const stride = width * bpp, out = Buffer.alloc(width * height * 4);
  let prev = Buffer.alloc(stride);
  for (let y = 0; y < height; y++) {
    const f = raw[y * (stride + 1)], line = Buffer.from(raw.subarray(y * (stride + 1) + 1, (y + 1) * (stride + 1)));
    for (let i = 0; i < stride; i++) {
      const a = i >= bpp ? line[i - bpp] : 0, b = prev[i], c = i >= bpp ? prev[i - bpp] : 0;
      const p = a + b - c, pa = Math.abs(p - a), pb = Math.abs(p - b), pc = Math.abs(p - c);
      const pred = [0, a, b, (a + b) >> 1, pa <= pb && pa <= pc ? a : pb <= pc ? b : c][f];
      line[i] = (line[i] + pred) & 255;
    }
    for (let x = 0; x < width; x++)
      for (let k = 0; k < 4; k++)
        out[(y * width + x) * 4 + k] = k === 3 ? (bpp === 4 ? line[x * 4 + 3] : 255) : line[x * bpp + (bpp === 1 ? 0 : k)];
    prev = line;
  }
  return { width, height, data: out };
}

