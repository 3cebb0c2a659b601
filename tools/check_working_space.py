#!/usr/bin/env python3
"""Converts renders in other RGB working spaces back to Rec.709 with colour-science.

    .venv/bin/python tools/check_working_space.py pixels.json [--tolerance 1e-4]

pixels.json: {"reference": {"chromaticities": [rx, ry, gx, gy, bx, by, wx, wy],
                            "rgb": [[r, g, b], ...]},
              "others": {NAME: {"chromaticities": [...], "rgb": [[r, g, b], ...]}, ...}}

Each colour space is built from the EXR's own `chromaticities` attribute
(colour.RGB_Colourspace with matrices derived from the primaries and white) and converted to
the reference's space with colour.RGB_to_RGB and the Bradford chromatic adaptation, as OCIO's
ACES configs do. A pixel passes when every component is within tolerance x (the reference
pixel's largest |component|, at least 1e-3 cd/m^2) of the reference.

Exit status: 0 if every pixel of every space passes, 1 if not, 2 on bad input.
"""

from __future__ import annotations

import argparse
import json
import sys

import colour
import numpy as np


def space(name: str, chromaticities: list[float]) -> colour.RGB_Colourspace:
    c = np.asarray(chromaticities, dtype=np.float64)
    return colour.RGB_Colourspace(
        name,
        primaries=c[:6].reshape(3, 2),
        whitepoint=c[6:8],
        use_derived_matrix_RGB_to_XYZ=True,
        use_derived_matrix_XYZ_to_RGB=True,
    )


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("pixels")
    parser.add_argument("--tolerance", type=float, default=1e-4)
    args = parser.parse_args()
    try:
        with open(args.pixels, encoding="utf-8") as f:
            doc = json.load(f)
        reference = doc["reference"]
        target = space("reference", reference["chromaticities"])
        want = np.asarray(reference["rgb"], dtype=np.float64)
    except (OSError, KeyError, ValueError) as e:
        print(f"bad input: {e}", file=sys.stderr)
        return 2
    scale = np.maximum(np.abs(want).max(axis=1, keepdims=True), 1e-3)
    ok = True
    for name, other in doc["others"].items():
        source = space(name, other["chromaticities"])
        rgb = np.asarray(other["rgb"], dtype=np.float64)
        got = colour.RGB_to_RGB(
            rgb, source, target, chromatic_adaptation_transform="Bradford"
        )
        err = np.abs(got - want) / scale
        worst = float(err.max())
        print(f"{name}: {len(rgb)} pixels, max relative error {worst:.2e}")
        ok &= worst <= args.tolerance
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
