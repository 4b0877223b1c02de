#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# A shell organ's sample_spacing against CalculiX S8R shells: the bowl (over
# three draws of its frames) and the plate (tools/scenes/shell_calculix.h)
# at each frame spacing with each wall triangle split into K x K points
# (sample_spacing = frame_spacing / K), against the finest CalculiX mesh
# stored in data/reference/shell-calculix.csv (tools/bench/shell-vs-calculix.sh
# writes it). Per row: the probe's vertical displacement's error, %, and
# the static solve's wall time (one thread). About 10 seconds.
# usage: tools/bench/shell-sample-spacing.sh [BUILD_DIR] [OUT.txt]
set -euo pipefail
here=$(cd "$(dirname "$0")/../.." && pwd)
build=${1:-$here/build}
out=${2:-$here/tools/bench/results/2core-debian_cpu/shell_sample_spacing.txt}
program=$build/tools/scenes/shell-calculix
reference=$here/data/reference/shell-calculix.csv
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
run() { # case spacings seeds
  for k in 1 2 3; do
    for seed in $3; do
      "$program" --case "$1" --no-calculix --spacings "$2" --split "$k" --seed "$seed" \
        --csv "$work/$1-$k-$seed.csv" >/dev/null
      tail -n +2 "$work/$1-$k-$seed.csv" | sed "s/^/$k,$seed,/"
    done
  done
}
{ run bowl 0.012,0.008,0.006,0.004 "1 2 3"; run plate 0.5,0.25,0.125 "1"; } > "$work/rows.csv"
# the finest CalculiX row per case is the last one
awk -F, -v ref="$reference" '
  BEGIN { while ((getline line < ref) > 0) { split(line, f, ","); if (f[1] != "case") uz[f[1]] = f[9] } }
  { key = $3 " " $6 " " $1; err[key] = err[key] sprintf(" %+6.2f", 100 * ($10 / uz[$3] - 1));
    ms[key] += $13; n[key]++; if (!(key in seen)) { seen[key] = 1; order[++rows] = key } }
  END {
    for (i = 1; i <= rows; ++i) {
      split(order[i], p, " "); split(err[order[i]], e, " "); s = 0; for (j in e) s += e[j]
      printf "%-5s %-13s %d %-40s %+6.2f %8.1f\n", p[1], p[2], p[3], err[order[i]], s / n[order[i]], ms[order[i]] / n[order[i]]
    }
  }' "$work/rows.csv" | sort -s -k1,1 -k2,2gr > "$work/sorted.txt"
{ echo "case  frame_spacing K  error % per draw (probe uz against the finest S8R mesh)  mean %  solve ms"
  cat "$work/sorted.txt"; } > "$work/table.txt"
cat "$work/table.txt"
mv "$work/table.txt" "$out"
