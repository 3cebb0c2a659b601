#!/usr/bin/env python3
"""Paired one-thread ray rates of two `limit_rays` bench binaries, NEW against OLD.

    tools/limit_rays_pairs.py OLD NEW SCENE.obj [SPP [PAIRS]]

After one warm-up run of each, runs `NEW SCENE SPP` and `OLD SCENE SPP` in turn PAIRS times
(default SPP 4, PAIRS 5) and prints, per ray class, the median (min-max) of the pair-by-pair
ratios NEW/OLD of the bench's one-thread Mrays per CPU-second of that thread (its "per CPU-s"
column, comparable under load), with the load average seen. The bench binaries are
target/release/deps/limit_rays-* (copy the old one away before rebuilding). Standard library
only.
"""
import statistics
import subprocess
import sys

CLASSES = ("primary", "diffuse", "shadow")


def rates(binary, scene, spp):
    """The per-CPU-s Mrays of each class from one run of the bench."""
    out = subprocess.run([binary, scene, spp], capture_output=True, text=True, check=True).stdout
    found = {}
    for line in out.splitlines():
        words = line.split()
        if words and words[0] in CLASSES:
            found[words[0]] = float(words[4])
    return found


def load():
    with open("/proc/loadavg") as f:
        return float(f.read().split()[0])


def main():
    if len(sys.argv) < 4:
        sys.exit(__doc__)
    old, new, scene = sys.argv[1:4]
    spp = sys.argv[4] if len(sys.argv) > 4 else "4"
    pairs = int(sys.argv[5]) if len(sys.argv) > 5 else 5
    loads = [load()]
    rates(new, scene, spp)
    rates(old, scene, spp)
    ratios = {c: [] for c in CLASSES}
    for _ in range(pairs):
        a, b = rates(new, scene, spp), rates(old, scene, spp)
        loads.append(load())
        for c in CLASSES:
            ratios[c].append(a[c] / b[c])
    spread = " / ".join(
        f"{statistics.median(v):.2f} ({min(v):.2f}-{max(v):.2f})" for v in ratios.values()
    )
    print(f"{scene}, SPP {spp}, {pairs} pairs, load {min(loads):.1f}-{max(loads):.1f}")
    print(f"NEW/OLD per CPU-s, primary / diffuse / shadow: {spread}")


if __name__ == "__main__":
    main()
