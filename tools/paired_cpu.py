#!/usr/bin/env python3
"""Paired whole-process timing of two commands, A against a baseline B.

    tools/paired_cpu.py [-n RUNS] [--warmup W] --vs "B ARGS..." -- A ARGS...

After W warm-up runs of each (not counted), A and B run in turn (A B A B ...) RUNS times
each; each run's user + system CPU seconds (the kernel's accounting of the reaped child,
os.wait4) and wall seconds are taken. Prints, per command, the median (min-max) CPU and wall
seconds, and the median (min-max) of the pair-by-pair ratios A/B: pairing keeps the ratio
meaningful when the machine's speed drifts during the call. Standard library only; the
commands' output is discarded.
"""
import argparse
import os
import shlex
import statistics
import subprocess
import sys
import time


def run(cmd):
    """CPU (user + system) and wall seconds of one run of `cmd`."""
    start = time.monotonic()
    proc = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.monotonic() - start
    proc.returncode = os.waitstatus_to_exitcode(status)
    if proc.returncode != 0:
        sys.exit(f"error: {shlex.join(cmd)} exited with {proc.returncode}")
    return usage.ru_utime + usage.ru_stime, wall


def spread(values):
    return f"{statistics.median(values):.3f} ({min(values):.3f}-{max(values):.3f})"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("-n", "--runs", type=int, default=5)
    ap.add_argument("--warmup", type=int, default=1)
    ap.add_argument("--vs", required=True, help="the baseline command B, one string")
    ap.add_argument("command", nargs=argparse.REMAINDER, help="-- A ARGS...")
    args = ap.parse_args()
    a = args.command[1:] if args.command[:1] == ["--"] else args.command
    b = shlex.split(args.vs)
    if not a or not b or args.runs < 1:
        ap.error("need --vs B, -- A and at least one run")
    for _ in range(args.warmup):
        run(a)
        run(b)
    runs = {"A": [], "B": []}
    for _ in range(args.runs):
        runs["A"].append(run(a))
        runs["B"].append(run(b))
    for name in "AB":
        cpu = [r[0] for r in runs[name]]
        wall = [r[1] for r in runs[name]]
        print(f"{name}: cpu {spread(cpu)} s, wall {spread(wall)} s")
    for i, what in enumerate(["cpu", "wall"]):
        ratios = [x[i] / y[i] for x, y in zip(runs["A"], runs["B"]) if y[i] > 0]
        print(f"A/B {what}: {spread(ratios)}")


if __name__ == "__main__":
    main()
