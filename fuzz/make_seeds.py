#!/usr/bin/env python3
"""Writes the small generated seeds of the reader targets into seeds/<target>/.

Each is a few triangles of a real feature of its format (materials, normals, UVs, colours,
both PLY encodings, data URIs and GLB chunks, DEM profiles, every npy dtype family), so the
fuzzer starts past the headers. Run from fuzz/: `python3 make_seeds.py`.
"""
import base64
import json
import os
import struct

SIDE = b"\n#%side\n"


def write(target, name, data):
    os.makedirs(f"seeds/{target}", exist_ok=True)
    with open(f"seeds/{target}/{name}", "wb") as f:
        f.write(data)


def grid(n):
    """An n x n grid of quads: positions, uvs, triangles (0-based)."""
    pos = [(x / n, ((x * 7 + z * 3) % 5) / 10, z / n) for z in range(n + 1) for x in range(n + 1)]
    uv = [(x / n, z / n) for z in range(n + 1) for x in range(n + 1)]
    tris = []
    for z in range(n):
        for x in range(n):
            a = z * (n + 1) + x
            tris += [(a, a + n + 1, a + 1), (a + 1, a + n + 1, a + n + 2)]
    return pos, uv, tris


# OBJ (+ MTL as the side file)
pos, uv, tris = grid(3)
obj = ["mtllib grid.mtl", "o grid"]
obj += [f"v {x} {y} {z}" for x, y, z in pos]
obj += [f"vt {u} {v}" for u, v in uv]
obj += ["vn 0 1 0", "usemtl red"]
half = len(tris) // 2
obj += [f"f {a+1}/{a+1}/1 {b+1}/{b+1}/1 {c+1}/{c+1}/1" for a, b, c in tris[:half]]
obj += ["usemtl tex", "s 1"]
obj += [f"f {a-len(pos)}/{a-len(pos)} {b-len(pos)}/{b-len(pos)} {c-len(pos)}/{c-len(pos)}" for a, b, c in tris[half:]]
obj += ["l 1 2", "p 3", "f 1 2 3 4"]
mtl = b"newmtl red\nKd 1 0 0\nd 0.5\nnewmtl tex\nKd 1 1 1\nmap_Kd -s 1 1 1 tex.png\nTr 0.1\n"
write("obj", "grid.obj", "\n".join(obj).encode() + SIDE + mtl)
colored = ["v 0 0 0 1 0 0", "v 1 0 0 0 1 0", "v 0 1 0 0 0 1", "v 1 1 0 1 1 1", "f 1 2 3", "f 2 4 3 \\", ""]
write("obj", "colors.obj", "\n".join(colored).encode())

# PLY, ascii and binary of both endiannesses
pos, uv, tris = grid(2)
props = [("float", "x"), ("float", "y"), ("float", "z"), ("float", "nx"), ("float", "ny"), ("float", "nz"),
         ("uchar", "red"), ("uchar", "green"), ("uchar", "blue"), ("float", "u"), ("float", "v")]


def ply(fmt):
    head = [f"ply", f"format {fmt} 1.0", "comment TextureFile tex.png", f"element vertex {len(pos)}"]
    head += [f"property {t} {n}" for t, n in props]
    head += [f"element face {len(tris)}", "property list uchar int vertex_indices", "end_header", ""]
    out = "\n".join(head).encode()
    end = {"ascii": None, "binary_little_endian": "<", "binary_big_endian": ">"}[fmt]
    rows = [(x, y, z, 0.0, 1.0, 0.0, 200, 100, 50, u, v) for (x, y, z), (u, v) in zip(pos, uv)]
    if end is None:
        out += "".join(" ".join(str(c) for c in r) + "\n" for r in rows).encode()
        out += "".join(f"3 {a} {b} {c}\n" for a, b, c in tris).encode()
    else:
        for r in rows:
            out += struct.pack(end + "6f3B2f", *r)
        for t in tris:
            out += struct.pack(end + "B3i", 3, *t)
    return out


write("ply", "ascii.ply", ply("ascii"))
write("ply", "le.ply", ply("binary_little_endian"))
write("ply", "be.ply", ply("binary_big_endian"))
write("ply", "strips.ply", b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
      b"property float z\nelement tristrips 1\nproperty list int int vertex_indices\nend_header\n"
      b"0 0 0\n1 0 0\n0 1 0\n1 1 0\n5 0 1 2 3 -1\n")


# glTF (data URI, external buffer as the side file) and GLB
def gltf_parts(uri):
    pos, uv, tris = grid(2)
    p = b"".join(struct.pack("<3f", *v) for v in pos)
    t = b"".join(struct.pack("<2f", *v) for v in uv)
    c = b"".join(struct.pack("<4B", 255, 128, 0, 255) for _ in pos)
    i = b"".join(struct.pack("<3H", *tri) for tri in tris)
    i += b"\0" * (-len(i) % 4)
    blob = p + t + c + i
    lo = [min(v[k] for v in pos) for k in range(3)]
    hi = [max(v[k] for v in pos) for k in range(3)]
    views = [(0, len(p)), (len(p), len(t)), (len(p) + len(t), len(c)), (len(p) + len(t) + len(c), len(tris) * 6)]
    doc = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "children": [1], "translation": [1, 0, 0]}, {"mesh": 0, "scale": [2, 2, 2]}],
        "meshes": [{"name": "grid", "primitives": [{
            "attributes": {"POSITION": 0, "TEXCOORD_0": 1, "COLOR_0": 2},
            "indices": 3, "material": 0, "mode": 4}]}],
        "materials": [{"name": "m", "doubleSided": True, "alphaMode": "MASK", "alphaCutoff": 0.3,
                       "pbrMetallicRoughness": {"baseColorFactor": [1, 0.5, 0.5, 1], "baseColorTexture": {"index": 0}}}],
        "textures": [{"source": 0}],
        "images": [{"uri": "tex.png"}],
        "buffers": [{"byteLength": len(blob)} | ({"uri": uri} if uri else {})],
        "bufferViews": [{"buffer": 0, "byteOffset": o, "byteLength": n} for o, n in views],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": len(pos), "type": "VEC3", "min": lo, "max": hi},
            {"bufferView": 1, "componentType": 5126, "count": len(pos), "type": "VEC2"},
            {"bufferView": 2, "componentType": 5121, "normalized": True, "count": len(pos), "type": "VEC4"},
            {"bufferView": 3, "componentType": 5123, "count": len(tris) * 3, "type": "SCALAR"},
        ],
    }
    return doc, blob


doc, blob = gltf_parts(None)
doc["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64.b64encode(blob).decode()
write("gltf", "data_uri.gltf", json.dumps(doc).encode())
doc, blob = gltf_parts("grid.bin")
write("gltf", "external.gltf", json.dumps(doc).encode() + SIDE + blob)
doc, blob = gltf_parts(None)
j = json.dumps(doc).encode()
j += b" " * (-len(j) % 4)
body = struct.pack("<II", len(j), 0x4E4F534A) + j + struct.pack("<II", len(blob), 0x004E4942) + blob
write("glb", "grid.glb", b"glTF" + struct.pack("<II", 2, 12 + len(body)) + body)


# USGS DEM: a type-A record, then type-B profiles
BLOCK = 1024


def fortran(v):
    s = f"{v:.15E}".replace("E", "D")
    return s


def dem(profiles, units=2):
    a = bytearray(b" " * BLOCK)

    def put(first, text):
        a[first - 1:first - 1 + len(text)] = text.encode()
    put(1, "FUZZ SEED DEM")
    put(529, f"{units:>6}{2:>6}{4:>6}")
    put(817, "0.300000E+020.300000E+020.100000E+01")
    put(853, f"{1:>6}{len(profiles):>6}")
    out = bytes(a)
    for j, (x, y, el) in enumerate(profiles):
        text = f"{1:>6}{j+1:>6}{len(el):>6}{1:>6}" + "".join(f"{fortran(v):>24}" for v in (x, y, 0.0, 0.0, 0.0))
        in_block, capacity = 144, 146
        for e in el:
            if capacity == 0:
                text += " " * (BLOCK - in_block)
                in_block, capacity = 0, 170
            text += f"{e:>6}"
            in_block += 6
            capacity -= 1
        text += " " * (BLOCK - in_block)
        out += text.encode()
    return out


write("dem", "square.dem", dem([(30.0 * j, 0.0, [100 + j * 3 + k for k in range(5)]) for j in range(4)]))
write("dem", "irregular.dem", dem([(0.0, 30.0, [10, -32767, 12]), (30.0, 0.0, [5, 6, 7, 8]), (60.0, 60.0, [1, 2])]))
write("dem", "feet.dem", dem([(0.0, 0.0, list(range(160))), (30.0, 0.0, list(range(160)))], units=1))


# npy: a dtype of each family, both orders
def npy(descr, fortran_order, shape, data):
    d = f"{{'descr': '{descr}', 'fortran_order': {fortran_order}, 'shape': {shape}, }}"
    while (10 + len(d) + 1) % 64:
        d += " "
    d += "\n"
    return b"\x93NUMPY\x01\x00" + struct.pack("<H", len(d)) + d.encode() + data


write("npy", "f4.npy", npy("<f4", "False", "(3, 4)", struct.pack("<12f", *[i * 0.5 for i in range(12)])))
write("npy", "be_i2.npy", npy(">i2", "False", "(4, 3)", struct.pack(">12h", *range(-6, 6))))
write("npy", "u1.npy", npy("|u1", "False", "(3, 3)", bytes(range(9))))
write("npy", "f8_nan.npy", npy("<f8", "False", "(3, 3)", struct.pack("<9d", 1, 2, float("nan"), 4, 5, 6, 7, 8, 9)))

# The streaming readers: first byte even for PLY, odd for OBJ
for name in ["ascii.ply", "le.ply", "be.ply"]:
    write("ooc", name, b"\0" + open(f"seeds/ply/{name}", "rb").read())
write("ooc", "grid.obj", b"\1" + open("seeds/obj/grid.obj", "rb").read().split(SIDE)[0])
write("ooc", "colors.obj", b"\3" + open("seeds/obj/colors.obj", "rb").read())

# Bake from memory: first byte picks the format (obj, ply, gltf, glb, dem, npy)
for k, (target, names) in enumerate([("obj", ["grid.obj", "colors.obj"]), ("ply", ["ascii.ply", "le.ply"]),
                                      ("gltf", ["data_uri.gltf", "external.gltf"]), ("glb", ["grid.glb"]),
                                      ("dem", ["square.dem", "irregular.dem"]), ("npy", ["f4.npy", "be_i2.npy"])]):
    for name in names:
        write("bake_from_memory", name, bytes([k]) + open(f"seeds/{target}/{name}", "rb").read())


def real_seeds(data, corpus="corpus"):
    """Small pieces of the real inputs in `data` (the shared data folder) for corpus/<target>/
    (not committed): the first faces of spot and lucy with the vertices they use, the
    FlightHelmet JSON alone, and St. Helens's header with its first profiles."""
    def put(target, name, payload):
        os.makedirs(f"{corpus}/{target}", exist_ok=True)
        with open(f"{corpus}/{target}/{name}", "wb") as f:
            f.write(payload)

    lines = open(f"{data}/spot/spot_triangulated.obj", "rb").read().split(b"\n")
    keep = 400
    faces = [l for l in lines if l.startswith(b"f ")
             and all(int(c.split(b"/")[0]) <= keep and int(c.split(b"/")[1]) <= keep for c in l.split()[1:])]
    vs = [l for l in lines if l.startswith(b"v ")][:keep]
    vts = [l for l in lines if l.startswith(b"vt ")][:keep]
    spot = b"\n".join(vs + vts + faces[:300]) + b"\n"
    put("obj", "spot_part.obj", spot)
    put("ooc", "spot_part.obj", b"\1" + spot)
    put("bake_from_memory", "spot_part.obj", b"\0" + spot)

    raw = open(f"{data}/scans/lucy.ply", "rb").read()
    end = raw.index(b"end_header\n") + len(b"end_header\n")
    nv = int(raw[:end].split(b"element vertex ")[1].split(b"\n")[0])
    vdata = raw[end:end + nv * 12]
    fdata = raw[end + nv * 12:]
    keep, tris = 1500, []
    for k in range(0, len(fdata), 13):
        a, b, c = struct.unpack("<3i", fdata[k + 1:k + 13])
        if max(a, b, c) < keep:
            tris.append(fdata[k:k + 13])
        if len(tris) == 2000:
            break
    head = raw[:end].replace(f"element vertex {nv}".encode(), f"element vertex {keep}".encode())
    head = head.split(b"element face ")[0] + f"element face {len(tris)}\n".encode() + \
        head.split(b"element face ")[1].split(b"\n", 1)[1]
    lucy = head + vdata[:keep * 12] + b"".join(tris)
    put("ply", "lucy_part.ply", lucy)
    put("ooc", "lucy_part.ply", b"\0" + lucy)
    put("bake_from_memory", "lucy_part.ply", b"\1" + lucy)

    helmet = open(f"{data}/FlightHelmet/FlightHelmet.gltf", "rb").read()
    put("gltf", "FlightHelmet.gltf", helmet)
    put("bake_from_memory", "FlightHelmet.gltf", b"\2" + helmet)

    dem_raw = open(f"{data}/terrain/SainteHelens.dem", "rb").read()
    header = bytearray(dem_raw[:BLOCK])
    out, at, profiles = b"", BLOCK, 4
    for _ in range(profiles):
        m = int(dem_raw[at + 12:at + 18])
        blocks = 1 + max(0, -(-(m - 146) // 170))
        out += dem_raw[at:at + blocks * BLOCK]
        at += blocks * BLOCK
    header[852:864] = f"{1:>6}{profiles:>6}".encode()
    put("dem", "st_helens_part.dem", bytes(header) + out)
    put("bake_from_memory", "st_helens_part.dem", b"\4" + bytes(header) + out)


if __name__ == "__main__" and len(os.sys.argv) > 1:
    real_seeds(os.sys.argv[1])


# bake_mesh: a closed cube (8 positions on the 1/8 grid, normals and UVs, two surfaces) and a
# grid with a duplicated, a flipped and a degenerate triangle
def grid_byte(v):
    return int(round(v * 8 + 64)) & 0x7F


cube = [(x, y, z) for x in (0, 1) for y in (0, 1) for z in (0, 1)]
faces = [(0, 1, 3), (0, 3, 2), (4, 6, 7), (4, 7, 5), (0, 4, 5), (0, 5, 1),
         (2, 3, 7), (2, 7, 6), (0, 2, 6), (0, 6, 4), (1, 5, 7), (1, 7, 3)]
seed = bytes([8 - 3, 0x13])
for p in cube:
    seed += bytes(grid_byte(c) for c in p) + bytes(grid_byte(c) for c in p) + bytes(grid_byte(c) for c in p[:2])
seed += b"".join(bytes([a, b, c, k % 2]) for k, (a, b, c) in enumerate(faces))
write("bake_mesh", "cube.bin", seed)
pos, _, tris = grid(3)
seed = bytes([len(pos) - 3, 0x04])
for p in pos:
    seed += bytes(grid_byte(c) for c in p) + bytes([grid_byte(p[1])])
tris = tris + [tris[0], tris[1][::-1], (0, 0, 1)]
seed += b"".join(bytes([a, b, c, 0]) for a, b, c in tris)
write("bake_mesh", "grid_extra.bin", seed)
