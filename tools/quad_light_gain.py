#!/usr/bin/env python3
"""What sampling the peers' box's light as one spherical rectangle would buy: a measurement.

The box's light is a mesh of two triangles forming a 0.46 × 0.38 rectangle (MeshLightAPI).
Next-event estimation today chooses one of the two triangles (by their importance at the
receiver, `light/spatial.rs`) and samples the spherical triangle it subtends. A UsdLux RectLight
of the same corners and radiance is sampled as one spherical rectangle (Ureña et al. 2013,
`light/rect.rs`): no choice, and the 2D sample spread over the whole light. This script writes
the box with the mesh light replaced by that RectLight (the light's own reflective surface goes
with it, which adds about 1 % of red-tinted indirect light to the mesh version: the light's
material is the walls' white), renders both with each sampler over several seeds, and prints
the relative variance of one image (the seeds' spread over the pixels away from the visible
light, over the squared mean there) and the median render time (the EXR header's
`spectralRender:wallTime`, one thread).

Run with the project's venv (tools/venv.sh), from the repository root, after `cargo build
--release`:
    .venv/bin/python tools/quad_light_gain.py [--seeds 8] [--spp 32]
"""

import argparse
import os
import subprocess
import tempfile

import numpy as np
import OpenEXR

from light_mask import emitter_mask
from variance_by_depth import read_rgb

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
EXE = os.path.join(ROOT, "target", "release", "spectral-render")
STAGE = os.path.join(ROOT, "..", "shared", "peers", "cbox.usda")
# The mesh light's corners are (±0.23, 0.99, −0.18 … 0.2), its normal −Y: a RectLight (local
# −Z emitting, width along local X, height along local Y) rotated −90° about X, centred there.
RECT = """        def RectLight "light"
        {
            color3f inputs:color = (1, 0.7607168, 0.36730134)
            float inputs:intensity = 18.387
            bool inputs:normalize = 0
            float inputs:width = 0.46
            float inputs:height = 0.38
            double3 xformOp:translate = (0, 0.99, 0.01)
            float3 xformOp:rotateXYZ = (-90, 0, 0)
            uniform token[] xformOpOrder = ["xformOp:translate", "xformOp:rotateXYZ"]
        }

"""


def rect_stage(path):
    s = open(STAGE).read()
    i, j = s.index('        def Mesh "light" ('), s.index('        def Mesh "floor" (')
    with open(path, "w") as f:
        f.write(s[:i] + RECT + s[j:])


def wall_time(path):
    with OpenEXR.File(path) as f:
        return float(np.ravel(f.header()["spectralRender:wallTime"])[0])


def runs(a, tmp, stage, sampler):
    imgs, times = [], []
    for seed in range(1, a.seeds + 1):
        out = os.path.join(tmp, f"{os.path.basename(stage)}_{sampler}_{seed}.exr")
        subprocess.run([EXE, stage, "-o", out, "--spp", str(a.spp), "--resolution",
                        f"{a.res}x{a.res}", "--max-depth", "7", "--seed", str(seed),
                        "--integrator", "path", "--sampler", sampler, "--threads", "1"],
                       check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        imgs.append(read_rgb(out))
        times.append(wall_time(out))
    return np.stack(imgs), float(np.median(times))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seeds", type=int, default=8)
    ap.add_argument("--spp", type=int, default=32)
    ap.add_argument("--res", type=int, default=256)
    a = ap.parse_args()
    print("| sampler | light | relative variance of one image | vs mesh | median render s "
          "| vs mesh | mean R, G, B away from the light |")
    print("|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        rect = os.path.join(tmp, "cbox_rect.usda")
        rect_stage(rect)
        for sampler in ("zsobol", "independent"):
            got = {name: runs(a, tmp, st, sampler) for name, st in (("mesh", STAGE),
                                                                     ("rect", rect))}
            mask = emitter_mask(got["mesh"][0].mean(0)) & emitter_mask(got["rect"][0].mean(0))
            base = None
            for name, (x, t) in got.items():
                m = x.mean(0)[mask]
                v = x.var(0, ddof=1)[mask].mean() / m.mean() ** 2
                base = base or (v, t)
                rgb = ", ".join(f"{c:.4f}" for c in m.mean(0))
                print(f"| {sampler} | {name} | {v:.5f} | {v / base[0]:.3f} | {t:.2f} | "
                      f"{t / base[1]:.3f} | {rgb} |")


if __name__ == "__main__":
    main()
