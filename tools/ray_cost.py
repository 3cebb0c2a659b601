#!/usr/bin/env python3
"""Instruction counts of the ray queries, from callgrind (deterministic, unlike wall-clock time
on a shared machine).

Runs the release binary under `valgrind --tool=callgrind` on a stage (default: the Cornell box
of ../shared/peers, 48x48, 8 spp, 1 thread) and prints, for each query function, the inclusive
instruction count, the number of calls and the instructions per call. Inclusive costs are summed
over call sites from the raw callgrind file, so inlining into different callers does not split
them. Compare builds with the same codegen settings: with `codegen-units > 1` unrelated code can
inline differently from build to build; `CARGO_PROFILE_RELEASE_CODEGEN_UNITS=1` avoids that.

Usage: tools/ray_cost.py [--bin PATH] [--keep FILE] [STAGE [RENDER ARGS...]]
"""
import argparse
import collections
import os
import re
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DEFAULT_STAGE = os.path.join(ROOT, "..", "shared", "peers", "cbox.usda")
DEFAULT_ARGS = ["--resolution", "48x48", "--spp", "8", "--threads", "1"]
FUNCTIONS = [
    "integrator::path::PathIntegrator::li_from",
    "scene::render_scene::Scene::intersect",
    "scene::render_scene::Scene::occluded",
    "accel::bvh::Bvh::intersect",
    "accel::bvh::Bvh::occluded",
    "geometry::triangle::intersect_packed",
    "geometry::triangle::plane_t",
    "scene::build::build",
]


def inclusive_costs(path):
    """(inclusive cost, calls) per function name, summed over all call sites, and the total."""
    names, cost, calls = {}, collections.Counter(), collections.Counter()
    callee, pending, total = None, None, 0
    with open(path) as f:
        for line in f:
            if line.startswith(("summary:", "totals:")):
                total = int(line.split()[1])
                continue
            m = re.match(r"(c?fn)=\((\d+)\)(?: (.*))?", line)
            if m:
                kind, key, name = m.groups()
                if name:
                    names[key] = name.strip()
                if kind == "cfn":
                    callee = key
                continue
            m = re.match(r"calls=(\d+)", line)
            if m:
                pending = int(m.group(1))
                continue
            if pending is not None:
                cost[names[callee]] += int(line.split()[-1])
                calls[names[callee]] += pending
                pending = None
    return cost, calls, total


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bin", default=os.path.join(ROOT, "target", "release", "spectral-render"))
    parser.add_argument("--keep", help="keep the callgrind output in this file")
    parser.add_argument("stage", nargs="?", default=DEFAULT_STAGE)
    parser.add_argument("args", nargs=argparse.REMAINDER)
    opts = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        out = opts.keep or os.path.join(tmp, "callgrind.out")
        cmd = ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", opts.bin,
               opts.stage, *(opts.args or DEFAULT_ARGS), "-o", os.path.join(tmp, "image.exr")]
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        cost, calls, total = inclusive_costs(out)
    print(f"{'function':45} {'Minstr':>9} {'calls':>9} {'instr/call':>11}")
    print(f"{'(whole program)':45} {total / 1e6:9.2f}")
    for suffix in FUNCTIONS:
        for name in sorted(n for n in cost if n.endswith(suffix)):
            print(f"{suffix:45} {cost[name] / 1e6:9.2f} {calls[name]:9d} "
                  f"{cost[name] / calls[name]:11.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
