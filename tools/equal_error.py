#!/usr/bin/env python3
"""Time to equal error on the Cornell box: ours (path, each sampler) against Mitsuba 3
(`llvm_ad_spectral`, `scalar_spectral`), interleaved in one run. Run by
tools/bench_equal_error.sh, which names the reference; see that script for the options.

For each configuration and sample count (64, 256 by default) and each of --rounds rounds
(configurations interleaved within a round, seeds 1, 2, ...):
- ours: the release binary on ../shared/peers/cbox.usda, --max-depth 7 (path with each sampler,
  and zsobol with --adaptive: the spp is then the mean of the pixels' counts; on request, zsobol
  with each --rr-depth and --split, the independent sampler unsplit from bounce 2
  (--unsplit-independent), and another build of ours, --baseline EXE, with only the common
  options, for an old commit's samples/s in the same run), timed by the render
  loop's own wall time (the EXR header's `spectralRender:wallTime`: scene load and EXR write
  not counted, as Mitsuba's scene load is not), with the whole process's wall time in a
  column of its own (sessions before 31 timed the whole process);
- Mitsuba: `mi.render` of the same box (`common.cbox_dict`, max_depth 8, 1-px box filter,
  its independent sampler) in this process, timed after one untimed warm-up render per
  variant (the llvm variant's JIT compile is not counted).
relRMSE = RMS over the pixels away from the visible light (compare_mitsuba.py's mask on the
reference) and the RGB channels of (image − reference), over the reference's mean there.
Time to relRMSE 5 %: where a round's (time, relRMSE) points cross 5 %, interpolated
linearly in log time and log error between the two sample counts that bracket it (64, 256 and
1024 spp by default; marked "measured"); where every count stays above 5 %, extrapolated from
the largest with error ∝ 1/√time (marked "extrapolated": the Monte Carlo rate, which the
low-discrepancy sampler beats, so its figure is then conservative). Each round's own points
give its time, and the table shows the mean over the rounds with their range: our default
(`--rr-depth auto --split auto`) lets a pilot choose its roulette and split per seed, so two
rounds may be two estimators, and the mean time of the rounds at their RMS error is not a
point of any of them (sessions before 42 pooled the rounds first: with seed 3's choice among
seeds 1–3 that read 14.7 s for rounds whose own times were 13.6–13.9 s). Sessions before 31
extrapolated from 256 spp alone. Samples/s: the median over every render of a row (rounds ×
sample counts) of its own samples/s, with their range: one render slowed by a neighbour on a
shared machine does not move it (sessions before 42 took the pixels × the largest count over
the mean time of its renders). The reference's own noise over the masked pixels is
subtracted from the squared error: mitsuba_reference.py writes a checkpoint at a quarter of
the reference's samples, whose passes are the reference's first quarter, so the two differ
with variance 3σ²/N per pixel (σ²/N the reference's own) — `ref_noise2` below. (Its log's
`est_rmse_of_ref` is over all pixels, where the light's edges dominate: 3× the masked figure
on the Cornell box, which over-subtracted.)
"""
import argparse
import os
import re
import subprocess
import sys
import tempfile
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PEERS = os.path.join(ROOT, "..", "shared", "peers")
sys.path.insert(0, PEERS)
sys.path.insert(0, os.path.join(ROOT, "tools"))
import common  # noqa: E402
from compare_mitsuba import emitter_mask  # noqa: E402

EXE = os.path.join(ROOT, "target", "release", "spectral-render")
# A render's line on stderr, as main prints it (read back by --from-log).
LOG_LINE = re.compile(r"round (\d+) (.+?) +(\d+) spp: +([\d.]+) s \(process +([\d.]+) s\), "
                      r"relRMSE (\S+)$")


def ours(sampler, spp, res, seed, tmp, rr_depth=None, adaptive=False, split=None, exe=None):
    tag = "base" if exe else sampler
    out = os.path.join(tmp, f"ours_{tag}_{rr_depth}_{adaptive}_{split}_{spp}_{seed}.exr")
    args = ["--sampler", sampler] if sampler else []
    args += ["--rr-depth", str(rr_depth)] if rr_depth else []
    args += ["--split", str(split)] if split else []
    args += ["--adaptive"] if adaptive else []
    t0 = time.perf_counter()
    subprocess.run([exe or EXE, os.path.join(PEERS, "cbox.usda"), "-o", out, "--spp", str(spp),
                    "--resolution", f"{res}x{res}", "--max-depth", "7", "--seed", str(seed),
                    "--integrator", "path"] + args,
                   check=True, stderr=subprocess.DEVNULL)
    process = time.perf_counter() - t0
    return render_seconds(out), process, common.read_exr(out)


def render_seconds(path):
    """The render loop's wall time that our renderer writes into the EXR header."""
    import OpenEXR
    with OpenEXR.File(path) as f:
        return float(np.ravel(f.header()["spectralRender:wallTime"])[0])


def mitsuba(variant, spp, res, seed, scenes):
    import mitsuba as mi
    mi.set_variant(variant)
    if variant not in scenes:
        scenes[variant] = mi.load_dict(common.cbox_dict(mi, res, spp, 0, 8))
        mi.render(scenes[variant], spp=spp, seed=0)  # warm-up (JIT)
    t0 = time.perf_counter()
    img = np.array(mi.render(scenes[variant], spp=spp, seed=seed), dtype=np.float64)
    t = time.perf_counter() - t0
    return t, t, img[..., :3]


def ref_noise2_masked(path, ref, mask):
    """The reference's own variance per pixel, averaged over `mask`: mean((q − ref)²)/3 with q
    its checkpoint at a quarter of its samples (same passes, so Var(q − ref) = 3σ²/N); 0 with a
    warning when that checkpoint is missing."""
    m = re.search(r"_(\d+)spp", os.path.basename(path))
    quarter = m and path.replace(m.group(0), f"_{int(m.group(1)) // 4}spp")
    if not quarter or not os.path.exists(quarter):
        print("warning: no quarter-spp checkpoint of the reference; its noise is not subtracted",
              file=sys.stderr)
        return 0.0
    q = common.read_exr(quarter)[..., :3].astype(np.float64)
    return float(np.mean((q - ref)[mask] ** 2) / 3.0)


def time_to(target, pts):
    """The time at which relRMSE reaches `target`, from (time, relRMSE) points in order of
    sample count: log-log interpolation between the first point at or below the target and
    the one before it, else 1/√time extrapolation from the nearest point."""
    for i, (t, e) in enumerate(pts):
        if e <= target and i > 0:
            (t0, e0), (t1, e1) = pts[i - 1], (t, e)
            if e0 > target:
                x = np.log(target / e0) / np.log(e1 / e0)
                return float(np.exp(np.log(t0) + x * np.log(t1 / t0))), "measured"
    t, e = pts[0] if pts[0][1] <= target else pts[-1]
    return t * (e / target) ** 2, "extrapolated"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--reference")
    ap.add_argument("--from-log", metavar="LOG",
                    help="print the table of a previous run from what it printed to stderr "
                         "(its per-render lines), rendering nothing")
    ap.add_argument("--res", type=int, default=256)
    ap.add_argument("--spp", type=int, nargs="+", default=[64, 256, 1024])
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--variants", nargs="+", default=["llvm_ad_spectral", "scalar_spectral"])
    ap.add_argument("--rr-depth", type=int, nargs="*", default=[],
                    help="extra rows: ours (zsobol) with --rr-depth N")
    ap.add_argument("--split", type=int, nargs="*", default=[],
                    help="extra rows: ours (zsobol) with --split N")
    ap.add_argument("--no-adaptive", action="store_true",
                    help="leave out the row of ours with --adaptive")
    ap.add_argument("--unsplit-independent", action="store_true",
                    help="a row of ours with the independent sampler, --rr-depth 2 --split 1: "
                         "the estimator of issue 18's first table")
    ap.add_argument("--baseline", metavar="EXE",
                    help="a row of another build of ours (say, the one issue 18 was measured "
                         "on), run with only --integrator path and the common options")
    a = ap.parse_args()
    if a.from_log:
        rows, names, counts, rounds = read_log(a.from_log)
        if not rounds:
            sys.exit(f"{a.from_log}: no complete round of render lines "
                     f"(\"round N NAME SPP spp: ...\")")
        print(f"cbox {a.res}x{a.res} (--res: the log does not say), {rounds} rounds, "
              f"from {os.path.basename(a.from_log)}")
        report(rows, names, counts, a.res)
        return
    if not a.reference:
        ap.error("--reference is required (unless --from-log)")
    ref = common.read_exr(a.reference)[..., :3].astype(np.float64)
    mask = emitter_mask(ref)
    ref_mean = ref[mask].mean()
    ref_noise2 = ref_noise2_masked(a.reference, ref, mask) / ref_mean ** 2
    configs = [("ours path zsobol", lambda spp, s, tmp: ours("zsobol", spp, a.res, s, tmp)),
               ("ours path independent",
                lambda spp, s, tmp: ours("independent", spp, a.res, s, tmp))]
    if not a.no_adaptive:
        configs.append(("ours path zsobol --adaptive",
                        lambda spp, s, tmp: ours("zsobol", spp, a.res, s, tmp, adaptive=True)))
    for d in a.rr_depth:
        configs.append((f"ours path zsobol rr-depth {d}",
                        lambda spp, s, tmp, d=d: ours("zsobol", spp, a.res, s, tmp, d)))
    for n in a.split:
        configs.append((f"ours path zsobol split {n}",
                        lambda spp, s, tmp, n=n: ours("zsobol", spp, a.res, s, tmp, split=n)))
    if a.unsplit_independent:
        configs.append(("ours path independent rr-depth 2 split 1",
                        lambda spp, s, tmp: ours("independent", spp, a.res, s, tmp, 2,
                                                 split=1)))
    if a.baseline:
        configs.append((f"ours path, {os.path.basename(a.baseline)}",
                        lambda spp, s, tmp: ours(None, spp, a.res, s, tmp, exe=a.baseline)))
    scenes = {}
    for v in a.variants:
        configs.append((f"Mitsuba {v}",
                        lambda spp, s, tmp, v=v: mitsuba(v, spp, a.res, s, scenes)))
    rows = {}  # (name, spp) -> list of (render seconds, process seconds, relRMSE)
    tmp = tempfile.mkdtemp()
    for r in range(a.rounds):
        for spp in a.spp:
            for name, run in configs:
                t, tp, img = run(spp, r + 1, tmp)
                err2 = np.mean((img[..., :3] - ref)[mask] ** 2) / ref_mean ** 2
                err = np.sqrt(max(err2 - ref_noise2, 0.0))
                rows.setdefault((name, spp), []).append((t, tp, err))
                print(f"round {r + 1} {name:28} {spp:5} spp: {t:7.2f} s "
                      f"(process {tp:7.2f} s), relRMSE {err:.4f}", file=sys.stderr)
    print(f"cbox {a.res}x{a.res}, max depth 7 (Mitsuba 8), {a.rounds} interleaved rounds, "
          f"reference {os.path.basename(a.reference)} (its relative noise "
          f"{np.sqrt(ref_noise2):.4f} subtracted), light masked")
    report(rows, [name for name, _ in configs], a.spp, a.res)


def read_log(path):
    """The renders of a previous run, from the lines it printed to stderr: (rows, names in
    order, sample counts, rounds). Only the rounds complete for every row and count are kept
    (a run stopped mid-round leaves a partial one), in round order."""
    by_round, names, counts = {}, [], []
    try:
        with open(path) as f:
            lines = f.read().splitlines()
    except OSError as e:
        sys.exit(f"{path}: {e.strerror}")
    for line in lines:
        m = LOG_LINE.search(line)
        if not m:
            if "round " in line and " spp: " in line:
                print(f"warning: {path}: not read: {line.strip()}", file=sys.stderr)
            continue
        r, name, spp = int(m.group(1)), m.group(2), int(m.group(3))
        by_round[(name, spp, r)] = (float(m.group(4)), float(m.group(5)), float(m.group(6)))
        if name not in names:
            names.append(name)
        if spp not in counts:
            counts.append(spp)
    found = sorted({r for _, _, r in by_round})
    rounds = [r for r in found if all((n, s, r) in by_round for n in names for s in counts)]
    if len(rounds) < len(found):
        print(f"warning: {path}: incomplete rounds left out: "
              f"{sorted(set(found) - set(rounds))}", file=sys.stderr)
    rows = {(n, s): [by_round[(n, s, r)] for r in rounds] for n in names for s in counts}
    return rows, names, counts, len(rounds)


def report(rows, names, counts, res):
    """The table: per row, samples/s (median and range over its renders), relRMSE at each
    count (RMS over the rounds), relRMSE² × spp at the largest, and the time to 5 % (mean
    and range of the rounds' own, by the render loop and by the whole process)."""
    px = res * res
    counts = sorted(counts)
    hdr = ["renderer", "samples/s (median)", "samples/s range"] + \
          [f"relRMSE {s} spp" for s in counts] + \
          [f"relRMSE²×spp @{counts[-1]}", "time to 5 % (s, mean of rounds)", "rounds' range",
           f"vs {names[0]}", "time to 5 %, whole process (s)"]
    print("| " + " | ".join(hdr) + " |")
    print("|" + "---|" * len(hdr))
    t5 = {name: rounds_time_to(0.05, [rows[(name, s)] for s in counts]) for name in names}
    base = t5[names[0]][0]
    for name in names:
        sps = np.array([px * s / t for s in counts for t, _, _ in rows[(name, s)]])
        errs = [float(np.sqrt(np.mean(np.array([x[2] for x in rows[(name, s)]]) ** 2)))
                for s in counts]
        per_sample = errs[-1] ** 2 * counts[-1]
        mean, lo, hi, how, mean_p = t5[name]
        cells = [name, f"{np.median(sps) / 1e6:.2f} M",
                 f"{sps.min() / 1e6:.2f}–{sps.max() / 1e6:.2f} M"] + \
                [f"{x:.4f}" for x in errs] + \
                [f"{per_sample:.2f}", f"{mean:.1f} ({how})", f"{lo:.1f}–{hi:.1f}",
                 f"{mean / base:.2f}×", f"{mean_p:.1f}"]
        print("| " + " | ".join(cells) + " |")


def rounds_time_to(target, per_count):
    """(mean, min, max, how, whole-process mean) of the rounds' own times to `target`;
    `per_count[c][r]` is round r's (render s, process s, relRMSE) at the c-th count."""
    times, process, hows = [], [], set()
    for r in range(min(len(runs) for runs in per_count)):
        pts = [runs[r] for runs in per_count]
        render, how = time_to(target, [(t, e) for t, _, e in pts])
        whole, _ = time_to(target, [(tp, e) for _, tp, e in pts])
        times.append(render)
        process.append(whole)
        hows.add(how)
    how = hows.pop() if len(hows) == 1 else "mixed"
    return float(np.mean(times)), min(times), max(times), how, float(np.mean(process))


if __name__ == "__main__":
    main()
