#!/usr/bin/env python3
"""twopass's ray queries against Embree 4 on the same scene and the same rays, in one run.

`twopass bench rays --export DIR` writes the scene's triangles, its three ray batches exactly as
twopass casts them (coherent camera rays, incoherent rays from surfaces, shadow segments to the
lights) and twopass's answers. This script casts the same rays with Embree 4 (the `embreex`
package from PyPI: Embree's single-ray `rtcIntersect1` / `rtcOccluded1`, called from a Cython
loop) and alternates the two engines for `--rounds` rounds, so their ratio is measured under the
same machine load. It reports, per query kind, millions of rays per second on one thread and on
`--threads` processes (each with its own copy of the scene, casting its share of the batch), the
ratio twopass / Embree, build times, and how far the answers agree. twopass is measured twice:
one ray at a time (`Accel::closest`, `Accel::any_hit`) and through the many-ray calls, the
rows marked `many` (`Accel::closest_many`,
`Accel::any_hit_many`: eight rays walked in turn, what each reads next prefetched, on trees
over 1 MiB, for batches that are not coherent; coherent ones such as the camera rays are
walked eight at a time as one packet, each node tested once for the packet, each ray only
at the leaves).
Embree is measured one ray at a time only: embreex binds `rtcIntersect1` / `rtcOccluded1` and none of
Embree 4's packet calls (`rtcIntersect4/8/16`), and Embree 4 has no stream API.

Embree's figures include embreex's per-ray cost of the Python-side loop (filling a ray from numpy
arrays, writing the answer back); the script measures it on a one-triangle scene that every ray
misses and prints it, so a reader can see how much of Embree's time it is.

Not part of the test suite (Embree is not a dependency of twopass). Usage, from the repository:

    pip install embreex numpy
    cargo build --release
    python3 crates/twopass/bench/embree_rays.py --generate 100000
"""

import argparse
import json
import multiprocessing as mp
import os
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

KINDS = ("camera", "incoherent", "occlusion")


def load(directory):
    """The exported scene, batches and twopass's answers."""
    with open(os.path.join(directory, "rays.json")) as f:
        manifest = json.load(f)
    positions = np.fromfile(os.path.join(directory, "positions.f32"), "<f4").reshape(-1, 3)
    triangles = np.fromfile(os.path.join(directory, "triangles.u32"), "<u4").reshape(-1, 3)
    batches = {}
    for b in manifest["batches"]:
        name = b["name"]
        rays = np.fromfile(os.path.join(directory, name + ".rays"), "<f4").reshape(-1, 7)
        origins, directions, t_max = rays[:, 0:3], rays[:, 3:6], rays[:, 6]
        # twopass accepts hits with t > 0; Embree with t >= tnear, and embreex fixes tnear at
        # 0. A ray leaving a plane that f32 represents exactly (a wall at y = 0) needs no
        # offset in twopass, and Embree would report its own surface at t = 0. So Embree's
        # rays start a millionth of the scene's size further along (the `t_start` below,
        # added back to its hit distances).
        diagonal = float(np.linalg.norm(positions.max(axis=0) - positions.min(axis=0)))
        t_start = (1e-6 * diagonal / np.linalg.norm(directions, axis=1)).astype(np.float32)
        batches[name] = {
            "query": b["query"],
            "origins": np.ascontiguousarray(origins + directions * t_start[:, None]),
            "directions": np.ascontiguousarray(directions),
            "t_max": np.ascontiguousarray(t_max - t_start),
            "t_start": t_start,
            "length": np.linalg.norm(directions, axis=1),
            "diagonal": diagonal,
            "ids": np.fromfile(os.path.join(directory, name + ".ids"), "<i4"),
            "t": np.fromfile(os.path.join(directory, name + ".t"), "<f4"),
        }
    return positions, triangles, batches


def embree_scene(positions, triangles):
    from embreex import rtcore_scene
    from embreex.mesh_construction import TriangleMesh

    scene = rtcore_scene.EmbreeScene()
    TriangleMesh(scene, positions.astype(np.float32), triangles.astype(np.int32))
    return scene


def cast(scene, batch, lo=0, hi=None, output=None):
    """One pass over rays lo..hi; returns embreex's answer (closest: primID, or with `output`
    a dict with primID and tfar; any hit: -1 for clear)."""
    sl = slice(lo, hi)
    query = "INTERSECT" if batch["query"] == "closest" else "OCCLUDED"
    return scene.run(
        # embreex writes each ray's final tfar into `dists`: give it a copy.
        batch["origins"][sl], batch["directions"][sl], dists=batch["t_max"][sl].copy(), query=query,
        output=output,
    )


def measure(scene, batch, seconds):
    """Rays per second on this thread, casting the whole batch repeatedly for `seconds`."""
    n = len(batch["t_max"])
    cast(scene, batch)  # warm-up
    start = time.perf_counter()
    passes = 0
    while passes == 0 or time.perf_counter() - start < seconds:
        cast(scene, batch)
        passes += 1
    return passes * n / (time.perf_counter() - start)


def worker(directory, kind, part, parts, passes, barrier, out):
    positions, triangles, batches = load(directory)
    scene = embree_scene(positions, triangles)
    batch = batches[kind]
    n = len(batch["t_max"])
    lo, hi = n * part // parts, n * (part + 1) // parts
    cast(scene, batch, lo, hi)  # warm-up
    barrier.wait()
    start = time.perf_counter()
    for _ in range(passes):
        cast(scene, batch, lo, hi)
    out.put(time.perf_counter() - start)


def measure_parallel(directory, kind, n, parts, rate_1, seconds):
    """Rays per second over `parts` processes, each with its own scene and share of the rays."""
    passes = max(1, round(seconds * rate_1 / n))
    ctx = mp.get_context("spawn")
    barrier, out = ctx.Barrier(parts), ctx.Queue()
    procs = [
        ctx.Process(target=worker, args=(directory, kind, p, parts, passes, barrier, out))
        for p in range(parts)
    ]
    for p in procs:
        p.start()
    times = [out.get() for _ in procs]
    for p in procs:
        p.join()
    return passes * n / max(times)


def agreement(batch, answer):
    ours = batch["ids"]
    if batch["query"] == "closest":
        embree = answer["primID"]
        hit_disagree = int(np.sum((ours >= 0) != (embree >= 0)))
        both = (ours >= 0) & (embree >= 0)
        t_ours, t_embree = batch["t"][both], (answer["tfar"] + batch["t_start"])[both]
        # Distance between the two hit points along the ray, in units of the scene's size.
        apart = np.abs(t_ours - t_embree) * batch["length"][both] / batch["diagonal"]
        return {
            "hit_or_miss_disagree": hit_disagree,
            "hits_apart_over_1e-5_of_scene": int(np.sum(apart > 1e-5)),
            "other_triangle": int(np.sum(ours[both] != embree[both])),
        }
    blocked = answer != -1
    return {"hit_or_miss_disagree": int(np.sum((ours == 1) != blocked))}


def python_overhead(batch, seconds):
    """Seconds per ray embreex spends outside Embree: rays that all miss a one-triangle scene."""
    far = np.array([[1e9, 1e9, 1e9], [1e9 + 1, 1e9, 1e9], [1e9, 1e9 + 1, 1e9]], np.float32)
    scene = embree_scene(far, np.array([[0, 1, 2]], np.uint32))
    return 1.0 / measure(scene, batch, seconds)


def twopass(args, directory, export):
    cmd = [args.twopass, "bench", "rays", "--json", "--quiet", "--seconds", str(args.seconds)]
    cmd += ["--generate", str(args.generate)] if args.scene is None else [args.scene]
    if export:
        cmd += ["--export", directory]
    env = dict(os.environ, RAYON_NUM_THREADS=str(args.threads))
    report = json.loads(subprocess.run(cmd, check=True, capture_output=True, env=env).stdout)
    rows = {r["query"].split()[0]: r for r in report["rows"]}
    return report, rows


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--twopass", default="target/release/twopass", help="the twopass binary")
    p.add_argument("--generate", type=int, default=100000, help="triangles of the generated room")
    p.add_argument("--scene", help="a scene file instead of --generate")
    p.add_argument("--rounds", type=int, default=2, help="alternating rounds per engine")
    p.add_argument("--seconds", type=float, default=1.0, help="measuring time per query, s")
    p.add_argument("--threads", type=int, default=os.cpu_count(), help="threads / processes")
    p.add_argument("--json", help="also write the results here")
    args = p.parse_args()

    with tempfile.TemporaryDirectory(prefix="twopass-rays-") as directory:
        report, _ = twopass(args, directory, export=True)
        positions, triangles, batches = load(directory)
        start = time.perf_counter()
        scene = embree_scene(positions, triangles)
        # embreex commits the scene on its first query.
        cast(scene, batches["camera"], 0, 1)
        embree_build = time.perf_counter() - start
        results = {k: {"twopass_1": [], "twopass_n": [], "many_1": [], "many_n": [],
                       "embree_1": [], "embree_n": []} for k in KINDS}
        for _ in range(args.rounds):
            _, rows = twopass(args, directory, export=False)
            for k in KINDS:
                results[k]["twopass_1"].append(rows[k]["mrays_1"])
                results[k]["twopass_n"].append(rows[k]["mrays_n"])
                results[k]["many_1"].append(rows[k]["many_mrays_1"])
                results[k]["many_n"].append(rows[k]["many_mrays_n"])
            for k in KINDS:
                rate = measure(scene, batches[k], args.seconds)
                results[k]["embree_1"].append(rate / 1e6)
                n = len(batches[k]["t_max"])
                par = measure_parallel(directory, k, n, args.threads, rate, args.seconds)
                results[k]["embree_n"].append(par / 1e6)
        agree = {k: agreement(
            batches[k],
            cast(scene, batches[k], output=1 if batches[k]["query"] == "closest" else None),
        ) for k in KINDS}
        overhead = {k: python_overhead(batches[k], args.seconds) for k in KINDS}

    print(f"scene: {report['scene']}, {report['triangles']} triangles; {args.threads} threads; "
          f"{args.rounds} alternating rounds")
    print(f"build: twopass {report['bvh_build_ms']:.1f} ms (median of 5), "
          f"Embree {1e3 * embree_build:.1f} ms (with embreex's scene setup)")
    print(f"{'query':<11} {'walk':<11} {'rays':>8} {'thr':>3} {'twopass Mrays/s':>18} "
          f"{'Embree Mrays/s':>16} {'ratio':>11} {'median':>6}  embreex ns/ray outside Embree")
    summary = []
    for k in KINDS:
        r = results[k]
        for walk, prefix in (("single", "twopass"), ("many", "many")):
            for t, suffix in (("1", "_1"), (str(args.threads), "_n")):
                ours, theirs = r[prefix + suffix], r["embree" + suffix]
                ratios = [x / y for x, y in zip(ours, theirs)]
                print(f"{k:<11} {walk:<11} {len(batches[k]['t_max']):>8} {t:>3} "
                      f"{min(ours):>8.2f}-{max(ours):<8.2f} {min(theirs):>7.2f}-{max(theirs):<7.2f} "
                      f"{min(ratios):>5.2f}-{max(ratios):<4.2f}x {statistics.median(ratios):>5.2f}x  "
                      f"{1e9 * overhead[k]:.0f}")
                summary.append({"query": k, "walk": walk, "threads": int(t), "twopass_mrays": ours,
                                "embree_mrays": theirs, "ratios": ratios})
    for k in KINDS:
        print(f"agreement {k}: {agree[k]}")
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"scene": report["scene"], "triangles": report["triangles"],
                       "twopass_build_ms": report["bvh_build_ms"],
                       "embree_build_ms": 1e3 * embree_build, "rows": summary,
                       "agreement": agree,
                       "embreex_overhead_ns": {k: 1e9 * v for k, v in overhead.items()}}, f, indent=2)
    return 0


if __name__ == "__main__":
    sys.exit(main())
