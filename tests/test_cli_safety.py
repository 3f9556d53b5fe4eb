"""The kinetwork command under careless or hostile use: validate without building the
equations, settings refused before anything runs, outputs that would overwrite the model or
each other, long texts summarised, and runs stopped by SIGINT or SIGTERM that still write
what they computed and exit 128 + the signal."""

import os
import pathlib
import resource
import select
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from conftest import double_pendulum
from procstat import cpu_seconds

import kinetwork as kn
import kinetwork.graph.model as graph_model
from kinetwork.cli import main
from kinetwork.graph.settings import MAX_STEPS


def chain(n, probe=False):
    """N rods on revolute z joints hanging under gravity, the first released at 0.5 rad."""
    m = kn.Model(f"chain{n}")
    mb = kn.multibody
    m.add(mb.Ground("ground", gravity=[0, -9.81, 0]))
    previous = "ground.frame"
    for i in range(n):
        m.add(mb.Revolute(f"j{i}", axis=[0, 0, 1], q0=0.5 if i == 0 else 0.0))
        m.add(mb.RigidBody(f"b{i}", mass=1.0, r_cm=[0, -0.5, 0], inertia=[0.08, 1e-4, 0.08]))
        m.add(mb.FixedTranslation(f"l{i}", r=[0, -1, 0]))
        m.connect(previous, f"j{i}.frame_a")
        m.connect(f"j{i}.frame_b", f"b{i}.frame_a")
        m.connect(f"j{i}.frame_b", f"l{i}.frame_a")
        previous = f"l{i}.frame_b"
    if probe:
        m.add(kn.Probe("probe", quantities=["angle"]))
        m.connect("probe.port", "j0.axis")
    return m


@pytest.fixture
def no_compiler(monkeypatch):
    """Building a System fails the test: what it guards must not compile."""
    def refuse(*args, **kwargs):
        raise AssertionError("the equations were built")
    upcall = graph_model.upcall            # Model.compile reaches the equations through it
    monkeypatch.setattr(graph_model, "upcall",
                        lambda name: refuse if name == "compile" else upcall(name))


def no_traceback(captured):
    return "Traceback" not in captured.out + captured.err


# -- validate -------------------------------------------------------------------------------
def test_validate_summarises_a_large_chain_without_building_its_equations(
        tmp_path, capsys, no_compiler):
    path = tmp_path / "chain.json"
    chain(1000).save(path)                  # 3001 components
    assert main(["validate", str(path)]) == 0
    lines = capsys.readouterr().out.splitlines()
    for line in ["components: 3001 (1000 multibody.Revolute, 1000 multibody.RigidBody, "
                 "1000 multibody.FixedTranslation, 1 multibody.Ground)",
                 "connections: 3000", "degrees of freedom: 1000", "loops: none",
                 "1-D rigid groups: 1000 on joint axes, 1000 fixed", "parameters: 0"]:
        assert line in lines
    assert not any(line.startswith(("states:", "equations:")) for line in lines)


def test_validate_compile_adds_the_equations(seed_file, capsys):
    assert main(["validate", str(seed_file)]) == 0
    plain = capsys.readouterr().out
    assert main(["validate", "--compile", str(seed_file)]) == 0
    full = capsys.readouterr().out
    assert "states: 4 (shoulder.q [rad]" in full and "states:" not in plain
    assert "equations: 4 states" in full and "equations:" not in plain
    assert "degrees of freedom: 2" in plain.splitlines()
    assert "degrees of freedom: 2" in full.splitlines()


def test_validate_of_a_model_with_loops_bounds_its_degrees_of_freedom(tmp_path, capsys,
                                                                      no_compiler):
    root = os.path.join(os.path.dirname(__file__), "..", "models", "fourbar.json")
    assert main(["validate", root]) == 0
    out = capsys.readouterr().out
    assert "degrees of freedom: at most 4, less one per independent closure equation" in out
    assert "loops: 1" in out


def test_validate_prints_a_long_description_and_long_lists_cut(tmp_path, capsys):
    m = double_pendulum()
    m.description = "lorem ipsum " * 100_000             # 1.2 MB
    for i in range(100):
        m.set_parameter(f"p{i}", float(i))
    path = tmp_path / "long.json"
    m.save(path)
    assert main(["validate", str(path)]) == 0
    out = capsys.readouterr().out
    assert len(out) < 5000
    assert "... (1200000 characters)" in out and "(107 in all)" in out


# -- settings -------------------------------------------------------------------------------
@pytest.mark.parametrize("option", [["--time-limit", "nan"], ["--time-limit", "inf"],
                                    ["--time-limit", "-1"], ["--time-limit", "0"],
                                    ["--max-steps", "0"], ["--max-steps", "-5"],
                                    ["--param", "c=nan"], ["--param", "c=inf"]])
def test_options_of_the_command_are_checked_when_parsed(seed_file, capsys, option):
    with pytest.raises(SystemExit) as info:
        main(["run", str(seed_file)] + option)
    assert info.value.code == 2
    captured = capsys.readouterr()
    assert option[0] in captured.err and no_traceback(captured)


@pytest.mark.parametrize("option, says", [
    (["--rtol", "nan"], "simulation.rtol: must be a finite number > 0, got nan"),
    (["--atol", "nan"], "simulation.atol: must be a finite number > 0, got nan"),
    (["--t-end", "inf"], "simulation.t_end: must be a finite number > 0, got inf"),
    (["--step", "1e-300"], f"1e+301 steps to cover 10 s, more than the {MAX_STEPS}"),
    (["--step", "1e-12", "--t-end", "2000"], "2e+15 steps to cover 2000 s"),
    (["--n-points", "1000000000"], "would need 14.9 GiB, more than the 2 GiB"),
])
def test_settings_are_refused_before_anything_is_built(seed_file, capsys, no_compiler,
                                                      option, says):
    assert main(["run", str(seed_file)] + option) == 1
    captured = capsys.readouterr()
    assert says in captured.err and no_traceback(captured)


def test_an_output_too_large_for_memory_is_refused_with_the_size_it_would_need(
        seed_file, capsys):
    # 1e8 points are allowed for time and one value; the seed's 13 values per point are not
    start = time.process_time()           # CPU time: other processes' load does not count
    assert main(["run", str(seed_file), "--n-points", "100000000"]) == 1
    err = capsys.readouterr().err
    assert "the results (13 values per point: time, states and probe signals) would need " \
           "about 15.6 GiB, more than the 2 GiB a run may keep" in err
    assert time.process_time() - start < 60


# -- outputs --------------------------------------------------------------------------------
@pytest.mark.parametrize("clash", ["out", "plot", "both", "link", "hardlink"])
def test_outputs_never_overwrite_the_model_or_each_other(seed_file, tmp_path, capsys,
                                                         no_compiler, clash):
    before = seed_file.read_bytes()
    other = tmp_path / "res.csv"
    if clash == "link":
        (tmp_path / "link.csv").symlink_to(seed_file)
        argv = ["--out", str(tmp_path / "link.csv")]
    elif clash == "hardlink":
        os.link(seed_file, tmp_path / "hard.png")
        argv = ["--plot", str(tmp_path / "hard.png")]
    else:
        argv = {"out": ["--out", str(seed_file)], "plot": ["--plot", str(seed_file)],
                "both": ["--out", str(other), "--plot", str(tmp_path / "." / "res.csv")]}[clash]
    assert main(["run", str(seed_file)] + argv) == 2
    captured = capsys.readouterr()
    assert "nothing was run" in captured.err and no_traceback(captured)
    assert seed_file.read_bytes() == before and not other.exists()


def children_cpu_seconds():
    """The CPU seconds of every child this process has waited for (a child's share is the
    difference across its wait)."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


# -- interrupted runs -----------------------------------------------------------------------
def ignoring_sigint():
    """Start a child as a script's background job starts: with SIGINT ignored."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


@pytest.mark.parametrize("signum, code, ignored", [(signal.SIGINT, 130, False),
                                                   (signal.SIGTERM, 143, False),
                                                   (signal.SIGINT, 130, True)])
def test_a_run_stopped_by_a_signal_writes_its_partial_results(tmp_path, signum, code, ignored):
    model = tmp_path / "chain.json"
    chain(30, probe=True).save(model)
    out = tmp_path / "out.csv"
    env = dict(os.environ, KINETWORK_JIT="0")           # no C compiler in the way
    # 1000 s of a 30-link chain: half a minute or more of integration
    waited = children_cpu_seconds()
    child = subprocess.Popen(
        [sys.executable, "-m", "kinetwork.cli", "run", str(model), "--out", str(out),
         "--t-end", "1000", "--n-points", "100001", "--quiet", "--progress"],
        env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
        preexec_fn=ignoring_sigint if ignored else None)
    try:
        # the progress bar's first output: the equations are built, the run has begun
        assert os.read(child.stderr.fileno(), 1)
        started, patience = cpu_seconds(child.pid), time.monotonic() + 120
        # a second and a half of the command's CPU (not of wall time: a loaded machine gives
        # it less): rows enough to be written when it stops
        while ((before := cpu_seconds(child.pid)) < 1.5 + started and child.poll() is None
               and time.monotonic() < patience):
            time.sleep(0.05)
        child.send_signal(signum)
        _, err = child.communicate(timeout=120)
        took = children_cpu_seconds() - waited - before
    finally:
        if child.poll() is None:
            child.kill()
            child.communicate()
    err = err.decode()
    assert child.returncode == code, err[-500:]
    # the CPU the command spent from the signal to its exit, not wall time (other processes'
    # load must not fail the test): stopping and writing the partial CSV, no more integrating
    assert took < 2.0, f"{took:.2f} s of CPU from the signal to the exit"
    assert f"interrupted by {signal.Signals(signum).name}" in err and "Traceback" not in err
    lines = out.read_text().splitlines()
    assert lines[0] == "t,probe.angle" and kn.read_csv(out).status in ("partial", "cut")
    data = np.loadtxt(out, delimiter=",", skiprows=1, ndmin=2)
    assert len(data) > 10 and np.all(np.isfinite(data)) and data[-1, 0] < 1000


def test_a_signal_while_the_command_starts_stops_it_with_nothing_run(tmp_path):
    # SIGINT from the first moment, every 20 ms, to a command started with it ignored (as a
    # script's background job is): those before its handlers are lost, as the system
    # ignores them; the first after them stops it, never a traceback from an import nor a
    # run to the end with exit 0. The signals end when it speaks: one in the last moments of
    # the interpreter, after Python gave the signals back to the system, would kill it.
    out = tmp_path / "out.csv"
    child = subprocess.Popen(
        [sys.executable, "-m", "kinetwork", "run", "models/double_pendulum.json", "--out",
         str(out), "--t-end", "1000", "--n-points", "100001", "--quiet"],
        env=dict(os.environ, KINETWORK_JIT="0"), stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE, preexec_fn=ignoring_sigint)
    try:
        while child.poll() is None and not select.select([child.stderr], [], [], 0.02)[0]:
            child.send_signal(signal.SIGINT)
        err = child.communicate(timeout=120)[1].decode()
    finally:
        if child.poll() is None:
            child.kill()
            child.communicate()
    assert child.returncode == 130, err[-500:]
    assert "interrupted by SIGINT" in err and "Traceback" not in err
    assert not out.exists() or kn.read_csv(out).status in ("partial", "cut")


def test_a_signal_caught_while_starting_is_answered_before_any_work(tmp_path, monkeypatch,
                                                                      capsys):
    from kinetwork import cli
    monkeypatch.setitem(cli._EARLY, "signum", signal.SIGTERM)
    out = tmp_path / "out.csv"
    assert main(["run", "models/double_pendulum.json", "--out", str(out)]) == 143
    assert "interrupted by SIGTERM" in capsys.readouterr().err and not out.exists()


def test_equations_of_a_model_with_a_long_table_are_refused_in_words(tmp_path, capsys):
    m = double_pendulum()
    x = np.linspace(0.0, 10.0, 200)               # an interpolant, not an expression
    m.add(kn.signals.Table("tab", table=np.column_stack([x, np.sin(x)]).tolist()))
    m.add(kn.rotational.Torque("push"))
    m.connect("tab.y", "push.u")
    m.connect("push.flange", "elbow.axis")
    m.save(tmp_path / "table.json")
    assert main(["equations", str(tmp_path / "table.json")]) == 1
    captured = capsys.readouterr()
    assert "cannot be printed in closed form" in captured.err and no_traceback(captured)


def test_cache_shows_and_clears_only_what_kinetwork_built(tmp_path, monkeypatch, capsys):
    from kinetwork import cli
    folder = tmp_path / "cache"
    monkeypatch.setenv("KINETWORK_CACHE", str(folder))
    assert cli.main(["run", "models/double_pendulum.json", "-q", "--jit", "--t-end", "0.1"]) == 0
    capsys.readouterr()
    assert cli.main(["cache"]) == 0
    shown = capsys.readouterr().out
    assert f"{folder}: 2 compiled libraries" in shown and "rhs_" in shown
    assert "and 1 derived System kept" in shown
    (folder / "notes.txt").write_text("mine")
    assert cli.main(["cache", "--clear"]) == 0
    # two libraries, their records, the kept System
    assert "removed 5 files" in capsys.readouterr().out
    assert sorted(p.name for p in folder.iterdir()) == ["notes.txt", "systems"]
    assert not list((folder / "systems").iterdir())
    assert cli.main(["cache"]) == 0 and ": 0 compiled libraries" in capsys.readouterr().out
