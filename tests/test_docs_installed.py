"""The docs run against an installed wheel, from a folder outside the checkout.

``tests/installed_wheel.py`` builds the wheel and installs it (``--no-deps``) in a fresh virtual
environment whose dependencies are this one's; there every code block of the README and the
docs runs (``test_docs.run_pages``), one page after another in one process, each page in a
fresh empty folder, so a snippet that needs a file of the checkout fails here. Every value a
snippet shows in a comment is checked (``test_docs.shown``). The pages are split in two: this
file runs the first half, ``test_docs_installed_2.py`` the second, so the two test workers
share them.
"""

import json
import pathlib
import subprocess
import zipfile

import pytest
from installed_wheel import ROOT, installed, reader_env
from test_docs import pages_of

RUNNER = """
import json, pathlib, sys
sys.path.insert(0, {tests!r})          # the docs' block runner, not the package
import kinetwork
import test_docs
assert pathlib.Path(kinetwork.__file__).is_relative_to({venv!r}), kinetwork.__file__
assert not pathlib.Path(kinetwork.__file__).is_relative_to({root!r})
print(json.dumps(test_docs.run_pages({folder!r}, {part}, {parts})))
"""

#: the installed-wheel run of the docs is split in this many test files
PARTS = 2


@pytest.fixture(scope="module")
def wheel_and_python(tmp_path_factory):
    return installed(tmp_path_factory)


def test_the_wheel_holds_what_the_docs_use(wheel_and_python):
    wheel, _ = wheel_and_python
    names = set(zipfile.ZipFile(wheel).namelist())
    tracked = subprocess.run(["git", "ls-files", "models", "kinetwork/studio/static",
                              "kinetwork/assets", "kinetwork/fmu/c", "kinetwork/studio/API.md"],
                             cwd=ROOT, capture_output=True, text=True, check=True).stdout.split()
    expected = {("kinetwork/" + name) if name.startswith("models/") else name
                for name in tracked if not name.endswith(".md") or name.endswith("API.md")}
    missing = sorted(expected - names)
    assert not missing, f"files the wheel lacks: {missing[:20]}"
    assert {"kinetwork/models/double_pendulum.json", "kinetwork/models/robots/industrial_arm.urdf",
            "kinetwork/studio/static/index.html", "kinetwork/assets/player.js",
            "kinetwork/py.typed"} <= names
    assert not any(name.startswith(("models/", "tests/", "docs/")) for name in names)


def test_the_parts_run_every_page_once():
    parts = [pages_of(part, PARTS) for part in range(PARTS)]
    every = [page for part in parts for page in part]
    assert sorted(every) == sorted(pages_of()) and len(set(every)) == len(every)
    assert "README.md" in every and "docs/how-to/urdf.md" in every and len(every) >= 25
    assert all(parts)


def run_part(wheel_and_python, tmp_path, part):
    """Run the docs pages of ``part`` in the wheel's environment; fail with every page's
    error."""
    _, python = wheel_and_python
    folder = tmp_path / "reader"
    folder.mkdir()
    script = RUNNER.format(tests=str(ROOT / "tests"), venv=str(python.parent.parent),
                           root=str(ROOT), folder=str(folder), part=part, parts=PARTS)
    done = subprocess.run([str(python), "-c", script], cwd=folder, capture_output=True,
                          text=True, env={**reader_env(), "MPLBACKEND": "Agg"})
    assert done.returncode == 0, done.stderr[-4000:]
    report = json.loads(done.stdout.strip().splitlines()[-1])
    failures = report["failures"]
    assert report["ran"] == pages_of(part, PARTS)
    assert not failures, "\n\n".join(f"{page}:\n{text}" for page, text in failures.items())
    assert not any(pathlib.Path(ROOT).glob("build")), "the build wrote into the checkout"


def test_the_first_half_of_the_docs_runs_against_the_installed_wheel(wheel_and_python,
                                                                     tmp_path):
    run_part(wheel_and_python, tmp_path, 0)
