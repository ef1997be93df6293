#!/usr/bin/env python3
"""Compare a run's summary.json with stored expected results.

usage: compare_summary.py EXPECTED.json SUMMARY.json [--update]

EXPECTED holds {"example": path, "tolerance": rel, "points": {name: {field: value}},
"counts": {name: value}, "checks": [...]}. Point values must agree to `tolerance` relative to
the largest stored displacement (or stress) of the file, so that components that are zero up to
round-off do not need a tolerance of their own. Counts must agree exactly.
"""
import json
import sys


def main():
    expected_path, summary_path = sys.argv[1], sys.argv[2]
    update = "--update" in sys.argv
    expected = json.load(open(expected_path))
    summary = json.load(open(summary_path))
    points = {p["name"]: p for p in summary["points"]}
    if update:
        for name, fields in expected["points"].items():
            for f in fields:
                fields[f] = points[name][f]
        for name in expected.get("counts", {}):
            expected["counts"][name] = summary["counts"][name]
        json.dump(expected, open(expected_path, "w"), indent=2)
        open(expected_path, "a").write("\n")
        print(f"updated {expected_path}")
        return 0
    tol = expected["tolerance"]
    failures = []
    for name, value in expected.get("counts", {}).items():
        if summary["counts"][name] != value:
            failures.append(f"counts.{name}: {summary['counts'][name]} != {value}")
    scale = {"u": 0.0, "s": 0.0}
    for fields in expected["points"].values():
        for f, v in fields.items():
            kind = "u" if f.startswith("u") else "s"
            scale[kind] = max(scale[kind], abs(v))
    worst = 0.0
    for name, fields in expected["points"].items():
        if name not in points:
            failures.append(f"point {name} missing")
            continue
        for f, v in fields.items():
            got = points[name][f]
            s = scale["u" if f.startswith("u") else "s"] or 1.0
            err = abs(got - v) / s
            worst = max(worst, err)
            if not err <= tol:
                failures.append(f"{name}.{f}: {got!r} != {v!r} (relative {err:.2e} > {tol})")
    res = summary["solver"].get("residual")
    if res is not None and res > 1e-10:
        failures.append(f"solver residual {res} > 1e-10")
    imbalance = max(abs(x) for x in summary["equilibrium_imbalance"])
    load = max(abs(x) for x in summary["applied_load_sum"]) or 1.0
    if imbalance / load > 1e-9:
        failures.append(f"equilibrium imbalance {imbalance} relative {imbalance/load:.2e} > 1e-9")
    for f in failures:
        print("FAIL:", f)
    print(f"{expected_path}: worst relative difference {worst:.2e} (tolerance {tol})")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
