#!/usr/bin/env python3
"""twopass's reference path tracer against Mitsuba 3's `path` integrator, per sample, in one run.

The script builds the scene of a twopass scene file (default `scenes/cornell-box.toml`) in
Mitsuba 3 with `mi.load_dict`, converted by `mitsuba_scene.py` beside it (shapes, materials,
emitters and camera: what it converts and how is written there), and renders it with the `path`
integrator with twopass's path length settings: at most 64 segments (`max_depth` 64),
Russian roulette after the third bounce (`rr_depth` 3). Both are unidirectional path tracers with
next-event estimation and MIS with the power heuristic; twopass survives roulette with
max(throughput) capped at 1, Mitsuba caps it at 0.95. Mitsuba's wheel ships Embree 3, which both
its CPU variants trace rays with; twopass uses its own BVH.

It first checks the conversion: Mitsuba's image at `--check-spp` samples against a converged
reference image (`--reference`: an EXR, or the `.npz` that `mitsuba_equal_error.py --out DIR
--references-only` caches in DIR): the mean per channel must agree within
`--tolerance` (relative), or the script stops before timing anything. It then renders, at the same
resolution and `--spp`, twopass (`twopass render --method reference --json`, its `render_seconds`:
the render alone, without parsing the scene, building the BVH or writing the image) and Mitsuba
(`mi.render` alone, timed after a warm-up render; scene loading excluded), alternating the engines
for `--rounds` rounds on each thread count of `--threads`, so their ratio is measured under the
same machine load. It reports camera samples per second per engine (ranges over rounds), the ratio
twopass / Mitsuba per round, and each engine's relative RMSE against the reference at equal spp,
`sqrt(mean((x - r)^2 / (r^2 + 0.01)))` over pixels and channels, so that "per sample" compares
samples of equal quality.

What is not measured: twopass's time includes its thread pool's tiling and the film; Mitsuba's
includes its block-based film and the development of the image into a tensor. Mitsuba's thread
count is set with `dr.set_thread_count`. The machine's load average is printed: with other work
on the cores, figures on several threads measure what the engines got, not how they scale.

With `--llvm` the `llvm_ad_rgb` variant (wavefront: the whole image's samples as SIMD arrays, JIT
compiled) is timed too, in each round, in a child process that loads the scene, renders once to
compile (cached on disk after the first run) and times a second render; its figures are wavefront
against twopass's one path at a time, not the same algorithm shape. Dr.Jit 1.5 needs a libLLVM
newer than 15 (LLVM 15 aborts on `fminimum`): `--libllvm` points it at one (e.g. Debian's
`libllvm19`). Both Mitsuba variants render in RGB, like twopass.

Not part of the test suite (Mitsuba is not a dependency of twopass). Usage, from the repository:

    pip install mitsuba OpenEXR numpy
    cargo build --release -p twopass
    python3 crates/twopass/bench/mitsuba_pt.py --reference REF.exr --spp 16 --rounds 3 \
        --llvm --libllvm /usr/lib/x86_64-linux-gnu/libLLVM-19.so
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

from mitsuba_scene import scene_dict


def read_exr(path):
    """An RGB EXR as a float32 array (height, width, 3)."""
    import OpenEXR

    with OpenEXR.File(path) as f:
        channels = f.parts[0].channels
        if "RGB" in channels:
            return np.asarray(channels["RGB"].pixels, np.float32)
        if "RGBA" in channels:
            # twopass's plain render EXR (R, G, B and A = 1), which the binding groups.
            return np.asarray(channels["RGBA"].pixels, np.float32)[..., :3]
        return np.stack([np.asarray(channels[c].pixels, np.float32) for c in "RGB"], axis=-1)


def read_reference(path):
    """The converged reference: an RGB EXR, or the `.npz` that `mitsuba_equal_error.py` caches
    (the mean of its two halves)."""
    if path.endswith(".npz"):
        z = np.load(path)
        return (0.5 * (z["a"].astype(np.float64) + z["b"])).astype(np.float32)
    return read_exr(path)


def rel_rmse(x, r):
    """The project's error metric: relative RMSE over all pixels and channels."""
    x, r = x.astype(np.float64), r.astype(np.float64)
    return float(np.sqrt(np.mean((x - r) ** 2 / (r * r + 0.01))))


class Mitsuba:
    """A Mitsuba scene in one variant, ready to render."""

    def __init__(self, variant, scene_file, width, height):
        import drjit as dr
        import mitsuba as mi

        mi.set_variant(variant)
        self.mi, self.dr, self.variant = mi, dr, variant
        start = time.perf_counter()
        self.scene = mi.load_dict(scene_dict(mi, scene_file, width, height))
        self.load_seconds = time.perf_counter() - start

    def render(self, spp, seed, threads=None):
        """(image as (h, w, 3) float32, seconds of `mi.render` alone)."""
        if threads is not None:
            self.dr.set_thread_count(threads)
        start = time.perf_counter()
        img = self.mi.render(self.scene, spp=spp, seed=seed)
        img = np.asarray(img, np.float32)  # forces evaluation (llvm variants are lazy)
        return img[..., :3], time.perf_counter() - start


def twopass(args, spp, seed, threads, out):
    cmd = [args.twopass, "render", args.scene, "--method", "reference", "--spp", str(spp),
           "--width", str(args.width), "--seed", str(seed), "--json", "--quiet", "-o", out]
    if threads is not None:
        cmd += ["--threads", str(threads)]
    report = json.loads(subprocess.run(cmd, check=True, capture_output=True).stdout)
    return read_exr(out), report["render_seconds"]


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--twopass", default="target/release/twopass", help="the twopass binary")
    p.add_argument("--scene", default="scenes/cornell-box.toml", help="twopass scene file")
    p.add_argument("--reference", required=True,
                   help="a converged image: an EXR, or mitsuba_equal_error.py's cached .npz")
    p.add_argument("--width", type=int, default=256, help="image width (square scenes)")
    p.add_argument("--spp", type=int, default=16, help="samples per pixel of the timed renders")
    p.add_argument("--check-spp", type=int, default=1024, help="spp of Mitsuba's check image")
    p.add_argument("--tolerance", type=float, default=0.01, help="allowed relative mean error")
    p.add_argument("--rounds", type=int, default=3, help="alternating rounds per thread count")
    p.add_argument("--threads", default=f"1,{os.cpu_count()}", help="thread counts, e.g. 1,2")
    p.add_argument("--llvm", action="store_true", help="also time the llvm_ad_rgb variant")
    p.add_argument("--libllvm", help="libLLVM for Dr.Jit (DRJIT_LIBLLVM_PATH), e.g. "
                   "/usr/lib/x86_64-linux-gnu/libLLVM-19.so: Dr.Jit 1.5 needs LLVM newer than 15")
    p.add_argument("--json", help="also write the results here")
    args = p.parse_args()

    ref = read_reference(args.reference)
    height = ref.shape[0] * args.width // ref.shape[1]
    if ref.shape[1] != args.width:
        raise SystemExit(f"the reference is {ref.shape[1]} pixels wide, not {args.width}")
    threads = [int(t) for t in args.threads.split(",")]

    # scalar_rgb renders in this process; llvm_ad_rgb in a child per round (llvm_round).
    mts = Mitsuba("scalar_rgb", args.scene, args.width, height)
    check, check_s = mts.render(args.check_spp, seed=12345)
    ref_mean = ref.astype(np.float64).mean(axis=(0, 1))
    mts_mean = check.astype(np.float64).mean(axis=(0, 1))
    rel = mts_mean / ref_mean - 1.0
    print(f"check: Mitsuba {args.check_spp} spp mean {np.round(mts_mean, 5).tolist()} against the "
          f"reference's {np.round(ref_mean, 5).tolist()}: {np.round(100 * rel, 3).tolist()} %; "
          f"relative RMSE {rel_rmse(check, ref):.4f} ({check_s:.1f} s)")
    if np.any(np.abs(rel) > args.tolerance):
        raise SystemExit("the Mitsuba scene does not match the reference: fix the conversion")

    load_before = os.getloadavg()[0]
    results = {}
    with tempfile.TemporaryDirectory(prefix="twopass-pt-") as tmp:
        out = os.path.join(tmp, "tp.exr")
        twopass(args, args.spp, 0, threads[0], out)  # warm the file cache
        mts.render(args.spp, 0, threads[0])  # warm-up
        samples = args.width * height * args.spp
        for t in threads:
            row = {"twopass": [], "mitsuba": [], "twopass_err": [], "mitsuba_err": [],
                   "llvm": [], "llvm_err": [], "llvm_first_s": []}
            for r in range(args.rounds):
                seed = 1 + r
                img, sec = twopass(args, args.spp, seed, t, out)
                row["twopass"].append(samples / sec)
                row["twopass_err"].append(rel_rmse(img, ref))
                img, sec = mts.render(args.spp, seed, t)
                row["mitsuba"].append(samples / sec)
                row["mitsuba_err"].append(rel_rmse(img, ref))
                if args.llvm:
                    rate, err, first = llvm_round(args, t, height, seed)
                    row["llvm"].append(rate)
                    row["llvm_err"].append(err)
                    row["llvm_first_s"].append(first)
            results[t] = row

    print(f"scene {args.scene}, {args.width} x {height}, {args.spp} spp, {args.rounds} "
          f"alternating rounds; Mitsuba {mts.mi.__version__} scene load {mts.load_seconds:.2f} s; "
          f"machine load average {load_before:.2f} before, {os.getloadavg()[0]:.2f} after "
          f"({os.cpu_count()} cores)")
    print(f"{'thr':>3} {'twopass Msamples/s':>19} {'Mitsuba scalar':>16} {'ratio tp/mts':>13} "
          f"{'relRMSE tp':>12} {'relRMSE mts':>12}")
    summary = []
    for t, row in results.items():
        tp, mt = row["twopass"], row["mitsuba"]
        ratios = [a / b for a, b in zip(tp, mt)]
        print(f"{t:>3} {min(tp) / 1e6:>9.3f}-{max(tp) / 1e6:<9.3f} {min(mt) / 1e6:>7.3f}-"
              f"{max(mt) / 1e6:<8.3f} {min(ratios):>6.2f}-{max(ratios):<6.2f} "
              f"{np.mean(row['twopass_err']):>12.4f} {np.mean(row['mitsuba_err']):>12.4f}")
        summary.append({"threads": t, "variant": "scalar_rgb", "twopass_samples_per_s": tp,
                        "mitsuba_samples_per_s": mt, "ratios": ratios,
                        "twopass_rel_rmse": row["twopass_err"],
                        "mitsuba_rel_rmse": row["mitsuba_err"]})
    for t, row in results.items():
        if not row["llvm"]:
            continue
        tp, mt = row["twopass"], row["llvm"]
        ratios = [a / b for a, b in zip(tp, mt)]
        print(f"{t:>3} {'':>19} {'Mitsuba llvm':>16} {'ratio tp/llvm':>13} {'':>12} "
              f"{'relRMSE llvm':>12}")
        print(f"{t:>3} {'':>19} {min(mt) / 1e6:>7.3f}-{max(mt) / 1e6:<8.3f} "
              f"{min(ratios):>6.2f}-{max(ratios):<6.2f} {'':>12} {np.mean(row['llvm_err']):>12.4f}"
              f"   (warm-up render incl. compilation {min(row['llvm_first_s']):.2f}-"
              f"{max(row['llvm_first_s']):.2f} s)")
        summary.append({"threads": t, "variant": "llvm_ad_rgb", "mitsuba_samples_per_s": mt,
                        "ratios": ratios, "mitsuba_rel_rmse": row["llvm_err"],
                        "warm_up_seconds": row["llvm_first_s"]})
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"scene": args.scene, "width": args.width, "height": height,
                       "spp": args.spp, "check_mean_rel": rel.tolist(),
                       "check_rel_rmse": rel_rmse(check, ref), "rows": summary}, f, indent=2)
    return 0


def llvm_round(args, threads, height, seed):
    """One timed `llvm_ad_rgb` render (samples/s, relative RMSE, seconds of the warm-up render)
    in a child process: Mitsuba holds one variant per process for its plugins, and a child
    keeps the JIT's thread pool apart from the scalar renders'."""
    spec = {"scene": args.scene, "width": args.width, "height": height, "spp": args.spp,
            "seed": seed, "threads": threads, "reference": args.reference}
    env = dict(os.environ)
    if args.libllvm:
        env["DRJIT_LIBLLVM_PATH"] = args.libllvm
    cmd = [sys.executable, __file__, "--llvm-child", json.dumps(spec)]
    got = json.loads(subprocess.run(cmd, check=True, capture_output=True, text=True,
                                    env=env).stdout)
    return got["rate"], got["err"], got["first_s"]


def llvm_child(spec):
    ref = read_reference(spec["reference"])
    mts = Mitsuba("llvm_ad_rgb", spec["scene"], spec["width"], spec["height"])
    samples = spec["width"] * spec["height"] * spec["spp"]
    _, first = mts.render(spec["spp"], 0, spec["threads"])
    img, sec = mts.render(spec["spp"], spec["seed"], spec["threads"])
    print(json.dumps({"rate": samples / sec, "err": rel_rmse(img, ref), "first_s": first}))


if __name__ == "__main__":
    if len(sys.argv) == 3 and sys.argv[1] == "--llvm-child":
        llvm_child(json.loads(sys.argv[2]))
        sys.exit(0)
    sys.exit(main())
