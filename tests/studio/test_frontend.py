"""The built front end committed in the package is what its sources build to: the studio's
page (kinetwork/studio/static) and the animation player (kinetwork/assets/player.js) are
built again from frontend/ into a temporary folder and compared file by file; and the studio's
shipped page has no test hook (window.__kinetwork is in the tests' own build only).

ESLint, the type check and the Vitest unit tests of the front end run in ``make test``
(``cd frontend && npm ci && npm run lint && npm test``)."""

import shutil
import subprocess

import pytest

from browser import browser_missing
from tests.studio.conftest import FRONTEND, REPO, npm_installed

STATIC = REPO / "kinetwork" / "studio" / "static"
PLAYER = REPO / "kinetwork" / "assets" / "player.js"


def files_of(folder):
    return {p.relative_to(folder).as_posix(): p.read_bytes()
            for p in sorted(folder.rglob("*")) if p.is_file()}


@pytest.fixture(scope="module")
def vite():
    if shutil.which("npm") is None or shutil.which("node") is None:
        browser_missing("Node and npm are needed to build the front end (apt-get install "
                        "nodejs npm)")
    npm_installed()
    return str(FRONTEND / "node_modules" / ".bin" / "vite")


def build(vite, *args):
    done = subprocess.run([vite, "build", "--logLevel", "warn", *args], cwd=FRONTEND,
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr


def test_the_committed_studio_page_is_what_its_sources_build(vite, tmp_path):
    build(vite, "--outDir", str(tmp_path / "studio"), "--emptyOutDir")
    built, committed = files_of(tmp_path / "studio"), files_of(STATIC)
    assert sorted(built) == sorted(committed), \
        "kinetwork/studio/static is stale: cd frontend && npm run build"
    for name in built:
        assert built[name] == committed[name], \
            f"{name} differs from its build: cd frontend && npm run build"


def test_the_committed_player_is_what_its_sources_build(vite, tmp_path):
    build(vite, "--config", "vite.player.config.js", "--outDir", str(tmp_path / "player"))
    assert (tmp_path / "player" / "player.js").read_bytes() == PLAYER.read_bytes(), \
        "kinetwork/assets/player.js is stale: cd frontend && npm run build"


def test_the_shipped_page_has_no_test_hook():
    scripts = [p for p in (STATIC / "assets").glob("*.js")]
    assert scripts
    for path in scripts:
        assert b"__kinetwork" not in path.read_bytes(), path.name
