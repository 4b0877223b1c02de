#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
# A copy of a scene file that works from any folder (its file paths made
# absolute, its `output` dropped), with the voxel size, the seed or every
# frame and sample spacing changed as asked. Used by the benches that
# prepare a shipped scene at other settings.
#
#   scene_copy.py SCENE.json OUT.json [--voxel M] [--seed N] [--spacing FACTOR]
import argparse
import json
import os

parser = argparse.ArgumentParser()
parser.add_argument("scene")
parser.add_argument("out")
parser.add_argument("--voxel", type=float)
parser.add_argument("--seed", type=int)
parser.add_argument("--spacing", type=float, default=1.0)
a = parser.parse_args()
base = os.path.dirname(os.path.abspath(a.scene))
s = json.load(open(a.scene))
if a.voxel is not None:
    s["voxel_size"] = a.voxel
if a.seed is not None:
    s["seed"] = a.seed
s.pop("output", None)


def absolute(p):
    return p if os.path.isabs(p) else os.path.normpath(os.path.join(base, p))


if "segmentation" in s:
    s["segmentation"]["file"] = absolute(s["segmentation"]["file"])
    labels = s["segmentation"].get("labels", "")
    if isinstance(labels, str) and not labels.startswith("totalsegmentator:"):
        s["segmentation"]["labels"] = absolute(labels)
for part in s.get("organs", []) + s.get("tissues", []):
    if "mesh" in part:
        part["mesh"] = absolute(part["mesh"])
    for key in ("frame_spacing", "sample_spacing"):
        if key in part:
            part[key] *= a.spacing
with open(a.out + ".tmp", "w") as f:
    json.dump(s, f, indent=1)
os.replace(a.out + ".tmp", a.out)
