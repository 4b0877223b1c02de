#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Shell organs against CalculiX S8R shells (tools/scenes/shell_calculix.h):
# the CalculiX ladders of the plate (the paper's cantilever as a thin shell)
# and the bowl (a hemisphere hanging from its rim), then fascia at several
# frame spacings against the finest mesh. Writes the reference that
# tests/t596 reads (data/reference/shell-calculix.csv: the CalculiX rows,
# finest mesh last per case) and the side-by-side table and CSV under
# tools/bench/results/2core-debian_cpu/. About 3 minutes on 2 cores (the
# plate's 256 x 16 mesh takes most of it).
# usage: tools/bench/shell-vs-calculix.sh [BUILD_DIR]
set -euo pipefail
here=$(cd "$(dirname "$0")/../.." && pwd)
build=${1:-$here/build}
program=$build/tools/scenes/shell-calculix
results=$here/tools/bench/results/2core-debian_cpu
reference=$here/data/reference/shell-calculix.csv
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$program" --case plate --elements 32,64,128,256 --spacings 0.5,0.4,0.3,0.25,0.2,0.15,0.125 \
  --reference "$work/plate-ref.csv" --csv "$work/plate.csv" | tee "$work/plate.txt"
"$program" --case bowl --elements 8,16,32,48 --spacings 0.012,0.008,0.006,0.004 \
  --reference "$work/bowl-ref.csv" --csv "$work/bowl.csv" | tee "$work/bowl.txt"
# outputs complete before they replace the stored ones
{ cat "$work/plate-ref.csv"; tail -n +2 "$work/bowl-ref.csv"; } > "$work/ref.csv"
{ cat "$work/plate.csv"; tail -n +2 "$work/bowl.csv"; } > "$work/all.csv"
cat "$work/plate.txt" "$work/bowl.txt" > "$work/all.txt"
mv "$work/ref.csv" "$reference"
mv "$work/all.csv" "$results/shell_calculix.csv"
mv "$work/all.txt" "$results/shell_calculix.txt"
