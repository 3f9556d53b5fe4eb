"""The output policy (``kinetwork.outputs``) and every writer of the library that goes through
it: never a file the writer reads (compared by inode: links and ``./x``), never a special file
or a folder, another kind of file only when forced, atomic with the old file whole on any
failure and no temporary left behind (an exception, a full disk, a signal)."""

import os
import signal
import socket
import subprocess
import sys
import textwrap

import numpy as np
import pytest
from conftest import double_pendulum

import kinetwork as kn
from kinetwork import outputs
from kinetwork.outputs import OutputRefused, kind_of

PNG = b"\x89PNG\r\n\x1a\n" + bytes(64)
CSV = b"t,probe1.angle\n0.0,0.05\n"


def listing(folder):
    return sorted(p.name for p in folder.iterdir())


def fill_text(text):
    def fill(tmp):
        with open(tmp, "w") as fh:
            fh.write(text)
    return fill


# -- what is at a path ------------------------------------------------------------------------
@pytest.mark.parametrize("head, kind", [
    (b"", "empty"), (PNG, "png"), (b"GIF89a...", "gif"), (b"%PDF-1.7", "pdf"),
    (b"CDF\x01\x00", "netcdf"), (b"\x89HDF\r\n\x1a\n", "netcdf"), (b"\xff\xd8\xff\xe0", "jpeg"),
    (b'{"format": "kinetwork.model", "version": 1}', "model"), (b'{"a": 1}', "json"),
    (b"[1, 2]", "json"), (b"t,x\n0,1\n", "csv"), (b"t\n0.0\n", "csv"),
    (b'<?xml version="1.0"?>\n<robot name="r">', "urdf"), (b"<svg xmlns=''>", "svg"),
    (b"<!DOCTYPE html><html>", "html"), (b"my notes\n", "text"), (bytes(range(256)), "binary"),
    (b"\x00\x00\x00 ftypisom", "mp4"), (b"\x7fELF\x02", "library"),
])
def test_a_file_is_known_by_its_first_bytes(head, kind):
    assert outputs.sniff(head) == kind


# -- the checks -------------------------------------------------------------------------------
@pytest.mark.parametrize("how", ["same", "dot", "symlink", "hardlink", "absolute"])
def test_an_input_is_never_an_output_whatever_its_name(tmp_path, monkeypatch, how):
    monkeypatch.chdir(tmp_path)
    model = tmp_path / "model.json"
    model.write_bytes(b'{"format": "kinetwork.model"}')
    path = {"same": "model.json", "dot": "./model.json", "absolute": str(model),
            "symlink": "link.json", "hardlink": "hard.json"}[how]
    if how == "symlink":
        os.symlink("model.json", "link.json")
    if how == "hardlink":
        os.link("model.json", "hard.json")
    with pytest.raises(OutputRefused, match="is an input here"):
        outputs.check(path, "model", reads=[("the model file", "model.json")], force=True)


def test_special_files_and_folders_are_refused_by_name(tmp_path):
    os.mkfifo(tmp_path / "pipe.csv")
    server = socket.socket(socket.AF_UNIX)
    server.bind(str(tmp_path / "sock.csv"))
    try:
        for path, what in [("/dev/null", "character device"), (tmp_path / "pipe.csv", "FIFO"),
                           (tmp_path / "sock.csv", "socket"), (tmp_path, "folder")]:
            with pytest.raises(kn.ModelError, match=what) as info:
                outputs.write(path, fill_text("x"), "csv", force=True)
            assert not isinstance(info.value, OutputRefused)     # not writable: exit 1
    finally:
        server.close()
    assert os.path.exists("/dev/null") and not os.path.isfile("/dev/null")
    assert listing(tmp_path) == ["pipe.csv", "sock.csv"]


@pytest.mark.parametrize("existing, kind, allowed", [
    (PNG, "png", True), (CSV, "csv", True), (b"", "csv", True), (PNG, "csv", False),
    (CSV, "model", False), (b"my notes\n", "csv", False), (b'{"a": 1}', "model", False),
    (b'{"format": "kinetwork.model"}', "model", True), (b'<robot name="r">', "model", False),
])
def test_a_file_of_another_kind_is_replaced_only_when_forced(tmp_path, existing, kind, allowed):
    path = tmp_path / "out"
    path.write_bytes(existing)
    if allowed:
        outputs.write(path, fill_text("new"), kind)
        assert path.read_text() == "new"
        return
    with pytest.raises(OutputRefused, match="--force"):
        outputs.write(path, fill_text("new"), kind)
    assert path.read_bytes() == existing
    outputs.write(path, fill_text("new"), kind, force=True)
    assert path.read_text() == "new"


def test_outputs_of_one_command_never_name_one_file(tmp_path):
    with pytest.raises(OutputRefused, match="the same file as"):
        outputs.check_all([("--out", tmp_path / "a.csv", "csv"),
                           ("--plot", tmp_path / "." / "a.csv", "png")])


def test_a_symbolic_link_to_a_regular_file_is_followed_not_replaced(tmp_path):
    (tmp_path / "real.csv").write_bytes(CSV)
    os.symlink("real.csv", tmp_path / "link.csv")
    outputs.write(tmp_path / "link.csv", fill_text("t\n1.0\n"), "csv")
    assert os.path.islink(tmp_path / "link.csv")
    assert (tmp_path / "real.csv").read_text() == "t\n1.0\n"


# -- atomic writes ----------------------------------------------------------------------------
@pytest.mark.parametrize("where", ["fill", "fsync", "replace"])
def test_a_failed_write_keeps_the_old_file_and_leaves_no_temporary(tmp_path, monkeypatch,
                                                                   where):
    path = tmp_path / "out.csv"
    path.write_bytes(CSV)

    def full(*args, **kwargs):
        raise OSError(28, "No space left on device")

    def fill(tmp):
        with open(tmp, "w") as fh:
            fh.write("t\n" + "0.5\n" * 1000)
        if where == "fill":
            full()
    if where == "fsync":
        monkeypatch.setattr(os, "fsync", full)
    if where == "replace":
        monkeypatch.setattr(os, "replace", full)
    with pytest.raises(OSError, match="No space left"):
        outputs.write(path, fill, "csv")
    assert path.read_bytes() == CSV and listing(tmp_path) == ["out.csv"]


def test_a_full_disk_while_writing_keeps_the_old_file(tmp_path):
    """A writer that meets a full disk half-way (ENOSPC, here as /dev/full answers it)."""
    path = tmp_path / "old.csv"
    path.write_bytes(CSV)

    def fill(tmp):
        with open(tmp, "wb") as fh, open("/dev/full", "wb") as full:
            fh.write(b"t\n0.1\n")
            full.write(b"x" * 65536)
            full.flush()                         # ENOSPC, as a full disk answers
    with pytest.raises(OSError) as info:
        outputs.write(path, fill, "csv")
    assert info.value.errno == 28
    assert path.read_bytes() == CSV and listing(tmp_path) == ["old.csv"]


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGINT])
def test_a_signal_while_writing_keeps_the_old_file_and_removes_the_temporary(tmp_path, signum):
    path = tmp_path / "out.csv"
    path.write_bytes(CSV)
    script = textwrap.dedent(f"""
        import os, signal, sys
        from kinetwork import outputs
        def fill(tmp):
            with open(tmp, "w") as fh:
                fh.write("t\\n1\\n")
                fh.flush()
                os.kill(os.getpid(), {int(signum)})     # arrives while the file is written
                fh.write("2\\n")
        try:
            outputs.write({str(path)!r}, fill, "csv")
        except outputs.Stopped as exc:
            sys.exit(100 + exc.signum)
        sys.exit(1)
    """)
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, timeout=120)
    assert done.returncode == 100 + signum, done.stderr.decode()[-500:]
    assert path.read_bytes() == CSV and listing(tmp_path) == ["out.csv"]


def test_a_temporary_of_a_write_cut_by_the_exit_goes_with_the_process(tmp_path):
    """A daemon thread still writing when the interpreter leaves: its temporary is removed at
    exit, the old file whole."""
    path = tmp_path / "out.csv"
    path.write_bytes(CSV)
    script = textwrap.dedent(f"""
        import threading, time
        from kinetwork import outputs
        started = threading.Event()
        def fill(tmp):
            open(tmp, "w").write("t\\n")
            started.set()
            time.sleep(60)
        threading.Thread(target=outputs.write, args=({str(path)!r}, fill, "csv"),
                         daemon=True).start()
        started.wait()
    """)
    subprocess.run([sys.executable, "-c", script], capture_output=True, timeout=120)
    assert path.read_bytes() == CSV and listing(tmp_path) == ["out.csv"]


# -- every writer of the library --------------------------------------------------------------
@pytest.fixture(scope="module")
def seed_results(tmp_path_factory):
    folder = tmp_path_factory.mktemp("seed")
    double_pendulum().save(folder / "seed.json")
    model = kn.load(folder / "seed.json")
    return folder / "seed.json", kn.simulate(model, t_end=0.2, n_points=21)


WRITERS = {
    "to_csv": lambda res, path, **kw: res.to_csv(path, **kw),
    "save_plot": lambda res, path, **kw: kn.plot.save_plot(res, path, **kw),
    "save_png": lambda res, path, **kw: __import__("kinetwork.quickplot").quickplot.save_png(
        res, path, **kw),
    "animate": lambda res, path, **kw: res.animate(path, **kw),
    "save": lambda res, path, **kw: res.system.model._source.save(path, **kw)
    if res.system.model._source else res.system.model.save(path, **kw),
}
SUFFIX = {"to_csv": ".csv", "save_plot": ".svg", "save_png": ".png", "animate": ".html",
          "save": ".json"}


@pytest.mark.parametrize("writer", WRITERS)
def test_every_writer_refuses_its_own_model_file_special_files_and_other_kinds(
        seed_results, tmp_path, writer):
    model_file, res = seed_results
    write = WRITERS[writer]
    before = model_file.read_bytes()
    os.symlink(model_file, tmp_path / f"model{SUFFIX[writer]}")
    if writer != "save":            # saving a model over its own file is what saving is
        with pytest.raises(OutputRefused, match="is an input here"):
            write(res, tmp_path / f"model{SUFFIX[writer]}", overwrite=True)
    os.mkfifo(tmp_path / f"pipe{SUFFIX[writer]}")
    with pytest.raises(kn.ModelError, match="FIFO"):
        write(res, tmp_path / f"pipe{SUFFIX[writer]}")
    other = tmp_path / f"other{SUFFIX[writer]}"
    other.write_bytes(b"my notes, kept\n")
    with pytest.raises(OutputRefused, match="holds text"):
        write(res, other)
    assert other.read_bytes() == b"my notes, kept\n" and model_file.read_bytes() == before
    write(res, other, overwrite=True)
    assert other.read_bytes() != b"my notes, kept\n"
    assert not [p for p in os.listdir(tmp_path) if p.endswith(".tmp")]


def test_a_sweep_writes_netcdf_only_over_netcdf(seed_results, tmp_path):
    from kinetwork.analysis.sweep import to_netcdf
    model_file, res = seed_results
    ds = kn.sweep(res.system, {"d": [0.1, 0.2]}, t_end=0.1, n_points=5, progress=False)
    with pytest.raises(OutputRefused, match="is an input here"):
        to_netcdf(ds, model_file, overwrite=True, reads=[("the model file", model_file)])
    (tmp_path / "s.nc").write_bytes(PNG)
    with pytest.raises(OutputRefused, match="holds a PNG image"):
        to_netcdf(ds, tmp_path / "s.nc")
    to_netcdf(ds, tmp_path / "s.nc", overwrite=True)
    assert kind_of(tmp_path / "s.nc") == "netcdf"
    to_netcdf(ds, tmp_path / "s.nc")                    # NetCDF over NetCDF: the last sweep
    assert listing(tmp_path) == ["s.nc"]


def test_a_csv_stopped_while_written_keeps_its_rows_and_says_where(seed_results, tmp_path,
                                                                  monkeypatch):
    from kinetwork.solver import results
    monkeypatch.setattr(results, "CSV_BLOCK_ROWS", 5)
    _, res = seed_results
    reason = res.to_csv(tmp_path / "out.csv", cancel=lambda: True)
    assert reason == "cancelled"
    lines = (tmp_path / "out.csv").read_text().splitlines()
    assert lines[0].startswith("t,probe1.angle")
    cut = kn.read_csv(tmp_path / "out.csv").cut
    assert cut == {"reason": "cancelled", "rows": 5, "t_written": res.t[4], "t_reached": 0.2}
    rows = np.loadtxt(tmp_path / "out.csv", delimiter=",", skiprows=1, ndmin=2)
    assert len(rows) == 5                       # the first block, then the cancel
    np.testing.assert_allclose(rows, res.columns()[1][:5], rtol=0, atol=0)
    assert listing(tmp_path) == ["out.csv", "out.meta.json"]
