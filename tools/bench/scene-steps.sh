#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The paper's Figure 7 scene (data/scenes/pelvis-female-shells.json: uterus
# and bladder as shells): 30 steps at dt 1e-4 .. 5e-2 s on 1 and 2 threads,
# each step's wall time as `fascia run --json` reports it, the process's CPU
# time per step (31 steps less 1, so the setup cancels; the least of three
# runs each) and the Newton iterations per step. CPU time is the figure to
# trust on a shared machine: wall time there grows with the other processes'
# load, which is printed.
# usage: tools/bench/pelvis-shells-steps.sh [BUILD_DIR] [OUT.txt]
set -euo pipefail
here=$(cd "$(dirname "$0")/../.." && pwd)
build=${1:-$here/build}
out=${2:-$here/tools/bench/results/2core-debian_cpu/pelvis_female_shells_steps.txt}
fascia=$build/tools/fascia
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
field() { sed -n "s/.*\"$1\":\([^,}]*\).*/\1/p"; }
cpu_s() { # user + sys seconds of: fascia run MODEL STEPS DT THREADS (getrusage: microseconds)
  python3 -c 'import resource, subprocess, sys
with open(sys.argv[1], "w") as out:
    subprocess.run(sys.argv[2:], stdout=out, check=True)
r = resource.getrusage(resource.RUSAGE_CHILDREN)
print(r.ru_utime + r.ru_stime)' "$work/run.json" "$fascia" run "$work/model.h5" --steps "$1" --dt "$2" --threads "$3" --json
}
"$fascia" prep "$here/data/scenes/pelvis-female-shells.json" -o "$work/model.h5" > "$work/prep.txt" 2>&1 ||
  { cat "$work/prep.txt" >&2; exit 1; }
{
  echo "# $(date -u +%Y-%m-%d) $(uname -m), $(nproc) cores, load average $(cut -d' ' -f1-3 /proc/loadavg)"
  "$fascia" inspect "$work/model.h5" | grep -E '^(frames|samples|pairs)'
  printf "%-7s %7s %9s %13s %13s %10s\n" dt threads converged wall_ms/step cpu_ms/step newton/step
  for threads in 1 2; do
    for dt in 1e-4 1e-3 1e-2 5e-2; do
      one=9e9 all=9e9 # the least of three runs each: other processes only add
      for k in 1 2 3; do
        one=$(awk -v a="$one" -v b="$(cpu_s 1 "$dt" "$threads")" 'BEGIN { print (b < a ? b : a) }')
        all=$(awk -v a="$all" -v b="$(cpu_s 31 "$dt" "$threads")" 'BEGIN { print (b < a ? b : a) }')
      done
      json=$(tail -n 1 "$work/run.json")
      awk -v dt="$dt" -v t="$threads" -v c="$(echo "$json" | field converged_steps)" \
          -v ms="$(echo "$json" | field ms_per_step)" -v n="$(echo "$json" | field newton_iterations)" \
          -v one="$one" -v all="$all" 'BEGIN {
        printf "%-7s %7d %6d/31 %13.1f %13.1f %10.1f\n", dt, t, c, ms, 1000 * (all - one) / 30, n / 31 }'
    done
  done
} > "$work/out.txt"
cat "$work/out.txt"
mv "$work/out.txt" "$out"
