#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The CT scene's thin layers against CalculiX (tools/bench/demo_calculix.c
# on a copy of data/scenes/abdomen-totalsegmentator.json): its gastric
# tissue alone (between the stomach, spleen, pancreas, duodenum and liver;
# the spine left out, the duodenum and gallbladder fixed), gravity off, the
# stomach moved 0.03 mm instead of 3 mm, static. At that motion both codes
# are in the linear range, and CalculiX solves its linear elasticity once
# (--linear): its nonlinear solve of these layers, one to three voxels
# thick, stalls. CalculiX's C3D10 tetrahedra hold the tissue on the organs'
# smooth surfaces, as fascia's exact attachment does, at each rung's voxel
# size (the region, so the reference, moves with the voxels), and C3D8I
# on the 1 mm voxels' faces for the staircase's share; fascia's rungs are
# the scene's ladder with 8 and 20 MLS neighbours. Writes
# tools/bench/results/2core-debian_cpu/ct_gastric_calculix.{txt,csv}.
# CalculiX's answers are kept in $CACHE (default /tmp/fascia-ct-calculix).
# About 15 minutes on the shared 2-core machine, most of it fascia's finest
# rung with 20 neighbours.
#   tools/bench/ct-vs-calculix.sh [BUILD_DIR]
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
build="${1:-$root/build}"
bench="$build/tools/scenes/demo-calculix"
out="$root/tools/bench/results/2core-debian_cpu"
cache="${CACHE:-/tmp/fascia-ct-calculix}"
work="$(mktemp -d "${TMPDIR:-/tmp}/fascia-ct-calculix.XXXXXX")"
trap 'rm -rf "$work"' EXIT
mkdir -p "$cache" "$out"
scene="$work/ct-gastric.json"
python3 "$root/tools/bench/scene_copy.py" "$root/data/scenes/abdomen-totalsegmentator.json" "$scene"
python3 - "$scene" <<'EOF'
import json, sys
path = sys.argv[1]
s = json.load(open(path))
s["name"] = "ct-gastric-small-motion"
s["organs"] = [o for o in s["organs"] if o["name"] != "spine"]  # the comparison takes 8 organs
for o in s["organs"]:
    if o["model"] == "rigid":
        o["model"] = "fixed"  # a static solve holds a rigid organ nowhere
    for key in o.get("motion", {}).get("keys", []):
        if "translation" in key:
            key["translation"] = [x / 100 for x in key["translation"]]
s["tissues"] = [t for t in s["tissues"] if t["name"] == "gastric"]
json.dump(s, open(path, "w"), indent=1)
EOF
# the scene's voxels are 3 mm at x1; a rung's voxels follow its samples
CCX="t10:3:3,t10:1.6667:3,t10:1.1667:3,t10:1.5:2,t10:1:2,8i:1:1"
RUNGS="3:1:1:n8,3:1:1:n20,1.6667:0.5:1:n8,1.6667:0.5:1:n20,1.1667:0.35:1:n8,1.1667:0.35:1:n20"
"$bench" "$scene" --linear --cache "$cache" --ccx "${CCX_MESHES:-$CCX}" --reference 3 --fascia "${RUNGS_LIST:-$RUNGS}" \
  --csv "$out/ct_gastric_calculix.csv" > "$out/ct_gastric_calculix.txt.tmp"
mv "$out/ct_gastric_calculix.txt.tmp" "$out/ct_gastric_calculix.txt"
cat "$out/ct_gastric_calculix.txt"
