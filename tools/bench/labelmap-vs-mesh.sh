#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: fascia developers
# The same geometry through both of prep's paths: a mesh scene, and the
# label map its organs make (fascia prep --labelmap) read back as a
# label-map scene with the same tissues. Prints, per tissue, the two tissue
# volumes, their difference, and the volume of one voxel layer on the
# tissue's faces against its organs (the scale the difference is judged
# by), with the time and peak memory of each prep. Exits 1 when a tissue
# differs by more than one voxel layer.
#
# usage: tools/bench/labelmap-vs-mesh.sh [SCENE.json [SMOOTHING [FASCIA]]]
#   SCENE      a mesh scene (default data/scenes/pelvis-female.json)
#   SMOOTHING  the label scene's segmentation.smoothing (default 1)
#   FASCIA     the fascia binary (default build/tools/fascia)
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
scene=${1:-$root/data/scenes/pelvis-female.json}
smoothing=${2:-1}
fascia=${3:-$root/build/tools/fascia}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

measure() { # name, then the command: its JSON summary to $work/name.json, time and memory to name.time
  local name=$1
  shift
  /usr/bin/time -f '%e %M' -o "$work/$name.time" "$@" --json > "$work/$name.json" 2> "$work/$name.log" ||
    { cat "$work/$name.log" >&2; exit 1; }
}

measure mesh "$fascia" prep "$scene" -o "$work/mesh.h5" --labelmap "$work/organs.nii.gz"
# the label scene: each organ from its label, the rest of the scene as it was
python3 - "$scene" "$work" "$smoothing" <<'EOF'
import json, sys
scene_path, work, smoothing = sys.argv[1], sys.argv[2], int(sys.argv[3])
scene = json.load(open(scene_path))
scene["segmentation"] = {"file": "organs.nii.gz", "labels": "organs.tsv", "smoothing": smoothing}
for organ in scene["organs"]:
    for key in ("mesh", "parts", "units", "transform"):
        organ.pop(key, None)
    organ["labels"] = organ["name"]
for tissue in scene["tissues"]:  # parts of a mesh do not exist in a label map
    tissue.get("coupling", {}).pop("parts", None)
    if "region" in tissue and "parts" in tissue["region"]:
        sys.exit("labelmap-vs-mesh: tissue '%s' has a region by parts, which a label map cannot name" % tissue["name"])
scene["output"] = "labels.h5"
with open(work + "/label-scene.json", "w") as out:
    json.dump(scene, out, indent=1)
EOF
measure labels "$fascia" prep "$work/label-scene.json" -o "$work/labels.h5"

python3 - "$work" "$scene" "$smoothing" <<'EOF'
import json, sys
work, scene, smoothing = sys.argv[1], sys.argv[2], sys.argv[3]
mesh, labels = (json.load(open("%s/%s.json" % (work, n))) for n in ("mesh", "labels"))
times = {n: open("%s/%s.time" % (work, n)).read().split() for n in ("mesh", "labels")}
h = mesh["voxel_size"]
print("scene %s, voxels %g mm, label scene smoothing %s" % (scene, 1e3 * h, smoothing))
print("%-16s %12s %12s %10s %14s %8s" % ("tissue", "mesh cm^3", "labels cm^3", "diff cm^3", "1 layer cm^3", "diff/layer"))
worst = 0
for m, l in zip(mesh["tissues"], labels["tissues"]):
    layer = m["organ_face_voxels"] * h ** 3
    diff = l["volume"] - m["volume"]
    worst = max(worst, abs(diff) / layer)
    print("%-16s %12.4f %12.4f %+10.4f %14.4f %8.3f" % (m["name"], 1e6 * m["volume"], 1e6 * l["volume"], 1e6 * diff,
                                                        1e6 * layer, diff / layer))
for n in ("mesh", "labels"):
    print("prep from %-6s %6.1f s, peak %5.0f MB" % (n, float(times[n][0]), float(times[n][1]) / 1024))
print("largest |diff| / layer: %.3f (%s one voxel layer)" % (worst, "within" if worst <= 1 else "NOT within"))
sys.exit(0 if worst <= 1 else 1)
EOF
