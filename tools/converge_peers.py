#!/usr/bin/env python3
"""Peer rows for `spectral-render converge --peers`: Mitsuba 3 renders of the Cornell box.

Renders Mitsuba's own `mi.cornell_box()` (the scene of ../shared/peers/cbox.usda, through the
peers' common.py: 1-px box filter, `path` with max_depth 8 = our --max-depth 7) at a series of
sample counts (1, 2, 4, 8, ... until one render takes longer than --time seconds or --max-spp is
reached), times every render (wall time of `mi.render` alone, measured with perf_counter; the
scene is loaded and, for llvm variants, the kernels compiled by one untimed warm-up render
first), writes each image as an EXR (R, G, B) and the rows as CSV with the columns of
`converge`'s report.csv. Errors are left empty: `converge --peers FILE.csv` computes them with
the same reference, mask and metrics as for our own configurations.

Each row is an independent render from scratch with its own seed (Mitsuba renders are not
progressive), so its time is what it costs to reach that image.

Run with the peers venv (../shared/peers/README.md; needs `libllvm19` for llvm variants and
DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so):

    ~/peers/venv/bin/python tools/converge_peers.py --out /tmp/peers \\
        --variants llvm_ad_spectral scalar_spectral --res 256 --time 20
    spectral-render converge ../shared/peers/cbox.usda --resolution 256x256 -o DIR \\
        --peers /tmp/peers/peers.csv
"""
import argparse
import csv
import os
import sys
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PEERS = os.path.join(ROOT, "..", "shared", "peers")
sys.path.insert(0, PEERS)
import common  # noqa: E402  (the peers' helpers: cbox_dict, write_exr)

# The columns of converge's report.csv (src/output/report.rs, COLUMNS).
COLUMNS = ["config", "source", "integrator", "wavelengths", "samples", "time_s", "elapsed_s",
           "dropped", "rel_mse", "rel_rmse", "rel_rmse_masked", "rel_mse_corrected",
           "rel_rmse_corrected", "rel_rmse_masked_corrected", "bias_masked",
           "bias_masked_bound", "error", "meter", "value", "ci95", "reference", "rel_error",
           "rel_ci95", "covered", "image"]


def renders(mi, variant, res, max_depth, budget, max_spp, out):
    """Rows of one variant: doubling spp until a render takes longer than the budget."""
    mi.set_variant(variant)
    scene = mi.load_dict(common.cbox_dict(mi, res, 1, 0, max_depth))
    np.array(mi.render(scene, spp=1, seed=999_999))  # warm-up: kernels compiled, untimed
    rows, spp = [], 1
    while spp <= max_spp:
        t0 = time.perf_counter()
        img = np.array(mi.render(scene, spp=spp, seed=spp))
        dt = time.perf_counter() - t0
        name = f"mitsuba_{variant}_{res}_{spp:06d}spp.exr"
        common.write_exr(os.path.join(out, name), img.astype(np.float32))
        rows.append({"config": f"mitsuba {variant}", "source": f"mitsuba {mi.__version__}",
                     "integrator": "path", "samples": spp, "time_s": dt, "image": name})
        print(f"{variant}: {spp} spp in {dt:.3f} s", file=sys.stderr)
        if dt > budget:
            break
        spp *= 2
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", required=True, help="directory for the EXRs and peers.csv")
    ap.add_argument("--variants", nargs="+", default=["llvm_ad_spectral", "scalar_spectral"])
    ap.add_argument("--res", type=int, default=256)
    ap.add_argument("--max-depth", type=int, default=common.MAX_DEPTH)
    ap.add_argument("--time", type=float, default=20.0,
                    help="stop after the first render that takes longer (seconds)")
    ap.add_argument("--max-spp", type=int, default=1 << 16)
    a = ap.parse_args()

    import mitsuba as mi

    os.makedirs(a.out, exist_ok=True)
    rows = []
    for v in a.variants:
        rows += renders(mi, v, a.res, a.max_depth, a.time, a.max_spp, a.out)
    path = os.path.join(a.out, "peers.csv")
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=COLUMNS, lineterminator="\n")
        w.writeheader()
        for r in rows:
            w.writerow({c: r.get(c, "") for c in COLUMNS})
    print(f"wrote {path} ({len(rows)} rows)", file=sys.stderr)


if __name__ == "__main__":
    main()
