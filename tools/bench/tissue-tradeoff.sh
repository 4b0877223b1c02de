#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Speed against accuracy on a prepared tissue model: the shipped
# female pelvis scene (uterus + bladder fixed, tissue sagging under gravity)
# prepared at several frame spacings (samples at 1/RATIO of it, default 3:
# at 1/2 the thin tissue is under-integrated, measured),
# solved statically; each row's error is that of the tissue's mean
# displacement at equilibrium (volume-weighted over samples, `fascia run
# --json` displacement.mean) against the finest resolution. Writes CSV on
# stdout (or to $1). NU sets the tissue's Poisson ratio, PATCH the radius of
# its volumetric patches per frame spacing (0: none; unset: prep's default),
# SCENE another pelvis scene of data/scenes (pelvis-female-tet.json: the
# tetrahedral shape functions), MODES=false its tetrahedra's patches
# without enhanced strain modes (unset: prep's default, with).
# Needs a build with prep (build/tools/fascia, or FASCIA=path).
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
fascia="${FASCIA:-$root/build/tools/fascia}"
scene="$root/data/scenes/${SCENE:-pelvis-female.json}"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
out="${1:-/dev/stdout}"
spacings="${SPACINGS:-0.008 0.006 0.005 0.004 0.003}" # m, coarse to fine; the last is the reference
ratio="${RATIO:-3}"                                       # frame spacing / sample spacing
nu="${NU:-}"                                              # Poisson ratio of the tissue (default: the scene's, 0.4)
patch="${PATCH:-}"                                        # patch radius / frame spacing (default: prep's rule; 0: none)
modes="${MODES:-}"                                        # tet: enhanced strain modes, true or false (default: prep's)
rows=()
# the first number under "key" in a JSON file (the top-level keys come first)
value() { tr -d '\n ' < "$1" | grep -o "\"$2\":[-0-9.e+]*" | head -n 1 | sed 's/.*://'; }
for h in $spacings; do
  half=$(awk -v h="$h" -v r="$ratio" 'BEGIN { printf "%.6g", h / r }')
  # the mesh paths are relative to the scene: make them absolute for the copy
  extra=""
  [ -n "$patch" ] && extra=", \"patch_radius\": $(awk -v h="$h" -v f="$patch" 'BEGIN { printf "%.6g", h * f }')"
  sed -e "s|\"frame_spacing\": [0-9.e-]*|\"frame_spacing\": $h$extra|" \
      -e "s|\"poisson_ratio\": [0-9.e-]*|\"poisson_ratio\": ${nu:-0.4}|" \
      -e "s|\"sample_spacing\": [0-9.e-]*|\"sample_spacing\": $half|" \
      -e "s|\"samples_per_tet\": \([0-9]\)}|\"samples_per_tet\": \1${modes:+, \"enhanced_modes\": $modes}}|" \
      -e "s|\"\.\./meshes/|\"$root/data/meshes/|g" "$scene" > "$work/scene-$h.json"
  t0=$(date +%s.%N)
  "$fascia" prep "$work/scene-$h.json" -o "$work/model-$h.h5" --json > "$work/prep-$h.json" 2>/dev/null
  t1=$(date +%s.%N)
  "$fascia" run "$work/model-$h.h5" --static --json > "$work/run-$h.json" 2>/dev/null
  t2=$(date +%s.%N)
  frames=$(value "$work/prep-$h.json" frames)
  samples=$(value "$work/prep-$h.json" samples)
  mean=$(tr -d '\n ' < "$work/run-$h.json" | grep -o '"displacement":{"mean":[-0-9.e+]*' | sed 's/.*://')
  strain=$(value "$work/run-$h.json" max_strain)
  rows+=("$h,$half,$frames,$samples,$mean,$strain,$(awk -v a="$t0" -v b="$t1" 'BEGIN{printf "%.0f",(b-a)*1000}'),$(awk -v a="$t1" -v b="$t2" 'BEGIN{printf "%.0f",(b-a)*1000}')")
  echo "tissue-tradeoff: frame spacing $h m: $frames frames, $samples samples" >&2
done
reference=$(echo "${rows[-1]}" | cut -d, -f5)
{
  echo "frame_spacing_m,sample_spacing_m,frames,samples,mean_displacement_m,max_strain,prep_ms,solve_ms,error_percent"
  for r in "${rows[@]}"; do
    e=$(echo "$r" | cut -d, -f5)
    echo "$r,$(awk -v e="$e" -v r="$reference" 'BEGIN { printf "%.3f", 100 * (e - r) / (r < 0 ? -r : r) }')"
  done
} > "$out"
