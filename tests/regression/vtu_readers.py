#!/usr/bin/env python3
"""regression.vtu_readers: every kind of VTU file cupid writes, opened by other tools.

Runs `cupid run` on small models (a PD-only static block, an FE-only beam, a coupled
PD + beam model, dynamic FE and PD runs with `vtu: true`) and reads every .vtu with
three independent readers:
  * meshio (Debian's python3-meshio),
  * VTK's own XML reader, vtkXMLUnstructuredGridReader (python3-vtk9; ParaView reads .vtu
    files with the same class), with every VTK error or warning counted as a failure,
  * tests/tools/read_vtu.py (standard library only; checks the file's structure).
The three must give bitwise the same points, cells and point data, and those must match
cupid's other outputs: the point count of summary.json, pd_nodes.csv (coordinates, u, f),
summary.json points lying on VTU points, history.csv at every step of a series, and the
data sets of model.pvd (files, times, block names and parts).

The tolerances only absorb the decimal rounding of the CSV files (a relative 1e-12 for
`%.12e`, 1e-10 for `%.10e` and `%.10g`); summary.json numbers (`%.17g`) and the three readers
are compared bitwise.

Run with the interpreter Debian's packages are installed for (tests/CMakeLists.txt passes
CUPID_SYSTEM_PYTHON, /usr/bin/python3): `python3` on PATH may be another one.
Environment: CUPID (the cupid binary), CUPID_SOURCE_DIR (the source tree).
"""
import csv
import json
import os
import re
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET

try:
    import numpy as np
    import meshio
    from vtkmodules.vtkCommonCore import vtkOutputWindow, vtkStringOutputWindow, vtkVersion
    from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader
    from vtkmodules.util.numpy_support import vtk_to_numpy
except ImportError as e:
    sys.exit("vtu_readers.py: %s (with %s): install python3-numpy, python3-meshio and "
             "python3-vtk9 (scripts/install-deps.sh) and run with /usr/bin/python3"
             % (e, sys.executable))

SRC = os.path.realpath(os.environ.get("CUPID_SOURCE_DIR", "."))
CUPID = os.path.realpath(os.environ.get("CUPID", os.path.join(SRC, "build", "cupid")))
sys.path.insert(0, os.path.join(SRC, "tests", "tools"))
import read_vtu  # noqa: E402  (tests/tools)


failures = []
checks = 0


def check(ok, what):
    global checks
    checks += 1
    if not ok:
        failures.append(what)
        print("FAIL: " + what)
    return ok


# ---------------------------------------------------------------- models

PD_ONLY = """\
title: PD-only block (regression.vtu_readers)
materials:
  steel: {E: 200000, nu: 0.25}
peridynamics:
  spacing: 1.0
  horizon: 3.0
  model: lps
  material: steel
  regions:
    - {x: [0, 4], y: [0, 10], z: [0, 3]}
constraints:
  - fix: {box: {y: [0, 3]}}
loads:
  - body: {box: {y: [7, 10]}, value: [10, 100, -5]}
output:
  vtu: true
  pd_nodes: true
  plots: false
  points:
    - {name: end, at: [2.5, 9.5, 1.5], stress: true}
"""

FE_ONLY = """\
title: FE-only beam (regression.vtu_readers)
materials:
  resin: {E: 10000, nu: 0.2}
beam:
  material: resin
  axis: {y: [0, 30, 70, 100], elements: [1, 1, 1], type: B2}
  section:
    expansion: TE2
    components:
      - {x: [0, 10], z: [0, 10]}
constraints:
  - clamp: {y: 0}
loads:
  - traction: {y: 100, value: [0, 100, 0]}
  - point: {at: [10, 100, 10], value: [50, 0, -80]}
output:
  vtu: true
  plots: false
  points:
    - {name: corner, at: [10, 100, 10]}
    - {name: joint, at: [0, 30, 10]}
"""

COUPLED = """\
title: coupled bar (regression.vtu_readers)
materials:
  resin: {E: 10000, nu: 0.2}
beam:
  material: resin
  axis: {y: [0, 20, 28, 40], elements: [1, 1, 1], type: B2}
  section:
    expansion: TE1
    components:
      - {x: [0, 6], z: [0, 6]}
peridynamics:
  spacing: 2.0
  horizon: 6.0
  model: bond
  material: resin
  regions:
    - {x: [0, 6], y: [20, 28], z: [0, 6]}
coupling: {method: fictitious}
constraints:
  - clamp: {y: 0}
loads:
  - traction: {y: 40, value: [0, 100, 0]}
  - point: {at: [6, 40, 6], value: [0, 0, -30]}
output:
  vtu: true
  pd_nodes: true
  plots: false
  points:
    - {name: tip, at: [6, 40, 6]}
    - {name: pd, at: [1, 21, 1]}
"""


def run(work, name, model):
    """Run cupid on a model (text, or a path relative to the source tree) into work/name."""
    out = os.path.join(work, name)
    if "\n" in model:
        path = os.path.join(work, name + ".yaml")
        with open(path, "w") as f:
            f.write(model)
    else:
        path = os.path.join(SRC, model)
    r = subprocess.run([CUPID, "run", path, "-o", out, "--quiet"], capture_output=True, text=True)
    if not check(r.returncode == 0, "%s: cupid run exited %d: %s" % (name, r.returncode,
                                                                     r.stderr.strip())):
        return None
    return out


# ---------------------------------------------------------------- readers


def read_meshio(path):
    m = meshio.read(path)
    types = {"vertex": 1, "line": 3, "quad": 9, "hexahedron": 12}
    cell_types = np.concatenate([np.full(len(b.data), types[b.type], dtype=np.uint8)
                                 for b in m.cells])
    conn = np.concatenate([b.data.ravel() for b in m.cells])
    data = {k: np.asarray(v).reshape(len(m.points), -1) for k, v in m.point_data.items()}
    return m.points, conn, cell_types, data


def read_vtk(path):
    # VTK reports problems through its output window and events instead of raising.
    log = vtkStringOutputWindow()
    vtkOutputWindow.SetInstance(log)
    events = []
    r = vtkXMLUnstructuredGridReader()
    for event in ("ErrorEvent", "WarningEvent"):
        r.AddObserver(event, lambda obj, ev: events.append(ev))
    r.SetFileName(path)
    r.Update()
    g = r.GetOutput()
    check(not log.GetOutput() and not events, "%s: VTK reported %s: %s"
          % (path, events, log.GetOutput().strip()[:400]))
    n = g.GetNumberOfPoints()
    points = vtk_to_numpy(g.GetPoints().GetData()) if n else np.zeros((0, 3))
    cells = g.GetCells()
    conn = vtk_to_numpy(cells.GetConnectivityArray()) if g.GetNumberOfCells() else np.zeros(0)
    types = vtk_to_numpy(g.GetCellTypesArray()) if g.GetNumberOfCells() else np.zeros(0)
    pd = g.GetPointData()
    data = {}
    for i in range(pd.GetNumberOfArrays()):
        a = vtk_to_numpy(pd.GetArray(i))
        data[pd.GetArrayName(i)] = a.reshape(n, -1)
    return points, conn, types, data


def read_reference(path):
    npts, ncells, arrays = read_vtu.read(path)
    named = {(s, n): np.array(v) for s, n, _, _, v in arrays}
    data = {n: np.array(v).reshape(npts, -1) for s, n, _, _, v in arrays if s == "PointData"}
    return (named[("Points", "Points")].reshape(npts, 3), named[("Cells", "connectivity")],
            named[("Cells", "types")], data)


def same(a, b):
    """Bitwise equality of two float arrays (NaN and the sign of zero included)."""
    a, b = np.ascontiguousarray(a, dtype=np.float64), np.ascontiguousarray(b, dtype=np.float64)
    return a.shape == b.shape and a.tobytes() == b.tobytes()


def read_all(path):
    """The file by all three readers, which must agree bitwise; returns (points, data) or None."""
    label = os.path.relpath(path, os.path.dirname(os.path.dirname(path)))
    results = {}
    for name, reader in (("read_vtu.py", read_reference), ("meshio", read_meshio),
                         ("VTK", read_vtk)):
        try:
            results[name] = reader(path)
        except (Exception, SystemExit) as e:  # any exception is a file the tool cannot read
            check(False, "%s: %s cannot read it: %s: %s" % (label, name, type(e).__name__, e))
    if not results:
        return None
    first = next(iter(results))
    points, conn, types, data = results[first]
    for name, (p, c, t, d) in results.items():
        if name == first:
            continue
        versus = "%s and %s" % (first, name)
        check(same(p, points), "%s: points differ between %s" % (label, versus))
        check(np.array_equal(np.asarray(c, dtype=np.int64), np.asarray(conn, dtype=np.int64)),
              "%s: connectivity differs between %s" % (label, versus))
        check(np.array_equal(np.asarray(t, dtype=np.int64), np.asarray(types, dtype=np.int64)),
              "%s: cell types differ between %s" % (label, versus))
        check(sorted(d) == sorted(data), "%s: point arrays %s by %s, %s by %s"
              % (label, sorted(data), first, sorted(d), name))
        for k in data:
            if k in d:
                check(same(d[k], data[k]), "%s: point array %s differs between %s"
                      % (label, k, versus))
    return points, data


# ---------------------------------------------------------------- comparisons


def close(a, b, rel):
    """|a - b| <= rel |b| elementwise (b: the exact double, a: its decimal rounding)."""
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    return a.shape == b.shape and bool(np.all(np.abs(a - b) <= rel * np.abs(b)))


def summary(out):
    with open(os.path.join(out, "summary.json")) as f:
        return json.load(f)


def at_points(label, points, data, pts, required=True):
    """summary.json points lying on VTU points: the VTU displacement there is bitwise theirs
    (the same evaluation of the same field; a PD point is its nearest node)."""
    found = 0
    for p in pts:
        hit = np.where((points[:, 0] == p["x"]) & (points[:, 1] == p["y"]) &
                       (points[:, 2] == p["z"]))[0]
        if len(hit) == 0:
            check(not required, "%s: summary point %s is not a VTU point" % (label, p["name"]))
            continue
        found += 1
        want = np.array([p["ux"], p["uy"], p["uz"]])
        for i in hit:
            check(same(data["displacement"][i], want),
                  "%s: displacement at %s: VTU %r, summary.json %r"
                  % (label, p["name"], data["displacement"][i].tolist(), want.tolist()))
    return found


def check_pd(out, label, s):
    vtu = read_all(os.path.join(out, "pd.vtu"))
    if vtu is None:
        return
    points, data = vtu
    check(len(points) == s["counts"]["pd_nodes"], "%s: pd.vtu has %d points, summary.json %d "
          "PD nodes" % (label, len(points), s["counts"]["pd_nodes"]))
    for k in ("displacement", "force", "material", "constrained_components"):
        check(k in data, "%s: pd.vtu has no %s" % (label, k))
    with open(os.path.join(out, "pd_nodes.csv")) as f:
        rows = list(csv.reader(f))
    check(rows[0] == ["x", "y", "z", "ux", "uy", "uz", "fx", "fy", "fz"],
          "%s: pd_nodes.csv header %s" % (label, rows[0]))
    table = np.array([[float(v) for v in r] for r in rows[1:]])
    if check(table.shape == (len(points), 9), "%s: pd_nodes.csv has %d rows for %d VTU points"
             % (label, len(table), len(points))):
        check(close(table[:, 0:3], points, 1e-10), "%s: pd.vtu points != pd_nodes.csv x,y,z"
              % label)
        check(close(table[:, 3:6], data["displacement"], 1e-12),
              "%s: pd.vtu displacement != pd_nodes.csv ux,uy,uz" % label)
        check(close(table[:, 6:9], data["force"], 1e-12),
              "%s: pd.vtu force != pd_nodes.csv fx,fy,fz" % label)
    check(np.all(np.isfinite(data["displacement"])), "%s: non-finite displacements" % label)
    return points, data


def check_pvd(out, label, expect, rel=0.0):
    """expect: [(file, name, part, time)] in order; times to @p rel (history.csv's rounding)."""
    root = ET.parse(os.path.join(out, "model.pvd")).getroot()
    got = [(d.get("file"), d.get("name"), int(d.get("part")), float(d.get("timestep")))
           for d in root.iter("DataSet")]
    check(len(got) == len(expect) and all(g[:3] == e[:3] and abs(g[3] - e[3]) <= rel * abs(e[3])
                                          for g, e in zip(got, expect)),
          "%s: model.pvd lists %s, expected %s" % (label, got, expect))
    for f, _, _, _ in got:
        check(os.path.isfile(os.path.join(out, f)), "%s: model.pvd names missing %s" % (label, f))


def static_pd(work):
    out = run(work, "pd_only", PD_ONLY)
    if not out:
        return
    s = summary(out)
    check(s["counts"]["fe_nodes"] == 0 and not os.path.exists(os.path.join(out, "beam.vtu")),
          "pd_only: a beam where there is none")
    vtu = check_pd(out, "pd_only", s)
    if vtu:
        points, data = vtu
        check("stress" in data and data["stress"].shape[1] == 6, "pd_only: pd.vtu has no stress")
        # The summary point is one node's position: nearest-node values, exact.
        check(at_points("pd_only", points, data, s["points"]) == 1, "pd_only: no point checked")
    check_pvd(out, "pd_only", [("pd.vtu", "pd", 0, 0.0)])


def static_fe(work):
    out = run(work, "fe_only", FE_ONLY)
    if not out:
        return
    s = summary(out)
    vtu = read_all(os.path.join(out, "beam.vtu"))
    if vtu:
        points, data = vtu
        check(sorted(data) == ["displacement", "stress"], "fe_only: beam.vtu arrays %s"
              % sorted(data))
        check(np.all(points[:, 1] >= 0) and np.all(points[:, 1] <= 100)
              and points[:, 1].min() == 0 and points[:, 1].max() == 100,
              "fe_only: beam.vtu does not span the axis")
        check(at_points("fe_only", points, data, s["points"]) == 2, "fe_only: no point checked")
    check(not os.path.exists(os.path.join(out, "pd.vtu")), "fe_only: a pd.vtu without PD")
    check_pvd(out, "fe_only", [("beam.vtu", "beam", 0, 0.0)])


def static_coupled(work):
    out = run(work, "coupled", COUPLED)
    if not out:
        return
    s = summary(out)
    pd = check_pd(out, "coupled", s)
    beam = read_all(os.path.join(out, "beam.vtu"))
    n = 0
    if pd:
        n += at_points("coupled", pd[0], pd[1], [p for p in s["points"] if p["region"] == "PD"])
    if beam:
        n += at_points("coupled", beam[0], beam[1],
                       [p for p in s["points"] if p["region"] == "FE"])
    check(n == 2, "coupled: %d of 2 summary points checked" % n)
    check_pvd(out, "coupled", [("beam.vtu", "beam", 0, 0.0), ("pd.vtu", "pd", 1, 0.0)])


def dynamic(work, model, kind):
    name = os.path.splitext(os.path.basename(model))[0]
    out = run(work, name, model)
    if not out:
        return
    s = summary(out)
    files = sorted(f for f in os.listdir(out) if f.endswith(".vtu"))
    check(len(files) > 2 and all(f.startswith(kind + "_") for f in files),
          "%s: VTU files %s" % (name, files))
    with open(os.path.join(out, "history.csv")) as f:
        rows = list(csv.reader(f))
    header, hist = rows[0], np.array([[float(v) for v in r] for r in rows[1:]])
    tip = s["points"][0]
    cols = [header.index("%s_u%s" % (tip["name"], c)) for c in "xyz"]
    steps = [int(f[len(kind) + 1:-4]) for f in files]
    expect = []
    for f, step in zip(files, steps):
        vtu = read_all(os.path.join(out, f))
        if vtu is None:
            continue
        points, data = vtu
        if kind == "pd":
            check(len(points) == s["counts"]["pd_nodes"], "%s/%s: %d points" % (name, f,
                                                                             len(points)))
            check(sorted(data) == ["displacement", "velocity"], "%s/%s: arrays %s"
                  % (name, f, sorted(data)))
            # The history point is the node nearest to it.
            d = np.linalg.norm(points - [tip["x"], tip["y"], tip["z"]], axis=1)
            near = [int(np.argmin(d))]
        else:
            check(sorted(data) == ["displacement", "stress"], "%s/%s: arrays %s"
                  % (name, f, sorted(data)))
            # TE0: the displacement is uniform over the section; the tip's section corners.
            near = list(np.where(points[:, 1] == tip["y"])[0])
            check(len(near) > 0, "%s/%s: no VTU point at y = %g" % (name, f, tip["y"]))
        row = hist[step]
        for i in near:
            check(close(row[cols], data["displacement"][i], 1e-10),
                  "%s/%s: tip displacement %r, history.csv %r at t = %g"
                  % (name, f, data["displacement"][i].tolist(), row[cols].tolist(), row[0]))
        if step == steps[-1]:
            for i in near:
                check(same(data["displacement"][i], [tip["ux"], tip["uy"], tip["uz"]]),
                      "%s/%s: last VTU differs from summary.json's final tip" % (name, f))
        expect.append((f, kind, 0, row[0]))
    check_pvd(out, name, expect, 1e-10)


def dynamic_coupled(work):
    """A coupled dynamic series (Arlequin truss): both parts at every output step, the beam as
    block "beam" (part 0) and the PD nodes as block "pd" (part 1) of model.pvd (issue 19)."""
    src = open(os.path.join(SRC, "examples/truss/truss_arlequin.yaml")).read()
    text = re.sub(r"duration: [0-9.e+-]+", "duration: 0.0005", src).replace("vtu: false", "vtu: true")
    model = os.path.join(work, "truss_arlequin_vtu.yaml")
    open(model, "w").write(text)
    out = run(work, "truss_arlequin_vtu", model)
    if not out:
        return
    s = summary(out)
    beams = sorted(f for f in os.listdir(out) if f.startswith("beam_") and f.endswith(".vtu"))
    pds = sorted(f for f in os.listdir(out) if f.startswith("pd_") and f.endswith(".vtu"))
    check(len(beams) >= 2 and [b[5:] for b in beams] == [p[3:] for p in pds],
          "coupled dynamics: beam files %s, PD files %s" % (beams, pds))
    expect = []
    for b, p in zip(beams, pds):
        for f, kind, part in ((b, "beam", 0), (p, "pd", 1)):
            vtu = read_all(os.path.join(out, f))
            check(vtu is not None and len(vtu[0]) > 0, "coupled dynamics: %s unreadable" % f)
            if kind == "pd" and vtu is not None:
                check(len(vtu[0]) == s["counts"]["pd_nodes"], "coupled dynamics: %s points" % f)
        root = ET.parse(os.path.join(out, "model.pvd")).getroot()
    got = [(d.get("file"), d.get("name"), int(d.get("part"))) for d in root.iter("DataSet")]
    want = [x for b, p in zip(beams, pds) for x in ((b, "beam", 0), (p, "pd", 1))]
    check(got == want, "coupled dynamics: model.pvd lists %s, expected %s" % (got[:4], want[:4]))


def main():
    check(os.access(CUPID, os.X_OK), "no cupid binary at %s (set CUPID)" % CUPID)
    with tempfile.TemporaryDirectory(prefix="cupid_vtu_readers.") as work:
        static_pd(work)
        static_fe(work)
        static_coupled(work)
        dynamic(work, "tests/models/dynamics/fe_truss.yaml", "beam")
        dynamic(work, "tests/models/dynamics/pd_truss.yaml", "pd")
        dynamic_coupled(work)
    print("vtu_readers: meshio %s (%s), VTK %s: %d checks, %d failed"
          % (meshio.__version__, os.path.dirname(meshio.__file__), vtkVersion.GetVTKVersion(),
             checks, len(failures)))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
