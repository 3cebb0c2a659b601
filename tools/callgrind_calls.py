#!/usr/bin/env python3
"""Inclusive cost per call of functions in a callgrind output file.

    tools/callgrind_calls.py CALLGRIND.OUT NAME [NAME...]

For every function whose name contains NAME, sums the calls made to it and the inclusive
events of those calls (the cost lines that follow each `calls=` line), and prints the call count
and every event per call. With `--toggle-collect`, only calls inside collected regions count.
Used for the per-ray figures of docs/design.md §8 ("BVH traversal against Embree, instruction
by instruction"): `rtcIntersect1`, `rtcOccluded1`, `limit_rays::trace_primary` and so on.
Standard library only.
"""
import re
import sys


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    path, wanted = sys.argv[1], sys.argv[2:]
    names, events, positions = {}, [], 1
    totals = {}
    callee, pending = None, None

    def name_of(spec):
        m = re.match(r"\((\d+)\)(?: (.*))?", spec)
        if not m:
            return spec
        if m.group(2) is not None:
            names[m.group(1)] = m.group(2)
        return names.get(m.group(1), "?")

    with open(path) as f:
        for line in f:
            line = line.rstrip("\n")
            if line.startswith("events:"):
                events = line.split()[1:]
            elif line.startswith("positions:"):
                positions = len(line.split()) - 1
            elif line.startswith("fn="):
                name_of(line[3:])
            elif line.startswith("cfn="):
                callee = name_of(line[4:])
            elif line.startswith("calls="):
                pending = (callee, int(line[6:].split()[0]))
            elif pending and line and (line[0].isdigit() or line[0] in "+-*"):
                target, calls = pending
                pending = None
                for w in wanted:
                    if w in target:
                        values = [int(v) for v in line.split()[positions:]]
                        values += [0] * (len(events) - len(values))
                        count, sums = totals.get(w, (0, [0] * len(events)))
                        totals[w] = (count + calls, [a + b for a, b in zip(sums, values)])
                        break
    for w in wanted:
        if w not in totals:
            print(f"{w}: not called")
            continue
        count, sums = totals[w]
        print(f"{w}: {count} calls")
        print("  " + "  ".join(f"{e} {v / count:.2f}" for e, v in zip(events, sums)))


if __name__ == "__main__":
    main()
