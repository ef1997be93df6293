#!/usr/bin/env python3
"""Whether two output folders hold the same run's results (issue 36: a resumed run against the
one never interrupted): the same file names, every file equal byte for byte, summary.json equal
value for value but for what describes the process rather than the results (keys ending in
_s: timings; keys naming memory; threads).

usage: same_outputs.py REFERENCE_DIR DIR   (exit 0, or 1 with what differs)"""
import json
import os
import sys


def strip(v):
    if isinstance(v, dict):
        return {k: strip(x) for k, x in v.items()
                if not (k.endswith("_s") or "memory" in k or k == "threads")}
    if isinstance(v, list):
        return [strip(x) for x in v]
    return v


def first_difference(a, b, path=""):
    """The first key path where a and b differ, with both values."""
    if isinstance(a, dict) and isinstance(b, dict):
        for k in list(a) + [k for k in b if k not in a]:
            if a.get(k) != b.get(k):
                return first_difference(a.get(k), b.get(k), f"{path}.{k}")
    if isinstance(a, list) and isinstance(b, list) and len(a) == len(b):
        for i, (x, y) in enumerate(zip(a, b)):
            if x != y:
                return first_difference(x, y, f"{path}[{i}]")
    return f"{path}: {a!r} against {b!r}"


def main():
    ref, got = sys.argv[1], sys.argv[2]
    a, b = sorted(os.listdir(ref)), sorted(os.listdir(got))
    if a != b:
        sys.exit(f"files differ: {sorted(set(a) ^ set(b))}")
    for f in a:
        pa, pb = os.path.join(ref, f), os.path.join(got, f)
        if f == "summary.json":
            a_, b_ = strip(json.load(open(pa))), strip(json.load(open(pb)))
            if a_ != b_:
                sys.exit(f"summary.json differs beyond its timings: {first_difference(a_, b_)}")
        elif open(pa, "rb").read() != open(pb, "rb").read():
            sys.exit(f"{f} differs")
    return 0


if __name__ == "__main__":
    sys.exit(main())
