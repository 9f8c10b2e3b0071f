"""Renders a twopass scene file with Mitsuba 3's path tracer into an EXR, for the tests that
compare twopass's images with a third-party renderer (crates/twopass/tests/third_party.rs).

    python3 tests/mitsuba/render.py SCENE.toml WIDTH HEIGHT SPP SEED OUT.exr

The scene is converted by crates/twopass/bench/mitsuba_scene.py (what it converts, and what it
refuses, is written there); Mitsuba's `scalar_rgb` variant renders it with the `path`
integrator (at most 64 segments, Russian roulette after the third bounce). The EXR holds the
linear RGB radiance per pixel, as twopass's renders do. Exit 1 with the converter's message
when the scene holds something that would not render the same light.
"""

import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "crates", "twopass", "bench"))


def main():
    if len(sys.argv) != 7:
        sys.exit(f"usage: {sys.argv[0]} SCENE.toml WIDTH HEIGHT SPP SEED OUT.exr")
    scene_file, width, height, spp, seed, out = sys.argv[1:]
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    from mitsuba_scene import scene_dict

    scene = mi.load_dict(scene_dict(mi, scene_file, int(width), int(height)))
    image = mi.render(scene, spp=int(spp), seed=int(seed))
    mi.Bitmap(image).write(out)


if __name__ == "__main__":
    main()
