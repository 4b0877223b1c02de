# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: fascia developers
"""fascia from Python: prepare a model, load it, step a solver, drive organs
from a host simulator and read their wrench. A thin layer over the C library
libfascia_sim.so (cffi, ABI mode: docs/python.md says why); every number is
computed there. Units are SI (m, s, kg, N, N m), positions in the world
frame, rotations unit quaternions (w, x, y, z).

    import fascia
    fascia.prep("scene.json", "model.h5")
    m = fascia.Model("model.h5")
    s = fascia.Solver(m, dt=0.01)
    s.set_organ_pose("uterus", [0, 0.002, 0], [1, 0, 0, 0])
    s.step()
    force, torque = s.organ_wrench("uterus")
"""
import json
import os
import shutil
import subprocess
import tempfile

import numpy as np

from ._cdef import CDEF, ENUMS
from . import _paths

__all__ = ["Error", "prep", "Model", "Solver", "version", "library_path"]


class Error(Exception):
    """A failure of the library, with its message (the object, what is wrong,
    what to do) and status name ("FASCIA_ERR_ARGUMENT", ...)."""

    def __init__(self, message, status=None):
        super().__init__(message)
        self.status = status


def _load():
    import cffi

    ffi = cffi.FFI()
    ffi.cdef(CDEF)
    path = library_path()
    try:
        lib = ffi.dlopen(path)
    except OSError as e:
        raise ImportError(
            f"fascia: cannot load the library '{path}' ({e}); build fascia (cmake --build build) or set "
            "FASCIA_LIBRARY to its libfascia_sim.so") from e
    return ffi, lib


def library_path():
    """The libfascia_sim.so this package uses: $FASCIA_LIBRARY, else the one
    it was built or installed with."""
    return os.environ.get("FASCIA_LIBRARY") or _paths.library()


_ffi, _lib = _load()


def version():
    """The library's version, "MAJOR.MINOR.PATCH"."""
    return _ffi.string(_lib.fascia_version()).decode()


class _Context:
    """A fascia_ctx: the last error message of the objects made on it."""

    def __init__(self, threads=0):
        d = _lib.fascia_ctx_def_default()
        d.threads = threads
        out = _ffi.new("fascia_ctx **")
        if _lib.fascia_ctx_create(_ffi.new("fascia_ctx_def *", d), out) != 0:
            raise Error("fascia: out of memory for a context")
        self.ptr = _ffi.gc(out[0], lambda p: _lib.fascia_ctx_destroy(_ffi.new("fascia_ctx **", p)))

    def check(self, status):
        if status != 0:
            raise Error(_ffi.string(_lib.fascia_ctx_message(self.ptr)).decode(errors="replace"),
                        _ffi.string(_lib.fascia_status_name(status)).decode())


def _as_path(path):
    return os.fsencode(os.fspath(path))


class Model:
    """A model file (fascia prep's output), loaded."""

    def __init__(self, path):
        self.path = os.fspath(path)
        self._ctx = _Context()
        out = _ffi.new("fascia_model **")
        self._ctx.check(_lib.fascia_model_load(self._ctx.ptr, _as_path(path), out))
        self.ptr = _ffi.gc(out[0], lambda p: _lib.fascia_model_destroy(_ffi.new("fascia_model **", p)))

    @property
    def organs(self):
        """Organ names, in the model's order."""
        return [_ffi.string(_lib.fascia_model_organ_name(self.ptr, k)).decode()
                for k in range(_lib.fascia_model_organ_count(self.ptr))]

    def organ_index(self, name):
        k = _lib.fascia_model_find_organ(self.ptr, name.encode())
        if k < 0:
            raise Error(f"model '{self.path}': no organ '{name}'; its organs are {', '.join(self.organs) or 'none'}",
                        "FASCIA_ERR_ARGUMENT")
        return k


def _vector(values, size, what):
    a = np.ascontiguousarray(values, dtype=np.float64)
    if a.shape != (size,):
        raise Error(f"{what}: expected {size} numbers, found shape {a.shape}", "FASCIA_ERR_ARGUMENT")
    return a


def _out(shape):
    a = np.empty(shape, dtype=np.float64)
    return a, _ffi.from_buffer("double[]", a)


class Solver:
    """Implicit Euler steps of a model (fascia/solver.h). dt: the time step
    (s); settings: fields of fascia_solver_def by name (backend="cpu",
    newton_iterations=8, precond="jacobi", ...). The model must outlive the
    solver (the solver keeps a reference). One thread at a time per solver;
    solvers in different threads are independent."""

    def __init__(self, model, dt=0.01, **settings):
        self.model = model
        self._ctx = _Context(settings.get("threads", 0))
        d = _lib.fascia_solver_def_default()
        fields = dict(_ffi.typeof("fascia_solver_def").fields)
        keep = []  # strings the def points at, alive until the solver is made
        for key, value in settings.items():
            if key not in fields or key.endswith("_"):
                valid = ", ".join(k for k in fields if not k.endswith("_") and k != "time_step")
                raise Error(f"Solver: no setting '{key}'; the settings are {valid}", "FASCIA_ERR_ARGUMENT")
            if key in ENUMS and isinstance(value, str):
                if value not in ENUMS[key]:
                    raise Error(f"Solver: {key} '{value}'; give one of {', '.join(ENUMS[key])}",
                                "FASCIA_ERR_ARGUMENT")
                value = ENUMS[key][value]
            if key == "backend":
                value = _ffi.new("char[]", value.encode())
                keep.append(value)
            setattr(d, key, value)
        d.time_step = dt
        out = _ffi.new("fascia_solver **")
        self._ctx.check(_lib.fascia_solver_create(self._ctx.ptr, model.ptr, _ffi.new("fascia_solver_def *", d), out))
        self.ptr = _ffi.gc(out[0], lambda p: _lib.fascia_solver_destroy(_ffi.new("fascia_solver **", p)))
        self._report = _ffi.new("fascia_solve_report *")
        self._frames = _lib.fascia_solver_frame_count(self.ptr)
        self._samples = _lib.fascia_solver_sample_count(self.ptr)
        self._t, self._q = _ffi.new("double[3]"), _ffi.new("double[4]")
        self._f, self._m = _ffi.new("double[3]"), _ffi.new("double[3]")

    # ------------------------------------------------------------ stepping

    def step(self, n=1):
        """n implicit Euler steps of the time step dt. On failure raises
        Error; the state is the one before the failed step."""
        step, ptr, report, check = _lib.fascia_solver_step, self.ptr, self._report, self._ctx.check
        for _ in range(n):
            status = step(ptr, report)
            if status:
                check(status)

    def solve_static(self):
        """Static equilibrium at the current time, from the current state."""
        self._ctx.check(_lib.fascia_solver_solve_static(self.ptr, self._report))

    @property
    def report(self):
        """What the last step or static solve did (fascia_solve_report)."""
        r = self._report
        out = {k: getattr(r, k) for k, _ in _ffi.typeof("fascia_solve_report").fields if k != "profile"}
        out["profile"] = {k: getattr(r.profile, k) for k, _ in _ffi.typeof("fascia_profile").fields}
        return out

    @property
    def time(self):
        """The solver's time, s."""
        return _lib.fascia_solver_time(self.ptr)

    @time.setter
    def time(self, value):
        self._ctx.check(_lib.fascia_solver_set_time(self.ptr, value))

    @property
    def dt(self):
        """The time step of the next step, s; may change between steps."""
        return _lib.fascia_solver_time_step(self.ptr)

    @dt.setter
    def dt(self, value):
        self._ctx.check(_lib.fascia_solver_set_time_step(self.ptr, value))

    @property
    def backend(self):
        return _ffi.string(_lib.fascia_solver_backend(self.ptr)).decode()

    # ------------------------------------------------------------ organs

    def set_organ_pose(self, name, translation, rotation_wxyz):
        """Drives an organ as a host simulator's organ: its coupling frames
        reach p = R p_rest + translation (m) at the end of the next step and
        stay (fascia_solver_organ_set_pose)."""
        t = _vector(translation, 3, f"organ '{name}' translation")
        q = _vector(rotation_wxyz, 4, f"organ '{name}' rotation")
        self._ctx.check(_lib.fascia_solver_organ_set_pose(self.ptr, self.model.organ_index(name),
                                                          _ffi.from_buffer("double[]", t),
                                                          _ffi.from_buffer("double[]", q)))

    def release_organ(self, name):
        """Hands a driven organ back to its model kind."""
        self._ctx.check(_lib.fascia_solver_organ_release(self.ptr, self.model.organ_index(name)))

    def organ_pose(self, name):
        """(translation [3], rotation [4] w x y z): p_world = R p_rest + t."""
        self._ctx.check(_lib.fascia_solver_organ_pose(self.ptr, self.model.organ_index(name), self._t, self._q))
        return np.array(list(self._t)), np.array(list(self._q))

    def organ_wrench(self, name, point=False):
        """(force [3] N, torque [3] N m) the tissue applies on the organ, the
        torque about its reference point: the centre of the volume its rest
        surface encloses, carried by its pose (fascia/organs.h). point=True
        adds that point (m) as a third array."""
        p = _ffi.new("double[3]") if point else _ffi.NULL
        self._ctx.check(_lib.fascia_solver_organ_wrench(self.ptr, self.model.organ_index(name), self._f, self._m, p))
        out = (np.array(list(self._f)), np.array(list(self._m)))
        return out + (np.array(list(p)),) if point else out

    # ------------------------------------------------------------ state

    def tissue_surface(self):
        """(points [V, 3] m, triangles [T, 3] vertex indices): the tissue's
        surface as the frames carry it now; empty when the model has none."""
        surface = _lib.fascia_model_tissue_surface(self.model.ptr)
        V, T = surface.vertex_count, surface.triangle_count
        points, buf = _out((V, 3))
        triangles = np.zeros((T, 3), dtype=np.int32)
        if V:
            self._ctx.check(_lib.fascia_solver_tissue_surface(self.ptr, buf, _ffi.NULL))
        if T:
            triangles[:] = np.frombuffer(_ffi.buffer(surface.triangles, 12 * T), dtype=np.int32).reshape(T, 3)
        return points, triangles

    def sample_positions(self):
        """[S, 3] the samples' deformed positions, m."""
        out, buf = _out((self._samples, 3))
        _lib.fascia_solver_sample_positions(self.ptr, buf)
        return out

    def frame_states(self):
        """(positions [N, 3] m, rotations [N, 4] w x y z, velocities [N, 6]
        linear m/s then angular rad/s): copies of the frames' state."""
        N = self._frames

        def copy(ptr, width):
            return np.frombuffer(_ffi.buffer(ptr, 8 * width * N), dtype=np.float64).reshape(N, width).copy()

        return (copy(_lib.fascia_solver_frame_positions(self.ptr), 3),
                copy(_lib.fascia_solver_frame_rotations(self.ptr), 4),
                copy(_lib.fascia_solver_frame_velocities(self.ptr), 6))


def _cli():
    cli = os.environ.get("FASCIA_CLI") or _paths.cli()
    if cli and os.path.exists(cli):
        return cli
    found = shutil.which("fascia")
    if not found:
        raise Error("fascia.prep: no 'fascia' program (built with prep) here nor on PATH; build fascia or set "
                    "FASCIA_CLI", "FASCIA_ERR_UNSUPPORTED")
    return found


def prep(scene, output):
    """Builds a model file from a scene: scene is a scene file's path or the
    scene as a dict (relative paths in it are taken from the current folder).
    Runs `fascia prep` (the prep library behind the CLI, with its checks:
    the output written under a temporary name, never over an input). Returns
    its summary (a dict: frames, samples, coupling, ...)."""
    tmp = None
    if isinstance(scene, dict):
        tmp = tempfile.NamedTemporaryFile("w", suffix=".json", prefix=".fascia-scene-", dir=os.getcwd(),
                                          delete=False)
        with tmp:
            json.dump(scene, tmp)
        scene = tmp.name
    try:
        run = subprocess.run([_cli(), "prep", os.fspath(scene), "-o", os.fspath(output), "--json"],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    finally:
        if tmp:
            os.unlink(tmp.name)
    last = run.stdout.strip().splitlines()[-1] if run.stdout.strip() else ""
    try:
        summary = json.loads(last) if last else {}
    except ValueError:
        summary = {}
    if run.returncode != 0:
        message = summary.get("error") or (run.stderr.strip().splitlines() or ["fascia prep failed"])[-1]
        raise Error(message, "FASCIA_ERR_ARGUMENT" if run.returncode == 2 else None)
    return summary
