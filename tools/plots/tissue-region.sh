#!/bin/sh
# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: fascia developers
# docs/tissue-region.png: the tissue prep builds between two tilted slabs
# (gap 0 to 3 max_gap), a slice at y = 0 of its region against the exact
# boundary of d_A + d_B <= max_gap. Needs python3 and gnuplot.
# usage: tools/plots/tissue-region.sh PATH_TO_FASCIA [OUT.png]
set -eu
fascia=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
out=${2:-docs/tissue-region.png}
here=$(cd "$(dirname "$0")" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
python3 - <<'PY'
s, L, sh = 1 / 3, 0.054, 0.0003  # B's slope, length, a shift off the voxel lattice
def hexa(name, corners):
    quads = [[1, 3, 7, 5], [2, 6, 8, 4], [1, 5, 6, 2], [3, 4, 8, 7], [1, 2, 4, 3], [5, 7, 8, 6]]
    with open(name, 'w') as f:
        for c in corners: f.write("v %.9g %.9g %.9g\n" % tuple(c))
        for q in quads: f.write("f %d %d %d\nf %d %d %d\n" % (q[0], q[1], q[2], q[0], q[2], q[3]))
A, B = [], []
for k in range(8):
    x, y = (L if k & 1 else 0), (0.014 if k & 2 else -0.014)
    A.append([(L if k & 1 else -0.012) + sh, y + sh, (0 if k & 4 else -0.008) + sh])
    B.append([x + sh, y + sh, s * x + (0.008 if k & 4 else 0) + sh])
hexa('a.obj', A)
hexa('b.obj', B)
open('scene.json', 'w').write('''{"fascia_scene": 1, "voxel_size": 0.0005, "seed": 5,
 "materials": {"soft": {"youngs_modulus": 3000, "poisson_ratio": 0.3}},
 "organs": [{"name": "A", "mesh": "a.obj", "model": "fixed"}, {"name": "B", "mesh": "b.obj", "model": "fixed"}],
 "tissues": [{"name": "t", "connects": ["A", "B"], "max_gap": 0.006, "material": "soft",
              "frame_spacing": 0.003, "sample_spacing": 0.0015}]}
''')
PY
FASCIA_PROGRESS=0 "$fascia" prep scene.json -o model.h5 --preview pv >/dev/null 2>&1
python3 - <<'PY'
import struct
d = open('pv/region.vtk', 'rb').read()
tag = b'LOOKUP_TABLE default\n'
i = d.index(tag) + len(tag)
head = d[:i].decode()
dims = [int(x) for x in head.split('DIMENSIONS')[1].split('\n')[0].split()]
org = [float(x) for x in head.split('ORIGIN')[1].split('\n')[0].split()]
h, sh = 0.0005, 0.0003
n = dims[0] * dims[1] * dims[2]
v = struct.unpack('>%di' % n, d[i:i + 4 * n])
j = round((sh - org[1]) / h)
with open('slice.dat', 'w') as f:
    for k in range(dims[2]):
        for i in range(dims[0]):
            f.write("%g %g %d\n" % (1e3 * (org[0] + i * h - sh), 1e3 * (org[2] + k * h - sh), v[i + dims[0] * (j + dims[1] * k)]))
        f.write("\n")
PY
gnuplot -e "out='$work/out.png'" "$here/tissue-region.gp"
cd - >/dev/null
cp "$work/out.png" "$out"
