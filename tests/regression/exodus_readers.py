#!/usr/bin/env python3
"""regression.exodus_readers: model.exo (output.exodus, issue 35) read back by meshio and
netCDF4 (Debian's python3-meshio and python3-netcdf4), against the VTU files of the same run.

Runs `cupid run` with `--set output.exodus=true` on:
  * the coupled bar (a static solve: one time step, the beam's hexahedra and the PD nodes),
  * the notched plate (explicit PD fracture: a time step per VTU frame),
  * the coupled SENB with load steps and crack growth (a time step per load step),
and checks, for each:
  * the database's structure: two element blocks named "beam" and "pd" (HEX8, and SPHERE
    with a `volume` attribute summing to the PD body's volume), the nodes the parts' points;
  * the time steps: their number and times equal model.pvd's (dynamics) or the load factors of
    damage.csv (load steps);
  * the nodal fields at every time step equal the VTU files' (each frame's pd_<step>.vtu in
    dynamics; the final pd.vtu and beam.vtu for a static solve and for the last load step),
    bitwise: both are the same doubles written in binary;
  * meshio reads the file (points, cells and point data as netCDF4 gives them);
and that without the library (CUPID_EXODUS_LIBRARY pointing nowhere) output.exodus is a model
error naming Debian's package.

Under MPI (CUPID_EXODUS_RANKS=N, tests/regression/mpi_exodus.sh): a PD-only explicit run and
crack growth on N z slabs (--solver petsc), rank 0 writing the gathered frames, checked the same
way against the run's own VTU files and damage.csv.

Run with the interpreter Debian's packages are installed for (/usr/bin/python3).
Environment: CUPID (the cupid binary), CUPID_SOURCE_DIR (the source tree), CUPID_EXODUS_RANKS,
CUPID_MPIEXEC.
"""
import csv
import os
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET

try:
    import numpy as np
    import meshio
    import netCDF4
except ImportError as e:
    sys.exit("exodus_readers.py: %s (with %s): install python3-numpy, python3-meshio and "
             "python3-netcdf4 (scripts/install-deps.sh) and run with /usr/bin/python3"
             % (e, sys.executable))

# meshio takes the first time step of each nodal variable and says so for each: quiet here
import meshio.exodus._exodus as _meshio_exodus  # noqa: E402
_meshio_exodus.warn = lambda *args, **kwargs: None

SRC = os.path.realpath(os.environ.get("CUPID_SOURCE_DIR", "."))
CUPID = os.path.realpath(os.environ.get("CUPID", os.path.join(SRC, "build", "cupid")))
RANKS = int(os.environ.get("CUPID_EXODUS_RANKS", "0"))
failures = []


def check(cond, what):
    if not cond:
        failures.append(what)
        print("FAIL:", what)


def run(name, model, *sets, solver=None):
    out = os.path.join(WORK, name)
    cmd = [CUPID, "run", os.path.join(SRC, model), "-o", out, "-q",
           "--set", "output.exodus=true", "--set", "output.plots=false"]
    if RANKS:
        cmd = [os.environ.get("CUPID_MPIEXEC", "mpiexec"), "-n", str(RANKS)] + cmd
    if solver:
        cmd += ["--solver", solver]
    for s in sets:
        cmd += ["--set", s]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit("%s: cupid exited %d: %s" % (name, r.returncode, r.stderr))
    return out


def names(ds, var):
    return [bytes(np.ma.getdata(row)).rstrip(b"\0").decode() for row in ds.variables[var][:]]


class Exo:
    """The parts of model.exo: per block its name, type, node range; the nodal variables."""

    def __init__(self, path):
        self.ds = netCDF4.Dataset(path)
        ds = self.ds
        self.blocks = names(ds, "eb_names")
        self.vars = names(ds, "name_nod_var")
        self.times = np.asarray(ds.variables["time_whole"][:], dtype=float)
        self.xyz = np.stack([np.asarray(ds.variables["coord" + c][:], dtype=float)
                             for c in "xyz"], axis=1)
        self.conn = [np.asarray(ds.variables["connect%d" % (b + 1)][:]) - 1
                     for b in range(len(self.blocks))]
        self.types = [ds.variables["connect%d" % (b + 1)].getncattr("elem_type")
                      for b in range(len(self.blocks))]

    def field(self, name, step, ncomp):
        """(nodes, ncomp) values of a field at a time step (0-based)."""
        sfx = {1: [""], 3: ["_x", "_y", "_z"], 6: ["_xx", "_yy", "_zz", "_xy", "_yz", "_xz"]}
        cols = []
        for s in sfx[ncomp]:
            k = self.vars.index(name + s)
            cols.append(np.asarray(self.ds.variables["vals_nod_var%d" % (k + 1)][step], dtype=float))
        return np.stack(cols, axis=1)

    def part_nodes(self, b):
        return np.unique(self.conn[b])


def vtu(path):
    return meshio.read(path)


def same_part(exo, b, mesh, step, label):
    """The block's nodes carry the VTU file's points and point data at this time step."""
    nodes = exo.part_nodes(b)
    first = nodes.min()
    n = len(mesh.points)
    check(len(nodes) == n and nodes.max() == first + n - 1,
          "%s: block %s has %d nodes, the VTU %d" % (label, exo.blocks[b], len(nodes), n))
    if len(nodes) != n:
        return
    check(np.array_equal(exo.xyz[first:first + n], mesh.points),
          "%s: block %s's coordinates differ from the VTU's" % (label, exo.blocks[b]))
    for name, values in mesh.point_data.items():
        v = values.reshape(n, -1)
        got = exo.field(name, step, v.shape[1])[first:first + n]
        check(np.array_equal(got, v), "%s: block %s's %s at time step %d differs from the VTU's "
              "(largest difference %.3g)" % (label, exo.blocks[b], name, step + 1,
                                              np.max(np.abs(got - v))))


def structure(exo, label, pd_volume=None):
    check(exo.blocks == ["beam", "pd"] or exo.blocks == ["pd"] or exo.blocks == ["beam"],
          "%s: blocks %s" % (label, exo.blocks))
    for b, name in enumerate(exo.blocks):
        want = "HEX8" if name == "beam" else "SPHERE"
        check(exo.types[b] == want, "%s: block %s is %s, not %s" % (label, name, exo.types[b], want))
        if name == "pd" and pd_volume is not None:
            vol = np.asarray(exo.ds.variables["attrib%d" % (b + 1)][:], dtype=float).sum()
            check(abs(vol - pd_volume) <= 1e-9 * pd_volume,
                  "%s: the SPHERE volumes sum to %.10g, the body's volume is %.10g"
                  % (label, vol, pd_volume))
            an = names(exo.ds, "attrib_name%d" % (b + 1))
            check(an == ["volume"], "%s: the SPHERE attribute is %s" % (label, an))
    m = meshio.read(os.path.join(exo.path_dir, "model.exo"))
    check(len(m.points) == len(exo.xyz), "%s: meshio reads %d points" % (label, len(m.points)))
    kinds = sorted(c.type for c in m.cells)
    check(set(kinds) <= {"hexahedron", "vertex"}, "%s: meshio's cells %s" % (label, kinds))
    check("displacement_x" in m.point_data, "%s: meshio sees no displacement" % label)


def pvd(path):
    root = ET.parse(path).getroot()
    return [(float(d.get("timestep")), d.get("file")) for d in root.iter("DataSet")]


def open_exo(out):
    exo = Exo(os.path.join(out, "model.exo"))
    exo.path_dir = out
    return exo


def static_bar():
    out = run("bar", "examples/bar/bar.yaml")
    exo = open_exo(out)
    structure(exo, "bar", pd_volume=10 * 40 * 10.0)
    check(len(exo.times) == 1 and exo.times[0] == 0.0, "bar: times %s" % exo.times)
    same_part(exo, exo.blocks.index("beam"), vtu(os.path.join(out, "beam.vtu")), 0, "bar")
    same_part(exo, exo.blocks.index("pd"), vtu(os.path.join(out, "pd.vtu")), 0, "bar")


def dynamic_plate(model="examples/notched_plate/notched_plate.yaml"):
    out = run("plate", model)
    exo = open_exo(out)
    structure(exo, "plate")
    frames = pvd(os.path.join(out, "model.pvd"))
    check(len(exo.times) == len(frames) and len(frames) > 2,
          "plate: %d time steps, model.pvd %d" % (len(exo.times), len(frames)))
    for k, (t, f) in enumerate(frames[:len(exo.times)]):
        check(exo.times[k] == t, "plate: time step %d at %r, model.pvd %r" % (k + 1, exo.times[k], t))
        same_part(exo, 0, vtu(os.path.join(out, f)), k, "plate " + f)


def growth_senb():
    out = run("senb", "examples/fracture/senb_coupled.yaml",
              "peridynamics.spacing=1.6666666666666667", "peridynamics.horizon=5.025")
    exo = open_exo(out)
    structure(exo, "senb")
    with open(os.path.join(out, "damage.csv")) as f:
        rows = list(csv.DictReader(f))
    lf = np.array([float(r["load_factor"]) for r in rows])
    check(len(exo.times) == len(rows) and len(rows) > 2,
          "senb: %d time steps, damage.csv %d rows" % (len(exo.times), len(rows)))
    check(np.allclose(exo.times, lf, rtol=1e-10, atol=0),
          "senb: the times are not damage.csv's load factors")
    last = len(exo.times) - 1
    same_part(exo, exo.blocks.index("beam"), vtu(os.path.join(out, "beam.vtu")), last, "senb")
    pd = vtu(os.path.join(out, "pd.vtu"))  # the last step's: displacement, force, damage
    b = exo.blocks.index("pd")
    nodes = exo.part_nodes(b)
    first = nodes.min()
    for name in ("displacement", "force", "damage"):
        v = pd.point_data[name].reshape(len(pd.points), -1)
        got = exo.field(name, last, v.shape[1])[first:first + len(pd.points)]
        check(np.array_equal(got, v), "senb: the last step's PD %s differs from pd.vtu's" % name)
    broken = [int(r["damaged_nodes"]) for r in rows]
    for k in (0, last):  # damage grows: the damaged nodes of each step's row
        d = exo.field("damage", k, 1)[first:first + len(pd.points), 0]
        check(int((d > 0).sum()) == broken[k],
              "senb: step %d has %d damaged nodes, damage.csv %d" % (k + 1, (d > 0).sum(), broken[k]))


def refused_without_library():
    """No Exodus II library on the system: output.exodus is a model error naming the package."""
    env = dict(os.environ, CUPID_EXODUS_LIBRARY="/nonexistent/libexoIIv2c.so")
    r = subprocess.run([CUPID, "check", os.path.join(SRC, "examples/bar/bar.yaml"), "--set",
                        "output.exodus=true"], capture_output=True, text=True, env=env)
    check(r.returncode == 1 and "output.exodus: the Exodus II library is not installed "
          "(Debian's libexodusii5" in r.stderr,
          "without the library: exit %d, %s" % (r.returncode, r.stderr.strip()))


def growth_slabs():
    """PD-only crack growth on slabs: a time step per load step, the last one pd.vtu's."""
    out = run("growth", "tests/models/growth/plate.yaml", solver="petsc")
    exo = open_exo(out)
    structure(exo, "growth")
    with open(os.path.join(out, "damage.csv")) as f:
        rows = list(csv.DictReader(f))
    check(len(exo.times) == len(rows) and len(rows) > 2,
          "growth: %d time steps, damage.csv %d rows" % (len(exo.times), len(rows)))
    pd = vtu(os.path.join(out, "pd.vtu"))
    last = len(exo.times) - 1
    for name in ("displacement", "force", "damage"):
        v = pd.point_data[name].reshape(len(pd.points), -1)
        got = exo.field(name, last, v.shape[1])
        check(np.array_equal(got, v), "growth: the last step's PD %s differs from pd.vtu's" % name)


with tempfile.TemporaryDirectory() as WORK:
    if RANKS:
        dynamic_plate("tests/models/mpi/plate_slabs_lps.yaml")
        growth_slabs()
    else:
        static_bar()
        dynamic_plate()
        growth_senb()
        refused_without_library()
if failures:
    sys.exit("%d failure(s)" % len(failures))
print("exodus_readers: all checks passed")
