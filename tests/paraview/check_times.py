# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: fascia developers
# Opens a run's results.xdmf and organs.pvd together in ParaView, as a user
# would, and checks that they share one time per saved step (the HDF5 file's
# /steps/time) and that every organ is there at each of them. Run by t930.
# Usage: pvbatch check_times.py RESULTS.xdmf RESULTS.h5 ORGANS.pvd ORGAN_COUNT
import sys
import xml.etree.ElementTree as ET

import h5py
import paraview.simple as pvs


def main(xdmf, h5, pvd, organ_count):
    times = list(h5py.File(h5, "r")["/steps/time"][:])
    tissue = [float(t) for t in pvs.XDMFReader(FileNames=[xdmf]).TimestepValues]
    organs = [float(t) for t in pvs.PVDReader(FileName=pvd).TimestepValues]
    both = sorted(set(tissue) | set(organs))
    ok = tissue == times and both == times
    for t in times:
        present = [d for d in ET.parse(pvd).getroot().iter("DataSet") if float(d.get("timestep")) == t]
        if len(present) != organ_count:
            print("FAIL %s: %d organs at t = %.17g, expected %d" % (pvd, len(present), t, organ_count))
            ok = False
    print("%s and %s: %d saved steps, %d times in ParaView with both loaded%s" %
          (xdmf, pvd, len(times), len(both), "" if ok else ": FAILED (tissue %s, organs %s)" % (tissue, organs)))
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])))
