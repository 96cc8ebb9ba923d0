#!/usr/bin/env bash
# How a cell's cost grows with its size (issue 43 item 4; docs/operations.md §9.4). For each DDS stack and
# 2, 8, 16 and 32 stations (the four dialects in turn, station files copied from deploy/stations into a
# private configuration), on its own domain and data directory, real clock:
#   up_s      `cellctl up --stations all` until it returns (every process announced, every station online
#             in the scheduler's view);
#   cores     the idle cell's CPU over CELL_BENCH_SCALE_IDLE seconds (default 10) after 10 s of settling;
#   rss_mb    the cell's resident memory; udp_in_per_s the host's UDP datagrams received per second;
#   join_ms   a new process (bus_discovery_bench --join) until it has heard every service's heartbeat.
# Prints the table, then per station and per doubling of the cell. About 6 minutes on a 2-core machine.
# Env: CELL_BUILD_DIR (default build/), CELL_BENCH_DOMAIN (default 103), CELL_BENCH_SCALE_SIZES (default
# "2 8 16 32"), CELL_BENCH_SCALE_STACKS (default "fastdds cyclonedds"), CELL_BENCH_SCALE_IDLE (default 10).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
# shellcheck source=lib/figures.sh
source "$ROOT/deploy/bench.d/lib/figures.sh"
# shellcheck source=lib/cell.sh
source "$ROOT/deploy/bench.d/lib/cell.sh"
bench_cell 96-scale 103 bus_discovery_bench
CTL="$BIN/cellctl"
sizes=(${CELL_BENCH_SCALE_SIZES:-2 8 16 32})
stacks=(${CELL_BENCH_SCALE_STACKS:-fastdds cyclonedds})
idle=${CELL_BENCH_SCALE_IDLE:-10}

# make_config N DIR: deploy/'s configuration with N stations, KT/OK/EM/BS in turn (KT01, OK01, EM01, BS01,
# KT02, ...), each a copy of the repository's first station of that dialect under a new id.
make_config() {
  local n=$1 dir=$2 i k id
  local tpl=(KT01 OK01 EM01 BS01) pre=(KT OK EM BS)
  rm -rf "$dir"
  mkdir -p "$dir/stations"
  cp -r "$ROOT/deploy/systemd" "$ROOT/deploy/dds" "$dir/"
  for ((i = 0; i < n; i++)); do
    k=$((i % 4))
    id=${pre[$k]}$(printf '%02d' $((i / 4 + 1)))
    sed "s/^id = \"${tpl[$k]}\"/id = \"$id\"/" "$ROOT/deploy/stations/${tpl[$k]}.toml" >"$dir/stations/$id.toml"
    [ ! -f "$ROOT/deploy/stations/${tpl[$k]}.tools" ] || cp "$ROOT/deploy/stations/${tpl[$k]}.tools" "$dir/stations/$id.tools"
  done
}

printf '%-11s %8s %9s %7s %7s %8s %12s %8s\n' stack stations processes up_s cores rss_mb udp_in_per_s join_ms \
  | tee "$work/table"
for stack in "${stacks[@]}"; do
  for n in "${sizes[@]}"; do
    export CELL_DDS=$stack CELL_CONFIG_DIR="$work/config-$n" CELL_DATA_DIR="$work/data-$stack-$n"
    make_config "$n" "$CELL_CONFIG_DIR"
    t0=$(date +%s.%N)
    if ! "$CTL" up --stations all >"$work/up.out" 2>&1; then
      printf '%-11s %8s  up failed: %s\n' "$stack" "$n" "$(tail -1 "$work/up.out" | cut -c1-160)" | tee -a "$work/table"
      continue
    fi
    up_s=$(awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }')
    sleep 10
    usage=$(python3 "$ROOT/deploy/bench.d/lib/cell_usage.py" "$idle" "$CELL_DATA_DIR")
    procs=$(sed 's/.*processes=\([0-9]*\).*/\1/' <<<"$usage")
    join_ms=$("$BIN/bus_discovery_bench" --join "$procs" | awk '/services heard/ { ms = $1 } /gave up/ { ms = "-" } END { print ms }')
    printf '%-11s %8s %9s %7s %7s %8s %12s %8s\n' "$stack" "$n" "$procs" "$up_s" \
      "$(sed 's/.*cores=\([0-9.]*\).*/\1/' <<<"$usage")" "$(sed 's/.*rss_mb=\([0-9]*\).*/\1/' <<<"$usage")" \
      "$(sed 's/.*udp_in_per_s=\([0-9]*\).*/\1/' <<<"$usage")" "$join_ms" | tee -a "$work/table"
    "$CTL" down >/dev/null
  done
done

echo
echo "per station (figure / stations) and per doubling (figure at 2n / figure at n):"
awk 'NR > 1 && NF == 8 {
       k = $1; n = $2; seen[k] = seen[k] " " n
       up[k, n] = $4; cores[k, n] = $5; rss[k, n] = $6; udp[k, n] = $7; join[k, n] = $8 }
     END {
       for (k in seen) {
         m = split(substr(seen[k], 2), ns, " ")
         for (i = 1; i <= m; i++) {
           n = ns[i]
           line = sprintf("%-11s %3d stations: %.1f s up, %.4f cores, %.1f MB, %.0f datagrams/s per station", k, n,
                          up[k, n], cores[k, n] / n, rss[k, n] / n, udp[k, n] / n)
           if (i > 1 && ns[i - 1] * 2 == n)
             line = line sprintf("; doubling: up x%.2f, cores x%.2f, rss x%.2f, datagrams x%.2f", up[k, n] / up[k, ns[i - 1]],
                                 cores[k, n] / cores[k, ns[i - 1]], rss[k, n] / rss[k, ns[i - 1]], udp[k, n] / udp[k, ns[i - 1]])
           print line
         }
       }
     }' "$work/table"
# The guard's figures (lib/figures.sh): idle cores per station at the largest size, per stack (lower is better).
for stack in "${stacks[@]}"; do
  bench_figure "scale.$stack.idle_cores_per_station" "$(awk -v k="$stack" -v n="${sizes[-1]}" \
    '$1 == k && $2 == n && NF == 8 { printf "%.4f", $5 / n }' "$work/table")" lower
done
