#!/usr/bin/env python3
"""Memory of instanced glTF scenes: N nodes showing one mesh against N nodes with a mesh each.

Writes, for each copy count, two .glb scenes of a floor and a lamp with N copies of a bent
grid of T triangles: `shared` (every node shows one mesh: glTF instancing) and `copied` (each
node has its own mesh of the same data). Then runs `twopass info --json` on each under
`/usr/bin/time -v` and reports the triangles the passes see, the triangles stored, the mesh and
trees' bytes as `info` counts them, the process's peak resident memory and the wall time.

    python3 crates/twopass/bench/instances.py --twopass target/release/twopass \
        --copies 1,10,100 --triangles 100000
"""

import argparse
import json
import math
import os
import struct
import subprocess
import sys
import tempfile
import time

import numpy as np


def grid(triangles):
    """A grid bent into a half pipe of about `triangles` triangles: (positions, indices)."""
    nu = max(2, int(math.sqrt(triangles / 2)))
    nv = max(1, triangles // (2 * nu))
    a = np.pi * np.arange(nu + 1) / nu
    z = 2.0 * np.arange(nv + 1) / nv
    A, Z = np.meshgrid(a, z)
    p = np.stack([np.cos(A), np.sin(A) + 0.01, Z], axis=-1).reshape(-1, 3).astype(np.float32)
    j, i = np.meshgrid(np.arange(nv), np.arange(nu), indexing="ij")
    a0 = (j * (nu + 1) + i).ravel()
    b0 = ((j + 1) * (nu + 1) + i).ravel()
    idx = np.stack([a0, a0 + 1, b0, a0 + 1, b0 + 1, b0], axis=-1).reshape(-1).astype(np.uint32)
    return p, idx


def glb(copies, shared, triangles):
    """The .glb bytes of the scene."""
    p, idx = grid(triangles)
    floor_p = np.array([[-1, 0, -1], [-1, 0, 1], [1, 0, 1], [1, 0, -1]], np.float32) * (3 * math.sqrt(copies) + 4)
    lamp_p = np.array([[-1, 8, -1], [1, 8, -1], [1, 8, 1], [-1, 8, 1]], np.float32)
    quad = np.array([0, 1, 2, 0, 2, 3], np.uint32)
    buf = bytearray()
    views, accessors, meshes = [], [], []

    def add(array, target, kind):
        while len(buf) % 4:
            buf.append(0)
        views.append({"buffer": 0, "byteOffset": len(buf), "byteLength": array.nbytes, "target": target})
        buf.extend(array.tobytes())
        acc = {"bufferView": len(views) - 1, "count": int(array.size // (3 if kind == "VEC3" else 1)), "type": kind}
        if kind == "VEC3":
            acc.update(componentType=5126, min=array.min(axis=0).tolist(), max=array.max(axis=0).tolist())
        else:
            acc.update(componentType=5125)
        accessors.append(acc)
        return len(accessors) - 1

    def mesh(name, positions, indices, material):
        pa = add(positions, 34962, "VEC3")
        ia = add(indices, 34963, "SCALAR")
        meshes.append({"name": name, "primitives": [{"attributes": {"POSITION": pa}, "indices": ia, "material": material}]})
        return len(meshes) - 1

    nodes = [{"name": "Floor", "mesh": mesh("Floor", floor_p, quad, 0)},
             {"name": "Lamp", "mesh": mesh("Lamp", lamp_p, quad, 1)}]
    one = mesh("Pipe", p, idx, 0) if shared else None
    side = math.ceil(math.sqrt(copies))
    for k in range(copies):
        m = one if shared else mesh(f"Pipe {k}", p, idx, 0)
        angle = 0.1 * k
        nodes.append({"name": f"Pipe {k}", "mesh": m,
                      "translation": [3.0 * (k % side) - 1.5 * side, 0.0, 3.0 * (k // side) - 1.5 * side],
                      "rotation": [0.0, math.sin(angle / 2), 0.0, math.cos(angle / 2)]})
    doc = {
        "asset": {"version": "2.0", "generator": "twopass bench/instances.py"},
        "scene": 0,
        "scenes": [{"nodes": list(range(len(nodes)))}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": [
            {"name": "Grey", "pbrMetallicRoughness": {"baseColorFactor": [0.6, 0.6, 0.6, 1], "metallicFactor": 0}},
            {"name": "Lamp", "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1], "metallicFactor": 0},
             "emissiveFactor": [1, 1, 1]},
        ],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": len(buf)}],
    }
    js = json.dumps(doc).encode()
    js += b" " * (-len(js) % 4)
    while len(buf) % 4:
        buf.append(0)
    total = 12 + 8 + len(js) + 8 + len(buf)
    return (struct.pack("<III", 0x46546C67, 2, total) + struct.pack("<II", len(js), 0x4E4F534A) + js
            + struct.pack("<II", len(buf), 0x004E4942) + bytes(buf))


def measure(twopass, path):
    """`twopass info --json` on `path` under /usr/bin/time -v: (info, peak MiB, seconds)."""
    start = time.perf_counter()
    out = subprocess.run(["/usr/bin/time", "-v", twopass, "info", str(path), "--json"],
                         capture_output=True, text=True, check=True)
    wall = time.perf_counter() - start
    peak = next(int(l.split(":")[1]) for l in out.stderr.splitlines() if "Maximum resident" in l)
    return json.loads(out.stdout), peak / 1024.0, wall


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--twopass", required=True)
    ap.add_argument("--copies", default="1,10,100")
    ap.add_argument("--triangles", type=int, default=100_000)
    ap.add_argument("--keep", help="folder to keep the scenes in")
    args = ap.parse_args()
    folder = args.keep or tempfile.mkdtemp(prefix="twopass-instances-")
    os.makedirs(folder, exist_ok=True)
    print("| copies | scene | triangles seen | stored | mesh + trees (MiB) | peak RSS (MiB) | `info` wall (s) |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for n in [int(c) for c in args.copies.split(",")]:
        for shared in (True, False):
            path = os.path.join(folder, f"pipes-{n}-{'shared' if shared else 'copied'}.glb")
            with open(path, "wb") as f:
                f.write(glb(n, shared, args.triangles))
            info, peak, wall = measure(args.twopass, path)
            print(f"| {n} | {'instanced' if shared else 'copied'} | {info['triangles']:,} | "
                  f"{info['stored_triangles']:,} | {info['geometry_bytes'] / 2**20:.1f} | {peak:.0f} | {wall:.2f} |")
            sys.stdout.flush()


if __name__ == "__main__":
    main()
