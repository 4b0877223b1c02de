# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: fascia developers
# The point arrays docs/results-format.md lists for the ParaView folder's
# tissue, tetrahedra, samples and frames files: {file kind: {array: components}}. Shared by
# check_run_pvd.py (pvbatch) and check_meshio.py (python3).


def documented(doc):
    kinds = {}
    for line in open(doc):
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 5 and cells[0] in ("tissue", "tetrahedra", "samples", "frames") and cells[1].startswith("`"):
            kinds.setdefault(cells[0], {})[cells[1].strip("`")] = int(cells[2])
    return kinds
