#!/usr/bin/env python3
"""Writes assets/scenes/cutout.glb: a floor under a sun and, 1 m above it, a quad cut out by
the alpha channel of a 4x4 checker base colour texture (glTF alphaMode MASK, cutoff 0.5), seen
from straight above by an orthographic camera. tests/gltf_alpha.rs measures its shadow and its
holes, and assets/references/cutout_direct.exr is Mitsuba 3 rendering voxgi's export of it.

    tools/cutout_scene.py [OUT.glb]

Standard library only (the PNG is written with zlib), so the bytes depend on nothing but this
file.
"""
import json
import math
import struct
import sys
import zlib

# Geometry (meters). The floor spans x in [-2, 2], z in [-1, 1] at y = 0; the cutout quad x in
# [-1.5, -0.5], z in [-0.5, 0.5] at y = 1. The sun shines along (1, -1, 0)/sqrt(2), so the quad's
# shadow is the quad moved by +1 in x: x in [-0.5, 0.5], next to the quad in the camera's view.
FLOOR = [(-2.0, 0.0, -1.0), (-2.0, 0.0, 1.0), (2.0, 0.0, 1.0), (2.0, 0.0, -1.0)]
LEAF = [(-1.5, 1.0, -0.5), (-1.5, 1.0, 0.5), (-0.5, 1.0, 0.5), (-0.5, 1.0, -0.5)]
# glTF uv (v runs down the image): u = x + 1.5, v = z + 0.5 over the quad.
LEAF_UV = [(p[0] + 1.5, p[2] + 0.5) for p in LEAF]
FLOOR_UV = [(0.0, 0.0)] * 4
SUN_IRRADIANCE_W_M2 = 2.0
LUMENS_PER_WATT = 683.0
CHECKER = 4  # texels per side; texel (col, row) is opaque where col + row is even


def png_rgba(width, height, pixel):
    rows = b"".join(
        b"\x00" + b"".join(bytes(pixel(x, y)) for x in range(width)) for y in range(height)
    )

    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    header = struct.pack(">IIBBBBB", width, height, 8, 6, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header)
            + chunk(b"IDAT", zlib.compress(rows, 9)) + chunk(b"IEND", b""))


def quat_from_to(a, b):
    """Unit quaternion (x, y, z, w) turning unit vector a onto unit vector b."""
    c = (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])
    w = 1.0 + sum(x * y for x, y in zip(a, b))
    n = math.sqrt(sum(x * x for x in c) + w * w)
    return [c[0] / n, c[1] / n, c[2] / n, w / n]


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "assets/scenes/cutout.glb"
    texture = png_rgba(CHECKER, CHECKER, lambda x, y: (200, 40, 40, 255 if (x + y) % 2 == 0 else 0))
    bin_ = bytearray()
    views = []

    def view(data, target=None):
        while len(bin_) % 4:
            bin_.append(0)
        v = {"buffer": 0, "byteOffset": len(bin_), "byteLength": len(data)}
        if target:
            v["target"] = target
        views.append(v)
        bin_.extend(data)
        return len(views) - 1

    accessors = []
    meshes = []
    for quad, uv in ((FLOOR, FLOOR_UV), (LEAF, LEAF_UV)):
        pos = b"".join(struct.pack("<3f", *p) for p in quad)
        nrm = b"".join(struct.pack("<3f", 0.0, 1.0, 0.0) for _ in quad)
        tex = b"".join(struct.pack("<2f", *t) for t in uv)
        idx = struct.pack("<6H", 0, 1, 2, 0, 2, 3)
        base = len(accessors)
        accessors += [
            {"bufferView": view(pos, 34962), "componentType": 5126, "count": 4, "type": "VEC3",
             "min": [min(p[i] for p in quad) for i in range(3)],
             "max": [max(p[i] for p in quad) for i in range(3)]},
            {"bufferView": view(nrm, 34962), "componentType": 5126, "count": 4, "type": "VEC3"},
            {"bufferView": view(tex, 34962), "componentType": 5126, "count": 4, "type": "VEC2"},
            {"bufferView": view(idx, 34963), "componentType": 5123, "count": 6, "type": "SCALAR"},
        ]
        meshes.append({"primitives": [{
            "attributes": {"POSITION": base, "NORMAL": base + 1, "TEXCOORD_0": base + 2},
            "indices": base + 3, "material": len(meshes)}]})
    image_view = view(texture)
    s = 1.0 / math.sqrt(2.0)
    gltf = {
        "asset": {"version": "2.0", "generator": "voxgi tools/cutout_scene.py"},
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [{
            "type": "directional", "intensity": SUN_IRRADIANCE_W_M2 * LUMENS_PER_WATT}]}},
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2, 3]}],
        "nodes": [
            {"mesh": 0, "name": "floor"},
            {"mesh": 1, "name": "leaf"},
            {"name": "sun", "rotation": quat_from_to((0.0, 0.0, -1.0), (s, -s, 0.0)),
             "extensions": {"KHR_lights_punctual": {"light": 0}}},
            # -Z turned to -Y (-90 degrees about X): image up is -Z, image right +X.
            {"name": "camera", "translation": [0.0, 5.0, 0.0], "rotation": [-s, 0.0, 0.0, s],
             "camera": 0},
        ],
        "cameras": [{"type": "orthographic", "orthographic": {
            "xmag": 2.0, "ymag": 1.0, "znear": 0.1, "zfar": 10.0}}],
        "meshes": meshes,
        "materials": [
            {"name": "floor", "pbrMetallicRoughness": {
                "baseColorFactor": [0.8, 0.8, 0.8, 1.0], "metallicFactor": 0.0,
                "roughnessFactor": 1.0}},
            {"name": "leaf", "alphaMode": "MASK", "alphaCutoff": 0.5, "doubleSided": True,
             "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "metallicFactor": 0.0,
                                      "roughnessFactor": 1.0}},
        ],
        "images": [{"bufferView": image_view, "mimeType": "image/png"}],
        "textures": [{"source": 0}],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": len(bin_)}],
    }
    while len(bin_) % 4:
        bin_.append(0)
    gltf["buffers"][0]["byteLength"] = len(bin_)
    js = json.dumps(gltf, separators=(",", ":")).encode()
    js += b" " * (-len(js) % 4)
    body = struct.pack("<II", len(js), 0x4E4F534A) + js + struct.pack("<II", len(bin_), 0x004E4942) + bin_
    with open(out, "wb") as f:
        f.write(struct.pack("<III", 0x46546C67, 2, 12 + len(body)) + body)


if __name__ == "__main__":
    main()
