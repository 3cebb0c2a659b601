#!/usr/bin/env python3
"""What adaptive sampling would buy the path tracer: a measurement, not a feature.

The issue-18 benchmark's error is the RMS over the pixels (away from the visible light) and
the RGB channels of the image's error. With a fixed budget of N samples per pixel on average,
that sum of per-pixel variances v_i / n_i is smallest when n_i ∝ √v_i (Neyman 1934, "On the
two different aspects of the representative method", optimum allocation; v_i the variance of
one sample of pixel i, channels summed). Against uniform n_i = N the gain in mean squared
error is then mean(v) / mean(√v)², whatever N (the *ideal* gain: the true v_i known).

A renderer knows v_i only from a pilot, and using the pilot's own samples to pick a pixel's
count biases the pixel (a pilot that caught a rare bright path asks for more samples, which
dilute it). The scheme simulated here stays unbiased: the film's two independent replicates
(even and odd samples, `sampling/zsobol.rs`) each take a pilot of n₁ samples, and each
replicate's further samples are allocated from the *other* replicate's pilot, so the count of
a replicate is independent of its own samples; the image is the plain average of the two
replicates' means (fixed weights ½). Its variance per pixel is (v_i/n_A,i + v_i/n_B,i)/4.
Counts are water-filled: n = max(n₁, c·σ̂) with c set so that the replicate's mean count is
N/2; σ̂ is the other pilot's per-pixel sample standard deviation, its variance first averaged
over a (2r+1)² box of pixels (r = 0: the pixel alone), since a handful of samples estimates a
pixel's variance poorly (MC samples are heavy-tailed).

Method: K renders of one sample per pixel with the independent sampler (seeds 1…K), so every
pixel has K independent samples. For each trial the two pilots are disjoint random subsets of
n₁ samples; the gain is evaluated with v_i from the K − 2n₁ samples in neither pilot (using
the pilot's samples for both the allocation and its evaluation would flatter the scheme).
The cost of a sample is taken as equal in every pixel (not measured here).

The renderer's `--adaptive` allocates over every pixel, the light's included; `--rules` compares
allocation rules on that footing (`pilot_scale`; `masked` is the rule over the masked pixels
alone, which a renderer cannot know).

Run with the project's venv (tools/venv.sh), from the repository root, after `cargo build
--release`:
    .venv/bin/python tools/adaptive_gain.py ../shared/peers/cbox.usda --samples 160 --zsobol-spp 64
    .venv/bin/python tools/adaptive_gain.py --pilots 0.125 --radii 2 --rules masked,all,floor,clip \
        --clips 4,8,16,32 --trials 3
"""

import argparse
import math
import os
import subprocess
import tempfile

import numpy as np

from light_mask import emitter_mask
from variance_by_depth import read_rgb

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
EXE = os.path.join(ROOT, "target", "release", "spectral-render")


def render(a, tmp, seed, spp=1, sampler="independent"):
    out = os.path.join(tmp, f"{sampler}_{spp}_{seed}.exr")
    subprocess.run([EXE, a.stage, "-o", out, "--spp", str(spp), "--resolution",
                    f"{a.res}x{a.res}", "--max-depth", str(a.max_depth), "--seed", str(seed),
                    "--integrator", "path", "--sampler", sampler],
                   check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return read_rgb(out)


def zsobol_ideal_gain(a, tmp, mask):
    """The ideal gain of the default sampler's images: v_i the variance of one M-spp zsobol
    image per pixel over `a.zsobol_seeds` seeds (independent scrambles), √v_i corrected by
    c4(k) = E[s]/σ for k normal samples, so that the mean of √v is not understated."""
    k = a.zsobol_seeds
    y = np.stack([render(a, tmp, 100 + s, a.zsobol_spp, "zsobol") for s in range(k)])
    v = y.var(0, ddof=1).sum(-1)[mask]
    c4 = math.sqrt(2 / (k - 1)) * math.gamma(k / 2) / math.gamma((k - 1) / 2)
    return v.mean() / (np.sqrt(v).mean() / c4) ** 2


def box_mean(img, r):
    """The mean over a (2r+1)² box around each pixel (edges repeated)."""
    if r == 0:
        return img
    n = 2 * r + 1
    c = np.pad(np.pad(img, r, mode="edge").cumsum(0).cumsum(1), ((1, 0), (1, 0)))
    s = c[n:, n:] - c[:-n, n:] - c[n:, :-n] + c[:-n, :-n]
    return np.maximum(s / (n * n), 0.0)  # the summed-area table's round-off can go below 0


def water_fill(sd, n1, mean_count):
    """Counts max(n1, c·sd) whose mean is `mean_count` (bisection on c)."""
    budget = mean_count * sd.size
    lo, hi = 0.0, budget / max(float(sd.sum()), 1e-300) * 1e3
    for _ in range(200):
        c = 0.5 * (lo + hi)
        if np.maximum(n1, c * sd).sum() > budget:
            hi = c
        else:
            lo = c
    return np.maximum(n1, lo * sd)


def water_fill_capped(sd, n1, mean_count, cap):
    """Counts clip(c·sd, n1, cap) whose mean is `mean_count` (bisection on c)."""
    budget = mean_count * sd.size
    lo, hi = 0.0, budget / max(float(sd.sum()), 1e-300) * 1e6
    for _ in range(200):
        c = 0.5 * (lo + hi)
        if np.clip(c * sd, n1, cap).sum() > budget:
            hi = c
        else:
            lo = c
    return np.clip(lo * sd, n1, cap)


def pilot_scale(p, rule, r, clip):
    """The allocation's per-pixel scale from one pilot p (samples × pixels × RGB) under `rule`:
    `masked`/`all`: the box-averaged standard deviation; `floor`: that over the box-averaged
    mean plus the image's mean (channels summed); `clip`: the standard deviation of the
    samples clipped per channel at `clip` × the pilot image's mean."""
    if rule == "clip":
        p = np.minimum(p, clip * p.mean())
    sd = np.sqrt(box_mean(p.var(0, ddof=1).sum(-1), r))
    if rule == "floor":
        mu = box_mean(p.mean(0).sum(-1), r)
        sd = sd / (mu + mu.mean())
    return sd


def realised_gain(x, mask, n_total, n1, r, rng, rule="masked", clip=8.0, cap=16.0):
    """One trial of the cross-replicate scheme: MSE of uniform sampling over the scheme's
    (over the pixels in `mask`). Rule `masked` allocates over the pixels in `mask` only (what a
    renderer cannot know); the others over every pixel, each replicate's count at most `cap` ×
    its mean, as the renderer's `--adaptive` does (`session/adaptive.rs`)."""
    k = x.shape[0]
    perm = rng.permutation(k)
    pilot_a, pilot_b, rest = perm[:n1], perm[n1:2 * n1], perm[2 * n1:]
    v = x[rest].var(0, ddof=1).sum(-1)
    sd_a, sd_b = (pilot_scale(x[p], rule, r, clip) for p in (pilot_a, pilot_b))
    if rule == "masked":
        n_a = water_fill(sd_b[mask], n1, n_total / 2)
        n_b = water_fill(sd_a[mask], n1, n_total / 2)
    else:
        top = cap * n_total / 2
        n_a = water_fill_capped(sd_b.ravel(), n1, n_total / 2, top).reshape(sd_b.shape)[mask]
        n_b = water_fill_capped(sd_a.ravel(), n1, n_total / 2, top).reshape(sd_a.shape)[mask]
    v = v[mask]
    return (v / n_total).sum() / ((v / n_a + v / n_b) / 4).sum()


def rules(a):
    """(rule, clip) pairs of --rules and --clips."""
    for rule in a.rules.split(","):
        clips = [float(c) for c in a.clips.split(",")] if rule == "clip" else [0.0]
        for clip in clips:
            yield rule, clip


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("stage", nargs="?", default=os.path.join(ROOT, "..", "shared", "peers",
                                                             "cbox.usda"))
    ap.add_argument("--samples", type=int, default=160, help="K one-sample renders")
    ap.add_argument("--res", type=int, default=256)
    ap.add_argument("--max-depth", type=int, default=7)
    ap.add_argument("--budgets", default="256,1024", help="mean samples per pixel N")
    ap.add_argument("--pilots", default="0.0625,0.125,0.25", help="2·n1 / N")
    ap.add_argument("--radii", default="0,1,2,4", help="box radii r of the variance's average")
    ap.add_argument("--trials", type=int, default=4)
    ap.add_argument("--zsobol-spp", type=int, default=0,
                    help="also the ideal gain of M-spp images with the zsobol sampler")
    ap.add_argument("--zsobol-seeds", type=int, default=12)
    ap.add_argument("--rules", default="masked",
                    help="allocation rules (pilot_scale): masked, all, floor, clip")
    ap.add_argument("--clips", default="8", help="rule clip's multiples of the mean")
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        x = np.stack([render(a, tmp, s) for s in range(1, a.samples + 1)])
        mask = emitter_mask(x.mean(0))
        z = zsobol_ideal_gain(a, tmp, mask) if a.zsobol_spp else None
    v = x.var(0, ddof=1).sum(-1)[mask]
    print(f"{a.stage}: {a.res}x{a.res}, max depth {a.max_depth}, {a.samples} samples per pixel "
          f"(independent sampler), {mask.sum()} pixels away from the light")
    print(f"ideal gain (true variances): {v.mean() / np.sqrt(v).mean() ** 2:.3f}")
    if z is not None:
        print(f"ideal gain of {a.zsobol_spp}-spp zsobol images ({a.zsobol_seeds} seeds): {z:.3f}")
    print("| rule | budget N | pilot 2·n1 | box | realised gain (mean of trials) | min..max |")
    print("|---|---|---|---|---|---|")
    rng = np.random.default_rng(1)
    for n_total in (int(b) for b in a.budgets.split(",")):
        for f in (float(p) for p in a.pilots.split(",")):
            n1 = max(2, round(n_total * f / 2))
            if 2 * n1 > a.samples - 2:
                continue
            for r in (int(q) for q in a.radii.split(",")):
                for rule, clip in rules(a):
                    g = [realised_gain(x, mask, n_total, n1, r, rng, rule, clip)
                         for _ in range(a.trials)]
                    name = f"{rule} {clip:g}" if rule == "clip" else rule
                    print(f"| {name} | {n_total} | {2 * n1} | {2 * r + 1}² | {np.mean(g):.3f} | "
                          f"{min(g):.3f}..{max(g):.3f} |", flush=True)


if __name__ == "__main__":
    main()
