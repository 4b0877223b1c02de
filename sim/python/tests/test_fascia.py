# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: fascia developers
"""The Python package against the C library: struct layouts as the compiler
sees them, a retraction loop giving the same bits as the same loop in C
(fascia_retract_loop), the organ pose and wrench, the time step, the arrays'
shapes, and errors raised with the library's message."""
import os
import pathlib
import subprocess
import sys

import numpy as np
import pytest

import fascia
from fascia import _cdef, _ffi

ROOT = pathlib.Path(__file__).resolve().parents[3]


def test_layout_matches_the_compiler():
    layout = os.environ.get("FASCIA_LAYOUT")
    if not layout:
        pytest.skip("FASCIA_LAYOUT (the fascia_python_layout program) not set")
    lines = subprocess.run([layout], check=True, stdout=subprocess.PIPE, text=True).stdout.split("\n")
    seen = set()
    for line in filter(None, lines):
        struct, field, value = line.split()
        seen.add(struct)
        if field == "sizeof":
            assert _ffi.sizeof(struct) == int(value), struct
        else:
            assert _ffi.offsetof(struct, field) == int(value), (struct, field)
    assert seen == set(_cdef.STRUCTS)
    for struct in _cdef.STRUCTS:  # every field cffi knows is one the compiler printed
        printed = {l.split()[1] for l in lines if l.startswith(struct + " ")} - {"sizeof"}
        assert printed == {name for name, _ in _ffi.typeof(struct).fields}, struct


def retract(model, steps, lift=0.002):
    s = fascia.Solver(model, dt=0.01, backend="cpu")
    for n in range(1, steps + 1):
        s.set_organ_pose("uterus", [0, lift * n / steps, 0], [1, 0, 0, 0])
        s.step()
        force, torque = s.organ_wrench("uterus")
    return s, force, torque


def test_retraction_same_bits_as_c(demo_model, tmp_path):
    loop = os.environ.get("FASCIA_RETRACT_LOOP")
    if not loop:
        pytest.skip("FASCIA_RETRACT_LOOP (the fascia_retract_loop program) not set")
    dump = tmp_path / "c.bin"
    subprocess.run([loop, str(demo_model), "uterus", "2", "5", "--dump", str(dump)], check=True,
                   stdout=subprocess.PIPE)
    c = np.fromfile(dump, dtype=np.float64)
    s, force, torque = retract(fascia.Model(demo_model), 5)
    x = s.frame_states()[0].ravel()
    assert np.array_equal(np.concatenate([x, force, torque]), c)
    assert force[1] < 0  # lifted up (+y): the tissue holds the uterus back


def test_pose_wrench_time_step(demo_model):
    m = fascia.Model(demo_model)
    assert m.organs == ["uterus", "bladder"]
    s = fascia.Solver(m, dt=0.01, backend="cpu", newton_iterations=30, precond="block_jacobi")
    angle = np.radians(2)
    q = [np.cos(angle / 2), 0, 0, np.sin(angle / 2)]
    s.set_organ_pose("bladder", [0.001, 0, 0], q)
    s.step(2)
    assert s.time == pytest.approx(0.02, abs=1e-15)
    t, r = s.organ_pose("bladder")
    assert np.array_equal(t, [0.001, 0, 0]) and np.allclose(r, q, atol=1e-16)
    force, torque, point = s.organ_wrench("bladder", point=True)
    assert force.shape == torque.shape == point.shape == (3,)
    assert np.all(np.isfinite(force)) and np.linalg.norm(force) > 0
    s.dt = 0.005
    s.step()
    assert s.dt == 0.005 and s.time == pytest.approx(0.025, abs=1e-15)
    positions, rotations, velocities = s.frame_states()
    assert positions.shape[1:] == (3,) and rotations.shape[1:] == (4,) and velocities.shape[1:] == (6,)
    points, triangles = s.tissue_surface()
    assert points.shape[1] == 3 and triangles.shape[1] == 3 and triangles.max() < len(points)
    assert s.sample_positions().shape[1] == 3
    assert s.report["newton_iterations"] >= 1


def test_errors_carry_the_library_message(demo_model, tmp_path):
    with pytest.raises(fascia.Error, match="nowhere.h5") as e:
        fascia.Model(tmp_path / "nowhere.h5")
    assert e.value.status == "FASCIA_ERR_IO"
    m = fascia.Model(demo_model)
    with pytest.raises(fascia.Error, match="no setting 'bogus'"):
        fascia.Solver(m, bogus=1)
    with pytest.raises(fascia.Error, match="time step"):
        fascia.Solver(m, dt=0)
    s = fascia.Solver(m, backend="cpu")
    with pytest.raises(fascia.Error, match="time step -1 s is impossible"):
        s.dt = -1
    with pytest.raises(fascia.Error, match="no organ 'liver'; its organs are uterus, bladder"):
        s.organ_wrench("liver")
    with pytest.raises(fascia.Error, match="nothing changed"):
        s.set_organ_pose("uterus", [0, float("nan"), 0], [1, 0, 0, 0])
    with pytest.raises(fascia.Error, match="expected 4 numbers"):
        s.set_organ_pose("uterus", [0, 0, 0], [1, 0, 0])
    with pytest.raises(fascia.Error, match="unknown backend|backend"):
        fascia.Solver(m, backend="abacus")


def test_prep_from_a_dict_and_its_errors(tmp_path):
    with pytest.raises(fascia.Error, match="nowhere.json"):
        fascia.prep(tmp_path / "nowhere.json", tmp_path / "m.h5")
    with pytest.raises(fascia.Error) as e:
        fascia.prep({"organs": []}, tmp_path / "m.h5")
    assert "scene" in str(e.value)
    assert not (tmp_path / "m.h5").exists()
    assert not any(p.name.startswith(".fascia-scene-") for p in pathlib.Path.cwd().iterdir())


def test_example_runs(demo_model):
    out = subprocess.run([sys.executable, str(ROOT / "examples" / "retract.py"), str(demo_model), "--steps", "3"],
                         check=True, stdout=subprocess.PIPE, text=True).stdout
    assert "ms per step" in out
