#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# A shipped scene's steps at dt 1e-4 .. 5e-2 s on 1 and 2 threads: the
# steps converged, the mean and the largest wall time of a step as
# `fascia run --json` reports them (ms_per_step, largest_step_ms), the
# process's CPU time per step (31 steps less 1, so the setup cancels; the
# least of three runs each) and the Newton iterations per step. CPU time is
# the figure to trust on a shared machine: wall time there grows with the
# other processes' load, which is printed.
# usage: tools/bench/scene-steps.sh SCENE.json [BUILD_DIR] [OUT.txt]
#   e.g. tools/bench/scene-steps.sh data/scenes/pelvis-female-shells.json
set -euo pipefail
here=$(cd "$(dirname "$0")/../.." && pwd)
scene=${1:?usage: scene-steps.sh SCENE.json [BUILD_DIR] [OUT.txt]}
name=$(basename "$scene" .json)
build=${2:-$here/build}
out=${3:-$here/tools/bench/results/2core-debian_cpu/${name//-/_}_steps.txt}
fascia=$build/tools/fascia
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cpu_s() { # user + sys seconds of: fascia run MODEL STEPS DT THREADS (getrusage: microseconds)
  python3 -c 'import resource, subprocess, sys
with open(sys.argv[1], "w") as out:
    subprocess.run(sys.argv[2:], stdout=out, check=True)
r = resource.getrusage(resource.RUSAGE_CHILDREN)
print(r.ru_utime + r.ru_stime)' "$work/run.json" "$fascia" run "$work/model.h5" --steps "$1" --dt "$2" --threads "$3" --json
}
"$fascia" prep "$scene" -o "$work/model.h5" > "$work/prep.txt" 2>&1 ||
  { cat "$work/prep.txt" >&2; exit 1; }
{
  echo "# $name: $(date -u +%Y-%m-%d) $(uname -m), $(nproc) cores, load average $(cut -d' ' -f1-3 /proc/loadavg), commit $(git -C "$here" rev-parse --short HEAD 2>/dev/null || echo unknown)"
  "$fascia" inspect "$work/model.h5" | grep -E '^(frames|samples|pairs)'
  printf "%-7s %7s %9s %13s %12s %13s %10s %10s\n" dt threads converged wall_ms/step largest_ms cpu_ms/step newton/step newton_max
  for threads in 1 2; do
    for dt in 1e-4 1e-3 1e-2 5e-2; do
      one=9e9 all=9e9 # the least of three runs each: other processes only add
      for k in 1 2 3; do
        one=$(awk -v a="$one" -v b="$(cpu_s 1 "$dt" "$threads")" 'BEGIN { print (b < a ? b : a) }')
        all=$(awk -v a="$all" -v b="$(cpu_s 31 "$dt" "$threads")" 'BEGIN { print (b < a ? b : a) }')
      done
      tail -n 1 "$work/run.json" | python3 -c 'import json, sys
j = json.loads(sys.stdin.read())
n = j["newton_iterations_per_step"]
print("%-7s %7d %6d/31 %13.1f %12.1f %13.1f %10.1f %10d" % (sys.argv[1], int(sys.argv[2]), j["converged_steps"],
      j["ms_per_step"], j["largest_step_ms"], 1000 * (float(sys.argv[4]) - float(sys.argv[3])) / 30,
      sum(n) / len(n), max(n)))' "$dt" "$threads" "$one" "$all"
    done
  done
} > "$work/out.txt"
cat "$work/out.txt"
mv "$work/out.txt" "$out"
