#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The README's first command: installs missing Debian packages, builds, and
# runs the main job on the shipped default model, the paper's cantilever:
# writes out/demo/beam.h5, solves it statically, then 50 dynamic steps with
# results for ParaView in out/demo/.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
"$root/tools/setup/debian-packages.sh"
"$root/tools/setup/build.sh" "$@"
fascia="${FASCIA_BUILD_DIR:-$root/build}/tools/fascia"
out="$root/out/demo"
mkdir -p "$out"
"$fascia" beam --frames 20x3x3 -o "$out/beam.h5"
"$fascia" inspect "$out/beam.h5"
"$fascia" run "$out/beam.h5" --static -o "$out/beam-static.h5"
"$fascia" run "$out/beam.h5" --steps 50 --dt 0.02 -o "$out/beam-dynamic.h5"
echo "demo: results in $out (open the .xdmf files in ParaView with the 'XDMF Reader')"
