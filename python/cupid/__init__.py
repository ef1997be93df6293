"""cupid from Python: run a model through libcupid and read its results as numpy arrays.

    import cupid
    p = cupid.Problem("examples/bar/bar.yaml")   # or a dict with the model file's keys
    p.solve()
    u = p.pd_displacement                        # (n, 3) numpy array
    u_tip, region = p.sample([[5, 100, 5]])
    print(p.info["reaction_sum"], p.info["imbalance"])
    p.write_outputs()                            # the model's output files, as `cupid run`

The library is loaded with ctypes (python3 and python3-numpy from Debian; nothing else):
from $CUPID_LIBRARY, else the package's own copy (`pip install ./python` puts one beside this
file), else the build tree beside this package (build/libcupid.so), else the system's (an
installed libcupid). Errors raise cupid.Error, whose message carries the model
file's file:line:col, and whose exit_code is the command line's (1 model, 2 numerical, 3 I/O,
4 internal).
"""
import ctypes
import ctypes.util
import json
import os

import numpy as np

__all__ = ["Problem", "Error", "GrowthStopped", "Interrupted", "library_path"]

_c_int64 = ctypes.c_int64


class Error(RuntimeError):
    """A cupid failure: .status (e.g. "model error"), .exit_code and the message."""

    def __init__(self, message, status, exit_code):
        super().__init__(message)
        self.status = status
        self.exit_code = exit_code


class GrowthStopped(Error):
    """Crack growth stopped before its last load step (a crack reached a coupling zone, or the
    body collapsed): the message says which. The problem stays solved up to there: its fields,
    info and write_outputs() hold the steps that ran (the command line exits with status 2)."""


class Interrupted(Error):
    """SIGINT (Ctrl-C) or SIGTERM stopped solve() at a checkpoint (a dynamic run or crack growth;
    the command line exits with status 5): Problem(..., resume=True) continues the run from it."""


_INTERRUPTED = 8  # CUPID_ERR_INTERRUPTED (error.h)


class _RunOptions(ctypes.Structure):  # cupid_run_options (problem.h)
    _fields_ = [("output_dir", ctypes.c_char_p), ("solver", ctypes.c_int),
                ("threads", ctypes.c_int), ("max_memory_gb", ctypes.c_double),
                ("quiet", ctypes.c_int), ("check_only", ctypes.c_int),
                ("replicate", ctypes.c_int), ("assembled", ctypes.c_int),
                ("allow_large", ctypes.c_int), ("resume", ctypes.c_int),
                ("sets", ctypes.POINTER(ctypes.c_char_p)),
                ("n_sets", ctypes.c_int)]


class _Info(ctypes.Structure):  # cupid_problem_info (problem.h)
    _fields_ = [("stage", ctypes.c_int), ("analysis", ctypes.c_char_p),
                ("coupling", ctypes.c_char_p), ("solver", ctypes.c_char_p),
                ("solver_reason", ctypes.c_char_p), ("method", ctypes.c_char_p),
                ("pd_nodes", _c_int64), ("bonds", _c_int64), ("fictitious_nodes", _c_int64),
                ("fe_nodes", _c_int64), ("fe_dofs", _c_int64), ("dofs", _c_int64),
                ("constrained_dofs", _c_int64), ("matrix_free", ctypes.c_int),
                ("iterations", ctypes.c_int), ("residual", ctypes.c_double),
                ("load_sum", ctypes.c_double * 3), ("reaction_sum", ctypes.c_double * 3),
                ("imbalance", ctypes.c_double), ("phase_seconds", ctypes.c_double * 6),
                ("total_seconds", ctypes.c_double), ("peak_memory_bytes", _c_int64),
                ("ghost_force", ctypes.c_double), ("quality_warnings", ctypes.c_int),
                ("stopped", ctypes.c_char_p), ("peak_load_factor", ctypes.c_double),
                ("peak_reaction", ctypes.c_double * 3)]


_SOLVERS = {None: -1, "auto": 0, "direct": 1, "petsc": 2, "krylov": 3}
_FIELDS = {"pd_coordinates": 0, "pd_displacement": 1, "pd_force": 2, "pd_load": 3,
           "pd_stress": 4, "beam_points": 5, "beam_displacement": 6, "pd_damage": 7}
_REGIONS = {0: "none", 1: "PD", 2: "FE"}
_PHASES = ("grid", "assembly", "coupling", "factorisation", "solve", "output")


def library_path():
    """Where libcupid is loaded from."""
    env = os.environ.get("CUPID_LIBRARY")
    if env:
        return env
    here = os.path.dirname(os.path.abspath(__file__))
    bundled = os.path.join(here, "libcupid.so")  # pip install ./python put it here
    if os.path.exists(bundled):
        return bundled
    local = os.path.join(here, "..", "..", "build", "libcupid.so")
    if os.path.exists(local):
        return os.path.normpath(local)
    found = ctypes.util.find_library("cupid")
    if not found:
        raise OSError("libcupid not found: build it (scripts/build.sh) or set CUPID_LIBRARY")
    return found


_lib = None


def _load():
    global _lib
    if _lib is not None:
        return _lib
    # OpenMP threads that spin at barriers hold the cores of a busy machine (the notched bar:
    # 7.7 s against 0.27 s, the command line's src/app/main.c): passive unless the user chose a
    # policy. libgomp reads it when it is loaded, here (unless something loaded it before).
    if "OMP_WAIT_POLICY" not in os.environ and "GOMP_SPINCOUNT" not in os.environ:
        os.environ["OMP_WAIT_POLICY"] = "PASSIVE"
    lib = ctypes.CDLL(library_path())
    P = ctypes.c_void_p
    sigs = {
        "cupid_problem_create_from_file": ([ctypes.c_char_p, ctypes.POINTER(_RunOptions),
                                            ctypes.POINTER(P)], ctypes.c_int),
        "cupid_problem_create_from_string": ([ctypes.c_char_p, ctypes.c_char_p,
                                              ctypes.POINTER(_RunOptions), ctypes.POINTER(P)],
                                             ctypes.c_int),
        "cupid_problem_setup": ([P], ctypes.c_int),
        "cupid_problem_solve": ([P], ctypes.c_int),
        "cupid_problem_write_outputs": ([P], ctypes.c_int),
        "cupid_problem_destroy": ([ctypes.POINTER(P)], None),
        "cupid_problem_get_field": ([P, ctypes.c_int, ctypes.POINTER(ctypes.POINTER(ctypes.c_double)),
                                     ctypes.POINTER(_c_int64), ctypes.POINTER(ctypes.c_int)],
                                    ctypes.c_int),
        "cupid_problem_sample": ([P, _c_int64, ctypes.POINTER(ctypes.c_double),
                                  ctypes.POINTER(ctypes.c_double), ctypes.POINTER(ctypes.c_double),
                                  ctypes.POINTER(ctypes.c_int)], ctypes.c_int),
        "cupid_problem_get_info": ([P, ctypes.POINTER(_Info)], ctypes.c_int),
        "cupid_error_message": ([], ctypes.c_char_p),
        "cupid_status_name": ([ctypes.c_int], ctypes.c_char_p),
        "cupid_status_exit_code": ([ctypes.c_int], ctypes.c_int),
        "cupid_version": ([], ctypes.c_char_p),
        "cupid_interrupt_install": ([], ctypes.c_int),
        "cupid_interrupt_uninstall": ([], None),
        "cupid_problem_output_directory": ([P], ctypes.c_char_p),
        "cupid_problem_output_point_count": ([P], ctypes.c_int),
        "cupid_problem_get_history": ([P, ctypes.POINTER(ctypes.POINTER(ctypes.c_double)),
                                       ctypes.POINTER(_c_int64), ctypes.POINTER(ctypes.c_int)],
                                      ctypes.c_int),
        "cupid_problem_output_point": ([P, ctypes.c_int, ctypes.POINTER(ctypes.c_char_p),
                                        ctypes.POINTER(ctypes.c_double),
                                        ctypes.POINTER(ctypes.c_int)], ctypes.c_int),
    }
    for name, (args, res) in sigs.items():
        f = getattr(lib, name)
        f.argtypes, f.restype = args, res
    _lib = lib
    return lib


def _check(status):
    if status != 0:
        lib = _lib
        kind = Interrupted if status == _INTERRUPTED else Error
        raise kind(lib.cupid_error_message().decode(), lib.cupid_status_name(status).decode(),
                   lib.cupid_status_exit_code(status))


def version():
    return _load().cupid_version().decode()


class _Text(tuple):
    """A model file's text and the name that stands for the file (Problem.from_text)."""

    def __new__(cls, text, name):
        return super().__new__(cls, (text, name))


class Problem:
    """A model being set up, solved and reported (include/cupid/problem.h).

    model: a path to a model file, or a dict with the model file's keys (model-format.md).
    output_dir, solver ("auto", "direct", "krylov", "petsc"), threads, max_memory_gb, quiet: as the
    command line's -o, --solver, --threads, --max-memory, --quiet. resume=True continues an
    interrupted dynamic run from its checkpoint, as --resume (solve() then ends with the files of
    a run that was never interrupted). Without output_dir the files
    go to the model's output.directory, by default out/<file name> (out/model for a dict).
    write_outputs() may be called again: it rewrites the report beside what the run wrote.
    """

    @classmethod
    def from_text(cls, text, name="<text>", **options):
        """A problem from a model file's text (YAML); name stands for the file in messages."""
        return cls(_Text(text, name), **options)

    def __init__(self, model, output_dir=None, solver=None, threads=0, max_memory_gb=0.0,
                 quiet=True, resume=False):
        lib = _load()
        if solver not in _SOLVERS:
            raise ValueError("solver must be one of auto, direct, krylov, petsc")
        self._out = output_dir.encode() if output_dir else None
        opts = _RunOptions(output_dir=self._out, solver=_SOLVERS[solver], threads=int(threads),
                           max_memory_gb=float(max_memory_gb), quiet=1 if quiet else 0,
                           resume=1 if resume else 0)
        self._p = ctypes.c_void_p()
        if isinstance(model, (dict, _Text)):
            # JSON is YAML (flow style): the reader takes a dict as a model file's text.
            text, name = (json.dumps(model), "<dict>") if isinstance(model, dict) else model
            _check(lib.cupid_problem_create_from_string(text.encode(), name.encode(),
                                                        ctypes.byref(opts), ctypes.byref(self._p)))
        else:
            _check(lib.cupid_problem_create_from_file(os.fsencode(model), ctypes.byref(opts),
                                                      ctypes.byref(self._p)))
        self._stage = 0

    def __del__(self):
        self.close()

    def close(self):
        """Free the problem (also done when it is garbage-collected)."""
        if getattr(self, "_p", None) and self._p.value and _lib is not None:
            _lib.cupid_problem_destroy(ctypes.byref(self._p))

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def setup(self):
        """Grid, beam, coupling layout, solver choice, constraints and loads."""
        if self._stage < 1:
            _check(_lib.cupid_problem_setup(self._p))
            self._stage = 1
        return self

    def solve(self):
        """The analysis (static, dynamic or evaluate); sets the problem up first if needed.
        Raises GrowthStopped when crack growth stopped before its last step (the problem is
        solved up to there: write_outputs() still writes it), and Interrupted when Ctrl-C or
        SIGTERM stopped a dynamic run or crack growth at a checkpoint (resume=True goes on)."""
        self.setup()
        if self._stage < 2:
            # Python's own handlers run between bytecodes, not during the solve: while it runs,
            # SIGINT/SIGTERM go to cupid's, which stop a resumable run at its next checkpoint
            # (Interrupted); a second signal, or one outside the steps, goes to Python's
            _lib.cupid_interrupt_install()
            try:
                status = _lib.cupid_problem_solve(self._p)
            finally:
                _lib.cupid_interrupt_uninstall()
            _check(status)
            self._stage = 2
            stopped = self.info["stopped"]
            if stopped:
                raise GrowthStopped(stopped, "growth stopped", 2)
        return self

    @property
    def output_dir(self):
        """Where write_outputs() writes (output_dir=, else the model's output.directory)."""
        return _lib.cupid_problem_output_directory(self._p).decode()

    def write_outputs(self):
        """The model's output files (summary.json, lines, VTU, plots) in the output directory."""
        _check(_lib.cupid_problem_write_outputs(self._p))
        return self

    def field(self, name):
        """A field as a copied (n, components) numpy array: pd_coordinates, pd_displacement,
        pd_force, pd_load, pd_stress (sxx syy szz syz sxz sxy), beam_points,
        beam_displacement, pd_damage (one column; no rows without pre-cracks or fracture)."""
        if name not in _FIELDS:
            raise KeyError("unknown field %r (one of %s)" % (name, ", ".join(_FIELDS)))
        values = ctypes.POINTER(ctypes.c_double)()
        n, comps = _c_int64(), ctypes.c_int()
        _check(_lib.cupid_problem_get_field(self._p, _FIELDS[name], ctypes.byref(values),
                                            ctypes.byref(n), ctypes.byref(comps)))
        if n.value == 0:
            return np.zeros((0, comps.value))
        flat = np.ctypeslib.as_array(values, shape=(n.value * comps.value,))
        return flat.reshape(n.value, comps.value).copy()

    pd_coordinates = property(lambda self: self.field("pd_coordinates"))
    pd_displacement = property(lambda self: self.field("pd_displacement"))
    pd_force = property(lambda self: self.field("pd_force"))
    pd_load = property(lambda self: self.field("pd_load"))
    pd_stress = property(lambda self: self.field("pd_stress"))
    pd_damage = property(lambda self: self.field("pd_damage"))
    beam_points = property(lambda self: self.field("beam_points"))
    beam_displacement = property(lambda self: self.field("beam_displacement"))

    def sample(self, points, stress=False):
        """Displacements (n, 3) at points (n, 3), as the output points sample them, and each
        point's region ("PD", "FE" or "none": NaN there); with stress=True also (n, 6)."""
        pts = np.ascontiguousarray(np.atleast_2d(np.asarray(points, dtype=float)))
        if pts.shape[1] != 3:
            raise ValueError("points must have 3 coordinates")
        n = pts.shape[0]
        u = np.empty((n, 3))
        s = np.empty((n, 6)) if stress else None
        reg = (ctypes.c_int * n)()
        dp = ctypes.POINTER(ctypes.c_double)
        _check(_lib.cupid_problem_sample(self._p, n, pts.ctypes.data_as(dp), u.ctypes.data_as(dp),
                                         s.ctypes.data_as(dp) if stress else None, reg))
        regions = [_REGIONS[r] for r in reg]
        return (u, regions, s) if stress else (u, regions)

    @property
    def history(self):
        """Type dynamic: a dict with "t" (steps,) and, for each output point, its name mapped to
        the (steps, 3) displacements, as history.csv holds them."""
        rows = ctypes.POINTER(ctypes.c_double)()
        n, cols = _c_int64(), ctypes.c_int()
        _check(_lib.cupid_problem_get_history(self._p, ctypes.byref(rows), ctypes.byref(n),
                                              ctypes.byref(cols)))
        h = (np.ctypeslib.as_array(rows, shape=(n.value * cols.value,)).reshape(n.value, cols.value).copy()
             if n.value else np.zeros((0, cols.value)))
        out = {"t": h[:, 0]}
        names = [p["name"] for p in self._point_names()]
        for k, name in enumerate(names):
            out[name] = h[:, 1 + 3 * k:4 + 3 * k]
        return out

    def _point_names(self):
        for k in range(_lib.cupid_problem_output_point_count(self._p)):
            name = ctypes.c_char_p()
            xyz = (ctypes.c_double * 3)()
            want = ctypes.c_int()
            _check(_lib.cupid_problem_output_point(self._p, k, ctypes.byref(name), xyz,
                                                   ctypes.byref(want)))
            yield {"name": name.value.decode(), "at": list(xyz), "stress": bool(want.value)}

    def sample_output_points(self):
        """The model's output points as summary.json lists them: name, x, y, z, ux, uy, uz,
        region and, where the point asks for it, sxx syy szz syz sxz sxy."""
        return [dict(p) for p in self._output_points()]

    def _output_points(self):
        n = _lib.cupid_problem_output_point_count(self._p)
        for k in range(n):
            name = ctypes.c_char_p()
            xyz = (ctypes.c_double * 3)()
            want = ctypes.c_int()
            _check(_lib.cupid_problem_output_point(self._p, k, ctypes.byref(name), xyz,
                                                   ctypes.byref(want)))
            u, regions, s = self.sample([list(xyz)], stress=True)
            row = {"name": name.value.decode(), "x": xyz[0], "y": xyz[1], "z": xyz[2],
                   "ux": u[0, 0], "uy": u[0, 1], "uz": u[0, 2], "region": regions[0]}
            if want.value:
                row.update(zip(("sxx", "syy", "szz", "syz", "sxz", "sxy"), s[0]))
            yield row

    @property
    def info(self):
        """Counts, solver, resultants, imbalance, phase times and, for a coupled model, the
        patch test's ghost force (-1 when not run) and the quality warnings, and for static
        crack growth why it stopped early (None: it did not) and the peak of constraint 0's
        reaction on the sawtooth envelope with its load factor, as a dict."""
        i = _Info()
        _check(_lib.cupid_problem_get_info(self._p, ctypes.byref(i)))
        d = {}
        for name, _ in _Info._fields_:
            v = getattr(i, name)
            if isinstance(v, bytes):
                v = v.decode()
            elif name in ("load_sum", "reaction_sum", "peak_reaction"):
                v = list(v)
            elif name == "phase_seconds":
                v = dict(zip(_PHASES, v))
            elif name == "quality_warnings":
                v = [w for bit, w in ((1, "ghost_force"), (2, "imbalance")) if v & bit]
            d[name] = v
        return d
