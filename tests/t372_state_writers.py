#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: fascia developers
# The writers map of docs/architecture.md, as the code must keep it:
#  - the organs (sim/src/organs/) know no solver: of sim/src/solve they
#    include motion.h alone (the prescribed motions), never the solver's
#    internals or the backend contract; the organ API that hands them the
#    solver's arrays is solve/organ_api.c;
#  - the CPU backend (sim/src/cpu/) knows no solver either: it includes
#    nothing of sim/src/solve, and is made from the contract's setup;
#  - the system's state (x, q, A) is written by fascia_system_set_state
#    from three places only: system.c (the rest state at creation), the CPU
#    backend (its trial states, cpu/backend_cpu.c) and the solver's
#    host_system (solve/solver.c), which every host query goes through;
#    its load factor (gravity_scale) by the same three, and by the solver's
#    loads gradient (the reactions' full load, put back after);
#  - the run's state, the solver's x, q, u, d and gradient, is written in
#    solve/solver.c alone: a backend hands its result back read-only
#    (fascia_step_result) and fascia_solver_take_result copies it; the
#    organs' functions get the arrays (fascia_organs_state) from solver.c,
#    or from solve/organ_api.c for an organ's release.
# A breach fails with the file and line.
import pathlib
import re
import sys

root = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else pathlib.Path(__file__).resolve().parent.parent)
src = root / "sim" / "src"
bad = []
organs = sorted(p for p in (src / "organs").iterdir() if p.suffix in (".c", ".h"))
cpu = sorted(p for p in (src / "cpu").iterdir() if p.suffix in (".c", ".h"))
for path in organs + cpu:
    for number, line in enumerate(path.read_text().splitlines(), 1):
        m = re.match(r'\s*#\s*include\s+"(solve/[^"]+)"', line)
        if m and (m.group(1) != "solve/motion.h" or path in cpu):
            who = "the CPU backend knows" if path in cpu else "the organs know"
            bad.append(f"{path.relative_to(root)}:{number}: includes sim/src/{m.group(1)}: {who} no solver")
def writes(pattern, allowed, what, advice):
    """Lines of sim/src's C files matching pattern outside the (file, function) pairs allowed (function None: any
    function of that file): each a breach in bad. Returns how many lines matched."""
    count = 0
    for path in sorted(src.rglob("*.c")):
        function = None
        name = path.relative_to(src).as_posix()
        for number, line in enumerate(path.read_text().splitlines(), 1):
            m = re.match(r"^[a-z].*?\b(\w+)\(", line)
            if m and not line.startswith(("typedef", "return")):
                function = m.group(1)
            if not re.search(pattern, line):
                continue
            count += 1
            if (name, None) in allowed or (name, function) in allowed:
                continue
            bad.append(f"{path.relative_to(root)}:{number}: writes the {what} in {function}(); {advice}")
    return count


calls = writes(r"(?<!void )fascia_system_set_state\(", {("cpu/system.c", None), ("cpu/backend_cpu.c", None),
                                                          ("solve/solver.c", "host_system")},
               "system's state", "go through the solver's host_system or the backend")
scales = writes(r"sys->gravity_scale\s*=[^=]", {("cpu/system.c", "fascia_system_create"),
                                                ("cpu/backend_cpu.c", "cpu_begin"), ("cpu/backend_cpu.c", "cpu_gradient"),
                                                ("solve/solver.c", "host_system"),
                                                ("solve/solver.c", "fascia_solver_loads_gradient")},
                "system's load factor", "the solver's load_factor is the run's, the backend's step values carry it")
run = r"(S|solver)->(x|q|u|d|gradient)\b"
states = writes(rf"(memcpy|memset)\(\s*{run}|{run}\s*\[[^]]*\]\s*[-+*/]?=[^=]|fascia_step_result\b.*=.*(S|solver)->",
                {("solve/solver.c", None)}, "run's state", "solver.c owns it: hand results back read-only")
handed = writes(r"fascia_organs_state\s+\w+\s*=", {("solve/solver.c", None), ("solve/organ_api.c", None)},
                "run's state (to the organs)", "only the solver hands the organs its arrays")
for b in bad:
    print(b)
print(f"t372: {len(organs)} files of sim/src/organs and {len(cpu)} of sim/src/cpu read, {calls} writes of the system's state, {scales} of its load "
      f"factor, {states} of the run's state, {handed} hand-overs to the organs, {len(bad)} out of place")
sys.exit(1 if bad or not organs or not cpu or 0 in (calls, scales, states, handed) else 0)
