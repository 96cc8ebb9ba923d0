#!/usr/bin/env python3
"""The bench guard (issue 38 item 4): collect the figures the bench scripts appended (one JSON object per
line), write them as one JSON document, and compare them with the accepted baseline.

  figures.py collect LINES OUT.json
  figures.py compare BASELINE.json LINES [TOLERANCE]

compare prints every figure beside its baseline and exits 1 when one is more than TOLERANCE (default 0.15)
worse in the direction its `better` names. A figure this run did not measure (a filtered run, rs274 not
installable) is listed and does not fail; a figure without a baseline is listed as new.
"""
import json
import sys


def load_lines(path):
    figures = {}
    with open(path, encoding="utf-8") as f:
        for n, line in enumerate(f, 1):
            line = line.strip()
            if not line:
                continue
            try:
                fig = json.loads(line)
                figures[fig["name"]] = {"value": float(fig["value"]), "better": fig["better"]}
            except (ValueError, KeyError) as e:
                sys.exit(f"{path}:{n}: not a figure ({e})")
            if fig["better"] not in ("higher", "lower"):
                sys.exit(f"{path}:{n}: better must be higher or lower, not {fig['better']!r}")
    return figures


def worse_by(value, base, better):
    """How much worse value is than base, as a fraction of base (negative: better)."""
    if base == 0:
        return 0.0
    return (base - value) / base if better == "higher" else (value - base) / base


def compare(baseline_path, lines_path, tolerance):
    with open(baseline_path, encoding="utf-8") as f:
        baseline = json.load(f)["figures"]
    run = load_lines(lines_path)
    failed = []
    print(f"{'figure':<44} {'baseline':>12} {'this run':>12} {'change':>9}")
    for name in sorted(set(baseline) | set(run)):
        if name not in run:
            print(f"{name:<44} {baseline[name]['value']:>12g} {'-':>12}  not measured")
            continue
        if name not in baseline:
            print(f"{name:<44} {'-':>12} {run[name]['value']:>12g}  new (no baseline)")
            continue
        b, v = baseline[name], run[name]
        w = worse_by(v["value"], b["value"], b["better"])
        mark = ""
        if w > tolerance:
            mark = f"  WORSE than {tolerance:.0%} ({b['better']} is better)"
            failed.append(name)
        print(f"{name:<44} {b['value']:>12g} {v['value']:>12g} {-w:>+8.1%}{mark}")
    if failed:
        print(f"bench compare: {len(failed)} figure(s) more than {tolerance:.0%} worse than "
              f"{baseline_path}: {', '.join(failed)}")
        return 1
    print(f"bench compare: every measured figure within {tolerance:.0%} of {baseline_path}")
    return 0


def main(argv):
    if len(argv) >= 4 and argv[1] == "collect":
        figures = load_lines(argv[2])
        with open(argv[3], "w", encoding="utf-8") as f:
            json.dump({"figures": figures}, f, indent=2, sort_keys=True)
            f.write("\n")
        return 0
    if len(argv) >= 4 and argv[1] == "compare":
        return compare(argv[2], argv[3], float(argv[4]) if len(argv) > 4 else 0.15)
    sys.exit(__doc__)


if __name__ == "__main__":
    sys.exit(main(sys.argv))
