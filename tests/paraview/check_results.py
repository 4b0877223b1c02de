# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: fascia developers
# Opens a results sidecar (NAME.xdmf) with every XDMF reader ParaView offers
# and checks what each shows against the HDF5 file, read with h5py: one time
# per saved step, the blocks "frames" and "samples" in that order at every
# step, their point counts, arrays and values; displacement = position - rest;
# every dataset with a unit and a meaning. Run by tests/t230 under pvbatch.
# Usage: pvbatch check_results.py RESULTS.xdmf RESULTS.h5
import sys

import h5py
import numpy as np
import paraview.simple as pvs
from paraview import servermanager
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonDataModel import vtkCompositeDataSet

READERS = ("Xdmf3ReaderS", "Xdmf3ReaderT", "XDMFReader")
failures = []


def fail(text):
    failures.append(text)
    print("FAIL " + text, flush=True)


def leaves(data, path=""):
    """(name path, dataset) of every leaf of a composite, in order."""
    if data is None:
        return []
    if data.IsA("vtkMultiBlockDataSet"):
        count, child = data.GetNumberOfBlocks(), data.GetBlock
    elif data.IsA("vtkPartitionedDataSet"):  # Xdmf3ReaderS: a multi-piece dataset
        count, child = data.GetNumberOfPartitions(), data.GetPartition
    else:
        return [(path, data)]
    out = []
    for i in range(count):
        meta = data.GetMetaData(i) if data.HasMetaData(i) else None
        name = meta.Get(vtkCompositeDataSet.NAME()) if meta and meta.Has(vtkCompositeDataSet.NAME()) else ""
        out += leaves(child(i), path + "/" + name)
    return out


def open_reader(kind, path):
    if kind == "XDMFReader":
        return pvs.XDMFReader(FileNames=[path])
    return getattr(pvs, kind)(FileName=[path])


def main(xdmf, h5):
    f = h5py.File(h5, "r")
    times = f["/steps/time"][:]
    blocks = ["frames"] + (["samples"] if "samples" in f else [])
    def check_attrs(name, obj):
        if isinstance(obj, h5py.Dataset) and not name.startswith("xdmf/step_") and name != "provenance":
            for a in ("unit", "meaning"):
                if a not in obj.attrs:
                    fail("%s: dataset /%s has no attribute '%s'" % (h5, name, a))

    f.visititems(check_attrs)
    expected_arrays = {
        "frames": ["displacement", "axis_x", "axis_y", "axis_z", "rest_position", "organ", "kind"],
        "samples": ["displacement", "rest_position", "organ", "material", "volume"] + list(f.get("/samples/fields", {}).keys()),
    }
    for kind in READERS:
        reader = open_reader(kind, xdmf)
        shown = [float(t) for t in reader.TimestepValues]
        if len(shown) != len(times) or not np.array_equal(np.array(shown), times):
            fail("%s: times %s, the file has %s" % (kind, shown, list(times)))
            continue
        for t, time in enumerate(times):
            reader.UpdatePipeline(time)
            got = leaves(servermanager.Fetch(reader))
            if len(got) != len(blocks):
                fail("%s step %d: %d blocks, expected %d" % (kind, t, len(got), len(blocks)))
                continue
            if kind == "XDMFReader" and [p for p, _ in got] != ["/" + b for b in blocks]:
                fail("%s step %d: blocks named %s, expected %s" % (kind, t, [p for p, _ in got], blocks))
            for block, (_, data) in zip(blocks, got):
                where = "%s step %d block %s" % (kind, t, block)
                position = f["/%s/position" % block][t]
                if data.GetNumberOfPoints() != len(position) or data.GetNumberOfCells() != len(position):
                    fail("%s: %d points and %d cells, the file has %d points" %
                         (where, data.GetNumberOfPoints(), data.GetNumberOfCells(), len(position)))
                    continue
                points = vtk_to_numpy(data.GetPoints().GetData())
                if not np.array_equal(points, position):
                    fail("%s: points differ from /%s/position[%d] by %g" %
                         (where, block, t, np.abs(points - position).max()))
                arrays = data.GetPointData()
                for name in expected_arrays[block]:
                    array = arrays.GetArray(name)
                    if array is None:
                        fail("%s: no array '%s'" % (where, name))
                        continue
                    value = vtk_to_numpy(array)
                    if name in f["/" + block]:
                        source = f["/%s/%s" % (block, name)]
                    else:
                        source = f["/samples/fields/" + name]
                    want = source[t] if source.maxshape[0] is None else source[:]  # a series, or static
                    if value.shape != want.shape or not np.array_equal(value, want, equal_nan=True):
                        fail("%s: array '%s' differs from the file" % (where, name))
                displacement = vtk_to_numpy(arrays.GetArray("displacement"))
                rest = f["/%s/rest_position" % block][:]
                if np.abs(displacement - (position - rest)).max() > 1e-15 * max(1.0, np.abs(position).max()):
                    fail("%s: displacement is not position - rest_position" % where)
        pvs.Delete(reader)
    # the axes are the columns of the rotation
    q = f["/frames/rotation"][:]
    w, x, y, z = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    ax = np.stack([1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y)], -1)
    if np.abs(ax - f["/frames/axis_x"][:]).max() > 1e-14:
        fail("/frames/axis_x is not the first column of /frames/rotation")
    print("%s: %d steps, blocks %s, read by %s: %s" %
          (xdmf, len(times), blocks, ", ".join(READERS), "FAILED" if failures else "all agree with the HDF5 file"))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2]))
