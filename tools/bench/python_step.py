#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: fascia developers
"""The cost of a step driven from Python against the same loop in C, on the
shipped demo scene (prepared into a temporary folder): each step poses the
uterus (a little higher), steps and reads its wrench; the C loop is
fascia_retract_loop (sim/python/retract_loop.c), the Python loop the
package's calls. Runs them alternately REPEATS times, reports the fastest of
each (ms per step) and the Python overhead in percent; --csv writes them.

    PYTHONPATH=build/python python3 tools/bench/python_step.py [--steps 150] [--repeats 5] [--csv FILE]
"""
import argparse
import os
import pathlib
import platform
import subprocess
import sys
import tempfile
import time

import fascia

ROOT = pathlib.Path(__file__).resolve().parents[2]


def python_loop(model_path, steps, lift):
    model = fascia.Model(model_path)
    s = fascia.Solver(model, dt=0.01, backend="cpu")
    start = time.perf_counter()
    for n in range(1, steps + 1):
        s.set_organ_pose("uterus", [0, lift * n / steps, 0], [1, 0, 0, 0])
        s.step()
        s.organ_wrench("uterus")
    return (time.perf_counter() - start) / steps * 1e3


def c_loop(program, model_path, steps, lift):
    out = subprocess.run([program, str(model_path), "uterus", str(lift * 1e3), str(steps)], check=True,
                         stdout=subprocess.PIPE, text=True).stdout
    return float(out.split("ms_per_step:")[1].split()[0])


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=int, default=150, help="steps per run (default 150: the demo's 1.5 s)")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--csv", help="write the figures here (a temporary name, renamed when complete)")
    parser.add_argument("--loop", default=os.environ.get("FASCIA_RETRACT_LOOP",
                                                         str(ROOT / "build" / "sim" / "python" / "fascia_retract_loop")))
    args = parser.parse_args()
    lift = 0.003
    with tempfile.TemporaryDirectory() as tmp:
        model = pathlib.Path(tmp) / "demo.h5"
        summary = fascia.prep(ROOT / "data" / "scenes" / "pelvis-female-demo.json", model)
        c_ms, py_ms = [], []
        for _ in range(args.repeats):
            c_ms.append(c_loop(args.loop, model, args.steps, lift))
            py_ms.append(python_loop(model, args.steps, lift))
    c, py = min(c_ms), min(py_ms)
    overhead = (py / c - 1) * 100
    print(f"demo: {summary['frames']} frames, {summary['samples']} samples; {args.steps} steps, best of {args.repeats}")
    print(f"C loop      {c:.4f} ms per step (pose, step, wrench)")
    print(f"Python loop {py:.4f} ms per step")
    print(f"Python overhead {overhead:+.2f} %")
    if args.csv:
        tmp = f"{args.csv}.tmp-{os.getpid()}"
        with open(tmp, "w") as f:
            f.write("scene,frames,samples,steps,repeats,c_ms_per_step,python_ms_per_step,overhead_percent,python,machine\n")
            f.write(f"pelvis-female-demo,{summary['frames']},{summary['samples']},{args.steps},{args.repeats},"
                    f"{c:.4f},{py:.4f},{overhead:.2f},{platform.python_version()},{platform.machine()}\n")
        os.replace(tmp, args.csv)
    return 0


if __name__ == "__main__":
    sys.exit(main())
