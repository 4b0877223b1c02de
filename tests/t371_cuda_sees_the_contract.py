#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: fascia developers
# cuda/ sees only the backend contract of the core: sim/contract/ (the
# operations and the tables of the arrays a backend uploads), besides the
# shared per-sample math (sim/point) and the public headers (sim/include).
# It fails on an include from cuda/ of any header of sim/src, and on a
# cuda/CMakeLists.txt that puts sim/src on an include path, with the file
# and line; and where the contract's own headers include sim/src.
import pathlib
import re
import sys

root = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else pathlib.Path(__file__).resolve().parent.parent)
src = root / "sim" / "src"
bad = []
files = sorted(p for p in (root / "cuda").iterdir() if p.suffix in (".c", ".h", ".cu"))
contract = sorted((root / "sim" / "contract").glob("*.h"))
for path in files + contract:
    for number, line in enumerate(path.read_text().splitlines(), 1):
        m = re.match(r'\s*#\s*include\s+"([^"]+)"', line)
        if m and (src / m.group(1)).is_file():
            bad.append(f"{path.relative_to(root)}:{number}: includes sim/src/{m.group(1)}, a private header of the core")
cmake = root / "cuda" / "CMakeLists.txt"
paths = 0
for number, line in enumerate(cmake.read_text().splitlines(), 1):
    if line.lstrip().startswith("#"):
        continue
    paths += "PROJECT_SOURCE_DIR}/sim" in line
    if re.search(r"sim/src\b", line):
        bad.append(f"{cmake.relative_to(root)}:{number}: puts sim/src on cuda/'s include path")
for b in bad:
    print(b)
print(f"t371: {len(files)} files of cuda/ and {len(contract)} of sim/contract read, {paths} include-path lines, "
      f"{len(bad)} breaches")
sys.exit(1 if bad or not files or not contract or paths == 0 else 0)
