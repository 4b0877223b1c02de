#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Installs the Debian 12 packages fascia builds with, only those missing.
# Needs root (or sudo) when something is missing; prints what it installs.
set -euo pipefail

packages=(
  build-essential cmake pkg-config     # compilers and build
  libhdf5-dev zlib1g-dev               # model and result files, compressed VTK outputs (simulator core)
  libsuitesparse-dev libopenblas-dev   # the direct linear solver: CHOLMOD on an optimized BLAS (simulator core)
  libcjson-dev                         # JSON for scene files and --json output
  libassimp-dev libcgal-dev libopenvdb-dev libboost-iostreams-dev libtbb-dev libeigen3-dev nettle-dev  # prep stage
  libnifti2-dev libteem-dev            # prep: label maps (NIfTI, NRRD); optional, prep reads meshes without them
  gnuplot-nox                          # pictures and plots without a display
  paraview python3-paraview python3-h5py python3-meshio  # tests open the results with ParaView's readers (pvbatch), h5py and meshio
  xvfb xauth                           # the demo's pictures rendered by ParaView without a display (xvfb-run)
  calculix-ccx                         # the cantilever's FE reference and bench's peer (data/reference/)
  python3-numpy python3-cffi python3-pytest  # the Python package (sim/python: cffi over libfascia_sim.so) and its tests
  snakemake                            # the cohort workflow (tools/cohort/Snakefile, docs/cohort.md)
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all Debian packages present"
  exit 0
fi
echo "setup: installing ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
