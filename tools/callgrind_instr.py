#!/usr/bin/env python3
"""One function's disassembly with each instruction's own count per call, from callgrind.

    tools/callgrind_instr.py CALLGRIND.OUT BINARY SYMBOL [PER [EVENT]]

CALLGRIND.OUT must come from `valgrind --tool=callgrind --dump-instr=yes` (add
`--branch-sim=yes` or `--cache-sim=yes` for those events). SYMBOL is the demangled name as
`nm -C BINARY` prints it (for example `spectral_render::accel::bvh::Bvh::intersect`). Prints
`objdump -d BINARY` of the symbol with, before each instruction, its self cost (calls made from
it are not counted) divided by PER (default 1: the number of queries, to read counts per ray),
for EVENT (default `Ir`; any name on the file's `events:` line, such as `Bcm`), and the total.
Used for the per-part figures of docs/design.md §8 ("BVH traversal: the per-ray set-up, the
leaf's loads and the rechecks"). Standard library and binutils only.
"""
import collections
import re
import subprocess
import sys


def self_costs(path, event):
    """Self cost of `event` per instruction address, summed over the whole file."""
    cost = collections.Counter()
    last = [0, 0]
    index, skip = 0, False
    with open(path) as f:
        for line in f:
            line = line.rstrip("\n")
            if line.startswith("events:"):
                index = line.split()[1:].index(event)
            elif line.startswith("calls="):
                skip = True  # the next cost line is the call's inclusive cost
            elif line and (line[0].isdigit() or line[0] in "+-*"):
                parts = line.split()
                for k, p in enumerate(parts[:2]):
                    if p == "*":
                        continue
                    if p[0] in "+-":
                        last[k] += int(p, 0)
                    else:
                        last[k] = int(p, 0)
                if skip:
                    skip = False
                elif len(parts) > 2 + index:
                    cost[last[0]] += int(parts[2 + index])
    return cost


def symbol_range(binary, symbol):
    """Start and end address of `symbol` (the next symbol's start)."""
    listing = subprocess.run(["nm", "-C", "-n", binary], capture_output=True, text=True).stdout
    rows = []
    for line in listing.splitlines():
        words = line.split(maxsplit=2)
        if len(words) == 3 and re.fullmatch("[0-9a-f]+", words[0]):
            rows.append((int(words[0], 16), words[2]))
    for k, (start, name) in enumerate(rows):
        if name == symbol:
            later = [a for a, _ in rows[k + 1 :] if a > start]
            return start, later[0]
    sys.exit(f"{symbol}: not in {binary}")


def main():
    if len(sys.argv) < 4:
        sys.exit(__doc__)
    path, binary, symbol = sys.argv[1:4]
    per = float(sys.argv[4]) if len(sys.argv) > 4 else 1.0
    event = sys.argv[5] if len(sys.argv) > 5 else "Ir"
    cost = self_costs(path, event)
    start, end = symbol_range(binary, symbol)
    disassembly = subprocess.run(
        ["objdump", "-d", "--no-show-raw-insn", "-C",
         f"--start-address={start}", f"--stop-address={end}", binary],
        capture_output=True, text=True,
    ).stdout
    total = 0
    for line in disassembly.splitlines():
        m = re.match(r"\s*([0-9a-f]+):\s*(.*)", line)
        if m:
            c = cost.get(int(m.group(1), 16), 0)
            total += c
            print(f"{c / per:10.2f}  {m.group(1)}: {m.group(2)}")
    print(f"total {event} {total / per:.2f}")


if __name__ == "__main__":
    main()
