#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Does a scene's answer converge as its voxels are refined? Prepares SCENE at
# each voxel size under each seed (a copy of the scene with only voxel_size
# and seed changed, its file paths made absolute), solves the static
# equilibrium at the end of the scene's motions on one thread, and prints
# the frames, the largest strain and the tissue's force on each organ, beside
# the prep's time and peak memory; then, per voxel size, the mean over the
# seeds with their spread, and the change of each mean from the previous
# voxel size. The spread over seeds is the discretization's own noise at a
# given frame spacing: a change smaller than it says nothing either way.
#
#   tools/bench/voxel-convergence.sh SCENE.json VOXEL_M [VOXEL_M ...]
#   e.g. SEEDS="1 2 3" tools/bench/voxel-convergence.sh data/scenes/abdomen-totalsegmentator.json 0.001 0.0005
#
# Environment: FASCIA (default build/tools/fascia), SEEDS (default "1 2 3"),
# SPACING (a factor on every frame_spacing and sample_spacing, default 1).
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
fascia="${FASCIA:-$root/build/tools/fascia}"
scene="$(cd "$(dirname "$1")" && pwd)/$(basename "$1")"
shift
work="$(mktemp -d "${TMPDIR:-/tmp}/fascia-voxels.XXXXXX")"
trap 'rm -rf "$work"' EXIT
echo "# tools/bench/voxel-convergence.sh $(basename "$scene"), seeds ${SEEDS:-1 2 3}, spacing x${SPACING:-1}," \
  "$(date +%F), $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg), commit $(git -C "$root" rev-parse --short HEAD)"
for voxel in "$@"; do
  for seed in ${SEEDS:-1 2 3}; do
    copy="$work/scene-$voxel-$seed.json"
    python3 "$root/tools/bench/scene_copy.py" "$scene" "$copy" --voxel "$voxel" --seed "$seed" --spacing "${SPACING:-1}"
    model="$work/model-$voxel-$seed.h5"
    /usr/bin/time -f "%e %M" -o "$work/time" "$fascia" prep "$copy" -o "$model" --json >"$work/prep.json" 2>/dev/null
    read -r seconds peak_kb <"$work/time"
    "$fascia" run "$model" --static --threads 1 --json >"$work/run.json" 2>/dev/null || true
    python3 - "$voxel" "$seed" "$seconds" "$peak_kb" "$work/prep.json" "$work/run.json" "$work/rows.json" <<'EOF'
import json, math, sys
voxel, seed, seconds, peak_kb, prep, run, rows = sys.argv[1:8]
p, r = json.load(open(prep)), json.load(open(run))
free = sum(t.get("free_frames", 0) for t in p["tissues"])
force = {k: math.dist(v["end"], v["start"]) for k, v in r.get("organ_force", {}).items()}
row = {"voxel": float(voxel), "seed": int(seed), "strain": r.get("max_strain", float("nan")), "force": force,
       "ended": r.get("ended")}
with open(rows, "a") as f:
    f.write(json.dumps(row) + "\n")
print("voxel %.4g mm seed %s: %d frames (%d free), %d samples; prep %.1f s, %.0f MB; static %s; largest strain %.3g; "
      "force (N): %s" % (1e3 * float(voxel), seed, p["frames"], free, p["samples"], float(seconds),
                         float(peak_kb) / 1024, r.get("ended"), row["strain"],
                         " ".join("%s %.3g" % kv for kv in force.items())))
EOF
  done
done
python3 - "$work/rows.json" <<'EOF'
import json, sys
rows = [json.loads(line) for line in open(sys.argv[1])]
voxels = sorted({r["voxel"] for r in rows}, reverse=True)
def stats(values):
    mean = sum(values) / len(values)
    return mean, min(values), max(values)
previous = None
for v in voxels:
    at = [r for r in rows if r["voxel"] == v and r["ended"] == "completed"]
    if not at:
        print("# voxel %.4g mm: no completed solve" % (1e3 * v))
        continue
    quantities = {"largest strain": [r["strain"] for r in at]}
    for organ in at[0]["force"]:
        quantities[organ] = [r["force"][organ] for r in at]
    means = {}
    line = []
    for name, values in quantities.items():
        mean, lo, hi = stats(values)
        means[name] = mean
        change = ""
        if previous and previous.get(name):
            change = " (%+.1f %%)" % (100 * (mean / previous[name] - 1))
        line.append("%s %.3g [%.3g-%.3g]%s" % (name, mean, lo, hi, change))
    print("# voxel %.4g mm, mean of %d seeds [range], change from the coarser voxel: %s" % (1e3 * v, len(at), "; ".join(line)))
    previous = means
EOF
