#!/usr/bin/env python3
"""Cornell box agreement with Mitsuba 3 (an outside reference nobody here wrote).

Renders ../shared/peers/cbox.usda with spectral-render and Mitsuba 3's `llvm_ad_spectral` (or
another variant) at the same resolution, sample count and depth (our --max-depth 7 = Mitsuba
max_depth 8), then reports the mean ratio per channel and the relative RMSE excluding the
directly visible emitter (±2 px), with each image's own noise estimated from two seeds, so that
what is left is the systematic difference.

Run with the peers venv (../shared/peers/README.md):
    ~/peers/venv/bin/python tools/compare_mitsuba.py [--spp 1024] [--res 256] [--variant llvm_ad_spectral]
Writes nothing in the repository (images go to a temp dir).
"""
import argparse
import os
import subprocess
import sys
import tempfile

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PEERS = os.path.join(ROOT, "..", "shared", "peers")
sys.path.insert(0, PEERS)
import common  # noqa: E402  (the peers' helpers: cbox_dict, read_exr)
from light_mask import emitter_mask  # noqa: E402,F401  (equal_error.py imports it from here)


def ours(spp, res, seed, out):
    exe = os.path.join(ROOT, "target", "release", "spectral-render")
    subprocess.run(["cargo", "build", "--release", "--quiet"], cwd=ROOT, check=True)
    subprocess.run([exe, os.path.join(PEERS, "cbox.usda"), "-o", out, "--spp", str(spp),
                    "--resolution", f"{res}x{res}", "--max-depth", "7", "--seed", str(seed)],
                   check=True, stderr=subprocess.DEVNULL)
    return common.read_exr(out)


def mitsuba(variant, spp, res, seed):
    import mitsuba as mi
    mi.set_variant(variant)
    scene = mi.load_dict(common.cbox_dict(mi, res, spp, seed, 8))
    return np.array(mi.render(scene, spp=spp, seed=seed), dtype=np.float64)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--spp", type=int, default=1024)
    ap.add_argument("--res", type=int, default=256)
    ap.add_argument("--variant", default="llvm_ad_spectral")
    a = ap.parse_args()
    tmp = tempfile.mkdtemp()
    o = [ours(a.spp, a.res, s, os.path.join(tmp, f"o{s}.exr")) for s in (1, 2)]
    m = [mitsuba(a.variant, a.spp, a.res, s) for s in (1, 2)]
    mask = emitter_mask(m[0]) & emitter_mask(o[0])
    om, mm = (o[0] + o[1]) / 2, (m[0] + m[1]) / 2
    ref_mean = mm[mask].mean()
    # Noise of each averaged image: half the RMS difference of its two seeds.
    noise = lambda pair: np.sqrt(np.mean((pair[0] - pair[1])[mask] ** 2)) / 2
    raw = np.sqrt(np.mean((om - mm)[mask] ** 2))
    systematic = np.sqrt(max(raw ** 2 - noise(o) ** 2 - noise(m) ** 2, 0.0))
    print(f"cbox {a.res}x{a.res}, {a.spp} spp x 2 seeds, max depth 7 (Mitsuba {a.variant} max_depth 8)")
    print(f"{'channel':8} {'ours mean':>10} {'Mitsuba mean':>13} {'ratio':>7}")
    for c, name in enumerate("RGB"):
        so, sm = om[..., c][mask].mean(), mm[..., c][mask].mean()
        print(f"{name:8} {so:10.5f} {sm:13.5f} {so / sm:7.4f}")
    print(f"relRMSE excl. emitter: raw {raw / ref_mean:.4f}, noise ours {noise(o) / ref_mean:.4f}, "
          f"Mitsuba {noise(m) / ref_mean:.4f}, systematic (noise removed) {systematic / ref_mean:.4f}")


if __name__ == "__main__":
    main()
