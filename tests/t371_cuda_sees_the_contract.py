#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: fascia developers
# cuda/ sees only the backend contract of the core: of sim/src it includes
# solve/backend.h alone (the contract, with the array tables a backend
# uploads), besides the shared per-sample math (sim/point) and the public
# headers (sim/include). A private header of sim/src included from cuda/
# (cpu/, model/, util/, organs/, io/ ...) fails this test, with the file and
# line that includes it.
import pathlib
import re
import sys

root = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else pathlib.Path(__file__).resolve().parent.parent)
src = root / "sim" / "src"
allowed = {"solve/backend.h"}
bad = []
files = sorted(p for p in (root / "cuda").iterdir() if p.suffix in (".c", ".h", ".cu"))
for path in files:
    for number, line in enumerate(path.read_text().splitlines(), 1):
        m = re.match(r'\s*#\s*include\s+"([^"]+)"', line)
        if m and (src / m.group(1)).is_file() and m.group(1) not in allowed:
            bad.append(f"{path.relative_to(root)}:{number}: includes sim/src/{m.group(1)}, a private header of the core")
for b in bad:
    print(b)
print(f"t371: {len(files)} files of cuda/ read, {len(bad)} includes of private core headers")
sys.exit(1 if bad or not files else 0)
