#!/usr/bin/env python3
"""Writes the sample scene of docs/PROBES.md: scene.gltf + scene.bin + floor.png + probes.json.

Three rooms in a row along X (red, white, blue walls), 3 m high, joined by doors; the white
room has a window to the sky in its south wall (+Z), where the default sun (azimuth 180:
from +Z, 35 degrees up) shines in; the red and blue rooms have emissive ceiling lamps; a
glossy pedestal, a mirror-like sphere and a gold sphere. Eight probes: one per room
(far-plane capture: the doors and the window leave alpha 0), a small sphere probe over the
pedestal and one by the gold sphere, one in each doorway (infinite, priority 1) and one
infinite probe over the whole house (priority -1); with the set's default view they show what
local probes are for: each room's reflections carry its own colours and light.

Only the Python standard library: the glTF JSON, the binary buffer and the PNG are written by
hand (glTF 2.0 specification; PNG specification, ISO/IEC 15948). Deterministic: the same
bytes every run.

    python3 examples/rooms/make_scene.py [OUT_DIR]      (default: this script's folder)
"""
import json
import math
import os
import struct
import sys
import zlib

H = 3.0          # ceiling height
GAP = 0.05       # half thickness of the walls between rooms
DOOR_W, DOOR_H = 0.5, 2.2   # half width, height
ROOMS = [        # name, x0, x1, wall material, floor material
    ("red", -6.0, -2.0 - GAP, "red_wall", "wood"),
    ("white", -2.0 + GAP, 2.0 - GAP, "white_wall", "checker"),
    ("blue", 2.0 + GAP, 6.0, "blue_wall", "wood"),
]
Z0, Z1 = -2.0, 2.0
WINDOW = (-0.8, 0.8, 1.0, 2.2)  # x0, x1, y0, y1 in the white room's +Z wall
ROOM_MARGIN = 2 * GAP            # a room probe's influence past its walls: the wall's thickness

MATERIALS = {
    # name: (base colour, metallic, roughness, emissive colour, emissive strength)
    "red_wall": ((0.70, 0.10, 0.08), 0.0, 0.8, None, 0),
    "white_wall": ((0.80, 0.80, 0.78), 0.0, 0.9, None, 0),
    "blue_wall": ((0.08, 0.15, 0.65), 0.0, 0.8, None, 0),
    "ceiling": ((0.85, 0.85, 0.85), 0.0, 1.0, None, 0),
    "wood": ((0.45, 0.28, 0.15), 0.0, 0.5, None, 0),
    "checker": ((1.0, 1.0, 1.0), 0.0, 0.35, None, 0),   # x the floor texture
    "jamb": ((0.5, 0.5, 0.5), 0.0, 0.7, None, 0),
    "warm_lamp": ((0.9, 0.9, 0.9), 0.0, 1.0, (1.0, 0.75, 0.45), 40.0),
    "cool_lamp": ((0.9, 0.9, 0.9), 0.0, 1.0, (0.6, 0.8, 1.0), 40.0),
    "glossy_red": ((0.8, 0.05, 0.05), 0.0, 0.08, None, 0),
    "mirror": ((0.95, 0.95, 0.95), 1.0, 0.05, None, 0),
    "gold": ((1.0, 0.77, 0.34), 1.0, 0.3, None, 0),
}


class Mesh:
    def __init__(self):
        self.pos, self.nrm, self.uv, self.idx = [], [], [], []

    def quad(self, a, b, c, d, n, uv_scale=1.0):
        """Counter-clockwise a b c d seen from the side n points to."""
        base = len(self.pos)
        for p, t in zip((a, b, c, d), ((0, 1), (1, 1), (1, 0), (0, 0))):
            self.pos.append(p)
            self.nrm.append(n)
            self.uv.append((t[0] * uv_scale, t[1] * uv_scale))
        self.idx += [base, base + 1, base + 2, base, base + 2, base + 3]

    def sphere(self, c, r, seg=24, rings=16):
        base = len(self.pos)
        for i in range(rings + 1):
            th = math.pi * i / rings
            for j in range(seg + 1):
                ph = 2 * math.pi * j / seg
                n = (math.sin(th) * math.cos(ph), math.cos(th), math.sin(th) * math.sin(ph))
                self.pos.append(tuple(c[k] + r * n[k] for k in range(3)))
                self.nrm.append(n)
                self.uv.append((j / seg, i / rings))
        for i in range(rings):
            for j in range(seg):
                a = base + i * (seg + 1) + j
                b = a + seg + 1
                self.idx += [a, a + 1, b, a + 1, b + 1, b]

    def box(self, lo, hi):
        x0, y0, z0 = lo
        x1, y1, z1 = hi
        self.quad((x0, y1, z0), (x0, y1, z1), (x1, y1, z1), (x1, y1, z0), (0, 1, 0))
        self.quad((x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1), (0, 0, 1))
        self.quad((x1, y0, z0), (x0, y0, z0), (x0, y1, z0), (x1, y1, z0), (0, 0, -1))
        self.quad((x1, y0, z1), (x1, y0, z0), (x1, y1, z0), (x1, y1, z1), (1, 0, 0))
        self.quad((x0, y0, z0), (x0, y0, z1), (x0, y1, z1), (x0, y1, z0), (-1, 0, 0))


def wall_x(m, x, z0, z1, facing, holes):
    """A wall in the plane x = const from z0 to z1, 0..H, facing +X or -X, minus rectangular
    holes (z0, z1, y0, y1), cut into rectangles."""
    def rect(za, zb, ya, yb):
        if za >= zb or ya >= yb:
            return
        if facing > 0:
            m.quad((x, ya, zb), (x, ya, za), (x, yb, za), (x, yb, zb), (1, 0, 0))
        else:
            m.quad((x, ya, za), (x, ya, zb), (x, yb, zb), (x, yb, za), (-1, 0, 0))
    cuts = sorted(holes)
    z = z0
    for hz0, hz1, hy0, hy1 in cuts:
        rect(z, hz0, 0, H)
        rect(hz0, hz1, 0, hy0)
        rect(hz0, hz1, hy1, H)
        z = hz1
    rect(z, z1, 0, H)


def wall_z(m, z, x0, x1, facing, holes):
    def rect(xa, xb, ya, yb):
        if xa >= xb or ya >= yb:
            return
        if facing > 0:
            m.quad((xa, ya, z), (xb, ya, z), (xb, yb, z), (xa, yb, z), (0, 0, 1))
        else:
            m.quad((xb, ya, z), (xa, ya, z), (xa, yb, z), (xb, yb, z), (0, 0, -1))
    x = x0
    for hx0, hx1, hy0, hy1 in sorted(holes):
        rect(x, hx0, 0, H)
        rect(hx0, hx1, 0, hy0)
        rect(hx0, hx1, hy1, H)
        x = hx1
    rect(x, x1, 0, H)


def build():
    meshes = {name: Mesh() for name in MATERIALS}
    door = (-DOOR_W, DOOR_W, 0.0, DOOR_H)
    for i, (_, x0, x1, wall, floor) in enumerate(ROOMS):
        f = meshes[floor]
        f.quad((x0, 0, Z1), (x1, 0, Z1), (x1, 0, Z0), (x0, 0, Z0), (0, 1, 0), uv_scale=2.0)
        meshes["ceiling"].quad((x0, H, Z0), (x1, H, Z0), (x1, H, Z1), (x0, H, Z1), (0, -1, 0))
        w = meshes[wall]
        wall_x(w, x0, Z0, Z1, +1, [door] if i > 0 else [])
        wall_x(w, x1, Z0, Z1, -1, [door] if i < len(ROOMS) - 1 else [])
        wall_z(w, Z0, x0, x1, +1, [])
        wall_z(w, Z1, x0, x1, -1, [WINDOW] if i == 1 else [])
    # door jambs and the floor of each doorway, closing the gap between the two wall sheets
    j = meshes["jamb"]
    for xc in (-2.0, 2.0):
        a, b = xc - GAP, xc + GAP
        j.quad((a, 0, -DOOR_W), (b, 0, -DOOR_W), (b, DOOR_H, -DOOR_W), (a, DOOR_H, -DOOR_W), (0, 0, 1))
        j.quad((b, 0, DOOR_W), (a, 0, DOOR_W), (a, DOOR_H, DOOR_W), (b, DOOR_H, DOOR_W), (0, 0, -1))
        j.quad((a, DOOR_H, -DOOR_W), (b, DOOR_H, -DOOR_W), (b, DOOR_H, DOOR_W), (a, DOOR_H, DOOR_W), (0, -1, 0))
        meshes["wood"].quad((a, 0, DOOR_W), (b, 0, DOOR_W), (b, 0, -DOOR_W), (a, 0, -DOOR_W), (0, 1, 0))
    # window sill and reveals are the wall's own edge (a zero-thickness opening)
    # lamps: panels just under the ceiling of the red and blue rooms, facing down
    for name, xc in (("warm_lamp", -4.0), ("cool_lamp", 4.0)):
        y = H - 0.02
        meshes[name].quad((xc - 0.4, y, -0.4), (xc + 0.4, y, -0.4), (xc + 0.4, y, 0.4), (xc - 0.4, y, 0.4), (0, -1, 0))
    meshes["glossy_red"].box((-4.6, 0.0, -1.2), (-3.4, 0.8, -0.2))
    meshes["mirror"].sphere((0.0, 0.6, -0.8), 0.6)
    meshes["gold"].sphere((4.2, 0.5, -0.6), 0.5)
    return meshes


def png_bytes(width, height, rgb_rows):
    def chunk(kind, data):
        c = struct.pack(">I", len(data)) + kind + data
        return c + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)
    raw = b"".join(b"\x00" + bytes(row) for row in rgb_rows)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
            + chunk(b"sRGB", b"\x00") + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def checker_png():
    n = 16
    rows = []
    for y in range(n):
        row = []
        for x in range(n):
            v = 225 if ((x // 4) + (y // 4)) % 2 == 0 else 40
            row += [v, v, v]
        rows.append(row)
    return png_bytes(n, n, rows)


def write_gltf(meshes, out_dir):
    buf = bytearray()
    accessors, views, gl_meshes, nodes = [], [], [], []
    names = [n for n in MATERIALS if meshes[n].idx]

    def add_view(data, target):
        while len(buf) % 4:
            buf.append(0)
        views.append({"buffer": 0, "byteOffset": len(buf), "byteLength": len(data), "target": target})
        buf.extend(data)
        return len(views) - 1

    for name in names:
        m = meshes[name]
        pos = b"".join(struct.pack("<3f", *p) for p in m.pos)
        nrm = b"".join(struct.pack("<3f", *n) for n in m.nrm)
        uv = b"".join(struct.pack("<2f", *t) for t in m.uv)
        idx = b"".join(struct.pack("<I", i) for i in m.idx)
        lo = [min(p[k] for p in m.pos) for k in range(3)]
        hi = [max(p[k] for p in m.pos) for k in range(3)]
        a0 = len(accessors)
        accessors.append({"bufferView": add_view(pos, 34962), "componentType": 5126, "count": len(m.pos),
                          "type": "VEC3", "min": [round(v, 6) for v in lo], "max": [round(v, 6) for v in hi]})
        accessors.append({"bufferView": add_view(nrm, 34962), "componentType": 5126, "count": len(m.pos), "type": "VEC3"})
        accessors.append({"bufferView": add_view(uv, 34962), "componentType": 5126, "count": len(m.pos), "type": "VEC2"})
        accessors.append({"bufferView": add_view(idx, 34963), "componentType": 5125, "count": len(m.idx), "type": "SCALAR"})
        gl_meshes.append({"name": name, "primitives": [{
            "attributes": {"POSITION": a0, "NORMAL": a0 + 1, "TEXCOORD_0": a0 + 2},
            "indices": a0 + 3, "material": names.index(name)}]})
        nodes.append({"name": name, "mesh": len(gl_meshes) - 1})

    materials = []
    for name in names:
        base, metal, rough, emit, strength = MATERIALS[name]
        mat = {"name": name, "pbrMetallicRoughness": {
            "baseColorFactor": list(base) + [1.0], "metallicFactor": metal, "roughnessFactor": rough}}
        if name == "checker":
            mat["pbrMetallicRoughness"]["baseColorTexture"] = {"index": 0}
        if emit:
            mat["emissiveFactor"] = list(emit)
            mat["extensions"] = {"KHR_materials_emissive_strength": {"emissiveStrength": strength}}
        materials.append(mat)

    gltf = {
        "asset": {"version": "2.0", "generator": "ibl examples/rooms/make_scene.py"},
        "extensionsUsed": ["KHR_materials_emissive_strength"],
        "scene": 0,
        "scenes": [{"name": "rooms", "nodes": list(range(len(nodes)))}],
        "nodes": nodes,
        "meshes": gl_meshes,
        "materials": materials,
        "textures": [{"source": 0, "sampler": 0}],
        "images": [{"uri": "floor.png"}],
        "samplers": [{"magFilter": 9728, "minFilter": 9728, "wrapS": 10497, "wrapT": 10497}],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"uri": "scene.bin", "byteLength": len(buf)}],
    }
    with open(os.path.join(out_dir, "scene.bin"), "wb") as f:
        f.write(bytes(buf))
    with open(os.path.join(out_dir, "scene.gltf"), "w") as f:
        json.dump(gltf, f, indent=1)
        f.write("\n")
    with open(os.path.join(out_dir, "floor.png"), "wb") as f:
        f.write(checker_png())
    return sum(len(meshes[n].idx) // 3 for n in names)


def write_probes(out_dir):
    probes = []
    rooms = {}
    for name, x0, x1, _, _ in ROOMS:
        cx, hx = (x0 + x1) / 2, (x1 - x0) / 2
        room = {"shape": "box", "center": [cx, H / 2, 0.0], "half_extent": [hx, H / 2, (Z1 - Z0) / 2]}
        rooms[name] = room
        # the influence reaches ROOM_MARGIN past the walls with a blend margin as wide, so
        # that the walls themselves get the full weight and the next room's walls none
        influence = {"shape": "box", "center": room["center"], "blend": ROOM_MARGIN,
                     "half_extent": [v + ROOM_MARGIN for v in room["half_extent"]]}
        probes.append({"name": name + "_room", "position": [cx, 1.5, 0.6], "influence": influence,
                       "proxy": room, "capture": "far-plane", "size": 64})
    # small probes where one room probe's single point of view is poorest: over the glossy
    # pedestal (sphere influence, sphere proxy) and beside the gold sphere (sphere influence,
    # the room's box as proxy)
    probes.append({"name": "red_pedestal", "position": [-4.0, 1.4, -0.7],
                   "influence": {"shape": "sphere", "radius": 1.3, "blend": 0.5},
                   "proxy": {"shape": "sphere", "radius": 1.6}, "capture": "far-plane", "size": 64})
    probes.append({"name": "blue_gold", "position": [4.2, 1.4, -0.6],
                   "influence": {"shape": "sphere", "radius": 1.3, "blend": 0.5},
                   "proxy": rooms["blue"], "capture": "far-plane", "size": 64})
    # the doorways: infinite captures that see both rooms, projected on the two rooms' box
    for name, xc, pair in (("door_west", -2.0, ("red", "white")), ("door_east", 2.0, ("white", "blue"))):
        a, b = rooms[pair[0]], rooms[pair[1]]
        lo = a["center"][0] - a["half_extent"][0]
        hi = b["center"][0] + b["half_extent"][0]
        probes.append({"name": name, "position": [xc, 1.1, 0.0],
                       "influence": {"shape": "box", "center": [xc, 1.2, 0.0], "half_extent": [0.7, 1.2, 0.9],
                                     "blend": 0.4},
                       "proxy": {"shape": "box", "center": [(lo + hi) / 2, H / 2, 0.0],
                                 "half_extent": [(hi - lo) / 2, H / 2, (Z1 - Z0) / 2]},
                       "priority": 1, "capture": "infinite", "size": 64})
    probes.append({"name": "house", "position": [0.0, 1.5, 0.6],
                   "influence": {"shape": "box", "center": [0.0, H / 2, 0.0], "half_extent": [6.5, 2.0, 2.5], "blend": 0.5},
                   "proxy": {"shape": "box", "center": [0.0, H / 2, 0.0], "half_extent": [6.0, H / 2, 2.0]},
                   "priority": -1, "capture": "infinite", "size": 64})
    data = {"format": "ibl-probes", "version": 1,
            "global": {"environment": "sky", "sky": {"sun_elevation": 35, "sun_azimuth": 180},
                       "size": 128, "preset": "gltf"},
            # the default camera of `ibl render scene.gltf --probes`: from the white room's
            # south-east corner toward the west door, the mirror sphere and the red room
            "view": {"position": [1.7, 1.7, 1.8], "target": [-2.6, 0.9, -0.7], "fov": 70},
            "probes": probes}
    with open(os.path.join(out_dir, "probes.json"), "w") as f:
        json.dump(data, f, indent=1)
        f.write("\n")


def main():
    out_dir = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.abspath(__file__))
    os.makedirs(out_dir, exist_ok=True)
    triangles = write_gltf(build(), out_dir)
    write_probes(out_dir)
    print(f"{out_dir}: scene.gltf ({triangles} triangles), scene.bin, floor.png, probes.json")


if __name__ == "__main__":
    main()
