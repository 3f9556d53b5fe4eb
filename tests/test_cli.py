"""The kinetwork command: outputs, summaries, and exit codes without tracebacks."""

import csv
import subprocess
import sys

import numpy as np
import pytest
from conftest import double_pendulum
from scenes.reference import seed_reference

import kinetwork as kn
from kinetwork.cli import main

QUANTITIES = ["angle", "speed", "acceleration", "torque"]


@pytest.fixture
def blowup_file(tmp_path):
    """A torque 1/(1-t)^3 on the shoulder: every integrator fails just before t = 1."""
    m = double_pendulum()
    m.add(kn.rotational.Torque("blowup", tau="1/(1-t)**3"))
    m.connect("blowup.flange", "shoulder.axis")
    path = tmp_path / "blowup.json"
    m.save(path)
    return path


def read_csv(path, partial=None):
    """(header, data) of a results CSV, numbers only; ``partial`` says whether its sidecar
    must say the run stopped early (None: either)."""
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    if partial is not None:
        assert (kn.read_csv(path).partial is not None) == partial
    return rows[0], np.array(rows[1:], dtype=float)


def no_traceback(captured):
    return "Traceback" not in captured.out + captured.err


def test_run_writes_csv_and_plot(seed_file, tmp_path, capsys):
    out, png = tmp_path / "res.csv", tmp_path / "probes.png"
    assert main(["run", str(seed_file), "--t-end", "2", "--n-points", "21",
                 "--out", str(out), "--plot", str(png)]) == 0
    header, data = read_csv(out)
    assert header == ["t"] + [f"{p}.{q}" for p in ("probe1", "probe2") for q in QUANTITIES]
    ref = kn.simulate(double_pendulum(), t_end=2.0, n_points=21)
    np.testing.assert_array_equal(data[:, 0], ref.t)
    np.testing.assert_allclose(data[:, 1], ref["probe1.angle"], rtol=1e-12)
    assert png.read_bytes()[:4] == b"\x89PNG"
    printed = capsys.readouterr().out
    assert "double_pendulum: 4 states (shoulder.q, elbow.q, shoulder.qd, elbow.qd)" in printed
    assert "t = 0 .. 2 s (21 points) with cvodes" in printed and "wall time" in printed
    assert f"wrote 21 points x 9 columns to {out}" in printed


def test_run_options_and_parameters(seed_file, tmp_path):
    out = tmp_path / "res.csv"
    assert main(["run", str(seed_file), "--t-end", "1", "--n-points", "11", "--method",
                 "RK45", "--rtol", "1e-9", "--atol", "1e-11", "--param", "c=5",
                 "--param", "d=0.25", "--out", str(out)]) == 0
    _, data = read_csv(out)
    ref = kn.simulate(double_pendulum(), t_end=1.0, n_points=11, method="DOP853",
                      rtol=1e-11, atol=1e-12, params={"c": 5.0, "d": 0.25})
    np.testing.assert_allclose(data[:, 1], ref["probe1.angle"], atol=1e-7)


def test_run_defaults_come_from_the_model(tmp_path):
    m = double_pendulum()
    m.simulation.update({"t_end": 0.5, "n_points": 6})
    m.save(tmp_path / "m.json")
    assert main(["run", str(tmp_path / "m.json"), "--out", str(tmp_path / "r.csv")]) == 0
    _, data = read_csv(tmp_path / "r.csv")
    np.testing.assert_allclose(data[:, 0], np.linspace(0, 0.5, 6))


def test_validate_summarises(seed_file, capsys):
    assert main(["validate", "--compile", str(seed_file)]) == 0
    out = capsys.readouterr().out
    system = double_pendulum().compile()
    for line in [
        "components: 9 (2 multibody.Revolute, 2 multibody.RigidBody, 2 Probe, "
        "1 multibody.Ground, 1 multibody.FixedTranslation, 1 rotational.SpringDamper)",
        "degrees of freedom: 2",
        "states: 4 (shoulder.q [rad], elbow.q [rad], shoulder.qd [rad/s], elbow.qd [rad/s])",
        "loops: none",
        f"equations: 4 states, 0 algebraic variables, 8 probe signals (8 values); "
        f"right-hand side {system.size()['operations']} operations per evaluation "
        f"(articulated-body algorithm, O(N))",
        "parameters: 7 (L1 = 1, L2 = 1, m1 = 1, m2 = 1, c = 1, d = 1, g = 9.8)",
    ]:
        assert line in out.splitlines()


def test_methods_lists_every_method_and_the_default(capsys):
    assert main(["methods"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("default: auto, rtol 1e-06, atol 1e-08")
    listed = [line.split()[0] for line in out.splitlines()[1:] if not line.startswith("    ")]
    assert listed == list(kn.METHODS)


@pytest.mark.parametrize("jit, code", [("--jit", "C"), ("--no-jit", "CasADi virtual machine")])
def test_run_fixed_step_and_jit_options(seed_file, tmp_path, capsys, jit, code):
    out = tmp_path / "out.csv"
    assert main(["run", str(seed_file), "--method", "rk", "--step", "0.002", jit,
                 "--t-end", "1", "--n-points", "101", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert f"with rk ({code}" in text and "500 steps" in text
    ref = seed_reference(np.linspace(0, 1, 101))
    data = np.loadtxt(out, delimiter=",", skiprows=1)
    np.testing.assert_allclose(data[:, 1], ref[:, 0], atol=1e-8)     # probe1.angle


def test_equations_text_reads_like_the_paper(seed_file, capsys):
    assert main(["equations", str(seed_file)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert "coordinates: q_shoulder = shoulder.q, q_elbow = elbow.q" in lines
    assert "M11 = L1**2*m1/4 + L1**2*m2 + L1*L2*m2*cos(q_elbow) + L2**2*m2/4" in lines
    assert "M22 = L2**2*m2/4" in lines
    assert "V2 = L1*L2*m2*qd_shoulder**2*sin(q_elbow)/2" in lines
    assert "G2 = L2*g*m2*sin(q_elbow + q_shoulder)/2" in lines


@pytest.mark.parametrize("fmt, expected", [
    ("latex", r"\dot{q}_{\mathrm{shoulder}}"),
    ("pretty", "M\u2082\u2082 ="),
])
def test_equations_other_formats(seed_file, capsys, fmt, expected):
    assert main(["equations", str(seed_file), "--format", fmt]) == 0
    assert expected in capsys.readouterr().out


def test_equations_as_built(seed_file, capsys):
    assert main(["equations", str(seed_file), "--no-simplify"]) == 0
    out = capsys.readouterr()
    assert "w0 = " in out.out and "M22 = " in out.out
    assert out.err == ""                      # asked for: no note about the size


@pytest.mark.parametrize("command", ["run", "validate", "equations"])
def test_missing_file_exits_1(tmp_path, capsys, command):
    missing = tmp_path / "missing.json"
    assert main([command, str(missing)]) == 1
    err = capsys.readouterr()
    assert f"{missing}: cannot read" in err.err and no_traceback(err)


@pytest.mark.parametrize("argv", [["--help"], ["run", "--help"], ["validate", "--help"],
                                  ["equations", "--help"], ["--version"]])
def test_help_exits_0(capsys, argv):
    with pytest.raises(SystemExit) as info:
        main(argv)
    assert info.value.code == 0
    assert "usage: kinetwork" in capsys.readouterr().out or "--version" in argv


def test_invalid_model_exits_1(tmp_path, capsys):
    bad = tmp_path / "bad.json"
    bad.write_text('{"format": "kinetwork.model", "version": 1, "name": "x", '
                   '"components": [{"name": "g", "type": "multibody.Groud"}], '
                   '"connections": []}')
    assert main(["validate", str(bad)]) == 1
    err = capsys.readouterr()
    assert "did you mean 'multibody.Ground'" in err.err and no_traceback(err)


@pytest.mark.parametrize("option", [["--param", "cc=2"], ["--rtol", "-1"],
                                    ["--plot", "probes.xyz"]])
def test_refused_settings_exit_1(seed_file, tmp_path, capsys, option):
    argv = ["run", str(seed_file), "--t-end", "0.1"] + option
    assert main([a.replace("probes.xyz", str(tmp_path / "p.xyz")) for a in argv]) == 1
    err = capsys.readouterr()
    assert err.err.startswith("kinetwork: error: ") and no_traceback(err)


@pytest.mark.parametrize("option", [["--method", "euler"], ["--param", "c"],
                                    ["--t-end", "soon"], ["--frobnicate"]])
def test_usage_errors_exit_2(seed_file, capsys, option):
    with pytest.raises(SystemExit) as info:
        main(["run", str(seed_file)] + option)
    assert info.value.code == 2
    assert no_traceback(capsys.readouterr())


def test_bad_plot_format_is_refused_before_simulating(seed_file, tmp_path, capsys):
    out = tmp_path / "res.csv"
    assert main(["run", str(seed_file), "--out", str(out), "--plot",
                 str(tmp_path / "probes")]) == 1
    assert "without a file extension" in capsys.readouterr().err
    assert not out.exists()


def test_unwritable_output_exits_1_naming_the_path(seed_file, tmp_path, capsys):
    blocker = tmp_path / "a_file"
    blocker.write_text("not a folder")
    out = blocker / "dir.csv"
    assert main(["run", str(seed_file), "--t-end", "0.1", "--out", str(out)]) == 1
    err = capsys.readouterr()
    assert f"cannot write {out}" in err.err and no_traceback(err)


def test_output_folders_are_made(seed_file, tmp_path):
    out, png = tmp_path / "new" / "res.csv", tmp_path / "plots" / "deep" / "p.png"
    assert main(["run", str(seed_file), "--t-end", "0.5", "--out", str(out),
                 "--plot", str(png)]) == 0
    assert out.exists() and png.exists()


def test_failed_integration_exits_3_with_partial_results(blowup_file, tmp_path, capsys):
    out, png = tmp_path / "partial.csv", tmp_path / "partial.png"
    code = main(["run", str(blowup_file), "--t-end", "2", "--n-points", "201",
                 "--out", str(out), "--plot", str(png)])
    assert code == 3
    err = capsys.readouterr()
    assert "failed after t = " in err.err and no_traceback(err)
    _, data = read_csv(out, partial=True)
    assert 0.9 <= data[-1, 0] <= 1.0
    assert png.exists()


def test_console_entry_point(seed_file):
    """The installed command: exit codes reach the shell, messages reach stderr."""
    ok = subprocess.run([sys.executable, "-m", "kinetwork.cli", "validate", str(seed_file)],
                        capture_output=True, text=True)
    assert ok.returncode == 0 and "degrees of freedom: 2" in ok.stdout
    bad = subprocess.run([sys.executable, "-m", "kinetwork.cli", "run", "nowhere.json"],
                         capture_output=True, text=True)
    assert bad.returncode == 1 and "nowhere.json" in bad.stderr
    assert "Traceback" not in bad.stderr


def test_quiet_run_prints_nothing(seed_file, tmp_path, capsys):
    out = tmp_path / "quiet.csv"
    assert main(["run", str(seed_file), "--quiet", "--out", str(out)]) == 0
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err == ""
    assert out.exists()


def test_step_budget_and_time_limit_end_in_exit_3_with_the_partial_csv(blowup_file, tmp_path,
                                                                         capsys):
    out = tmp_path / "budget.csv"
    code = main(["run", str(blowup_file), "--t-end", "2", "--n-points", "201", "--method",
                 "rk45", "--max-steps", "40", "-q", "--out", str(out)])
    assert code == 3
    err = capsys.readouterr().err
    assert "rk45 failed after t = " in err and "step budget of 40 steps" in err
    assert no_traceback(capsys.readouterr())
    _, data = read_csv(out, partial=True)
    assert 0.5 < data[-1, 0] < 1.0
    # no C compiler in the way; how far 0.2 s of wall time gets depends on the machine and
    # its load (on a busy one, nowhere): what was reached is written, the reason said
    code = main(["run", str(seed_file_long(tmp_path)), "--time-limit", "0.2", "-q",
                 "--no-jit", "--out", str(out)])
    assert code == 3
    assert "time limit" in capsys.readouterr().err
    _, data = read_csv(out, partial=True)
    assert 0 <= data[-1, 0] < 1e5 and np.all(np.isfinite(data))
    assert "time limit" in kn.read_csv(out).partial["reason"]


def seed_file_long(tmp_path):
    """The seed over 1e5 s with a million output points: far more than 0.2 s of work."""
    model = double_pendulum()
    model.simulation = {"t_end": 1e5, "n_points": 1000001}
    path = tmp_path / "long.json"
    model.save(path)
    return path


def test_progress_bar_goes_to_stderr(seed_file, capfd, monkeypatch):
    from kinetwork.solver import progress
    monkeypatch.setattr(progress, "DELAY", 0.0)      # this run is shorter than the delay
    assert main(["run", str(seed_file), "--progress", "--t-end", "5"]) == 0
    captured = capfd.readouterr()
    assert "t = " in captured.err and "%" in captured.err      # the bar
    assert "simulated t = 0 .. 5 s" in captured.out


def test_validate_says_how_a_driven_tree_is_solved(tmp_path, capsys):
    m = kn.Model("driven")
    m.add(kn.multibody.Ground("ground", gravity=[0, -9.81, 0]))
    m.add(kn.multibody.Revolute("j1"))
    m.add(kn.multibody.FixedTranslation("l1", r=[1, 0, 0]))
    m.add(kn.multibody.RigidBody("b1", mass=1.0))
    m.add(kn.multibody.Revolute("j2"))
    m.add(kn.multibody.RigidBody("b2", mass=1.0, r_cm=[1, 0, 0]))
    m.add(kn.rotational.Position("drive", phi_ref="0.5*sin(2*t)"))
    for a, b in [("ground.frame", "j1.frame_a"), ("j1.frame_b", "l1.frame_a"),
                 ("l1.frame_b", "b1.frame_a"), ("l1.frame_b", "j2.frame_a"),
                 ("j2.frame_b", "b2.frame_a"), ("drive.flange", "j1.axis")]:
        m.connect(a, b)
    m.save(tmp_path / "driven.json")
    assert main(["validate", "--compile", str(tmp_path / "driven.json")]) == 0
    out = capsys.readouterr().out
    assert "states: 2 (j2.q [rad], j2.qd [rad/s])" in out
    assert "(articulated-body algorithm with the prescribed accelerations, O(N))" in out
