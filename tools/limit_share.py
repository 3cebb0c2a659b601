#!/usr/bin/env python3
"""Our BVH's one-ray rates as a share of Embree 3's, per ray class (issue 18's traversal goal).

    tools/limit_share.py LIMIT_RAYS_BENCH EMBREE_RAYS ROUNDS [SCENE.obj ...]

Alternates, ROUNDS times per scene, `EMBREE_RAYS SCENE --threads 1 --runs 3 --spp 4 --modes 1`
(`../shared/limit/embree_rays.cpp`, built by `../shared/limit/build.sh`) and `LIMIT_RAYS_BENCH
SCENE 4` (target/release/deps/limit_rays-*, `cargo bench --bench limit_rays --no-run`), and
prints the medians of each one's one-thread Mrays/s for the primary, diffuse and shadow rays,
our share of Embree's, and the load average after the scene. Scenes default to
`../shared/limit/scenes/cbox.obj`; the spheres come from `../shared/limit/gen_scene.py --kind
sphere --tris N`. Meaningful on a quiet machine only. Standard library only.
"""
import statistics
import subprocess
import sys

CLASSES = ("primary", "diffuse", "shadow")


def embree(binary, scene):
    """Embree's one-thread Mrays/s per class (mode 1: one ray per call)."""
    args = [binary, scene, "--threads", "1", "--runs", "3", "--spp", "4", "--modes", "1"]
    out = subprocess.run(args, capture_output=True, text=True, check=True).stdout
    rates = {}
    for line in out.splitlines():
        w = line.split()
        if len(w) > 5 and w[0] in CLASSES and w[1] == "1":
            rates[w[0]] = float(w[5])
    return rates


def ours(binary, scene):
    """The bench's one-thread Mrays/s per class (its "Mrays/s 1 thr" column)."""
    out = subprocess.run([binary, scene, "4"], capture_output=True, text=True, check=True).stdout
    rates = {}
    for line in out.splitlines():
        w = line.split()
        if w and w[0] in CLASSES:
            rates[w[0]] = float(w[3])
    return rates


def load():
    with open("/proc/loadavg") as f:
        return f.read().split()[0]


def main():
    if len(sys.argv) < 4:
        sys.exit(__doc__)
    bench, emb, rounds = sys.argv[1], sys.argv[2], int(sys.argv[3])
    scenes = sys.argv[4:] or ["../shared/limit/scenes/cbox.obj"]
    for scene in scenes:
        e = {c: [] for c in CLASSES}
        o = {c: [] for c in CLASSES}
        for _ in range(rounds):
            a, b = embree(emb, scene), ours(bench, scene)
            for c in CLASSES:
                e[c].append(a[c])
                o[c].append(b[c])
        me = {c: statistics.median(e[c]) for c in CLASSES}
        mo = {c: statistics.median(o[c]) for c in CLASSES}
        fmt = lambda d: " / ".join(f"{d[c]:.2f}" for c in CLASSES)
        share = {c: mo[c] / me[c] for c in CLASSES}
        print(f"{scene}: Embree {fmt(me)}, ours {fmt(mo)} Mrays/s, share {fmt(share)}, "
              f"load {load()}", flush=True)


if __name__ == "__main__":
    main()
