"""Every command of ``kinetwork`` under hostile paths and arguments: outputs that would damage
a file (the command's own input by any name, a device, a FIFO, a folder, a file of another
kind), stops while a large result is written, inputs that never end or never come, and
arguments that used to end in a traceback. Each case ends in a result, a refusal naming its
place (exit 1 or 2) or a failed run with what it reached (exit 3), and no file is damaged."""

import os
import pathlib
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from conftest import double_pendulum
from test_cli_safety import no_compiler, no_traceback  # noqa: F401  (a fixture)

import kinetwork as kn
from kinetwork.cli import main

URDF = pathlib.Path(__file__).parent / "data" / "planar_arm.urdf"
PNG = b"\x89PNG\r\n\x1a\n" + bytes(64)


@pytest.fixture
def scene(tmp_path, monkeypatch):
    """A folder holding the seed's model, a URDF, a FIFO, a folder and files of other kinds;
    the current folder."""
    monkeypatch.chdir(tmp_path)
    double_pendulum().save(tmp_path / "dp.json")
    (tmp_path / "robot.urdf").write_bytes(URDF.read_bytes())
    os.mkfifo(tmp_path / "pipe.out")
    (tmp_path / "folder.out").mkdir()
    (tmp_path / "notes.out").write_text("my notes, kept\n")
    (tmp_path / "picture.out").write_bytes(PNG)
    return tmp_path


def snapshot(folder):
    """Every regular file's bytes, and what the others are."""
    out = {}
    for p in sorted(folder.iterdir()):
        out[p.name] = p.read_bytes() if p.is_file() and not p.is_symlink() else \
            ("link", os.readlink(p)) if p.is_symlink() else ("special", p.stat().st_mode)
    return out


COMMANDS = {
    "run --out": (["run", "dp.json", "--t-end", "0.1", "--out"], "dp.json", ".csv"),
    "run --plot": (["run", "dp.json", "--t-end", "0.1", "--plot"], "dp.json", ".png"),
    "sweep --out": (["sweep", "dp.json", "--param", "d=0.1,0.2", "--t-end", "0.1", "--out"],
                    "dp.json", ".nc"),
    "import -o": (["import", "robot.urdf", "-o"], "robot.urdf", ".json"),
    "animate --html": (["animate", "dp.json", "--t-end", "0.1", "--html"], "dp.json", ".html"),
    "diagram -o": (["diagram", "dp.json", "-o"], "dp.json", ".svg"),
}


def target(scene, command, how):
    """The output path of ``how`` for ``command`` (made in ``scene``)."""
    argv, source, suffix = COMMANDS[command]
    if how == "input":
        return source
    if how == "input ./":
        return f"./{source}"
    if how in ("input symlink", "input hardlink"):
        name = f"alias{suffix}"
        (os.symlink if how == "input symlink" else os.link)(source, scene / name)
        return name
    if how == "fifo":
        os.rename(scene / "pipe.out", scene / f"pipe{suffix}")
        return f"pipe{suffix}"
    if how == "folder":
        os.rename(scene / "folder.out", scene / f"folder{suffix}")
        return f"folder{suffix}"
    if how == "device":
        return "/dev/null"
    if how == "other kind":
        os.rename(scene / "notes.out", scene / f"notes{suffix}")
        return f"notes{suffix}"
    raise AssertionError(how)


@pytest.mark.parametrize("how, code, says", [
    ("input", 2, "is an input here"), ("input ./", 2, "is an input here"),
    ("input symlink", 2, "is an input here"), ("input hardlink", 2, "is an input here"),
    ("fifo", 1, "FIFO"), ("folder", 1, "folder"), ("device", 1, "device"),
    ("other kind", 2, "--force"),
])
@pytest.mark.parametrize("command", COMMANDS)
def test_no_command_damages_a_file_it_did_not_make(scene, capsys, no_compiler, command, how,
                                                   code, says):
    path = target(scene, command, how)
    before = snapshot(scene)
    argv = COMMANDS[command][0] + [path]
    result = main(argv)
    captured = capsys.readouterr()
    if command.startswith("diagram") and not path.endswith(".svg"):
        assert result == 1 and "name a .svg file" in captured.err    # refused by its name
    else:
        assert result == code and says in captured.err, captured.err
    assert no_traceback(captured)
    assert snapshot(scene) == before                     # nothing written, nothing replaced
    assert os.path.exists("/dev/null") and not os.path.isfile("/dev/null")


@pytest.mark.parametrize("command", ["run --out", "import -o", "animate --html", "diagram -o"])
def test_force_replaces_a_file_of_another_kind_and_nothing_else(scene, capsys, command):
    path = target(scene, command, "other kind")
    assert main(COMMANDS[command][0] + [path, "--force"]) == 0
    assert (scene / path).read_bytes() != b"my notes, kept\n"
    captured = capsys.readouterr()
    assert no_traceback(captured)
    assert not [p for p in os.listdir(scene) if p.endswith(".tmp")]


def test_outputs_of_the_same_kind_are_replaced_as_before(scene, capsys):
    for _ in range(2):                          # the last run's CSV and plot, then again
        assert main(["run", "dp.json", "--t-end", "0.1", "--out", "r.csv", "--plot",
                     "r.png"]) == 0
    assert main(["import", "robot.urdf", "-o", "r.json"]) == 0
    assert main(["import", "robot.urdf", "-o", "r.json", "--probes"]) == 0
    assert no_traceback(capsys.readouterr())


# -- stopped while writing --------------------------------------------------------------------
def test_sigterm_while_a_large_csv_is_written_keeps_the_rows_written(tmp_path):
    """The run is finished; SIGTERM comes while its CSV (a million rows) is being written:
    the file ends where the writing stopped with a line saying so, no temporary is left,
    and the command exits 143."""
    double_pendulum().save(tmp_path / "dp.json")
    out = tmp_path / "out.csv"
    env = dict(os.environ, KINETWORK_JIT="0")
    child = subprocess.Popen(
        [sys.executable, "-m", "kinetwork", "run", "dp.json", "--n-points", "1000000",
         "--out", "out.csv", "--quiet"], cwd=tmp_path, env=env, stdout=subprocess.PIPE,
        stderr=subprocess.PIPE)
    try:
        while child.poll() is None and not [p for p in os.listdir(tmp_path)
                                            if p.endswith(".tmp")]:
            time.sleep(0.05)                    # the writing has begun
        child.send_signal(signal.SIGTERM)
        _, err = child.communicate(timeout=120)
    finally:
        if child.poll() is None:
            child.kill()
            child.communicate()
    err = err.decode()
    assert child.returncode == 143, err[-500:]
    assert "Traceback" not in err and "interrupted by SIGTERM" in err
    lines = out.read_text().splitlines()
    assert lines[0].startswith("t,probe1.angle")
    table = kn.read_csv(out)
    assert table.cut["reason"] == "interrupted by SIGTERM" and table.cut["t_reached"] == 10.0
    assert table.cut["rows"] == len(table.t) and table.cut["t_written"] == table.t[-1]
    rows = np.loadtxt(out, delimiter=",", skiprows=1, ndmin=2)
    assert 0 < len(rows) < 1_000_000 and np.all(np.diff(rows[:, 0]) > 0)
    assert sorted(os.listdir(tmp_path)) == ["dp.json", "out.csv", "out.meta.json"]


def test_the_time_limit_covers_the_probe_signals_and_the_writing(tmp_path, capsys):
    """Two million output points take longer than the limit to compute and to write as CSV
    on any machine: the command stops, keeps what it reached with a last line saying why,
    and exits 3."""
    double_pendulum().save(tmp_path / "dp.json")
    out = tmp_path / "out.csv"
    assert main(["run", str(tmp_path / "dp.json"), "--n-points", "2000000", "--time-limit",
                 "1", "--out", str(out), "--quiet"]) == 3
    captured = capsys.readouterr()
    assert "the time limit" in captured.err and no_traceback(captured)
    lines = out.read_text().splitlines()
    table = kn.read_csv(out)
    assert "the time limit" in (table.partial or table.cut)["reason"]
    assert len(lines) - 1 < 2_000_000
    assert sorted(os.listdir(tmp_path)) == ["dp.json", "out.csv", "out.meta.json"]


# -- inputs -------------------------------------------------------------------------------------
@pytest.mark.parametrize("command", [["validate"], ["run"], ["diagram", "-o", "d.svg"]])
def test_a_fifo_without_a_writer_as_the_model_is_refused_not_waited_for(scene, capsys,
                                                                        command):
    os.rename("pipe.out", "pipe.json")
    argv = [command[0], "pipe.json", *command[1:]]
    assert main(argv) == 1
    captured = capsys.readouterr()
    assert "pipe.json" in captured.err and no_traceback(captured)


@pytest.mark.parametrize("data, code, says", [
    ("utf16", 0, ""), ("binary", 1, "is binary, not a CSV table"),
    ("/dev/zero", 1, "is binary, not a CSV table"), ("fifo", 1, "header row"),
])
def test_fit_reads_what_a_measurement_file_may_be_and_refuses_the_rest(scene, capsys, data,
                                                                      code, says):
    text = "t,probe1.angle\n0.0,0.05\n0.5,0.0367\n1.0,0.0124\n1.5,-0.0071\n"
    if data == "utf16":
        (scene / "m.csv").write_text(text, encoding="utf-16")     # a spreadsheet's export
    elif data == "binary":
        (scene / "m.csv").write_bytes(bytes(range(256)) * 8)
    path = {"utf16": "m.csv", "binary": "m.csv", "/dev/zero": "/dev/zero",
            "fifo": "pipe.out"}[data]
    assert main(["fit", "dp.json", "--data", path, "--fit", "d=0:5"]) == code
    captured = capsys.readouterr()
    assert says in captured.err and no_traceback(captured)
    if code == 0:
        assert "d" in captured.out


# -- arguments that used to end in a traceback ----------------------------------------------
@pytest.mark.parametrize("argv, codes, says", [
    (["run", "dp.json", "--rtol", "10"], {1}, "relative tolerance of 1 or more"),
    (["linearize", "dp.json", "--at-time", "1e300"], {1, 3}, ""),
    (["linearize", "dp.json", "--at-time", "nan"], {1}, "must be finite"),
    (["import", "robot.urdf", "-o", "folder.out"], {1}, "is a folder"),
    (["import", "/dev/zero", "-o", "r.json"], {1}, "larger than 64 MiB"),
    (["run", "dp.json", "--param", "d=1 kg^100^100^100"], {1}, "beyond 100"),
    (["run", "dp.json", "--param", "m1=1 kg*(km/m)^(100*100*100*100)"], {1}, "beyond 100"),
    (["animate", "dp.json", "--gif", "a.gif", "--fps", "1000"], {1}, "at most 50 frames"),
    (["animate", "dp.json", "--gif", "a.gif", "--t-end", "1e9"], {1}, "more than the 1500"),
    (["sweep", "dp.json", "--param", "d=0.1,0.2", "--batch", "1000000000"], {1}, "at most"),
    (["sweep", "dp.json", "--param", "d=0:1:100000", "--n-points", "10000"], {1}, "GiB"),
    (["run", "dp.json", "--n-points", "6000000", "--error-estimate"], {1}, "3 runs"),
])
def test_hostile_arguments_end_in_a_refusal_or_a_result(scene, capsys, argv, codes, says):
    try:
        code = main(argv)
    except SystemExit as exc:               # argparse refuses by exiting 2
        code = exc.code
    captured = capsys.readouterr()
    assert code in codes and says in captured.err, captured.err
    assert no_traceback(captured)
