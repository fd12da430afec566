#!/usr/bin/python3
"""ibl's DDS files read by OpenImageIO (Debian's python3-openimageio, 2.4), an independent
reader with its own BC6H decoder, compared with ibl's own read of the same files.

OpenImageIO 2.4 reads no float DDS (half or float texels, legacy FourCC or DX10 header:
"Unsupported compression type"), but it reads BC6H (DX10 header, DXGI 95 and 96): as a cube,
its six faces stacked +X -X +Y -Y +Z -Z. Checked here:
  - a BC6H_UF16 cube (ibl convert --format bc6h), every face;
  - a BC6H_SF16 cube (--format bc6h-signed), every face;
  - a bake's specular.dds (ibl bake --format bc6h), level 0 of every face.
Tolerance: none. BC6H decoding is integer arithmetic fixed by the Direct3D 11 format
specification (endpoints, interpolation weights, the final scale to a half float), so two
correct decoders give the same half values bit for bit; ibl's read, written to PFM as float32,
holds those halves exactly. A face order that differs would fail: the test checks that the
faces of each cube differ from one another (and a row order that differs fails the equality:
no face of the sky is symmetric top to bottom).
Not checked: levels below the first. OpenImageIO 2.4.7 reports a cube DDS's level 1 at level
0's size (16 texels for a 16-texel cube whose level 1 is 8), so its later levels do not line
up with the file's; Babylon.js's DDSTools reads them (tests/viewer/dds_test.mjs).

Usage: /usr/bin/python3 dds_oiio_test.py IBL WORKDIR
Exit 77 (CTest: skipped) when the OpenImageIO module is not installed."""
import os
import shutil
import subprocess
import sys

try:
    import numpy as np
    import OpenImageIO as oiio
except ImportError as e:
    print(f"dds_oiio_test: skipped: {e} (scripts/install-deps.sh installs python3-openimageio)")
    sys.exit(77)

IBL, WORK = sys.argv[1], sys.argv[2]
FACES = ["px", "nx", "py", "ny", "pz", "nz"]
passed = failed = 0


def check(name, ok, detail=""):
    global passed, failed
    if ok:
        passed += 1
    else:
        failed += 1
    print(("ok   " if ok else "FAIL ") + name + (f"  ({detail})" if detail else ""))


def ibl(*args):
    subprocess.run([IBL, *args, "-q"], cwd=WORK, check=True)


def read_pfm(path):
    """PFM (Pf grey or PF RGB), rows returned top first, as RGB float32."""
    with open(path, "rb") as f:
        data = f.read()
    header, pos = [], 0
    while len(header) < 4:  # kind, width, height, scale: whitespace separated, one byte after
        while data[pos:pos + 1].isspace():
            pos += 1
        end = pos
        while not data[end:end + 1].isspace():
            end += 1
        header.append(data[pos:end].decode("latin1"))
        pos = end
    pos += 1
    kind, width, height, scale = header[0], int(header[1]), int(header[2]), float(header[3])
    channels = 3 if kind == "PF" else 1
    pixels = np.frombuffer(data, dtype="<f4" if scale < 0 else ">f4", count=width * height * channels,
                           offset=pos).reshape(height, width, channels)[::-1]
    return np.repeat(pixels, 3, axis=2) if channels == 1 else pixels


def oiio_levels(path):
    """Every level OpenImageIO reports, as float arrays, and the file's compression name."""
    inp = oiio.ImageInput.open(path)
    if inp is None:
        return None, oiio.geterror()
    compression = inp.spec().get_string_attribute("compression")
    levels, level = [], 0
    while inp.seek_subimage(0, level):
        levels.append(inp.read_image("float"))
        level += 1
    inp.close()
    return levels, compression


def check_cube(name, dds, expect_compression):
    """OpenImageIO's level 0 (faces stacked) against ibl's read of the same file."""
    levels, compression = oiio_levels(os.path.join(WORK, dds))
    if levels is None:
        check(f"{name}: OpenImageIO opens {dds}", False, compression)
        return
    stem = dds.replace(os.sep, "_")  # outside the bake folder: only ibl bake writes there
    ibl("convert", dds, "--out-layout", "faces", "-o", stem + ".pfm")
    ours = [read_pfm(os.path.join(WORK, f"{stem}_{f}.pfm")) for f in FACES]
    size = ours[0].shape[0]
    stacked = levels[0]
    check(f"{name}: OpenImageIO reads {compression}, six faces of {size}",
          compression == expect_compression and stacked.shape == (6 * size, size, 3),
          f"{compression}, {stacked.shape}")
    if stacked.shape != (6 * size, size, 3):
        return
    worst = max(float(np.abs(stacked[k * size:(k + 1) * size] - ours[k]).max()) for k in range(6))
    check(f"{name}: every texel equal to ibl's read", worst == 0.0, f"largest difference {worst}")
    closest_other = min(float(np.abs(stacked[k * size:(k + 1) * size] - ours[j]).max())
                        for k in range(6) for j in range(6) if j != k)
    check(f"{name}: the faces differ (a wrong face order would fail)", closest_other > 0.01,
          f"smallest largest difference between two faces {closest_other:.4g}")


shutil.rmtree(WORK, ignore_errors=True)
os.makedirs(WORK)
print(f"OpenImageIO {oiio.VERSION_STRING}")
ibl("sky", "-o", "sky.exr", "--size", "64")
ibl("convert", "sky.exr", "--size", "16", "--format", "bc6h", "-o", "cube_uf16.dds")
check_cube("BC6H_UF16 cube", "cube_uf16.dds", "BC6HU")
ibl("convert", "sky.exr", "--size", "16", "--format", "bc6h-signed", "-o", "cube_sf16.dds")
check_cube("BC6H_SF16 cube", "cube_sf16.dds", "BC6HS")
ibl("bake", "sky.exr", "--size", "32", "--format", "bc6h", "-o", "bake")
check_cube("bake --format bc6h: specular.dds", os.path.join("bake", "specular.dds"), "BC6HU")

print(f"DDS through OpenImageIO: {passed} passed, {failed} failed")
sys.exit(1 if failed else 0)
