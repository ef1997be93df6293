#!/usr/bin/env python3
"""Helpers of the adaptive-zone tests (tests/verification/fracture_adaptive_*.sh): a run's rows
and summary, two runs' rows compared, the conversions, and the final zone of a run as the
`--set` arguments of a model that has it from the start.

    import adaptive_rows as ar          (PYTHONPATH=$SRC/tests/tools)
    python3 adaptive_rows.py zone DIR   (prints the two --set values, one a line)"""
import csv
import json
import sys


def rows(d):
    """damage.csv of run directory d, as dicts."""
    with open(d + "/damage.csv") as f:
        return list(csv.DictReader(f))


def summary(d):
    with open(d + "/summary.json") as f:
        return json.load(f)


def conversions(d, *keys):
    """The conversions of run d as tuples of the given keys."""
    return [tuple(c[k] for k in keys) for c in summary(d)["adaptive"]["conversions"]]


def without_nodes(d):
    """Run d's rows but for the pd_nodes column (a fixed zone's file has none)."""
    return [{k: v for k, v in r.items() if k != "pd_nodes"} for r in rows(d)]


def same(a, b, tol, steps=None, what=""):
    """Runs a and b: the largest difference of the reactions and the output points'
    displacements over the steps (all when None), relative to b's largest such value, at most
    tol."""
    ra, rb = rows(a), rows(b)
    assert len(ra) == len(rb), (what, len(ra), len(rb))
    cols = [c for c in rb[0] if c.startswith("reaction") or c.startswith("load_u")]
    scale = max(abs(float(y[c])) for y in rb for c in cols)
    worst = max(abs(float(x[c]) - float(y[c])) / scale
                for x, y in zip(ra, rb) if not steps or int(x["step"]) in steps for c in cols)
    print("%s: worst relative difference %.2e (bound %.0e)" % (what, worst, tol))
    assert worst <= tol, what


def zone_sets(d):
    """The final zone of run d as --set values: peridynamics.regions and the overlaps."""
    keys = lambda b: "{" + ", ".join("%s: %s" % (k, json.dumps(v)) for k, v in b.items()) + "}"
    a = summary(d)["adaptive"]
    return ["peridynamics.regions=[%s]" % ", ".join(keys(b) for b in a["regions"]),
            "coupling.arlequin.overlap=[%s]" % ", ".join(keys(b) for b in a["overlaps"])]


if __name__ == "__main__":
    if len(sys.argv) != 3 or sys.argv[1] != "zone":
        sys.exit(__doc__)
    print("\n".join(zone_sets(sys.argv[2])))
