#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Configures and builds fascia into build/ (Release). Extra arguments go to
# cmake's configure step, e.g. -DFASCIA_CUDA=OFF.
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
build="${FASCIA_BUILD_DIR:-$root/build}"
jobs="$(nproc 2>/dev/null || echo 2)"
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DFASCIA_WERROR=ON "$@"
cmake --build "$build" -j "$jobs"
