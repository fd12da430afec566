#!/usr/bin/env python3
"""Writes the starting corpus of the flat-image readers: PNG (every bit depth and colour
type, palette with and without transparency, Adam7 interlacing, gAMA / sRGB / iCCP / cHRM
chunks, every filter type, split IDAT, 1-pixel and odd sizes), Radiance HDR (new-style
per-channel RLE, old-style repeats, flat, each orientation), PFM (colour and grey, both byte
orders), JPEG through cjpeg (baseline and progressive, grey, RGB, 4:4:4 / 4:2:2 / 4:4:0 / 4:2:0,
one sequential scan per component, restart markers, optimised tables, arithmetic coding), and DDS files with the legacy float
FourCCs made from ibl's DX10 files. Usage: images.py OUT_DIR (writes OUT_DIR/NAME/...)."""
import math
import os
import struct
import subprocess
import sys
import tempfile
import zlib

OUT = sys.argv[1]


def write(target, name, data):
    os.makedirs(os.path.join(OUT, target), exist_ok=True)
    with open(os.path.join(OUT, target, name), "wb") as f:
        f.write(data)


def wave(x, y, c, top):
    """Smooth samples in [0, top] (they compress well, so files stay small)."""
    return int(round(top * 0.5 * (1 + math.sin(0.45 * x + 0.3 * y + 1.7 * c))))


# ---- PNG -------------------------------------------------------------------------------

def chunk(kind, body):
    return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))


CHANNELS = {0: 1, 2: 3, 3: 1, 4: 2, 6: 4}  # colour type -> samples per pixel
ADAM7 = [(0, 0, 8, 8), (4, 0, 8, 8), (0, 4, 4, 8), (2, 0, 4, 4), (0, 2, 2, 4), (1, 0, 2, 2), (0, 1, 1, 2)]


def pack_row(samples, depth):
    if depth >= 8:
        width = depth // 8
        return b"".join(s.to_bytes(width, "big") for s in samples)
    out, acc, bits = bytearray(), 0, 0
    for s in samples:
        acc = (acc << depth) | s
        bits += depth
        if bits == 8:
            out.append(acc)
            acc, bits = 0, 0
    if bits:
        out.append(acc << (8 - bits))
    return bytes(out)


def paeth(a, b, c):
    p = a + b - c
    pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
    return a if pa <= pb and pa <= pc else b if pb <= pc else c


def filter_rows(rows, bpp, filters):
    """Applies PNG filter filters[i % len] to row i (raw bytes rows of one pass)."""
    out, prev = bytearray(), bytes(len(rows[0])) if rows else b""
    for i, row in enumerate(rows):
        f = filters[i % len(filters)]
        enc = bytearray()
        for j, v in enumerate(row):
            a = row[j - bpp] if j >= bpp else 0
            b = prev[j]
            c = prev[j - bpp] if j >= bpp else 0
            pred = [0, a, b, (a + b) // 2, paeth(a, b, c)][f]
            enc.append((v - pred) & 0xFF)
        out += bytes([f]) + enc
        prev = row
    return bytes(out)


def png(w, h, depth, colour, interlace=False, filters=(0, 1, 2, 3, 4), extra=b"", idat_split=0,
        palette=None, trns=None):
    spp = CHANNELS[colour]
    top = (1 << depth) - 1
    bpp = max(1, spp * depth // 8)

    def sample(x, y, c):
        if colour == 3:
            return (x * 3 + y * 5) % len(palette)
        return wave(x, y, c, top)

    def rows_of(xs, ys):
        return [pack_row([sample(x, y, c) for x in xs for c in range(spp)], depth) for y in ys]

    if interlace:
        raw = b""
        for x0, y0, dx, dy in ADAM7:
            xs, ys = range(x0, w, dx), range(y0, h, dy)
            if len(xs) and len(ys):
                raw += filter_rows(rows_of(xs, ys), bpp, filters)
    else:
        raw = filter_rows(rows_of(range(w), range(h)), bpp, filters)
    ihdr = struct.pack(">IIBBBBB", w, h, depth, colour, 0, 0, 1 if interlace else 0)
    body = chunk(b"IHDR", ihdr) + extra
    if palette is not None:
        body += chunk(b"PLTE", b"".join(bytes(p) for p in palette))
    if trns is not None:
        body += chunk(b"tRNS", trns)
    data = zlib.compress(raw, 9)
    if idat_split:
        for i in range(0, len(data), idat_split):
            body += chunk(b"IDAT", data[i:i + idat_split])
    else:
        body += chunk(b"IDAT", data)
    return b"\x89PNG\r\n\x1a\n" + body + chunk(b"IEND", b"")


def icc_profile(space):
    """A minimal well-formed ICC v2 display profile header with no tags."""
    h = bytearray(132)
    struct.pack_into(">I", h, 0, 132)
    h[4:8] = b"none"
    struct.pack_into(">I", h, 8, 0x02100000)
    h[12:16] = b"mntr"
    h[16:20] = space
    h[20:24] = b"XYZ "
    h[36:40] = b"acsp"
    struct.pack_into(">iii", h, 68, 63190, 65536, 54061)  # D50 in s15Fixed16
    return bytes(h)


def iccp(space):
    return chunk(b"iCCP", b"fuzz\x00\x00" + zlib.compress(icc_profile(space)))


GAMA_LINEAR = chunk(b"gAMA", struct.pack(">I", 100000))
GAMA_22 = chunk(b"gAMA", struct.pack(">I", 45455))
SRGB = chunk(b"sRGB", b"\x00")
CHRM = chunk(b"cHRM", struct.pack(">8I", 31270, 32900, 64000, 33000, 30000, 60000, 15000, 6000))
TEXT = chunk(b"tEXt", b"Comment\x00ibl corpus") + chunk(b"zTXt", b"Title\x00\x00" + zlib.compress(b"probe"))
PHYS = chunk(b"pHYs", struct.pack(">IIB", 2835, 2835, 1))


def pngs():
    for depth in (1, 2, 4, 8, 16):
        write("png", "grey%d_7x5.png" % depth, png(7, 5, depth, 0))
    for depth in (8, 16):
        write("png", "greyalpha%d_5x4.png" % depth, png(5, 4, depth, 4))
        write("png", "rgb%d_6x3.png" % depth, png(6, 3, depth, 2))
        write("png", "rgba%d_3x6.png" % depth, png(3, 6, depth, 6))
    pal = [(i * 37 % 256, i * 91 % 256, i * 53 % 256) for i in range(13)]
    for depth in (1, 2, 4, 8):
        n = min(len(pal), 1 << depth)
        write("png", "palette%d_9x4.png" % depth, png(9, 4, depth, 3, palette=pal[:n]))
    write("png", "palette8_trns_5x5.png", png(5, 5, 8, 3, palette=pal, trns=bytes([0, 128, 255, 7])))
    write("png", "grey8_trns_4x4.png", png(4, 4, 8, 0, trns=struct.pack(">H", 100)))
    write("png", "rgb16_trns_4x4.png", png(4, 4, 16, 2, trns=struct.pack(">HHH", 1, 2, 3)))
    write("png", "interlaced_rgba8_11x9.png", png(11, 9, 8, 6, interlace=True))
    write("png", "interlaced_grey2_13x7.png", png(13, 7, 2, 0, interlace=True))
    write("png", "interlaced_palette4_3x3.png", png(3, 3, 4, 3, interlace=True, palette=pal[:16 if len(pal) >= 16 else len(pal)]))
    write("png", "interlaced_rgb16_1x1.png", png(1, 1, 16, 2, interlace=True))
    write("png", "pixel_rgb8_1x1.png", png(1, 1, 8, 2))
    write("png", "gama_linear_rgb16_5x3.png", png(5, 3, 16, 2, extra=GAMA_LINEAR))
    write("png", "gama22_rgb8_5x3.png", png(5, 3, 8, 2, extra=GAMA_22 + CHRM))
    write("png", "srgb_rgba8_4x4.png", png(4, 4, 8, 6, extra=SRGB + GAMA_22 + CHRM))
    write("png", "iccp_rgb8_4x4.png", png(4, 4, 8, 2, extra=iccp(b"RGB ")))
    write("png", "iccp_grey8_4x4.png", png(4, 4, 8, 0, extra=iccp(b"GRAY")))
    write("png", "text_phys_rgb8_6x2.png", png(6, 2, 8, 2, extra=TEXT + PHYS))
    write("png", "split_idat_rgba16_9x9.png", png(9, 9, 16, 6, idat_split=7))
    for f in range(5):
        write("png", "filter%d_rgb8_8x6.png" % f, png(8, 6, 8, 2, filters=(f,)))
    write("any", "grey16_9x5.png", png(9, 5, 16, 0, extra=GAMA_LINEAR))
    write("any", "interlaced_palette8_7x7.png", png(7, 7, 8, 3, interlace=True, palette=pal, trns=b"\x00\x80"))


# ---- JPEG (cjpeg) ----------------------------------------------------------------------

def jpegs():
    def pnm(w, h, grey):
        if grey:
            px = bytes(wave(x, y, 0, 255) for y in range(h) for x in range(w))
            return b"P5\n%d %d\n255\n" % (w, h) + px
        px = bytes(wave(x, y, c, 255) for y in range(h) for x in range(w) for c in range(3))
        return b"P6\n%d %d\n255\n" % (w, h) + px

    variants = [
        ("baseline_420_17x11.jpg", 17, 11, False, []),
        ("baseline_444_9x9.jpg", 9, 9, False, ["-sample", "1x1"]),
        ("baseline_422_13x8.jpg", 13, 8, False, ["-sample", "2x1"]),
        ("baseline_440_8x13.jpg", 8, 13, False, ["-sample", "1x2"]),
        ("grey_15x7.jpg", 15, 7, True, []),
        ("progressive_420_19x12.jpg", 19, 12, False, ["-progressive"]),
        ("progressive_grey_10x10.jpg", 10, 10, True, ["-progressive"]),
        ("progressive_444_7x5.jpg", 7, 5, False, ["-progressive", "-sample", "1x1"]),
        ("restart_rows_24x16.jpg", 24, 16, False, ["-restart", "1"]),
        ("restart_blocks_16x16.jpg", 16, 16, False, ["-restart", "2B", "-sample", "1x1"]),
        ("optimized_q30_20x9.jpg", 20, 9, False, ["-optimize", "-quality", "30"]),
        ("float_dct_q98_6x6.jpg", 6, 6, False, ["-dct", "float", "-quality", "98"]),
        ("pixel_1x1.jpg", 1, 1, False, []),
        ("arithmetic_8x8.jpg", 8, 8, False, ["-arithmetic"]),
        ("rgb_9x7.jpg", 9, 7, False, ["-rgb"]),
        ("sequential_scans_12x10.jpg", 12, 10, False, ["-scans", "SCANS"]),
        ("progressive_restart_18x9.jpg", 18, 9, False, ["-progressive", "-restart", "1B"]),
    ]
    with tempfile.TemporaryDirectory() as tmp:
        # one sequential scan per component (non-interleaved), as some encoders write
        scans = os.path.join(tmp, "scans.txt")
        with open(scans, "w") as f:
            f.write("0;\n1;\n2;\n")
        for name, w, h, grey, args in variants:
            args = [scans if a == "SCANS" else a for a in args]
            src = os.path.join(tmp, "in.pnm")
            with open(src, "wb") as f:
                f.write(pnm(w, h, grey))
            opts = (["-grayscale"] if grey else []) + args
            data = subprocess.run(["cjpeg"] + opts + [src], check=True, capture_output=True).stdout
            write("jpeg", name, data)
            if name in ("progressive_420_19x12.jpg", "grey_15x7.jpg"):
                write("any", name, data)


# ---- Radiance HDR ----------------------------------------------------------------------

def rgbe(r, g, b):
    m = max(r, g, b)
    if m < 1e-32:
        return bytes(4)
    mant, e = math.frexp(m)
    s = mant * 256.0 / m
    return bytes([int(r * s), int(g * s), int(b * s), e + 128])


def hdr_pixels(w, h):
    return [[rgbe(0.1 + wave(x, y, 0, 50) / 7.0, wave(x, y, 1, 9) / 9.0, 0.02 * (x % 3)) for x in range(w)]
            for y in range(h)]


def rle_channel(vals):
    out, i = bytearray(), 0
    while i < len(vals):
        run = 1
        while i + run < len(vals) and run < 127 and vals[i + run] == vals[i]:
            run += 1
        if run > 2:
            out += bytes([128 + run, vals[i]])
            i += run
            continue
        j = i
        while j < len(vals) and j - i < 128 and not (j + 2 < len(vals) and vals[j] == vals[j + 1] == vals[j + 2]):
            j += 1
        out += bytes([j - i]) + bytes(vals[i:j])
        i = j
    return bytes(out)


def hdr(w, h, resolution, mode, header_extra=b""):
    px = hdr_pixels(w, h)
    head = b"#?RADIANCE\n# ibl corpus\n" + header_extra + b"FORMAT=32-bit_rle_rgbe\n\n" + resolution + b"\n"
    body = bytearray()
    for row in px:
        if mode == "rle":
            body += bytes([2, 2, w >> 8, w & 0xFF])
            for c in range(4):
                body += rle_channel([p[c] for p in row])
        elif mode == "old":
            prev, run = None, 0
            for p in row:
                if p == prev and run < 255:
                    run += 1
                    continue
                if run:
                    body += bytes([1, 1, 1, run])
                body += p
                prev, run = p, 0
            if run:
                body += bytes([1, 1, 1, run])
        else:
            body += b"".join(row)
    return head + bytes(body)


def hdrs():
    write("hdr", "rle_minus_y_plus_x_16x6.hdr", hdr(16, 6, b"-Y 6 +X 16", "rle", b"EXPOSURE=1.5\nGAMMA=1.0\n"))
    write("hdr", "rle_plus_y_plus_x_20x5.hdr", hdr(20, 5, b"+Y 5 +X 20", "rle"))
    write("hdr", "rle_minus_y_minus_x_9x4.hdr", hdr(9, 4, b"-Y 4 -X 9", "rle"))
    write("hdr", "rle_plus_y_minus_x_33x3.hdr", hdr(33, 3, b"+Y 3 -X 33", "rle"))
    write("hdr", "flat_narrow_7x5.hdr", hdr(7, 5, b"-Y 5 +X 7", "flat"))  # < 8 wide: never RLE
    write("hdr", "flat_wide_12x3.hdr", hdr(12, 3, b"-Y 3 +X 12", "flat"))
    write("hdr", "old_rle_10x4.hdr", hdr(10, 4, b"-Y 4 +X 10", "old"))
    write("hdr", "pixel_1x1.hdr", hdr(1, 1, b"-Y 1 +X 1", "flat"))
    write("hdr", "rle_long_run_300x1.hdr", hdr(300, 1, b"-Y 1 +X 300", "rle"))
    write("any", "rle_plus_y_9x8.hdr", hdr(9, 8, b"+Y 8 +X 9", "rle"))


# ---- PFM -------------------------------------------------------------------------------

def pfm(w, h, colour, little):
    n = 3 if colour else 1
    vals = [0.01 * wave(x, y, c, 300) - 0.5 for y in range(h) for x in range(w) for c in range(n)]
    fmt = ("<" if little else ">") + "%df" % len(vals)
    head = b"%s\n%d %d\n%s\n" % (b"PF" if colour else b"Pf", w, h, b"-1.0" if little else b"1.0")
    return head + struct.pack(fmt, *vals)


def pfms():
    write("pfm", "colour_le_5x3.pfm", pfm(5, 3, True, True))
    write("pfm", "colour_be_4x6.pfm", pfm(4, 6, True, False))
    write("pfm", "grey_le_7x2.pfm", pfm(7, 2, False, True))
    write("pfm", "grey_be_3x3.pfm", pfm(3, 3, False, False))
    write("pfm", "pixel_le_1x1.pfm", pfm(1, 1, True, True))
    # a single space between the fields and a large scale magnitude (ignored)
    write("pfm", "spaces_scale_2x2.pfm", b"PF 2 2 -255.5\n" + struct.pack("<12f", *range(12)))
    write("any", "grey_be_6x4.pfm", pfm(6, 4, False, False))


# ---- DDS with legacy FourCCs (from ibl's DX10 files) -------------------------------------

LEGACY = {"rgba16f": 113, "rgba32f": 116, "rg16f": 112, "rg32f": 115}


def legacy_dds():
    folder = os.path.join(OUT, "dds")
    for name in sorted(os.listdir(folder)):
        stem, ext = os.path.splitext(name)
        fmt = stem.split("_")[-1]
        if ext != ".dds" or fmt not in LEGACY or stem.startswith("legacy_") or stem.startswith("c_"):
            continue
        if not (stem.startswith("2d_") or stem.startswith("cube_") or stem.startswith("3d_")):
            continue
        with open(os.path.join(folder, name), "rb") as f:
            data = bytearray(f.read())
        out = bytearray(data[:128]) + data[148:]  # drop DDS_HEADER_DXT10
        struct.pack_into("<I", out, 84, LEGACY[fmt])  # ddspf.dwFourCC
        write("dds", "legacy_" + name, bytes(out))


if __name__ == "__main__":
    pngs()
    jpegs()
    hdrs()
    pfms()
    legacy_dds()
