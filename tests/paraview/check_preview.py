# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: fascia developers
# Opens prep's preview (preview.pvd) in ParaView as a user would and checks
# its blocks: every organ under its name, then region, frames, samples and
# coupling; the frames' kind says what holds each (1 on a fixed organ,
# 2 prescribed, 3 rigid: the kind of the organ it is shared with, 0 free);
# the counts of frames, samples, shared frames and region voxels as given.
# Run by t932.
# Usage: pvbatch check_preview.py PREVIEW.pvd ORGAN:KIND,... FRAMES SAMPLES SHARED REGION_VOXELS
import sys

import paraview.simple as pvs
from paraview import servermanager as sm
from paraview.vtk.util.numpy_support import vtk_to_numpy


def main(pvd, organs, frames, samples, shared, region_voxels):
    organs = [o.split(":") for o in organs.split(",")]
    failures = []
    reader = pvs.OpenDataFile(pvd)
    reader.UpdatePipeline()
    data = sm.Fetch(reader)
    blocks = {}
    for k in range(data.GetNumberOfBlocks()):
        b = data.GetBlock(k)
        while b is not None and b.IsA("vtkMultiBlockDataSet"):
            b = b.GetBlock(0)
        blocks[data.GetMetaData(k).Get(data.NAME())] = b
    names = [o for o, _ in organs] + ["region", "frames", "samples", "coupling"]
    if list(blocks) != names:
        failures.append("blocks %s, expected %s" % (list(blocks), names))
    else:
        f = blocks["frames"].GetPointData()
        kind, with_organ = vtk_to_numpy(f.GetArray("kind")), vtk_to_numpy(f.GetArray("shared_with_organ"))
        for k, (name, organ_kind) in enumerate(organs):
            on = kind[with_organ == k]
            if len(on) == 0 or (on != int(organ_kind)).any():
                failures.append("frames shared with %s: kinds %s, expected %s" % (name, sorted(set(on)), organ_kind))
        if (kind[with_organ < 0] != 0).any():
            failures.append("frames shared with no organ: kinds %s, expected 0" % sorted(set(kind[with_organ < 0])))
        counts = (blocks["frames"].GetNumberOfPoints(), blocks["samples"].GetNumberOfPoints(),
                  blocks["coupling"].GetNumberOfPoints(),
                  int((vtk_to_numpy(blocks["region"].GetPointData().GetArray("region")) > 0).sum()))
        if counts != (frames, samples, shared, region_voxels):
            failures.append("frames, samples, shared frames, region voxels %s, expected %s" %
                            (counts, (frames, samples, shared, region_voxels)))
    for f in failures:
        print("FAIL " + f)
    print("%s: blocks %s, %d failures" % (pvd, list(blocks), len(failures)))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2], *[int(a) for a in sys.argv[3:7]]))
