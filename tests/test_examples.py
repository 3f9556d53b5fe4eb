"""The example models ship inside the package: listed, found by name, copied out whole."""

import json
import pathlib
import subprocess

import pytest

import kinetwork as kn
from kinetwork import examples
from kinetwork.cli import main

ROOT = pathlib.Path(__file__).resolve().parents[1]


def test_every_model_file_is_an_example_or_a_part_of_one():
    """The package lists what models/ holds: every model file but the subsystem definitions."""
    listed = examples.names()
    files = sorted(p.relative_to(ROOT / "models").as_posix()[:-5]
                   for p in (ROOT / "models").rglob("*.json"))
    parts = [f for f in files if json.loads((ROOT / "models" / f"{f}.json").read_text())
             .get("ports")]
    assert sorted(listed) == sorted(set(files) - set(parts))
    assert {"double_pendulum", "engine_v6/EngineV6", "robot/arm_axes"} <= set(listed)
    assert "engine_v6/Cylinder" not in listed
    for name, line in examples.summaries().items():
        assert 0 < len(line) <= 100, name


def test_the_package_ships_the_models():
    """kinetwork/models is what a wheel installs (a link to models/ in a checkout), and the
    package data names its files."""
    assert examples.folder() == (ROOT / "models").resolve()
    assert (ROOT / "kinetwork" / "models" / "double_pendulum.json").is_file()
    assert '"models/**/*.json"' in (ROOT / "pyproject.toml").read_text()


def test_path_by_name_and_a_close_name():
    assert examples.path("double_pendulum") == examples.path("double_pendulum.json")
    assert kn.load(examples.path("double_pendulum")).name == "double_pendulum"
    with pytest.raises(kn.ModelError, match="did you mean double_pendulum"):
        examples.path("double_pendulm")


def test_copy_takes_the_definitions_and_never_overwrites(tmp_path):
    written = examples.copy("engine_v6/EngineV6", tmp_path / "mine")
    assert [p.name for p in written] == ["EngineV6.json", "Cylinder.json"]
    model = kn.load(written[0])
    assert len(model.components) > 6
    before = written[0].read_bytes()
    written[0].write_text("my edits")
    with pytest.raises(kn.ModelError, match="already exist.*nothing was copied"):
        examples.copy("engine_v6/EngineV6", tmp_path / "mine")
    assert written[0].read_text() == "my edits"
    assert before == (ROOT / "models" / "engine_v6" / "EngineV6.json").read_bytes()


def test_cli_lists_runs_and_copies_by_name(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["examples"]) == 0
    out = capsys.readouterr().out
    assert "double_pendulum" in out and "The seed paper's 2-DOF robot arm" in out
    assert main(["run", "double_pendulum", "--t-end", "0.5", "--out", "dp.csv", "-q"]) == 0
    assert (tmp_path / "dp.csv").read_text().startswith("t,probe1.angle")
    assert main(["examples", "copy", "fourbar", "here"]) == 0
    assert (tmp_path / "here" / "fourbar.json").read_bytes() == \
        (ROOT / "models" / "fourbar.json").read_bytes()
    assert main(["examples", "copy", "fourbar", "here"]) == 1
    assert "already exists" in capsys.readouterr().err
    # a file of that name wins over the example
    (tmp_path / "double_pendulum").write_text("{")
    assert main(["validate", "double_pendulum"]) == 1
    assert main(["run", "fourbr", "-q"]) == 1
    assert "did you mean fourbar" in capsys.readouterr().err


def test_installed_wheel_lists_and_runs_the_examples(tmp_path, tmp_path_factory):
    """A wheel built from the tree carries the models, found without the checkout."""
    from installed_wheel import installed, reader_env
    built, python = installed(tmp_path_factory)
    import zipfile
    names = zipfile.ZipFile(built).namelist()
    assert "kinetwork/models/double_pendulum.json" in names
    assert "kinetwork/models/engine_v6/Cylinder.json" in names
    assert not any(n.startswith("models/") for n in names)
    # installed alone (not the checkout) and used from an empty folder: the docs' paths
    # (models/double_pendulum.json) and an example's bare name load the installed examples
    folder = tmp_path / "reader"
    folder.mkdir()
    script = ("import kinetwork as kn, pathlib\n"
              "assert pathlib.Path(kn.__file__).is_relative_to(pathlib.Path(%r))\n"
              "a = kn.load('models/double_pendulum.json')\n"
              "b = kn.load('double_pendulum')\n"
              "c = kn.load(kn.examples.path('engine_v6/EngineV6'))\n"
              "res = kn.simulate(a, t_end=0.5)\n"
              "print(a.name, b.name, c.name, len(res.t))\n" % str(python.parent.parent))
    out = subprocess.run([str(python), "-c", script], cwd=folder, capture_output=True,
                         text=True, env=reader_env())
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.split()[:3] == ["double_pendulum", "double_pendulum", "EngineV6"]


def test_a_missing_path_that_names_an_example_loads_it(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    for name in ("double_pendulum", "double_pendulum.json", "models/double_pendulum.json"):
        assert kn.load(name).name == "double_pendulum"
    (tmp_path / "models").mkdir()
    mine = kn.load(ROOT / "models" / "double_pendulum.json")
    mine.name = "mine"
    mine.save(tmp_path / "models" / "double_pendulum.json")
    assert kn.load("models/double_pendulum.json").name == "mine"     # a file that exists wins
    for name in ("no_such_model", "/abs/double_pendulum.json", "../double_pendulum"):
        with pytest.raises(kn.ModelError):
            kn.load(name)
