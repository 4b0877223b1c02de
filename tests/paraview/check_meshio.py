# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: fascia developers
# Reads every per-step samples, frames and tetrahedra file of a run's
# ParaView folder with meshio, as a Python user would: the points, one
# vertex cell each (tetrahedra: tetra cells on the frames), the arrays of
# docs/results-format.md's table, displacement = position - rest.
# Run by t931.
# Usage: python3 check_meshio.py DIR RESULTS-FORMAT.md SAMPLES FRAMES
import glob
import sys

import meshio
import numpy

from documented_arrays import documented


def main(folder, doc, samples, frames):
    kinds = {kind: set(names) for kind, names in documented(doc).items()}  # (the tissue's .vtp: not meshio's)
    failures, files = [], 0
    for kind, count in (("samples", samples), ("frames", frames), ("tetrahedra", frames)):
        for path in sorted(glob.glob("%s/%s-*.vtu" % (folder, kind))):
            files += 1
            mesh = meshio.read(path)
            cells = sum(len(c.data) for c in mesh.cells if c.type == "vertex")
            if kind == "tetrahedra":  # on the frames; its cells are tetrahedra, its only array the displacement
                tetra = sum(len(c.data) for c in mesh.cells if c.type == "tetra")
                if len(mesh.points) != count or tetra == 0 or set(mesh.point_data) != kinds.get(kind):
                    failures.append("%s: %d points, %d tetrahedra, arrays %s" % (path, len(mesh.points), tetra,
                                                                                sorted(mesh.point_data)))
                continue
            if len(mesh.points) != count or cells != count:
                failures.append("%s: %d points, %d vertex cells, expected %d" % (path, len(mesh.points), cells, count))
            if set(mesh.point_data) != kinds.get(kind):
                failures.append("%s: arrays %s, the docs list %s" % (path, sorted(mesh.point_data), kinds.get(kind)))
                continue
            gap = numpy.abs(mesh.points - mesh.point_data["rest_position"] - mesh.point_data["displacement"]).max()
            if gap > 0:
                failures.append("%s: displacement differs from position - rest by %g" % (path, gap))
    if files == 0:
        failures.append("no samples-*.vtu or frames-*.vtu in %s" % folder)
    for f in failures:
        print("FAIL " + f)
    print("meshio %s read %d files in %s, %d failures" % (meshio.__version__, files, folder, len(failures)))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])))
