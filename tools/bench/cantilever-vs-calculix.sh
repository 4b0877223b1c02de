#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# fascia's cantilever (fascia beam, static) against the converged CalculiX
# reference of data/reference/cantilever-calculix.csv: tip uz error per shape
# kind, volumetric integration, Poisson ratio and law (docs/mechanics.md).
# usage: tools/bench/cantilever-vs-calculix.sh [BUILD_DIR] [FRAMES] [LAWS] [NUS]
#        defaults: build 20x3x3 "stvk neohookean" "0.3 0.45 0.49"
set -euo pipefail
here=$(cd "$(dirname "$0")/../.." && pwd)
build=${1:-$here/build}
frames=${2:-20x3x3}
laws=${3:-stvk neohookean}
nus=${4:-0.3 0.45 0.49}
fascia=$build/tools/fascia
reference=$here/data/reference/cantilever-calculix.csv
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# law,E,nu -> tip_uz of the reference
ref_uz() { awk -F, -v law="$1" -v nu="$2" '$1 == law && $2 == 40000 && $3 == nu { print $5 }' "$reference"; }
field() { sed -n "s/.*\"$1\":\([^,}]*\).*/\1/p"; }
printf "%-10s %-12s %-7s %-8s %5s %10s %10s %9s %7s %5s %9s\n" law shape volumetric frames nu uz_m ref_uz_m err_uz% newton conv seconds
for law in $laws; do
  for nu in $nus; do
    ref=$(ref_uz "$law" "$nu")
    [ -n "$ref" ] || { echo "no reference for $law nu=$nu in $reference" >&2; exit 1; }
    for shape in hex tet meshless:8 meshless:16; do
      for volumetric in full reduced; do
        kind=${shape%%:*}
        extra=()
        [ "$kind" = meshless ] && extra=(--neighbours "${shape##*:}")
        "$fascia" beam --frames "$frames" --shape "$kind" "${extra[@]}" --law "$law" --nu "$nu" \
          --volumetric "$volumetric" -o "$work/beam.h5"
        out=$("$fascia" run "$work/beam.h5" --static --json --threads 1 || true)
        uz=$(echo "$out" | sed -n 's/.*"tip":{"displacement":\[[^,]*,[^,]*,\([^]]*\)\].*/\1/p')
        newton=$(echo "$out" | field newton_iterations)
        conv=$(echo "$out" | field converged)
        ms=$(echo "$out" | field wall_ms)
        awk -v law="$law" -v shape="$shape" -v vol="$volumetric" -v fr="$frames" -v nu="$nu" -v uz="$uz" \
            -v ref="$ref" -v n="$newton" -v c="$conv" -v ms="$ms" 'BEGIN {
          printf "%-10s %-12s %-7s %-8s %5s %10.4f %10.4f %9.2f %7s %5s %9.1f\n", law, shape, vol, fr, nu, uz, ref,
                 100 * (uz - ref) / (ref < 0 ? -ref : ref), n, c, ms / 1000 }'
      done
    done
  done
done
