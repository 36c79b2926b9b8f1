#!/usr/bin/env python3
"""Writes scenes/metal_spheres.gltf: glTF's metallic-roughness chart, two rows
of five spheres (top: gold metal, bottom: red dielectric) at roughness 0.2,
0.4, 0.6, 0.8 and 1, on a grey floor, with no camera and no lights, so
that penumbra frames it and lights it as it does any such asset. One UV
sphere mesh (48 x 24 segments) shared by every node; the data is embedded.

    python3 scenes/metal_spheres.py   # rewrites scenes/metal_spheres.gltf
"""
import base64
import json
import math
import struct
from pathlib import Path

SEG_U, SEG_V = 48, 24


def sphere():
    pos, nrm, idx = [], [], []
    for j in range(SEG_V + 1):
        theta = math.pi * j / SEG_V
        for i in range(SEG_U + 1):
            phi = 2 * math.pi * i / SEG_U
            n = (math.sin(theta) * math.cos(phi), math.cos(theta), math.sin(theta) * math.sin(phi))
            pos.append(n)
            nrm.append(n)
    for j in range(SEG_V):
        for i in range(SEG_U):
            a = j * (SEG_U + 1) + i
            b = a + SEG_U + 1
            # Counter-clockwise seen from outside.
            idx += [a, a + 1, b, a + 1, b + 1, b]
    return pos, nrm, idx


def floor():
    x, z = 6.0, 2.0
    pos = [(-x, 0, -z), (x, 0, -z), (x, 0, z), (-x, 0, z)]
    return pos, [(0, 1, 0)] * 4, [0, 2, 1, 0, 3, 2]


def main():
    blob = bytearray()
    views, accessors, meshes = [], [], []

    def add(data, fmt, count, kind, ctype, target, minmax=None):
        while len(blob) % 4:
            blob.append(0)
        off = len(blob)
        for d in data:
            blob.extend(struct.pack(fmt, *d) if isinstance(d, tuple) else struct.pack(fmt, d))
        views.append({"buffer": 0, "byteOffset": off, "byteLength": len(blob) - off, "target": target})
        acc = {"bufferView": len(views) - 1, "componentType": ctype, "count": count, "type": kind}
        if minmax:
            acc["min"], acc["max"] = minmax
        accessors.append(acc)
        return len(accessors) - 1

    def mesh(geometry, material):
        pos, nrm, idx = geometry
        lo = [min(p[k] for p in pos) for k in range(3)]
        hi = [max(p[k] for p in pos) for k in range(3)]
        p = add(pos, "<3f", len(pos), "VEC3", 5126, 34962, (lo, hi))
        n = add(nrm, "<3f", len(nrm), "VEC3", 5126, 34962)
        i = add(idx, "<I", len(idx), "SCALAR", 5125, 34963)
        meshes.append({"primitives": [{"attributes": {"POSITION": p, "NORMAL": n}, "indices": i, "material": material}]})
        return len(meshes) - 1

    roughness = [0.2, 0.4, 0.6, 0.8, 1.0]
    materials, nodes = [], []
    ball = sphere()
    for row, (name, colour, metallic) in enumerate([("gold", [1.0, 0.766, 0.336, 1], 1.0), ("red plastic", [0.8, 0.05, 0.05, 1], 0.0)]):
        for col, r in enumerate(roughness):
            materials.append({"name": f"{name}, roughness {r}", "pbrMetallicRoughness": {"baseColorFactor": colour, "metallicFactor": metallic, "roughnessFactor": r}})
            m = mesh(ball, len(materials) - 1)
            nodes.append({"mesh": m, "translation": [2.2 * (col - 2), 1.0 + 2.2 * (1 - row), 0.0]})
    materials.append({"name": "floor", "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1], "metallicFactor": 0.0, "roughnessFactor": 0.8}})
    nodes.append({"mesh": mesh(floor(), len(materials) - 1), "translation": [0, -0.001, 0]})
    doc = {
        "asset": {"version": "2.0", "generator": "scenes/metal_spheres.py (penumbra)"},
        "scene": 0,
        "scenes": [{"nodes": list(range(len(nodes)))}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": materials,
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": len(blob), "uri": "data:application/octet-stream;base64," + base64.b64encode(bytes(blob)).decode()}],
    }
    out = Path(__file__).with_name("metal_spheres.gltf")
    out.write_text(json.dumps(doc, separators=(",", ":")) + "\n")


if __name__ == "__main__":
    main()
