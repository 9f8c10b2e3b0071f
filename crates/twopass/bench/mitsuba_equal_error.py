#!/usr/bin/env python3
"""twopass's default render against Mitsuba 3's path tracer at equal error, scene by scene.

For each twopass scene file given (converted by `mitsuba_scene.py` beside this file; what it
converts is written there), in one run:

1. **A converged reference** from Mitsuba's `llvm_ad_rgb` path tracer at `--reference-spp`
   (cached in `--out`), rendered as two independent halves: their difference gives the
   reference's own noise, printed with every figure. Before it is used it is checked against
   twopass's own path tracer (`render --method reference --spp --check-spp`): the mean per
   channel must agree within `--tolerance` (relative), or the scene is skipped as
   "conversion differs": an equal-error figure against a reference of another image means
   nothing.
2. **twopass**: `twopass render SCENE` with the scene's defaults (method `hybrid` unless
   `--twopass-args` says otherwise), the whole process timed (wall and CPU seconds of the
   child: parsing, BVH, solve, image, writing), its relative RMSE against the reference.
3. **Mitsuba at the same error**: `llvm_ad_rgb` renders at 1, 2, 4, ... spp (each in a fresh
   child process, after a warm-up render so the JIT's compile is not counted; images above
   `--chunk` spp are rendered in chunks of independent seeds, which the wavefront's memory
   needs) until its error is at or below twopass's; the spp that gives twopass's error is
   interpolated on log spp against log error between the last two rungs, and its render time
   linearly in spp. Mitsuba's time is `mi.render` alone (scene loading, Python start and the
   JIT excluded; wall and CPU seconds of its threads): the comparison is in Mitsuba's favour.

It reports, per scene: twopass's error, wall and CPU seconds; Mitsuba's equal-error spp and
render seconds (wall and CPU); the ratios Mitsuba / twopass (above 1: twopass is faster). On a
loaded machine the CPU ratio is the steadier figure. The
metric is the project's relative RMSE, `sqrt(mean((x - r)^2 / (r^2 + 0.01)))` over pixels and
channels; both engines are measured against the same reference, so its noise counts the same
for both (and the error it adds is printed).

Not part of the test suite (Mitsuba is not a dependency of twopass). Usage, from the repository:

    pip install mitsuba OpenEXR numpy
    cargo build --release -p twopass
    python3 crates/twopass/bench/mitsuba_equal_error.py --out /tmp/eq \
        --libllvm /usr/lib/x86_64-linux-gnu/libLLVM-19.so scenes/cornell-box.toml ROOM.toml
"""

import argparse
import json
import math
import os
import resource
import subprocess
import sys
import tempfile
import time

import numpy as np

from mitsuba_pt import read_exr, rel_rmse


def self_cpu():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def child_cpu():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def run_twopass(args, scene, extra, out):
    """(image, wall seconds, CPU seconds, summary) of one whole `twopass render` process."""
    cmd = [args.twopass, "render", scene, "--width", str(args.width), "--json", "--quiet",
           "-o", out] + extra
    cpu0, wall0 = child_cpu(), time.perf_counter()
    done = subprocess.run(cmd, capture_output=True, text=True)
    wall, cpu = time.perf_counter() - wall0, child_cpu() - cpu0
    if done.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)}: exit {done.returncode}: {done.stderr.strip()}")
    return read_exr(out), wall, cpu, json.loads(done.stdout)


def run_mitsuba(args, scene, spp, seed, out, warm=True):
    """Mitsuba's image at `spp` (rendered in a child process), its `mi.render` seconds and the
    CPU seconds of its threads meanwhile."""
    spec = {"scene": scene, "width": args.width, "spp": spp, "seed": seed, "out": out,
            "chunk": args.chunk, "warm": warm}
    env = dict(os.environ)
    if args.libllvm:
        env["DRJIT_LIBLLVM_PATH"] = args.libllvm
    cmd = [sys.executable, os.path.abspath(__file__), "--child", json.dumps(spec)]
    got = json.loads(subprocess.run(cmd, check=True, capture_output=True, text=True,
                                    env=env).stdout)
    return np.load(out), got["seconds"], got["cpu"]


def image_height(scene_file, width):
    """The height twopass gives an image `width` wide: the camera's aspect ratio kept."""
    import tomllib

    with open(scene_file, "rb") as f:
        cam = tomllib.load(f)["camera"]
    w, h = cam.get("resolution", cam.get("film_size", [1, 1]))
    return max(1, round(width * h / w))


def child(spec):
    """Renders in this process: `llvm_ad_rgb`, chunks of at most `chunk` spp, distinct seeds."""
    import drjit as dr
    import mitsuba as mi

    from mitsuba_scene import scene_dict

    mi.set_variant("llvm_ad_rgb")
    width = spec["width"]
    height = image_height(spec["scene"], width)
    scene = mi.load_dict(scene_dict(mi, spec["scene"], width, height))
    spp, chunk = spec["spp"], spec["chunk"]
    sizes = [chunk] * (spp // chunk) + ([spp % chunk] if spp % chunk else [])
    if spec["warm"]:
        np.asarray(mi.render(scene, spp=sizes[0], seed=2**31 - 1))
    total = np.zeros((height, width, 3), np.float64)
    seconds, cpu = 0.0, 0.0
    for i, n in enumerate(sizes):
        start, cpu0 = time.perf_counter(), self_cpu()
        img = np.asarray(mi.render(scene, spp=n, seed=spec["seed"] * 65536 + i), np.float32)
        seconds += time.perf_counter() - start
        cpu += self_cpu() - cpu0
        total += img[..., :3].astype(np.float64) * n
    dr.sync_thread()
    np.save(spec["out"], (total / spp).astype(np.float32))
    print(json.dumps({"seconds": seconds, "cpu": cpu}))


def reference(args, scene, tmp):
    """The cached reference of `scene` and its own relative noise."""
    stem = os.path.splitext(os.path.basename(scene))[0]
    path = os.path.join(args.out, f"{stem}-mitsuba-{args.width}-{args.reference_spp}spp.npz")
    if not os.path.exists(path):
        half = args.reference_spp // 2
        a, sa, _ = run_mitsuba(args, scene, half, 1001, os.path.join(tmp, "a.npy"), warm=False)
        b, sb, _ = run_mitsuba(args, scene, half, 2002, os.path.join(tmp, "b.npy"), warm=False)
        np.savez(path, a=a, b=b, seconds=sa + sb)
    z = np.load(path)
    ref = 0.5 * (z["a"] + z["b"])
    # The halves' difference has twice a half's variance; the mean has half of it.
    noise = rel_rmse(z["a"], z["b"]) / 2.0
    return ref, noise


def equal_error(args, scene, target, tmp):
    """Mitsuba's rungs [(spp, error, seconds, CPU seconds)] until its error reaches `target`,
    and the interpolated (spp, seconds, CPU seconds) at `target` (None if `--max-spp` is not
    enough)."""
    rungs = []
    spp = 1
    while spp <= args.max_spp:
        img, sec, cpu = run_mitsuba(args, scene, spp, 7 + spp, os.path.join(tmp, "m.npy"))
        rungs.append((spp, rel_rmse(img, args.ref), sec, cpu))
        if rungs[-1][1] <= target:
            break
        spp *= 2
    if rungs[-1][1] > target:
        return rungs, None
    if len(rungs) == 1:
        return rungs, (rungs[0][0], rungs[0][2], rungs[0][3])
    (s0, e0, t0, c0), (s1, e1, t1, c1) = rungs[-2], rungs[-1]
    f = (math.log(e0) - math.log(target)) / max(math.log(e0) - math.log(e1), 1e-9)
    s = math.exp(math.log(s0) + f * (math.log(s1) - math.log(s0)))
    w = (s - s0) / (s1 - s0)
    return rungs, (s, t0 + w * (t1 - t0), c0 + w * (c1 - c0))


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("scenes", nargs="+", help="twopass scene files")
    p.add_argument("--twopass", default="target/release/twopass", help="the twopass binary")
    p.add_argument("--twopass-args", default="", help="extra `twopass render` arguments")
    p.add_argument("--width", type=int, default=256, help="image width (square scenes)")
    p.add_argument("--reference-spp", type=int, default=4096, help="the reference's spp")
    p.add_argument("--check-spp", type=int, default=64, help="twopass path tracer's check spp")
    p.add_argument("--tolerance", type=float, default=0.02, help="allowed relative mean error")
    p.add_argument("--max-spp", type=int, default=2048, help="Mitsuba's highest rung")
    p.add_argument("--chunk", type=int, default=64, help="Mitsuba's spp per wavefront")
    p.add_argument("--out", required=True, help="folder for references and the JSON report")
    p.add_argument("--references-only", action="store_true",
                   help="render the missing references and stop (they can take long)")
    p.add_argument("--libllvm", help="libLLVM for Dr.Jit (DRJIT_LIBLLVM_PATH), newer than 15")
    args = p.parse_args()
    os.makedirs(args.out, exist_ok=True)
    extra = args.twopass_args.split()
    rows = []
    with tempfile.TemporaryDirectory(prefix="twopass-eq-") as tmp:
        for scene in args.scenes:
            _, noise = reference(args, scene, tmp)
            print(f"{scene}: reference of {args.reference_spp} spp, noise {100 * noise:.2f} %",
                  flush=True)
        if args.references_only:
            return 0
        for scene in args.scenes:
            ref, noise = reference(args, scene, tmp)
            args.ref = ref
            out = os.path.join(tmp, "tp.exr")
            check, _, _, _ = run_twopass(
                args, scene, ["--method", "reference", "--spp", str(args.check_spp)], out)
            rel = check.astype(np.float64).mean(axis=(0, 1)) / ref.astype(np.float64).mean(
                axis=(0, 1)) - 1.0
            row = {"scene": scene, "reference_noise": noise, "check_mean_rel": rel.tolist(),
                   "check_rel_rmse": rel_rmse(check, ref)}
            print(f"{scene}: reference noise {100 * noise:.2f} %; twopass path tracer "
                  f"{args.check_spp} spp mean {np.round(100 * rel, 2).tolist()} %, "
                  f"relative RMSE {100 * row['check_rel_rmse']:.2f} %", flush=True)
            if np.any(np.abs(rel) > args.tolerance):
                print(f"{scene}: conversion differs; skipped", flush=True)
                row["skipped"] = "conversion differs"
                rows.append(row)
                continue
            img, wall, cpu, summary = run_twopass(args, scene, extra, out)
            err = rel_rmse(img, ref)
            rungs, at = equal_error(args, scene, err, tmp)
            row.update({"twopass_args": extra, "twopass_rel_rmse": err, "twopass_wall_s": wall,
                        "twopass_cpu_s": cpu, "method": summary.get("method"),
                        "mitsuba_rungs": rungs})
            if at is None:
                print(f"{scene}: twopass {100 * err:.2f} % in {wall:.2f} s wall ({cpu:.2f} s "
                      f"CPU); Mitsuba above it at {args.max_spp} spp", flush=True)
            else:
                row.update({"mitsuba_spp": at[0], "mitsuba_s": at[1], "mitsuba_cpu_s": at[2],
                            "ratio": at[1] / wall, "cpu_ratio": at[2] / cpu})
                print(f"{scene}: twopass {100 * err:.2f} % in {wall:.2f} s wall ({cpu:.2f} s "
                      f"CPU); Mitsuba {at[0]:.0f} spp in {at[1]:.2f} s ({at[2]:.2f} s CPU): "
                      f"Mitsuba / twopass {at[1] / wall:.2f}x wall, {at[2] / cpu:.2f}x CPU",
                      flush=True)
            rows.append(row)
    with open(os.path.join(args.out, "equal-error.json"), "w") as f:
        json.dump({"width": args.width, "reference_spp": args.reference_spp,
                   "load_average": os.getloadavg(), "rows": rows}, f, indent=2)
    return 0


if __name__ == "__main__":
    if len(sys.argv) == 3 and sys.argv[1] == "--child":
        child(json.loads(sys.argv[2]))
        sys.exit(0)
    sys.exit(main())
