# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: fascia developers
# Opens a run's outputs with every reader a user may pick, an organ named
# with XML's special characters and non-ASCII among them:
#   - Python's XML parser: run.pvd, organs.pvd, results.xdmf and every file
#     run.pvd lists are well-formed, and the organ's name reads back as given;
#   - meshio: every file run.pvd lists (tissue, samples, frames, organs), with
#     field data length_unit_m = 1 and TimeValue = the .pvd's time (none in
#     a fixed organ's file, listed at every time), zlib compressed;
#   - h5py: results.h5, every dataset the XDMF sidecar names exists in it;
#   - ParaView (when run by pvbatch): run.pvd's blocks carry the organ's
#     name, the XDMF sidecar opens, and the tissue surface opens coloured by
#     strain (its active scalars) without being told.
# Run by t933.
# Usage: [pvbatch|python3] check_outputs.py DIR RESULTS.h5 NAME.txt
#   NAME.txt: the organ's name (UTF-8), in a file: no shell quoting to get wrong
import os
import sys
import xml.etree.ElementTree as ET

failures = []


def fail(text):
    failures.append(text)


def check_xml(folder, results, name):
    pvd = {}
    for path in (folder + "/run.pvd", folder + "/organs.pvd", results[:-3] + ".xdmf"):
        try:
            root = ET.parse(path).getroot()
        except ET.ParseError as e:
            fail("%s: not well-formed XML (%s)" % (path, e))
            continue
        if path.endswith(".pvd"):
            pvd[os.path.basename(path)] = [(float(d.get("timestep")), d.get("name"), d.get("file"))
                                           for d in root.iter("DataSet")]
    entries = pvd.get("run.pvd", [])
    if not any(n == name for _, n, _ in entries):
        fail("run.pvd: no block named %r among %s" % (name, sorted({n for _, n, _ in entries})))
    if not any(n == name for _, n, _ in pvd.get("organs.pvd", [])):
        fail("organs.pvd: no block named %r" % name)
    for _, _, f in entries:
        try:
            ET.parse(folder + "/" + f)
        except (ET.ParseError, OSError) as e:
            fail("%s: not well-formed XML (%s)" % (f, e))
    return entries


def check_meshio(folder, entries):
    try:
        import meshio
    except ImportError:
        print("meshio part skipped: meshio (Debian's python3-meshio) is not installed")
        return 0
    read = 0
    for t, name, f in entries:
        path = folder + "/" + f
        with open(path, "rb") as stream:
            head = stream.read(400)
        if b'compressor="vtkZLibDataCompressor"' not in head:
            fail("%s: not zlib-compressed" % f)
        try:
            mesh = meshio.read(path)
        except Exception as e:  # meshio raises several kinds
            fail("%s (%s): meshio cannot read it (%s)" % (f, name, e))
            continue
        read += 1
        unit = mesh.field_data.get("length_unit_m")
        time = mesh.field_data.get("TimeValue")
        if unit is None or float(unit.ravel()[0]) != 1:
            fail("%s: field data length_unit_m %s, expected 1" % (f, unit))
        shared = sum(e[2] == f for e in entries) > 1  # a fixed organ's one file serves every step: no time
        if (time is None) != shared or (time is not None and float(time.ravel()[0]) != t):
            fail("%s: field data TimeValue %s, the .pvd says %r%s" % (f, time, t, " for every step" if shared else ""))
        if name not in ("samples", "frames") and not any(c.type == "triangle" for c in mesh.cells):
            fail("%s (%s): no triangles, cells %s" % (f, name, [c.type for c in mesh.cells]))
    print("meshio read %d of %d files" % (read, len(entries)))
    return read


def check_h5(results):
    try:
        import h5py
    except ImportError:
        print("h5py part skipped: h5py (Debian's python3-h5py) is not installed")
        return
    root = ET.parse(results[:-3] + ".xdmf").getroot()
    with h5py.File(results, "r") as h5:
        for item in root.iter("DataItem"):
            file, _, dataset = item.text.strip().partition(":")
            if file != os.path.basename(results) or dataset not in h5:
                fail("results.xdmf names %s:%s, not in %s" % (file, dataset, results))
        if "unit" not in h5["/frames/position"].attrs:
            fail("%s /frames/position: no unit attribute" % results)


def check_paraview(folder, results, name):
    try:
        import paraview.simple as pvs
        from paraview import servermanager as sm
        from vtkmodules.vtkCommonDataModel import vtkMultiBlockDataSet
    except ImportError:
        print("ParaView part skipped: not run by pvbatch")
        return
    reader = pvs.OpenDataFile(folder + "/run.pvd")
    data = sm.Fetch(reader)
    blocks = [data.GetMetaData(k).Get(vtkMultiBlockDataSet.NAME()) for k in range(data.GetNumberOfBlocks())]
    if name not in blocks:
        fail("ParaView: run.pvd's blocks %s, no %r" % (blocks, name))
    xdmf = pvs.OpenDataFile(results[:-3] + ".xdmf")
    xdmf.UpdatePipeline()
    if not xdmf.PointData.keys():
        fail("ParaView: %s opens with no point arrays" % xdmf)
    tissue = sorted(f for f in os.listdir(folder) if f.startswith("tissue-"))
    if not tissue:
        fail("%s: no tissue-*.vtu" % folder)
        return
    surface = pvs.OpenDataFile(folder + "/" + tissue[-1])
    display = pvs.Show(surface, pvs.CreateView("RenderView"))
    coloured = list(display.ColorArrayName)
    if coloured[1:] != ["strain"]:
        fail("ParaView: %s opens coloured by %s, not strain" % (tissue[-1], coloured))


def main(folder, results, name):
    entries = check_xml(folder, results, name)
    check_meshio(folder, entries)
    check_h5(results)
    check_paraview(folder, results, name)
    for f in failures:
        print("FAIL " + f)
    print("%s: %d files listed, %d failures" % (folder, len(entries), len(failures)))
    return 1 if failures else 0


if __name__ == "__main__":
    with open(sys.argv[3], encoding="utf-8") as name_file:
        status = main(sys.argv[1], sys.argv[2], name_file.read())
    sys.stdout.flush()
    os._exit(status)
