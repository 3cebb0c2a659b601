#!/usr/bin/env python3
"""Applies PyOpenColorIO's display transforms to a grid of scene-linear values.

    .venv/bin/python tools/ocio_reference.py request.json answer.json

request.json: {"config": PATH, "grid": [[r, g, b], ...],
               "transforms": [[input, display, view], ...]}
answer.json:  {"version": OCIO version, "results": [[[r, g, b], ...] per transform]}

Each transform is `config.getProcessor(input, display, view)` (a DisplayViewTransform from
the colour space `input`), run on the default CPU processor with float32 RGB, as an OCIO
application previews an image. tests/ocio.rs compares the answers with output/ocio.rs.
"""

from __future__ import annotations

import json
import sys

import numpy as np
import PyOpenColorIO as ocio


def main() -> int:
    if len(sys.argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    with open(sys.argv[1], encoding="utf-8") as f:
        request = json.load(f)
    config = ocio.Config.CreateFromFile(request["config"])
    grid = np.asarray(request["grid"], dtype=np.float32)
    results = []
    for src, display, view in request["transforms"]:
        processor = config.getProcessor(src, display, view, ocio.TRANSFORM_DIR_FORWARD)
        cpu = processor.getDefaultCPUProcessor()
        pixels = np.ascontiguousarray(grid.copy())
        cpu.applyRGB(pixels)
        results.append(pixels.astype(float).tolist())
    with open(sys.argv[2], "w", encoding="utf-8") as f:
        json.dump({"version": ocio.__version__, "results": results}, f)
    return 0


if __name__ == "__main__":
    sys.exit(main())
