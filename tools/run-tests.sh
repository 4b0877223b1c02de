#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The README's test command: installs missing Debian packages, builds, and runs
# every test with ctest. Tests that need a GPU are skipped with a line saying so.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
"$root/tools/setup/debian-packages.sh"
"$root/tools/setup/build.sh" "$@"
cd "${FASCIA_BUILD_DIR:-$root/build}"
if ! command -v nvidia-smi >/dev/null 2>&1 || ! nvidia-smi -L >/dev/null 2>&1; then
  echo "run-tests: no NVIDIA GPU here: GPU tests (label gpu) are skipped"
fi
ctest --output-on-failure -j "$(nproc 2>/dev/null || echo 2)" --timeout 900
