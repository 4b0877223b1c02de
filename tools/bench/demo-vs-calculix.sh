#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The demo's tissue against CalculiX, statically (tools/bench/demo_calculix.c):
# CalculiX's meshes of the tissue's 1 mm voxels (C3D8I, C3D20R, C3D8I split
# in 2 x 2 x 2: the reference, last), fascia's
# default and finer rungs, their force errors, displacement errors and
# slip, side by side; then the mechanisms one at a time (no volumetric
# patches, more MLS neighbours, finer samples or frames alone). Writes
# tools/bench/results/2core-debian_cpu/demo_calculix.{txt,csv} and, with
# --reference, data/reference/demo-calculix.csv (tests/t598; CCX then defaults
# to the C3D10 tetrahedra held on the organs' smooth surfaces). CalculiX's
# answers are kept in $CACHE (default /tmp/fascia-demo-calculix) so that a
# rerun solves only what is new. CCX and RUNGS pick the meshes and rungs
# (demo-calculix's --ccx and --fascia), NAME the results' file name
# (default demo_calculix); RUNGS=exact the attachment "exact" ladder below
# (written with NAME=demo_calculix_exact CCX=8i:1:1,8i:1:2 RUNGS=exact). On the shared 2-core machine, with ccx's
# iterative Cholesky: C3D8I 21 s, its split mesh 12 minutes; with SPOOLES
# (ccx's default, CCX_SOLVER=SPOOLES): C3D8I 2 minutes, C3D20R 22 minutes.
#   tools/bench/demo-vs-calculix.sh [BUILD_DIR] [--reference]
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
build="${1:-$root/build}"
[ "${1:-}" = "--reference" ] && build="$root/build"
bench="$build/tools/scenes/demo-calculix"
out="$root/tools/bench/results/2core-debian_cpu"
cache="${CACHE:-/tmp/fascia-demo-calculix}"
name="${NAME:-demo_calculix}"
# the attachment "exact" (tag e) against "frames", with and without patches,
# samples converged, other layers, and at 0.5 mm voxels (forces only)
EXACT_RUNGS="1:1,1:0.7,1:0.5,1:0.35,1:1:1:e,1:0.7:1:e,1:0.5:1:e,1:0.35:1:e,1:1:1:e+flat,1:0.7:1:e+flat,1:0.5:1:e+flat"
EXACT_RUNGS+=",1:1:0.5:e,1:0.7:0.7:e,1:1:1:e0.5,1:0.5:1:e0.5,1:1:1:e2,1:0.5:1:e2"
EXACT_RUNGS+=",0.5:1:1:e,0.5:0.7:1:e,0.5:0.5:1:e,0.5:0.7:0.5:e,0.5:0.5:0.5:e,0.5:0.5:0.5:e+flat"
[ "${RUNGS:-}" = exact ] && RUNGS="$EXACT_RUNGS"
# against the converged tetrahedra held on the smooth surfaces: the default
# rungs, 10 MLS neighbours, and the exact ladder's other rungs (written with
# NAME=demo_calculix_tet RUNGS=tet and CCX the tetrahedra of
# tools/bench/results/2core-debian_cpu/demo_calculix_tet.txt, the finest last)
DEFAULT_RUNGS="1:1,1:0.7,1:0.5,1:0.35,1:1:1:flat,1:0.7:1:flat,1:0.5:1:flat,1:1:1:n12,1:1:1:n16,1:1:0.7,1:1:0.5,1:0.7:1.43"
TET_RUNGS="$DEFAULT_RUNGS,1:1:1:n10,1:0.7:1:n10,1:0.5:1:n10"
TET_RUNGS+=",1:1:1:e,1:0.7:1:e,1:0.5:1:e,1:0.35:1:e,1:1:1:e+flat,1:0.7:1:e+flat,1:0.5:1:e+flat"
TET_RUNGS+=",1:1:0.5:e,1:0.7:0.7:e,1:1:1:e0.5,1:0.5:1:e0.5"
TET_RUNGS+=",0.5:1:1:e,0.5:0.7:1:e,0.5:0.5:1:e,0.5:0.7:0.5:e,0.5:0.5:0.5:e,0.5:0.5:0.5:e+flat"
[ "${RUNGS:-}" = tet ] && RUNGS="$TET_RUNGS"
mkdir -p "$cache" "$out"
ref=()
for a in "$@"; do [ "$a" = "--reference" ] && ref=(--write-reference "$root/data/reference/demo-calculix.csv"); done
# the stored reference is the tetrahedra held on the smooth surfaces (data/reference/README.md)
[ ${#ref[@]} -gt 0 ] && CCX="${CCX:-t10:1:1.5:0.025}"
cd "$root"
"$bench" data/scenes/pelvis-female-demo.json --cache "$cache" --ccx "${CCX:-8i:1:1,20r:1:1,8i:1:2}" \
  --ccx-solver "${CCX_SOLVER:-ITERATIVE CHOLESKY}" \
  --fascia "${RUNGS:-$DEFAULT_RUNGS}" \
  --slip --csv "$out/$name.csv" "${ref[@]}" > "$out/$name.txt.tmp"
mv "$out/$name.txt.tmp" "$out/$name.txt"
cat "$out/$name.txt"
