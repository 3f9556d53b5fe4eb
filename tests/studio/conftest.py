"""Fixtures of the studio's end-to-end tests: the real server (uvicorn in a thread, on a free
port, over a copy of the example models) serving a test build of the page, and Debian's
Chromium driven by Playwright.

The page the tests drive is the studio's own, built with its test hook (``window.__kinetwork``,
which the studio's shipped build does not have): ``vite build --mode e2e`` into a folder of
the test session, from ``frontend/`` (``npm ci`` first when its packages are not installed).

Nothing here is autouse, so the server's own tests (test_server.py) are untouched. The
fixtures fail, saying why, when Chromium, Playwright, FastAPI/uvicorn or Node is missing
(``browser_missing`` in tests/browser.py: skipped only when asked).
"""

import fcntl
import os
import pathlib
import shutil
import subprocess

import pytest
from browser import browser_missing

from tests.studio.helpers import serving

REPO = pathlib.Path(__file__).resolve().parents[2]
FRONTEND = REPO / "frontend"
CHROMIUM = "/usr/bin/chromium"
E2E_TOKEN = "e2e-token-0123456789abcdef"
VIEWPORT = {"width": 1600, "height": 1000}


def _why_not():
    """Why the end-to-end tests cannot run here, or None."""
    if not os.path.exists(CHROMIUM):
        return f"{CHROMIUM} is missing (as root: apt-get install -y chromium chromium-driver)"
    for module, what in (("playwright.sync_api", "playwright"), ("fastapi", "fastapi"),
                         ("uvicorn", "uvicorn")):
        try:
            __import__(module)
        except ImportError:
            return f"{what} is not installed (the studio extras: pip install fastapi uvicorn " \
                   f"playwright)"
    if shutil.which("npm") is None or shutil.which("node") is None:
        return "Node and npm are needed to build the studio's test page (apt-get install nodejs npm)"
    return None


def npm_installed():
    """``frontend/node_modules`` from the lockfile (``npm ci``, once, whichever test process
    gets there first)."""
    with open(FRONTEND / "package-lock.json") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)        # one npm ci at a time, between test workers
        try:
            if not (FRONTEND / "node_modules" / ".bin" / "vite").exists():
                subprocess.run(["npm", "ci", "--no-audit", "--no-fund"], cwd=FRONTEND,
                               check=True, capture_output=True, text=True, timeout=900)
        finally:
            fcntl.flock(lock, fcntl.LOCK_UN)


@pytest.fixture(scope="session")
def test_page(tmp_path_factory):
    """The studio's page built with its test hook, in a folder of this test session."""
    why = _why_not()
    if why:
        browser_missing(why)
    npm_installed()
    out = tmp_path_factory.mktemp("studio-e2e-build")
    done = subprocess.run([str(FRONTEND / "node_modules" / ".bin" / "vite"), "build",
                           "--mode", "e2e", "--outDir", str(out), "--emptyOutDir",
                           "--logLevel", "warn"], cwd=FRONTEND, capture_output=True, text=True,
                          timeout=600)
    assert done.returncode == 0, f"the test build of the studio failed:\n{done.stderr}"
    return out


class Studio:
    """A running studio: its folder, address and token."""

    def __init__(self, root, port):
        self.root, self.port, self.token = root, port, E2E_TOKEN
        self.base = f"http://127.0.0.1:{port}"

    def url(self, **query):
        from urllib.parse import urlencode
        return f"{self.base}/?" + urlencode({"token": self.token, **query})


@pytest.fixture
def studio(tmp_path, test_page):
    """The studio's server over a folder holding a copy of models/ (so saving touches no
    file of the repository), serving the test build of the page."""
    from kinetwork.studio.server import create_app

    shutil.copytree(REPO / "models", tmp_path / "models")
    with serving(create_app(tmp_path, E2E_TOKEN, static=test_page)) as port:
        yield Studio(tmp_path, port)


@pytest.fixture
def root(tmp_path):
    """A studio folder holding a copy of the example models."""
    shutil.copytree(REPO / "models", tmp_path / "models")
    return tmp_path


@pytest.fixture
def browser(chromium):
    """Debian's Chromium, headless, shared with the whole run (tests/conftest.py)."""
    why = _why_not()
    if why:
        browser_missing(why)
    return chromium


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    """Keep each phase's report on the test item, so ``page`` can tell a failure."""
    outcome = yield
    setattr(item, f"report_{call.when}", outcome.get_result())


@pytest.fixture
def page(browser, request):
    """A fresh page (its own context) that records console errors and uncaught exceptions in
    ``page.errors``; when the test fails, a screenshot goes to $KINETWORK_E2E_SHOTS (if
    set) to show why."""
    context = browser.new_context(viewport=VIEWPORT)
    pg = context.new_page()
    pg.errors = []
    pg.on("console", lambda m: m.type == "error" and pg.errors.append(f"console: {m.text}"))
    pg.on("pageerror", lambda e: pg.errors.append(f"uncaught: {e}"))
    pg.set_default_timeout(30_000)
    try:
        yield pg
    finally:
        report = getattr(request.node, "report_call", None)
        shots = os.environ.get("KINETWORK_E2E_SHOTS")
        if shots and report is not None and report.failed:
            os.makedirs(shots, exist_ok=True)
            pg.screenshot(path=os.path.join(shots, f"{request.node.name}.png"))
        context.close()
