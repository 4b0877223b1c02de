# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: fascia developers
# Opens a run's ParaView folder as a user would (run.pvd in pvbatch) and
# checks it against docs/results-format.md: ParaView picks its PVD reader,
# one time per saved step, the blocks tissue (when the model has its
# surface), samples, frames and every organ by name at each, the arrays of
# each file exactly as the docs' table lists them, displacement = position
# - rest position, and every frame shared with an organ on that organ's
# surface as drawn at that step. Run by t931.
# Usage: pvbatch check_run_pvd.py DIR RESULTS-FORMAT.md STEPS ORGAN,ORGAN,... [TOLERANCE]
#   TOLERANCE: how far (m) a shared frame may be from its organ's drawn
#   surface (default 1e-6: exact for fixed, prescribed, rigid and driven
#   organs; a deformable organ's skinned surface follows its frames less
#   closely)
import glob
import sys

import paraview.simple as pvs
from paraview import servermanager as sm
from paraview.vtk.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonDataModel import vtkMultiBlockDataSet
from vtkmodules.vtkFiltersCore import vtkImplicitPolyDataDistance
from vtkmodules.vtkFiltersGeometry import vtkGeometryFilter

from documented_arrays import documented


def arrays(block):
    pd = block.GetPointData()
    return {pd.GetArrayName(k): pd.GetArray(k).GetNumberOfComponents() for k in range(pd.GetNumberOfArrays())}


def leaf(block):
    while block is not None and block.IsA("vtkMultiBlockDataSet"):
        block = block.GetBlock(0)
    return block


def main(folder, doc, steps, organs, tolerance=1e-6):
    failures = []
    kinds = documented(doc)
    if set(kinds) != {"tissue", "tetrahedra", "samples", "frames"}:
        failures.append("the docs' table lists %s, not tissue, tetrahedra, samples and frames" % sorted(kinds))
    reader = pvs.OpenDataFile(folder + "/run.pvd")
    if reader.GetXMLName() != "PVDReader":
        failures.append("ParaView opens run.pvd with %s" % reader.GetXMLName())
    times = list(reader.TimestepValues)
    if len(times) != steps:
        failures.append("%d times, %d saved steps" % (len(times), steps))
    optional = [k for k, pattern in (("tissue", "tissue-*.vtu"), ("tetrahedra", "tetrahedra-*.vtu"))
                if glob.glob(folder + "/" + pattern)]
    names = optional + ["samples", "frames"] + organs
    for t in times:
        reader.UpdatePipeline(t)
        data = sm.Fetch(reader)
        got = [data.GetMetaData(k).Get(vtkMultiBlockDataSet.NAME()) for k in range(data.GetNumberOfBlocks())]
        if got != names:
            failures.append("t = %.17g: blocks %s, expected %s" % (t, got, names))
            continue
        blocks = {n: leaf(data.GetBlock(k)) for k, n in enumerate(got)}
        for kind in names[:-len(organs)] if organs else names:
            b = blocks[kind]
            if arrays(b) != kinds.get(kind):
                failures.append("t = %.17g %s: arrays %s, the docs list %s" % (t, kind, arrays(b), kinds.get(kind)))
                continue
            if kind == "tetrahedra":  # on the frames: their displacement
                continue
            x = vtk_to_numpy(b.GetPoints().GetData())
            u = vtk_to_numpy(b.GetPointData().GetArray("displacement"))
            rest = vtk_to_numpy(b.GetPointData().GetArray("rest_position"))
            if abs(x - rest - u).max() > 0:
                failures.append("t = %.17g %s: displacement differs from position - rest by %g" %
                                (t, kind, abs(x - rest - u).max()))
        for o in organs:
            if arrays(blocks[o]):
                failures.append("t = %.17g organ %s: arrays %s, the docs list none" % (t, o, arrays(blocks[o])))
        frames = blocks["frames"]
        x = vtk_to_numpy(frames.GetPoints().GetData())
        coupled = vtk_to_numpy(frames.GetPointData().GetArray("coupled_organ"))
        for k, o in enumerate(organs):
            polydata = vtkGeometryFilter()  # the organ's triangles as PolyData
            polydata.SetInputData(blocks[o])
            polydata.Update()
            surface = vtkImplicitPolyDataDistance()
            surface.SetInput(polydata.GetOutput())
            on = [abs(surface.EvaluateFunction(list(p))) for p in x[coupled == k]]
            if not on or max(on) > tolerance:
                failures.append("t = %.17g organ %s: %d shared frames, up to %s m off its surface" %
                                (t, o, len(on), max(on) if on else "-"))
    for f in failures:
        print("FAIL " + f)
    print("%s/run.pvd: %d times, blocks %s, %d failures" % (folder, len(times), names, len(failures)))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4].split(","),
                  *[float(a) for a in sys.argv[5:6]]))
