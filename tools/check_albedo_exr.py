#!/usr/bin/env python3
"""Reads the albedo layer of a `spectral-render --aov albedo` EXR back with the `OpenEXR`
Python module and prints, per channel albedo.R/G/B, its pixel type, its mean over a pixel
rectangle and its value at one pixel, for tests/aov.rs to check.

Usage: check_albedo_exr.py FILE.exr X0,Y0,X1,Y1 X,Y
  (the rectangle's columns X0..X1 and rows Y0..Y1, end exclusive, from the top left)
Prints one line per channel: NAME DTYPE MEAN VALUE. Exit status 1 when a channel is missing.
"""

import sys

import numpy as np
import OpenEXR


def main(path, rect, pixel):
    x0, y0, x1, y1 = (int(v) for v in rect.split(","))
    x, y = (int(v) for v in pixel.split(","))
    # separate_channels: one array per channel, not albedo.R/G/B grouped into "albedo".
    with OpenEXR.File(path, separate_channels=True) as f:
        channels = {name: np.array(c.pixels) for name, c in f.channels().items()}
    status = 0
    for name in ("albedo.R", "albedo.G", "albedo.B"):
        if name not in channels:
            print(f"{name} missing")
            status = 1
            continue
        c = channels[name]
        mean = float(c[y0:y1, x0:x1].mean())
        print(f"{name} {c.dtype} {mean:.6f} {float(c[y, x]):.6f}")
    return status


if __name__ == "__main__":
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    sys.exit(main(*sys.argv[1:]))
