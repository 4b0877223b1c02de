#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Does a scene's answer converge as its voxels are refined? Prepares SCENE at
# each voxel size (a copy of the scene with only voxel_size changed, its file
# paths made absolute), runs the demo's 30 steps of 0.05 s on one thread, and
# prints the frames, the largest strain and the change of the tissue's force
# on each organ over the run, beside the prep's time and peak memory.
#
#   tools/bench/voxel-convergence.sh SCENE.json VOXEL_M [VOXEL_M ...]
#   e.g. tools/bench/voxel-convergence.sh data/scenes/abdomen-totalsegmentator.json 0.003 0.0015 0.001 0.0005
#
# Environment: FASCIA (default build/tools/fascia), STEPS (30), DT (0.05).
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
fascia="${FASCIA:-$root/build/tools/fascia}"
scene="$(cd "$(dirname "$1")" && pwd)/$(basename "$1")"
shift
work="$(mktemp -d "${TMPDIR:-/tmp}/fascia-voxels.XXXXXX")"
trap 'rm -rf "$work"' EXIT
echo "# tools/bench/voxel-convergence.sh $(basename "$scene"), $(date +%F), $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg), commit $(git -C "$root" rev-parse --short HEAD)"
for voxel in "$@"; do
  copy="$work/scene-$voxel.json"
  python3 - "$scene" "$voxel" "$copy" <<'EOF'
import json, os, sys
scene, voxel, out = sys.argv[1], float(sys.argv[2]), sys.argv[3]
base = os.path.dirname(scene)
s = json.load(open(scene))
s["voxel_size"] = voxel
s.pop("output", None)
absolute = lambda p: p if os.path.isabs(p) else os.path.normpath(os.path.join(base, p))
if "segmentation" in s:
    s["segmentation"]["file"] = absolute(s["segmentation"]["file"])
    labels = s["segmentation"].get("labels", "")
    if isinstance(labels, str) and not labels.startswith("totalsegmentator:"):
        s["segmentation"]["labels"] = absolute(labels)
for organ in s.get("organs", []):
    if "mesh" in organ:
        organ["mesh"] = absolute(organ["mesh"])
for tissue in s.get("tissues", []):
    if "mesh" in tissue:
        tissue["mesh"] = absolute(tissue["mesh"])
json.dump(s, open(out, "w"), indent=1)
EOF
  model="$work/model-$voxel.h5"
  /usr/bin/time -f "%e %M" -o "$work/time" "$fascia" prep "$copy" -o "$model" --json >"$work/prep.json" 2>/dev/null
  read -r seconds peak_kb <"$work/time"
  "$fascia" run "$model" --steps "${STEPS:-30}" --dt "${DT:-0.05}" --threads 1 --json >"$work/run.json" 2>/dev/null || true
  python3 - "$voxel" "$seconds" "$peak_kb" "$work/prep.json" "$work/run.json" <<'EOF'
import json, math, sys
voxel, seconds, peak_kb, prep, run = sys.argv[1:6]
p, r = json.load(open(prep)), json.load(open(run))
free = sum(t.get("free_frames", 0) for t in p["tissues"])
forces = " ".join("%s %.3g" % (k, math.dist(v["end"], v["start"])) for k, v in r.get("organ_force", {}).items())
print("voxel %.4g mm: %d frames (%d free), %d samples; prep %.1f s, %.0f MB; run %s, %d/%d steps converged, "
      "%.2f ms/step; largest strain %.3g; force change (N): %s"
      % (1e3 * float(voxel), p["frames"], free, p["samples"], float(seconds), float(peak_kb) / 1024, r.get("ended"),
         r.get("converged_steps", 0), r.get("steps", 0), r.get("ms_per_step", 0), r.get("max_strain", float("nan")),
         forces))
EOF
done
