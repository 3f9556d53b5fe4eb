"""The wheel a reader installs, built once per test session and installed in a fresh
virtual environment, for the tests that must not see the checkout.

The wheel is built from a copy of the package's sources (so the build leaves nothing in the
checkout) with ``pip wheel --no-deps --no-build-isolation``; the environment is a new venv in
the session's temporary folder whose ``.pth`` line points at this interpreter's
site-packages, so its dependencies are the ones installed already (no network), and the wheel
is installed into it with ``--no-deps``. xdist workers share one build: the first builds it
under a lock, the others wait and reuse it.
"""

import fcntl
import os
import pathlib
import shutil
import site
import subprocess
import sys
import sysconfig

ROOT = pathlib.Path(__file__).resolve().parents[1]


def installed(tmp_path_factory):
    """(the wheel, the venv's python) of this session's build."""
    shared = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):         # one build for all workers
        shared = shared.parent
    home = shared / "kinetwork-wheel"
    home.mkdir(exist_ok=True)
    with open(home / "lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        python = home / "venv" / "bin" / "python"
        done = home / "done"
        if not done.exists():
            wheel = _build(home)
            _venv(home / "venv", wheel)
            done.write_text(str(wheel))
        return pathlib.Path(done.read_text()), python


def _build(home):
    tree, out = home / "tree", home / "dist"
    shutil.rmtree(tree, ignore_errors=True)
    ignore = shutil.ignore_patterns("__pycache__", "*.egg-info", "*.pyc")
    shutil.copytree(ROOT / "kinetwork", tree / "kinetwork", symlinks=True, ignore=ignore)
    shutil.copytree(ROOT / "models", tree / "models", ignore=ignore)
    for name in ("pyproject.toml", "README.md"):
        shutil.copy(ROOT / name, tree / name)
    run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q",
         "-w", str(out), str(tree)])
    [wheel] = out.glob("kinetwork-*.whl")
    return wheel


def _venv(folder, wheel):
    run([sys.executable, "-m", "venv", "--without-pip", str(folder)])
    python = folder / "bin" / "python"
    own = subprocess.run([str(python), "-c", "import sysconfig; "
                          "print(sysconfig.get_paths()['purelib'])"],
                         capture_output=True, text=True, check=True).stdout.strip()
    # this interpreter's site-packages (its venv's, inside the checkout after `make test`, and
    # those its .pth names), never the checkout's sources: a .pth line adds a folder without
    # reading the .pth files inside it, so an editable install of the checkout found in a
    # site-packages is not followed
    here = {sysconfig.get_paths()["purelib"], *site.getsitepackages()}
    paths = [p for p in sys.path if p in here or p.endswith("site-packages")]
    paths = [p for p in dict.fromkeys(paths) if pathlib.Path(p).resolve() != ROOT]
    (pathlib.Path(own) / "zz_dependencies.pth").write_text("\n".join(paths) + "\n")
    run([str(python), "-m", "pip", "install", "--no-deps", "--no-index", "-q", str(wheel)])


def reader_env():
    """This process's environment without what would point the wheel's Python elsewhere
    (PYTHONPATH, VIRTUAL_ENV): a reader's shell."""
    return {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}


def run(argv, **kwargs):
    done = subprocess.run(argv, capture_output=True, text=True, **kwargs)
    assert done.returncode == 0, f"{argv[:4]}: {done.stdout[-2000:]}{done.stderr[-2000:]}"
    return done
