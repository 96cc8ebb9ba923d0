#!/usr/bin/env bash
# What the bus adds to raw DDS (issue 21, item 1): round trips between two processes on loopback, the same
# exchange three ways on each vendor, in one run: raw (the vendor's own API: Fast DDS's DataWriter and
# DataReader, Cyclone's C API), the bus's pub/sub (a Writer and a Reader per direction) and the bus's
# request/reply (Client and Server). Same transport (UDPv4 on 127.0.0.1, no shared memory), same QoS
# (reliable, volatile, keep-all), same type (cell::ProgramRequest, its octet sequence the payload; 61,440 B is
# the largest it holds). Each cell: the median over CELL_BENCH_RUNS runs of each run's median (and the
# largest p99), and its ratio to raw on the same vendor. Interleaved, so load on a shared machine falls on
# all three alike. Then DDS Security (issue 22): the request/reply on the program store's own topics,
# operator to program-store, and the pub/sub ping-pong on a station's segment and probe topics, interpreter
# to axis servo and back, each secured against unsecured (target: at most 2x at 4 KiB), and the start-up of
# a one-station local cell (`cellctl up`) secured against unsecured.
# Env: CELL_BUILD_DIR (default build/), CELL_BENCH_DOMAIN (default 93), CELL_BENCH_RUNS (default 3).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
BIN="${CELL_BUILD_DIR:-$ROOT/build}/bin"
for exe in bus_pingpong_bench cellctl; do
  [ -x "$BIN/$exe" ] || { echo "45-bus-overhead: $BIN/$exe not built" >&2; exit 1; }
done
export CELL_DOMAIN="${CELL_BENCH_DOMAIN:-93}"
RUNS="${CELL_BENCH_RUNS:-3}"
work="$(mktemp -d "${TMPDIR:-/tmp}/cell-bus-overhead.XXXXXX")"
out="$work/results"
cleanup() {
  for d in "$work"/cell-*; do [ -d "$d" ] && CELL_DATA_DIR="$d" "$BIN/cellctl" down >/dev/null 2>&1; done
  rm -rf "$work"
}
trap cleanup EXIT

# The RESULT lines of bus_pingpong_bench per "IMPL SIZE": median(key) is the median of the runs' medians,
# p99[key] the largest p99; the tables below add their END blocks.
RESULTS_AWK='
  $1 == "RESULT" { key = $2 " " $3; n[key]++; med[key, n[key]] = $4; if ($5 > p99[key]) p99[key] = $5 }
  function median(key,   i, j, t, m, a) {
    m = n[key]; for (i = 1; i <= m; i++) a[i] = med[key, i]
    for (i = 1; i <= m; i++) for (j = i + 1; j <= m; j++) if (a[j] < a[i]) { t = a[i]; a[i] = a[j]; a[j] = t }
    return a[int((m + 1) / 2)]
  }'

one() {  # IMPL SIZE COUNT
  "$BIN/bus_pingpong_bench" pong "$1" &
  local pong=$!
  if ! timeout 120 "$BIN/bus_pingpong_bench" ping "$1" "$2" "$3" >>"$out"; then
    kill "$pong" 2>/dev/null || true
    echo "45-bus-overhead: $1 $2 B failed" >&2
    wait "$pong" 2>/dev/null || true
    return 1
  fi
  wait "$pong" || true
}

for _ in $(seq "$RUNS"); do
  for vendor in fastdds cyclonedds; do
    for size in 64 4096 61440; do
      count=1000
      [ "$size" -gt 4096 ] && count=300
      for kind in raw bus rpc; do one "$kind-$vendor" "$size" "$count"; done
    done
  done
done

echo "bus over raw DDS: round trip on loopback, median (largest p99) in us; x = median / raw median, same vendor"
awk "$RESULTS_AWK"'
  END {
    printf "%-11s %7s %20s %26s %26s\n", "vendor", "bytes", "raw", "bus pub/sub", "bus request/reply"
    split("fastdds cyclonedds", vs, " "); split("64 4096 61440", ss, " ")
    for (v = 1; v <= 2; v++) for (s = 1; s <= 3; s++) {
      r = median("raw-" vs[v] " " ss[s]); b = median("bus-" vs[v] " " ss[s]); q = median("rpc-" vs[v] " " ss[s])
      printf "%-11s %7d %9.1f (%8.1f) %9.1f (%8.1f) %5.2fx %9.1f (%8.1f) %5.2fx\n", vs[v], ss[s],
        r, p99["raw-" vs[v] " " ss[s]], b, p99["bus-" vs[v] " " ss[s]], b / r, q, p99["rpc-" vs[v] " " ss[s]], q / r
    }
  }' "$out"

# DDS Security: the same request/reply on cell/program_store, unsecured (rpc-) and secured (srpc-).
"$BIN/cellctl" pki init --dir "$work/pki" --station KT01 >/dev/null
: >"$out"
for _ in $(seq "$RUNS"); do
  for vendor in fastdds cyclonedds; do
    for size in 64 4096; do
      for kind in rpc srpc bus sbus; do CELL_BENCH_PKI="$work/pki" one "$kind-$vendor" "$size" 1000; done
    done
  done
done
echo
echo "DDS Security: round trips, median (largest p99) in us; x = secured / unsecured"
echo "  request/reply: operator -> program-store (cell/program_store); pub/sub: interpreter-KT01 -> axis-servo-KT01"
echo "  (cell/station/KT01/segments) and back (cell/station/KT01/probe)"
awk "$RESULTS_AWK"'
  END {
    printf "%-14s %-11s %7s %20s %26s\n", "exchange", "vendor", "bytes", "unsecured", "secured"
    split("fastdds cyclonedds", vs, " "); split("64 4096", ss, " ")
    split("rpc bus", ks, " "); name["rpc"] = "request/reply"; name["bus"] = "pub/sub"
    for (k = 1; k <= 2; k++) for (v = 1; v <= 2; v++) for (s = 1; s <= 2; s++) {
      u = median(ks[k] "-" vs[v] " " ss[s]); q = median("s" ks[k] "-" vs[v] " " ss[s])
      printf "%-14s %-11s %7d %9.1f (%8.1f) %9.1f (%8.1f) %5.2fx%s\n", name[ks[k]], vs[v], ss[s], u,
        p99[ks[k] "-" vs[v] " " ss[s]], q, p99["s" ks[k] "-" vs[v] " " ss[s]], q / u,
        (ss[s] == 4096 ? (q / u <= 2 ? "  (target <= 2x: met)" : "  (target <= 2x: MISSED)") : "")
    }
  }' "$out"

# Start-up of a one-station local cell (virtual clock) until `cellctl up` reports every process ready.
now() { date +%s.%N; }
up_time() {  # DATA_DIR [--secure]
  local t0 t1
  t0=$(now)
  CELL_DATA_DIR="$1" CELL_HTTP=127.0.0.1:0 "$BIN/cellctl" up --stations KT01 --clock virtual "${@:2}" >/dev/null
  t1=$(now)
  CELL_DATA_DIR="$1" "$BIN/cellctl" down >/dev/null
  echo "$t1 - $t0" | bc -l
}
plain=$(up_time "$work/cell-plain")
fresh=$(up_time "$work/cell-secure" --secure)
again=$(up_time "$work/cell-secure" --secure)
printf 'cellctl up (one station, virtual clock): unsecured %.2f s; secured %.2f s with a new PKI, %.2f s with the PKI kept (%.2fx)\n' \
  "$plain" "$fresh" "$again" "$(echo "$again / $plain" | bc -l)"
