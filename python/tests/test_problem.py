"""The Python package against the command line (issue 15): the same model through cupid.Problem
and `cupid run` gives the same numbers; fields, sampling, dict models and errors."""
import json
import os
import subprocess

import numpy as np
import pytest

import cupid

SRC = os.environ.get("CUPID_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
CLI = os.environ.get("CUPID", os.path.join(SRC, "build", "cupid"))
BAR = os.path.join(SRC, "tests", "models", "mpi", "coupled_bar.yaml")


@pytest.fixture(scope="module")
def bar(tmp_path_factory):
    out = tmp_path_factory.mktemp("cli")
    subprocess.run([CLI, "run", BAR, "-o", str(out), "--quiet"], check=True)
    summary = json.load(open(out / "summary.json"))
    p = cupid.Problem(BAR)
    p.solve()
    return p, summary


def test_points_equal_the_cli(bar):
    p, summary = bar
    pts = np.array([[q["x"], q["y"], q["z"]] for q in summary["points"]])
    u, regions = p.sample(pts)
    umax = np.abs(p.pd_displacement).max()
    for k, q in enumerate(summary["points"]):
        # the same code path: equal to the last printed digit
        assert np.allclose(u[k], [q["ux"], q["uy"], q["uz"]], rtol=0, atol=1e-12 * umax)
        assert regions[k] == q["region"]


def test_counts_and_resultants_equal_the_cli(bar):
    p, summary = bar
    info = p.info
    for key in ("pd_nodes", "bonds", "fictitious_nodes", "fe_dofs", "dofs", "constrained_dofs"):
        assert info[key] == summary["counts"][key], key
    scale = np.abs(summary["applied_load_sum"]).max()
    assert np.allclose(info["load_sum"], summary["applied_load_sum"], rtol=0, atol=1e-12 * scale)
    assert np.allclose(info["reaction_sum"], summary["reaction_sum"], rtol=0, atol=1e-12 * scale)
    assert info["coupling"] == "fictitious" and info["stage"] == 2
    # the coupling's quality report (docs/coupling.md): the same figures as summary.json's
    q = summary["coupling_quality"]
    assert info["ghost_force"] == q["patch_test"]["ghost_force"] and 0 <= info["ghost_force"] < 1e-12
    assert info["quality_warnings"] == q["warnings"] == []


def test_fields_have_the_model_shape(bar):
    p, summary = bar
    n = summary["counts"]["pd_nodes"]
    assert p.pd_coordinates.shape == (n, 3)
    assert p.pd_displacement.shape == (n, 3)
    assert p.pd_force.shape == (n, 3)
    assert p.pd_stress.shape == (n, 6)
    assert p.beam_points.shape == p.beam_displacement.shape and p.beam_points.shape[0] > 0
    assert np.all(np.isfinite(p.pd_displacement)) and np.all(np.isfinite(p.beam_displacement))
    # sampling at a PD node's centre gives that node's displacement
    x = p.pd_coordinates
    k = int(np.argmax(x[:, 1]))
    u, regions = p.sample(x[k])
    assert regions == ["PD"]
    assert np.allclose(u[0], p.pd_displacement[k], rtol=1e-12, atol=0)


def pd_bar(E=10000.0, load=100.0):
    """A 10 x 10 x 20 LPS bar, fixed at y < 0, pulled at y = 20 (as examples/pd_bar)."""
    return {
        "title": "dict bar",
        "materials": {"resin": {"E": E, "nu": 0.2}},
        "peridynamics": {"spacing": 1.0, "horizon": 3.0, "model": "lps", "material": "resin",
                         "regions": [{"x": [0, 10], "y": [-3, 20], "z": [0, 10]}]},
        "constraints": [{"fix": {"box": {"y": [-3, 0]}}}],
        "loads": [{"traction": {"y": 20, "value": [0, load, 0]}}],
        "analysis": {"type": "static", "solver": "direct"},
        "output": {"directory": "unused"},
    }


def test_a_dict_model_runs_and_is_linear():
    u1 = cupid.Problem(pd_bar(load=100.0)).solve().pd_displacement
    u2 = cupid.Problem(pd_bar(load=200.0)).solve().pd_displacement
    assert np.abs(u1[:, 1]).max() > 0
    # linear elasticity: twice the load, twice the displacement (to the solver's residual)
    assert np.allclose(u2, 2 * u1, rtol=0, atol=1e-9 * np.abs(u2).max())


def test_model_errors_carry_file_line_col(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text(open(BAR).read().replace("spacing: 2.0", "spacing: -2.0"))
    with pytest.raises(cupid.Error) as e:
        cupid.Problem(str(bad)).solve()
    assert e.value.exit_code == 1
    assert str(bad) + ":" in str(e.value)
    line = str(e.value).split(str(bad) + ":")[1].split(":")[0]
    assert line.isdigit()


def test_stage_order_and_unknown_field(bar):
    p, _ = bar
    with pytest.raises(KeyError):
        p.field("temperature")
    q = cupid.Problem(pd_bar())
    with pytest.raises(cupid.Error) as e:
        q.field("pd_displacement")  # before solve
    assert e.value.exit_code == 4


def test_dynamic_history_equals_history_csv(tmp_path):
    model = os.path.join(SRC, "tests", "models", "dynamics", "fe_truss.yaml")
    subprocess.run([CLI, "run", model, "-o", str(tmp_path), "--quiet"], check=True)
    rows = np.loadtxt(tmp_path / "history.csv", delimiter=",", skiprows=1)
    header = open(tmp_path / "history.csv").readline().strip().split(",")
    p = cupid.Problem(model).solve()
    h = p.history
    assert h["t"].shape[0] == rows.shape[0] > 10
    assert np.allclose(h["t"], rows[:, 0], rtol=1e-9, atol=0)
    scale = np.abs(rows[:, 1:]).max()
    for k, name in enumerate(n for n in h if n != "t"):
        assert header[1 + 3 * k] == name + "_ux"
        # history.csv prints 11 significant digits
        assert np.allclose(h[name], rows[:, 1 + 3 * k:4 + 3 * k], rtol=0, atol=1e-9 * scale)


def test_from_text_gives_the_file_and_its_errors():
    text = open(BAR).read()
    u_text = cupid.Problem.from_text(text, "bar.yaml").solve().pd_displacement
    u_file = cupid.Problem(BAR).solve().pd_displacement
    assert np.array_equal(u_text, u_file)
    with pytest.raises(cupid.Error) as e:
        cupid.Problem.from_text(text.replace("spacing: 2.0", "spacing: -2.0"), "edited.yaml")
    assert "edited.yaml:" in str(e.value) and e.value.exit_code == 1


def test_damage_field_of_a_cracking_plate():
    """Dynamic fracture through the package: a small notched plate pulled by grips moving
    with t breaks bonds at the notch; pd_damage is one column, 0 far from the crack, and its
    damaged nodes are those summary.json counts."""
    model = {
        "materials": {"glass": {"E": 72000, "nu": 0.25, "density": 2.44e-9}},
        "peridynamics": {"spacing": 1.0, "horizon": 3.015, "model": "bond",
                         "influence": "constant", "material": "glass",
                         "regions": [{"x": [0, 12], "y": [0, 24], "z": [0, 2]}],
                         "precracks": [{"normal": "y", "at": 12, "x": [0, 4], "z": [0, 2]}],
                         "fracture": {"criterion": "stretch", "critical_stretch": 1e-3}},
        "constraints": [
            {"displacement": {"box": {"y": [21, 24]}, "value": [0, "100*t", 0]}},
            {"displacement": {"box": {"y": [0, 3]}, "value": [0, "-100*t", 0]}}],
        "analysis": {"type": "dynamic",
                     "dynamic": {"integrator": "central", "dt": 5e-8, "duration": 6e-5,
                                 "every": 100, "lumped": True}},
        "output": {"vtu": False, "plots": False},
    }
    p = cupid.Problem(model)
    p.setup()
    d0 = p.pd_damage
    assert d0.shape == (p.info["pd_nodes"], 1) and d0.max() > 0  # the notch, before solving
    p.solve()
    d = p.pd_damage
    x = p.pd_coordinates
    assert d.shape == (x.shape[0], 1) and np.all(np.isfinite(d))
    assert (d[:, 0] > d0[:, 0]).any(), "no bond broke"
    # off the crack band; the free edge x = 11.5 loses a bond or two at the grips (so does
    # LAMMPS in tests/verification/fracture_lammps)
    far = (np.abs(x[:, 1] - 12.0) > 4.0) & (x[:, 0] < 11)
    assert np.all(d[far, 0] == 0.0)
    # a model without fracture has no damage rows
    assert cupid.Problem(pd_bar()).setup().pd_damage.shape[0] == 0


def test_crack_growth_peak_and_stop(tmp_path):
    """Quasi-static growth through the package: the plate of tests/models/growth/plate.yaml runs
    to its end (stopped is None) with the envelope's peak equal to summary.json's; the SENB whose
    crack reaches an Arlequin overlap stops (info names the overlap, solve still succeeds and
    the files are written: the command line turns this into exit status 2; solve() raises
    GrowthStopped, issue 33)."""
    plate = os.path.join(SRC, "tests", "models", "growth", "plate.yaml")
    p = cupid.Problem(plate, output_dir=str(tmp_path / "plate"))
    p.solve()
    p.write_outputs()
    info = p.info
    peak = json.load(open(tmp_path / "plate" / "summary.json"))["fracture"]["peak_reactions"][0]
    assert info["stopped"] is None
    assert info["peak_load_factor"] == peak["load_factor"] > 0
    assert info["peak_reaction"] == peak["reaction"]
    stop = os.path.join(SRC, "tests", "models", "growth", "senb_interface.yaml")
    q = cupid.Problem(stop, output_dir=str(tmp_path / "stop"))
    with pytest.raises(cupid.GrowthStopped) as stopped:
        q.solve()
    assert stopped.value.exit_code == 2 and "Arlequin overlap {x: [8, 12]}" in str(stopped.value)
    assert "Arlequin overlap {x: [8, 12]}" in q.info["stopped"]


def test_growth_outputs_twice_quiet_and_dict_folder(tmp_path, capfd, monkeypatch):
    """Issue 33: a second write_outputs() keeps what the first wrote (it removed damage.csv,
    model.pvd and the frames as stale); a collapsed growth raises GrowthStopped and prints
    nothing with quiet=True; a dict model without output.directory writes to out/model (it made
    a folder named "out/<dict>")."""
    plate = os.path.join(SRC, "tests", "models", "growth", "plate.yaml")
    p = cupid.Problem(plate, output_dir=str(tmp_path / "twice"))
    p.solve()
    p.write_outputs()
    first = sorted(os.listdir(tmp_path / "twice"))
    assert "damage.csv" in first and "summary.json" in first
    p.write_outputs()
    assert sorted(os.listdir(tmp_path / "twice")) == first
    capfd.readouterr()
    apart = os.path.join(SRC, "tests", "models", "growth", "pulled_apart.yaml")
    q = cupid.Problem(apart, output_dir=str(tmp_path / "apart"), quiet=True)
    with pytest.raises(cupid.GrowthStopped) as stopped:
        q.solve()
    assert "the body collapsed at load step 2" in str(stopped.value)
    q.write_outputs()
    assert capfd.readouterr().err == ""
    fr = json.load(open(tmp_path / "apart" / "summary.json"))["fracture"]
    assert fr["collapse"]["step"] == 2
    monkeypatch.chdir(tmp_path)
    model = {"materials": {"m": {"E": 1000, "nu": 0.25}},
             "peridynamics": {"spacing": 1, "horizon": 2, "material": "m",
                              "regions": [{"x": [0, 2], "y": [0, 4], "z": [0, 2]}]},
             "constraints": [{"fix": {"box": {"y": [0, 1]}}}],
             "loads": [{"traction": {"y": 4, "value": [0, 1, 0]}}]}
    r = cupid.Problem(model)
    assert r.output_dir == "out/model"
    r.solve().write_outputs()
    assert os.path.exists(tmp_path / "out" / "model" / "summary.json")


def test_resume_an_interrupted_run(tmp_path):
    """Issue 36: a run stopped by SIGTERM (exit 5, a checkpoint) continued from Python with
    resume=True ends with the uninterrupted run's files and history, to the bit."""
    import signal
    import time
    text = open(os.path.join(SRC, "examples", "notched_plate", "notched_plate.yaml")).read()
    text = text.replace("  plots: true", "  plots: false\n  checkpoint: 0.05\n  points:\n"
                        "    - {name: tip, at: [10.5, 20.5, 1.5]}")
    model = tmp_path / "plate.yaml"
    model.write_text(text)
    ref = cupid.Problem(str(model), output_dir=str(tmp_path / "ref")).solve().write_outputs()
    out = tmp_path / "run"
    proc = subprocess.Popen([CLI, "run", str(model), "-o", str(out), "--quiet"],
                            stderr=subprocess.PIPE)
    time.sleep(0.4)
    proc.send_signal(signal.SIGTERM)
    assert proc.wait() in (0, 5), proc.stderr.read()
    if proc.returncode == 5:
        assert b"--resume" in proc.stderr.read()
        p = cupid.Problem(str(model), output_dir=str(out), resume=True).solve().write_outputs()
        for name in ref.history:
            assert np.array_equal(p.history[name], ref.history[name])
    for name in ("damage.csv", "energies.csv", "history.csv", "pd_002500.vtu", "model.pvd"):
        assert (out / name).read_bytes() == (tmp_path / "ref" / name).read_bytes(), name
    with pytest.raises(cupid.Error) as e:
        cupid.Problem(str(model), output_dir=str(tmp_path / "none"), resume=True).solve()
    assert e.value.exit_code == 3 and "nothing to resume" in str(e.value)


def test_ctrl_c_stops_solve_at_a_checkpoint(tmp_path):
    """Issue 36: SIGINT during solve() (cupid's handlers while it runs) writes a checkpoint and
    raises cupid.Interrupted (exit code 5); resume=True then ends with the uninterrupted files."""
    import signal
    import sys
    import time
    text = open(os.path.join(SRC, "examples", "notched_plate", "notched_plate.yaml")).read()
    text = text.replace("  plots: true", "  plots: false")
    model = tmp_path / "plate.yaml"
    model.write_text(text)
    ref = cupid.Problem(str(model), output_dir=str(tmp_path / "ref")).setup()
    t0 = time.monotonic()
    ref.solve().write_outputs()
    seconds = time.monotonic() - t0
    script = ("import sys, cupid\n"
              f"p = cupid.Problem({str(model)!r}, output_dir={str(tmp_path / 'run')!r}).setup()\n"
              "print('set up', flush=True)\n"
              "try:\n"
              "    p.solve()\n"
              "except cupid.Interrupted as e:\n"
              "    print('interrupted', e.exit_code)\n"
              "    sys.exit(5)\n")
    proc = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, env=os.environ)
    assert proc.stdout.readline() == b"set up\n"
    time.sleep(0.5 * seconds)  # half-way through the steps, as the reference ran them
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate()
    if proc.returncode == 0:
        pytest.skip("the run ended before the signal came")
    assert proc.returncode == 5 and b"interrupted 5" in out, (out, err)
    cupid.Problem(str(model), output_dir=str(tmp_path / "run"), resume=True).solve().write_outputs()
    for name in ("damage.csv", "energies.csv", "pd_002500.vtu", "model.pvd"):
        assert (tmp_path / "run" / name).read_bytes() == (tmp_path / "ref" / name).read_bytes(), name
