"""Fixtures of the whole test run. The scenes the tests build are in ``tests/scenes`` (a
package: ``from scenes import double_pendulum``), importable because pyproject.toml puts
``tests/`` on the path (``[tool.pytest.ini_options] pythonpath``)."""

import pytest

from browser import browser_missing
from scenes import double_pendulum

@pytest.fixture(autouse=True, scope="session")
def jit_cache(tmp_path_factory):
    """Compiled models go to a folder of this test run, not to the user's cache."""
    mp = pytest.MonkeyPatch()
    mp.setenv("KINETWORK_CACHE", str(tmp_path_factory.mktemp("kinetwork-cache")))
    yield
    mp.undo()


@pytest.fixture
def seed_model():
    return double_pendulum()


@pytest.fixture
def seed_file(tmp_path):
    """The seed model saved as a file, as the command line reads it."""
    path = tmp_path / "double_pendulum.json"
    double_pendulum().save(path)
    return path


#: Debian's Chromium, driven by Playwright (its own browser download is not reachable here)
CHROMIUM = "/usr/bin/chromium"

CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
                 "--disable-component-update", "--disable-sync", "--no-first-run"]


@pytest.fixture(scope="session")
def chromium():
    """One headless Chromium for the whole run, shared by every browser test (Playwright's
    sync API allows one driver per thread: a second one in the same run fails)."""
    import os
    if not os.path.exists(CHROMIUM):
        browser_missing(f"{CHROMIUM} is missing (as root: apt-get install -y chromium)")
    from playwright import sync_api
    with sync_api.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        try:
            yield browser
        finally:
            browser.close()
