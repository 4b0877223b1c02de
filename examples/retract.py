#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: fascia developers
"""A retraction driven from Python, as a host simulator would drive it: each
step the host's uterus pose (lifted a little more, tilted a little more) goes
to fascia, fascia steps the tissue, and the tissue's wrench on the uterus
comes back (what a haptic device would render).

    PYTHONPATH=build/python python3 examples/retract.py [MODEL.h5] [--steps N] [--lift-mm MM]

Without MODEL.h5 it prepares the shipped demo scene
(data/scenes/pelvis-female-demo.json) into a temporary folder first.
"""
import argparse
import pathlib
import sys
import tempfile
import time

import numpy as np

import fascia


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("model", nargs="?", help="a model file (default: the demo scene, prepared now)")
    parser.add_argument("--organ", default="uterus")
    parser.add_argument("--steps", type=int, default=50, help="steps of 0.01 s (default 50)")
    parser.add_argument("--lift-mm", type=float, default=3.0, help="lift at the end, mm (default 3)")
    parser.add_argument("--tilt-deg", type=float, default=4.0, help="tilt about x at the end, degrees (default 4)")
    args = parser.parse_args()

    with tempfile.TemporaryDirectory() as tmp:
        model_path = args.model
        if model_path is None:
            scene = pathlib.Path(__file__).resolve().parents[1] / "data" / "scenes" / "pelvis-female-demo.json"
            model_path = pathlib.Path(tmp) / "demo.h5"
            summary = fascia.prep(scene, model_path)
            print(f"prepared {scene.name}: {summary['frames']} frames, {summary['samples']} samples")
        model = fascia.Model(model_path)
        solver = fascia.Solver(model, dt=0.01, backend="cpu")
        print(f"fascia {fascia.version()}, organs {', '.join(model.organs)}, backend {solver.backend}")
        print("step  time_s  lift_mm  force_N (x y z)                  torque_mN_m (x y z)")
        start = time.perf_counter()
        for n in range(1, args.steps + 1):
            # the host's pose of the organ: up (+y, against the demo's gravity) and tilted about x
            lift = args.lift_mm * 1e-3 * n / args.steps
            half = np.radians(args.tilt_deg) * n / args.steps / 2
            solver.set_organ_pose(args.organ, [0, lift, 0], [np.cos(half), np.sin(half), 0, 0])
            solver.step()
            force, torque = solver.organ_wrench(args.organ)
            if n % max(1, args.steps // 10) == 0 or n == args.steps:
                f, t = force, torque * 1e3
                print(f"{n:4d}  {solver.time:6.3f}  {lift * 1e3:7.3f}  "
                      f"{f[0]:9.5f} {f[1]:9.5f} {f[2]:9.5f}   {t[0]:9.5f} {t[1]:9.5f} {t[2]:9.5f}")
        elapsed = time.perf_counter() - start
        print(f"{elapsed / args.steps * 1e3:.3f} ms per step (pose, step, wrench), {args.steps} steps")
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except fascia.Error as e:
        print(f"retract: {e}", file=sys.stderr)
        sys.exit(1)
