# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: fascia developers
# A results file against its documentation: every dataset and root attribute
# of the HDF5 file (read with h5py) is in docs/results-format.md's table,
# every entry of the table that is not optional is in the file, and every
# dataset carries the attributes the docs give it (unit and meaning; and
# time_meaning on /steps/time), nothing else. Run by t230.
# Usage: python3 check_results_docs.py RESULTS.h5 RESULTS-FORMAT.md
import re
import sys

import h5py

OPTIONAL = ("optional", "when it had one", "with samples", "only with")


def documented(doc):
    """[(regex of paths or root attribute names, optional?)] from the table."""
    entries, inside = [], False
    for line in open(doc):
        if line.startswith("| path | shape | type | unit | meaning |"):
            inside = True
            continue
        if inside and not line.startswith("|"):
            break
        if not inside or line.startswith("|---"):
            continue
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        names = re.findall(r"`([^`]+)`", cells[0])
        optional = any(word in cells[4] for word in OPTIONAL)
        if cells[0].startswith("`/` attribute"):
            entries.append(("@" + names[1], optional))
            continue
        folder = names[0].rsplit("/", 1)[0]
        for k, name in enumerate(names):
            path = name if name.startswith("/") else folder + "/" + name
            pattern = re.escape(path).replace("NAME", "[^/]+").replace("step_t", "step_[0-9]+")
            entries.append((pattern, optional))
    return entries


def main(h5, doc):
    entries, failures, seen = documented(doc), [], set()
    with h5py.File(h5, "r") as f:
        found = ["@" + a for a in f.attrs]
        f.visititems(lambda name, obj: found.append("/" + name) if isinstance(obj, h5py.Dataset) else None)
        for path in found:
            match = [p for p, _ in entries if re.fullmatch(p, path)]
            if not match:
                failures.append("%s is in the file, not in the docs' table" % path)
            seen.update(match)
            if not path.startswith("@"):
                # the docs: every dataset but /provenance and the views under /xdmf/step_t
                bare = path == "/provenance" or re.match(r"/xdmf/step_[0-9]+/", path)
                allowed = set() if bare else {"unit", "meaning"} | ({"time_meaning"} if path == "/steps/time" else set())
                if set(f[path].attrs) != allowed:
                    failures.append("%s has attributes %s, the docs give %s" % (path, sorted(f[path].attrs),
                                                                               sorted(allowed)))
    for pattern, optional in entries:
        if not optional and pattern not in seen:
            failures.append("the docs' %s is not in the file" % pattern.replace("\\", ""))
    for f in failures:
        print("FAIL " + f)
    print("%s against %s: %d paths, %d table entries, %d failures" % (h5, doc, len(found), len(entries), len(failures)))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2]))
