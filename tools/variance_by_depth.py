#!/usr/bin/env python3
"""Where the path tracer's variance per sample comes from, by path length and by colour.

Renders a stage with `--max-depth D` for several D and seeds (one thread, the same seeds for
every D), and prints for each sampler and D, over the pixels that do not see the light (a pixel
brighter than 5 in any channel, grown by 2 px, as tools/compare_mitsuba.py masks it):

- var × spp: the variance of one image per pixel, averaged over the pixels (the unbiased
  estimate from the seeds' spread, which needs no reference), times spp: the variance per
  sample. Given absolute and relative to the squared mean of the D = max image, so that the
  rows add up: each row's increment over the one above is what paths of those lengths add
  (their covariance with the shorter paths included);
- the same for luminance Y = 0.2126 R + 0.7152 G + 0.0722 B (Rec. 709 / sRGB primaries);
- chroma: the variance of RGB − Y · (mean RGB / mean Y) per pixel, the part of the noise that
  changes colour and not brightness (wavelength sampling's share, mostly).

Run with the project's venv (tools/venv.sh), from the repository root, after `cargo build
--release`:
    .venv/bin/python tools/variance_by_depth.py ../shared/peers/cbox.usda --depths 1,2,3,7
"""

import argparse
import os
import subprocess
import tempfile

import numpy as np
import OpenEXR

from light_mask import emitter_mask

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
EXE = os.path.join(ROOT, "target", "release", "spectral-render")
Y_WEIGHTS = np.array([0.2126, 0.7152, 0.0722])


def read_rgb(path):
    with OpenEXR.File(path) as f:
        ch = f.channels()
        for name in ("RGB", "RGBA"):
            if name in ch:
                return np.array(ch[name].pixels, dtype=np.float64)[..., :3]
        return np.stack([np.array(ch[c].pixels, np.float64) for c in "RGB"], -1)


def render(a, tmp, depth, sampler, seed):
    out = os.path.join(tmp, f"d{depth}_{sampler}_{seed}.exr")
    subprocess.run([EXE, a.stage, "-o", out, "--spp", str(a.spp), "--resolution",
                    f"{a.res}x{a.res}", "--max-depth", str(depth), "--seed", str(seed),
                    "--integrator", "path", "--sampler", sampler, "--threads", "1"],
                   check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return read_rgb(out)


def variances(imgs, mask, spp):
    """(RGB, Y, chroma) variance of one image per pixel, mean over mask, times spp."""
    var_rgb = imgs.var(0, ddof=1)[mask].mean() * spp
    y = imgs @ Y_WEIGHTS
    var_y = y.var(0, ddof=1)[mask].mean() * spp
    tint = imgs.mean(0) / np.maximum(y.mean(0), 1e-12)[..., None]
    chroma = imgs - y[..., None] * tint[None]
    var_c = chroma.var(0, ddof=1)[mask].mean() * spp
    return var_rgb, var_y, var_c


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("stage")
    ap.add_argument("--depths", default="1,2,3,7")
    ap.add_argument("--samplers", default="independent,zsobol")
    ap.add_argument("--seeds", type=int, default=8)
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--res", type=int, default=128)
    a = ap.parse_args()
    depths = [int(d) for d in a.depths.split(",")]
    with tempfile.TemporaryDirectory() as tmp:
        mask = None
        for sampler in a.samplers.split(","):
            rows = []
            for d in depths:
                imgs = np.stack([render(a, tmp, d, sampler, s) for s in range(1, a.seeds + 1)])
                if mask is None:
                    mask = emitter_mask(imgs.mean(0)) if d == max(depths) else None
                rows.append((d, imgs))
            if mask is None:
                mask = emitter_mask(rows[-1][1].mean(0))
            full = rows[-1][1].mean(0)
            m2 = full[mask].mean() ** 2
            my2 = (full @ Y_WEIGHTS)[mask].mean() ** 2
            print(f"{a.stage}, {sampler}, {a.res}², {a.spp} spp, {a.seeds} seeds, "
                  f"{int(mask.sum())} of {mask.size} pixels")
            print("depth | var×spp RGB (/mean²) | luminance (/mean_Y²) | chroma (/mean²) | "
                  "share of RGB")
            for d, imgs in rows:
                v, vy, vc = variances(imgs, mask, a.spp)
                print(f"{d:5d} | {v:.3e} ({v / m2:.3f}) | {vy:.3e} ({vy / my2:.3f}) | "
                      f"{vc:.3e} ({vc / m2:.3f}) | "
                      f"{v / (variances(rows[-1][1], mask, a.spp)[0]):.3f}")


if __name__ == "__main__":
    main()
