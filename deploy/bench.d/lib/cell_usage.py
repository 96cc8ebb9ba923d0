#!/usr/bin/env python3
"""What an idle local cell costs (deploy/bench.d/96-scale.sh, deploy/hosts): cell_usage.py SECONDS DATA_DIR...

Reads the processes of `cellctl up` ($DATA_DIR/cell-up.json; of every DATA_DIR given, one per host of a cell
across hosts) and prints one line of key=value figures over
SECONDS: cores (utime + stime of the cell's processes / wall), rss_mb (sum of VmRSS), threads, and udp_in_per_s
(the host's UDP datagrams received per second, /proc/net/snmp: the cell's discovery and heartbeat traffic, as
long as nothing else on the host talks UDP; only this network namespace's), and spent_cpu_s: the CPU-seconds the
processes had used when the window began (since they started: what coming up cost).
"""
import json
import os
import sys
import time


def cpu_ticks(pid):
    try:
        with open(f"/proc/{pid}/stat") as f:
            fields = f.read().rsplit(")", 1)[1].split()
        return int(fields[11]) + int(fields[12])
    except OSError:
        return None


def udp_in():
    with open("/proc/net/snmp") as f:
        lines = [l.split() for l in f if l.startswith("Udp:")]
    return int(lines[1][lines[0].index("InDatagrams")])


def main():
    seconds, pids = float(sys.argv[1]), []
    for data in sys.argv[2:]:
        with open(os.path.join(data, "cell-up.json")) as f:
            pids += [p["pid"] for p in json.load(f)]
    t0 = {p: cpu_ticks(p) for p in pids}
    u0, w0 = udp_in(), time.monotonic()
    time.sleep(seconds)
    t1 = {p: cpu_ticks(p) for p in pids}
    u1, wall = udp_in(), time.monotonic() - w0
    ticks = sum(t1[p] - t0[p] for p in pids if t0[p] is not None and t1[p] is not None)
    rss_kb = threads = 0
    for p in pids:
        try:
            with open(f"/proc/{p}/status") as f:
                for line in f:
                    if line.startswith("VmRSS:"):
                        rss_kb += int(line.split()[1])
                    elif line.startswith("Threads:"):
                        threads += int(line.split()[1])
        except OSError:
            pass
    spent = sum(t for t in t0.values() if t is not None) / os.sysconf('SC_CLK_TCK')
    print(f"processes={len(pids)} cores={ticks / os.sysconf('SC_CLK_TCK') / wall:.3f} "
          f"rss_mb={rss_kb / 1024:.0f} threads={threads} udp_in_per_s={(u1 - u0) / wall:.0f} "
          f"spent_cpu_s={spent:.1f}")


if __name__ == "__main__":
    main()
