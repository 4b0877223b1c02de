#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# What preparing each shipped scene gives and costs: its frames (shared with
# organs), samples and tissue volume, the wall time and peak memory of
# `fascia prep` on 1 and 2 threads, and `fascia prep --estimate` beside the
# larger peak (docs/cohort.md). The figures of data/scenes/README.md's table
# and docs/cohort.md's estimate table come from here. Writes
# tools/bench/results/2core-debian_cpu/prep_scenes.txt and prep_estimate.csv.
#
#   tools/bench/prep-scenes.sh [SCENE.json[@VOXEL_M] ...]   (default: every data/scenes/*.json)
#   e.g. tools/bench/prep-scenes.sh data/scenes/abdomen-totalsegmentator.json@0.001
#
# Environment: FASCIA (default build/tools/fascia).
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
fascia="${FASCIA:-$root/build/tools/fascia}"
out="$root/tools/bench/results/2core-debian_cpu"
work="$(mktemp -d "${TMPDIR:-/tmp}/fascia-prep-scenes.XXXXXX")"
trap 'rm -rf "$work"' EXIT
scenes=("$@")
[ ${#scenes[@]} -gt 0 ] || scenes=("$root"/data/scenes/*.json)
mkdir -p "$out"
{
  echo "# tools/bench/prep-scenes.sh, $(date +%F), $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg)," \
    "commit $(git -C "$root" rev-parse --short HEAD)"
  echo "scene,voxel_size_m,estimate_mib,peak_1_thread_kib,peak_2_threads_kib,ratio_to_larger" >"$work/csv"
  for arg in "${scenes[@]}"; do
    scene="${arg%@*}"
    name="$(basename "$scene" .json)"
    if [ "$arg" != "$scene" ]; then # at another voxel size: a copy that works from here
      python3 "$root/tools/bench/scene_copy.py" "$scene" "$work/scene.json" --voxel "${arg##*@}"
      scene="$work/scene.json"
    fi
    for threads in 1 2; do
      /usr/bin/time -f "%e %M" -o "$work/time-$threads" "$fascia" prep "$scene" -o "$work/model.h5" \
        --threads "$threads" --json >"$work/prep-$threads.json" 2>/dev/null
    done
    "$fascia" prep "$scene" --estimate --json >"$work/estimate.json" 2>/dev/null
    python3 - "$name" "$work" <<'EOF' >>"$work/csv"
import json, os, sys
name, work = sys.argv[1], sys.argv[2]
p = json.load(open(os.path.join(work, "prep-2.json")))
e = json.load(open(os.path.join(work, "estimate.json")))
peaks = [int(open(os.path.join(work, "time-%d" % t)).read().split()[1]) for t in (1, 2)]
seconds = [float(open(os.path.join(work, "time-%d" % t)).read().split()[0]) for t in (1, 2)]
tissues = "; ".join("%s %s, %d frames (%d free), %.3g cm^3" % (t["name"], t.get("form", "volume"), t["frames"],
                    t.get("free_frames", 0), 1e6 * t["volume"]) for t in p["tissues"])
print("%s: %d frames (%d shared), %d samples, %.3g cm^3 of tissue, %g mm voxels; prep %.1f s and %.0f MB on 2 threads "
      "(%.1f s, %.0f MB on 1); estimate %d MiB; %s" % (name, p["frames"], p["coupling_frames"], p["samples"],
      1e6 * p["tissue_volume"], 1e3 * p["voxel_size"], seconds[1], peaks[1] / 1024, seconds[0], peaks[0] / 1024,
      e["peak_mib"], tissues), file=sys.stderr)
print("%s,%g,%d,%d,%d,%.2f" % (name, p["voxel_size"], e["peak_mib"], peaks[0], peaks[1],
                                e["peak_mib"] * 1024 / max(peaks)))
EOF
  done
} 2>&1 | tee "$out/prep_scenes.txt.tmp"
mv "$out/prep_scenes.txt.tmp" "$out/prep_scenes.txt"
mv "$work/csv" "$out/prep_estimate.csv"
cat "$out/prep_estimate.csv"
