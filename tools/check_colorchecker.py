#!/usr/bin/env python3
"""Checks rendered ColorChecker patches against colour-science.

    .venv/bin/python tools/check_colorchecker.py measured.json [--max-delta-e 1.0]
    .venv/bin/python tools/check_colorchecker.py --print-reference 100 > reference.json

Input JSON: {"luminance": L, "patches": {"dark_skin": [X, Y, Z], ...}} with all 24 patches
(names as in spectra/colorchecker/), the renderer's mean absolute XYZ (Y in cd/m^2) of each
Lambertian patch lit by a uniform D65 dome of luminance L (cd/m^2).

Reference, per patch: the radiance of a Lambertian reflector under a uniform dome of radiance
L_e(lambda) is rho(lambda) * L_e(lambda), so the expected XYZ is
    colour.sd_to_XYZ(rho * D65_L, cmfs, k=683, method="Integration")
with no illuminant weighting (colour's default illuminant of ones), where D65_L is CIE D65
scaled so that 683 * sum(D65_L * y_bar) = L, and rho, D65 and the CIE 1931 2 degree CMFs are
colour-science 0.4.7's curves aligned to 1 nm over 360-830 nm exactly as in spectra/
(tools/gen_spectra.py). Both XYZs are converted to CIELAB relative to the white XYZ of D65_L
(Y_white = L) and compared with CIEDE2000 (colour.delta_E(..., method="CIE 2000")).

Exit status: 0 if every patch has Delta E < --max-delta-e, 1 if not, 2 on bad input.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import warnings
from pathlib import Path

warnings.simplefilter("ignore")  # colour warns about optional packages it does not need here

sys.dont_write_bytecode = True  # no tools/__pycache__ in the work tree
sys.path.insert(0, str(Path(__file__).resolve().parent))
import colour  # noqa: E402
import numpy as np  # noqa: E402
from gen_spectra import CHECKER_NAME, CMFS_NAME, COLORCHECKER_STEMS, aligned  # noqa: E402

K_M = 683.0


def xyz(sd, cmfs) -> np.ndarray:
    """Absolute tristimulus values K_m * sum(sd * cmf) dlambda, no illuminant weighting."""
    return np.asarray(colour.sd_to_XYZ(sd, cmfs, k=K_M, method="Integration"), dtype=float)


def references(luminance: float) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """(patch stem -> reference XYZ, white XYZ) for a D65 dome of `luminance` cd/m^2."""
    cmfs = aligned(colour.MSDS_CMFS[CMFS_NAME])
    d65 = aligned(colour.SDS_ILLUMINANTS["D65"])
    d65_l = d65 * (luminance / xyz(d65, cmfs)[1])
    white = xyz(d65_l, cmfs)
    sds = colour.SDS_COLOURCHECKERS[CHECKER_NAME]
    refs = {stem: xyz(aligned(sds[name]) * d65_l, cmfs) for name, stem in COLORCHECKER_STEMS.items()}
    return refs, white


def lab(XYZ: np.ndarray, white: np.ndarray) -> np.ndarray:
    return colour.XYZ_to_Lab(XYZ / white[1], colour.XYZ_to_xy(white))


def load(path: str) -> tuple[float, dict[str, np.ndarray]]:
    def bad(msg: str):
        print(f"error: {path}: {msg}", file=sys.stderr)
        sys.exit(2)

    try:
        doc = json.loads(Path(path).read_text())
    except (OSError, ValueError) as e:
        bad(f"cannot read: {e}")

    if not isinstance(doc, dict) or "luminance" not in doc or "patches" not in doc:
        bad('expected {"luminance": L, "patches": {...}}')
    lum = doc["luminance"]
    if not isinstance(lum, (int, float)) or not math.isfinite(lum) or lum <= 0:
        bad(f"luminance must be a positive number, got {lum!r}")
    patches = doc["patches"]
    if not isinstance(patches, dict):
        bad("patches must be an object")
    names = list(COLORCHECKER_STEMS.values())
    missing = [n for n in names if n not in patches]
    unknown = [n for n in patches if n not in names]
    if missing or unknown:
        bad(f"missing patches {missing}, unknown patches {unknown}")
    out = {}
    for n in names:
        v = patches[n]
        ok = isinstance(v, list) and len(v) == 3
        ok = ok and all(isinstance(c, (int, float)) and math.isfinite(c) for c in v)
        if not ok:
            bad(f"patch {n}: expected [X, Y, Z] finite numbers, got {v!r}")
        out[n] = np.asarray(v, dtype=float)
    return float(lum), out


def main() -> int:
    ap = argparse.ArgumentParser(description="Check rendered ColorChecker XYZ against colour-science (CIEDE2000).")
    ap.add_argument("measured", nargs="?", help="JSON file with luminance and patch XYZs")
    ap.add_argument("--max-delta-e", type=float, default=1.0, help="fail if any patch has Delta E >= this (default 1)")
    ap.add_argument("--print-reference", type=float, metavar="L", help="print the reference JSON for luminance L and exit")
    args = ap.parse_args()

    if args.print_reference is not None:
        refs, _ = references(args.print_reference)
        doc = {"luminance": args.print_reference, "patches": {k: v.tolist() for k, v in refs.items()}}
        print(json.dumps(doc, indent=1))
        return 0
    if args.measured is None:
        ap.error("a measured JSON file is required")

    lum, measured = load(args.measured)
    refs, white = references(lum)
    print(f"ColorChecker ({CHECKER_NAME}) under a uniform D65 dome of {lum:g} cd/m^2; white XYZ {np.round(white, 4)}")
    print(f"{'patch':<14} {'reference X':>11} {'Y':>10} {'Z':>10}   {'measured X':>11} {'Y':>10} {'Z':>10}   {'dE2000':>7}")
    worst = ("none", -1.0)
    failed = []
    for name, ref in refs.items():
        m = measured[name]
        de = float(colour.delta_E(lab(ref, white), lab(m, white), method="CIE 2000"))
        flag = "" if de < args.max_delta_e else "  FAIL"
        print(f"{name:<14} {ref[0]:11.4f} {ref[1]:10.4f} {ref[2]:10.4f}   {m[0]:11.4f} {m[1]:10.4f} {m[2]:10.4f}   {de:7.3f}{flag}")
        if de > worst[1] or not math.isfinite(de):
            worst = (name, de)
        if not de < args.max_delta_e:
            failed.append(name)
    print(f"max dE2000 {worst[1]:.3f} ({worst[0]}); {len(failed)} of 24 patches at or above {args.max_delta_e:g}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
