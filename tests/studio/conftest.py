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


class Tab:
    """A module's browser tab, handed to its tests one after the other: a new tab costs
    Chromium ~3 s of CPU (a renderer process started, the studio's scripts compiled afresh),
    a tab reused ~1 s. Each test's studio has its own server on its own port, so its own
    origin: nothing of the page's (storage, scripts, workers) survives from the last test.
    A tab is reused only after a test that passed and left it as it got it (no listener of
    its own left on it, the page and its context open, back on a blank page); otherwise the
    next test gets a new context, as every test used to."""

    EVENTS = ("console", "pageerror", "dialog", "download", "popup", "request", "response",
              "requestfailed", "requestfinished", "close", "crash", "load",
              "domcontentloaded", "frameattached", "framedetached", "framenavigated",
              "filechooser", "websocket", "worker")

    def __init__(self, browser):
        self.browser, self.context, self.page, self.counts = browser, None, None, None

    def listeners(self):
        impl = self.page._impl_obj
        return {e: impl.listener_count(e) for e in self.EVENTS}

    def take(self):
        """The tab, reset for a test: the window size, the timeout, an empty error list."""
        if self.page is None:
            self.context = self.browser.new_context(viewport=VIEWPORT)
            pg = self.context.new_page()
            pg.errors = []
            pg.on("console", lambda m: m.type == "error" and pg.errors.append(f"console: {m.text}"))
            pg.on("pageerror", lambda e: pg.errors.append(f"uncaught: {e}"))
            self.page = pg
            self.counts = self.listeners()
        pg = self.page
        pg.errors.clear()
        pg.set_viewport_size(VIEWPORT)
        pg.set_default_timeout(30_000)
        return pg

    def give_back(self, passed):
        """Keep the tab for the next test if it is as it was handed out; else drop it."""
        pg, keep = self.page, passed
        try:
            keep = keep and not pg.is_closed() and self.listeners() == self.counts
            if keep:
                origin = pg.evaluate("() => location.origin")
                # away from the studio (its server is stopped), accepting "leave the page?"
                def leave(dialog):
                    dialog.accept()
                pg.on("dialog", leave)
                try:
                    pg.goto("about:blank")
                finally:
                    pg.remove_listener("dialog", leave)
                keep = pg.url == "about:blank"
                # what the page kept in the browser for its origin (the panes' sizes...): a
                # later test's server may get the same port, so the same origin
                if keep and origin.startswith("http"):
                    cdp = self.context.new_cdp_session(pg)
                    try:
                        cdp.send("Storage.clearDataForOrigin",
                                 {"origin": origin, "storageTypes": "all"})
                    finally:
                        cdp.detach()
        except Exception:       # a context the test closed, a page that would not leave
            keep = False
        if not keep:
            self.close()

    def close(self):
        context, self.context, self.page = self.context, None, None
        if context is not None:
            try:
                context.close()
            except Exception:   # closed by the test already
                pass


@pytest.fixture(scope="module")
def tab(chromium):
    """One browser tab for the module's tests that take ``page`` (see Tab)."""
    why = _why_not()
    if why:
        browser_missing(why)
    t = Tab(chromium)
    yield t
    t.close()


@pytest.fixture
def page(tab, request):
    """The module's tab (see Tab), at the default window size, recording console errors and
    uncaught exceptions in ``page.errors``; when the test fails, a screenshot goes to
    $KINETWORK_E2E_SHOTS (if set) to show why."""
    pg = tab.take()
    passed = False
    try:
        yield pg
        report = getattr(request.node, "report_call", None)
        passed = report is not None and report.passed
    finally:
        report = getattr(request.node, "report_call", None)
        shots = os.environ.get("KINETWORK_E2E_SHOTS")
        if shots and report is not None and report.failed and not pg.is_closed():
            os.makedirs(shots, exist_ok=True)
            pg.screenshot(path=os.path.join(shots, f"{request.node.name}.png"))
        tab.give_back(passed)
