#!/usr/bin/env python3
"""Predicted against actual machine time per corpus program (issue 40 "Measured"; deploy/bench.d/48-predict.sh).

Drives a running cell (cellctl up --clock virtual, KT01 OK01 EM01 BS01) through cellctl: for each dialect,
the positive conformance programs (tests/conformance/<d>/NAME.<d> with NAME.expected, no NAME.diag) in name
order, stored under a short name; once the scheduler's prediction on the dialect's station is in
(`program show --json`, predicted_s), the program runs as a pallet on that station (`pallet run`) and the
job's cycle_s (machine seconds the station measured on the virtual clock) is the actual. A run that stops at
an operator's stop (M00, M01) is given cycle start (`station start`): the wait is no machine time on the
virtual clock (docs/predict.md judgement call 1). Programs without a prediction (input waits, probes without
a part model, an alarm) or whose run does not complete in 30 s are listed with the reason and skipped; a
program of no machine time (no motion) agrees when the run measured none either. Programs run in name order
until PER_DIALECT of a second or more have run (PER_DIALECT 0: every one). Prints one line per program, a
summary per dialect with its wall time, and "figure predict.<d>.worst_ratio V" (1 + the largest
|predicted / actual - 1|).

Usage: predict_actual.py SOURCE_DIR CELLCTL PER_DIALECT
"""
import glob
import json
import os
import subprocess
import sys
import time

ROOT, CTL, PER = sys.argv[1], sys.argv[2], int(sys.argv[3])
STATIONS = (("ktapl", "KT01", "K"), ("okuma", "OK01", "O"), ("emco", "EM01", "E"), ("balt", "BS01", "B"))


def ctl(*args, check=True):
    r = subprocess.run([CTL, *args], capture_output=True, text=True, timeout=120)
    if check and r.returncode != 0:
        raise RuntimeError(f"cellctl {' '.join(args)}: {r.stderr.strip()}")
    return r


def corpus(dialect):
    def positive(f):
        stem = f[: f.rfind(".")]
        return os.path.exists(stem + ".expected") and not os.path.exists(stem + ".diag")
    # CELL_BENCH_PREDICT_ONLY=e35_g03_abs,e34_g02_abs: those programs alone, in name order, on the fresh cell
    only = set(filter(None, os.environ.get("CELL_BENCH_PREDICT_ONLY", "").split(",")))
    def chosen(f):
        return not only or os.path.basename(f).rsplit(".", 1)[0] in only
    return sorted(f for f in glob.glob(f"{ROOT}/tests/conformance/{dialect}/*.{dialect}")
                  if positive(f) and chosen(f))


def predicted(name, station):
    """The scheduler's prediction (a number or None) and its reason, once it has answered (10 s at most)."""
    shown = {}
    for _ in range(200):
        shown = json.loads(ctl("program", "show", name, "--json").stdout)
        why = shown["predicted_why"].get(station)
        if shown["predicted_s"].get(station) is not None or (why and not why.startswith("not predicted yet")):
            break
        time.sleep(0.05)
    return shown["predicted_s"].get(station), shown["predicted_why"].get(station)


def ratio(pred, actual):
    """predicted / actual; a program of no machine time agrees with a run that measured none (1 ms: a tick)."""
    if actual < 0.001:
        return 1.0 if pred < 0.001 else float("inf")
    return pred / actual


def run_to_end(job, station):
    """The job once it has ended (or after 30 s of wall time), cycle start given at each operator's stop."""
    deadline = time.monotonic() + 30
    while True:
        ctl("job", "wait", job, "--timeout", "1", check=False)
        j = json.loads(ctl("job", "show", job, "--json").stdout)
        if j.get("state") in ("COMPLETED", "FAILED", "CANCELLED") or time.monotonic() > deadline:
            return j
        # M00 / M01: the run waits for the operator (a press while it runs is not counted by the station)
        ctl("station", "start", station, check=False)


def main():
    seq = pallet = 0
    rows = []
    walls = {}
    for dialect, station, letter in STATIONS:
        taken = 0
        t0 = time.monotonic()
        for f in corpus(dialect):
            if PER and taken >= PER:
                break
            seq += 1
            name, base = f"{letter}{seq:03d}", os.path.basename(f)
            put = ctl("program", "put", f, "--name", name, "--dialect", dialect, check=False)
            if put.returncode:
                print(f"  {dialect:6} {base:40} not stored: {put.stderr.strip()}")
                continue
            pred, why = predicted(name, station)
            if pred is None:
                print(f"  {dialect:6} {base:40} no prediction: {why}")
                continue
            pallet = pallet % 200 + 1
            ctl("pallet", "set", str(pallet), name)
            job = ctl("pallet", "run", str(pallet), "--station", station).stdout.split()[0]
            j = run_to_end(job, station)
            if j.get("state") != "COMPLETED" or j.get("cycle_s") is None:
                ctl("job", "cancel", job, check=False)
                print(f"  {dialect:6} {base:40} predicted {pred:8.3f} s, the run {j.get('state')}: {j.get('reason')}")
                continue
            actual = j["cycle_s"]
            taken += pred >= 1  # N counts programs of a second or more; shorter ones run besides
            rows.append((dialect, base, pred, actual))
            print(f"{dialect:6} {station} {base:40} predicted {pred:8.3f} s  actual {actual:8.3f} s  "
                  f"ratio {ratio(pred, actual):.4f}", flush=True)
        walls[dialect] = time.monotonic() - t0
    print()
    for dialect, station, _ in STATIONS:
        r = [(b, p, a) for d, b, p, a in rows if d == dialect]
        if not r:
            print(f"{dialect}: no program ran on {station}")
            continue
        errors = [(abs(ratio(p, a) - 1), b, ratio(p, a)) for b, p, a in r]
        within = sum(1 for e, _, _ in errors if e <= 0.01)
        worst = max(errors)
        print(f"{dialect} on {station}: {len(r)} programs, {within} within 1% (target: each), "
              f"mean |predicted/actual - 1| {sum(e for e, _, _ in errors) / len(errors):.4f}, "
              f"worst {worst[2]:.4f} ({worst[1]}), {walls[dialect]:.0f} s wall")
        print(f"figure predict.{dialect}.worst_ratio {1 + worst[0]:.4f}")


main()
