#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
# demo-calculix's cache of CalculiX answers (--cache DIR) gives an answer
# only to the deck it answers: the demo scene and a copy with another
# Poisson ratio share the mesh's name (2 mm voxels, C3D8I) but not the
# answer; the copy's second run reads its own answer back. On 2 mm voxels:
# about 40 s. Skips (77) without ccx.
#   t558_reference_demo_cache.py DEMO_CALCULIX SCENE.json
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

if shutil.which("ccx") is None:
    print("t558: skipped: CalculiX (ccx) is not installed")
    sys.exit(77)
program, scene = sys.argv[1], sys.argv[2]
work = tempfile.mkdtemp(prefix="t558-")
base = os.path.dirname(os.path.abspath(scene))
s = json.load(open(scene))
s.pop("output", None)
for organ in s["organs"]:
    organ["mesh"] = os.path.normpath(os.path.join(base, organ["mesh"]))
for material in s["materials"].values():
    material["poisson_ratio"] = 0.3
other = os.path.join(work, "other.json")
json.dump(s, open(other, "w"))
cache = os.path.join(work, "cache")
os.mkdir(cache)


def calculix_row(scene_path):
    """CalculiX's uterus force and whether it came from the cache."""
    run = subprocess.run([program, scene_path, "--ccx", "8i:2:1", "--fascia", "2:1", "--cache", cache],
                         capture_output=True, text=True)
    row = re.search(r"^\s+1 C3D8I 2 mm\s+\d+\s+\d+\s+(\S+)\s+\S+\s+\S+(.*)$", run.stdout, re.M)
    if run.returncode != 0 or not row:
        print(run.stdout, run.stderr)
        sys.exit("t558: demo-calculix failed on " + scene_path)
    return float(row.group(1)), "(cached)" in row.group(2)


failures = 0


def check(ok, what):
    global failures
    print(("ok   " if ok else "FAIL ") + what)
    failures += not ok


first, first_cached = calculix_row(scene)
second, second_cached = calculix_row(other)
third, third_cached = calculix_row(other)
check(not first_cached, "the demo's answer is solved, the cache being empty")
check(not second_cached, "the copy with another Poisson ratio is solved, not read from the demo's answer")
check(abs(second - first) > 1e-3 * first, "the two answers differ (%.5f against %.5f N)" % (second, first))
check(third_cached and third == second, "the copy's second run reads its own answer back")
shutil.rmtree(work)
sys.exit(1 if failures else 0)
