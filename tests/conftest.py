"""Fixtures of the whole test run. The scenes the tests build are in ``tests/scenes`` (a
package: ``from scenes import double_pendulum``), importable because pyproject.toml puts
``tests/`` on the path (``[tool.pytest.ini_options] pythonpath``)."""

import pytest

from browser import browser_missing
from scenes import double_pendulum

#: the files that take longest (seconds of CPU of one run, the browser's and the compiler's
#: included, 2026-11-29), longest first: pytest-xdist's ``--dist loadfile`` hands files out in
#: collection order, so these go first and the short ones fill in around them, instead of one
#: worker finishing a long file alone while the other waits (longest-first scheduling; a stale
#: figure only costs balance)
LONG_FILES = {
    "studio/test_e2e_wires.py": 90, "test_models.py": 69, "studio/test_e2e_editing.py": 57,
    "studio/test_e2e.py": 51, "studio/test_e2e_layout.py": 36, "test_entry_points.py": 31,
    "solver/test_time_events.py": 30, "test_docs_installed.py": 30,
    "test_docs_installed_2.py": 30, "solver/test_stability.py": 29,
    "equations/test_point_mass_chains.py": 28, "graph/test_fuzz.py": 28,
    "equations/test_loops.py": 27, "analysis/test_sweep.py": 27, "studio/test_server.py": 26,
    "studio/test_e2e_work.py": 25, "test_build_cache.py": 24, "studio/test_e2e_analysis.py": 23,
    "solver/test_driver.py": 23, "fmu/test_export.py": 22, "solver/test_methods.py": 22,
    "test_first_answer.py": 21, "studio/test_e2e_viewer.py": 30, "solver/test_jit_tiers.py": 20,
    "studio/test_e2e_room.py": 45,
}


def pytest_configure(config):
    """pytest-xdist 3.x hands out ``--dist loadfile``'s files by their number of tests, most
    first (``--loadscope-reorder``, on by default), which undid the order below: the files
    with few but long tests (the installed-wheel docs, the Dask sweeps, the long chains) ran
    last, one worker alone for minutes. The order of collection is kept instead."""
    if hasattr(config.option, "loadscopereorder"):
        config.option.loadscopereorder = False


#: the test files that drive Chromium (checked at collection: ``browser_files_named``)
BROWSER_FILES = ("tests/studio/test_e2e", "tests/test_animation.py")


def is_browser_file(path):
    """Whether the test file at ``path`` (relative to the checkout) drives Chromium."""
    return path.startswith(BROWSER_FILES)


def pytest_xdist_make_scheduler(config, log):
    """``--dist loadfile``, except that the files which drive Chromium go to one worker, one
    after another: two software-rendering browsers at once on two cores slow each other's
    pages (and the tests' waits on them) instead of filling the time the other workers wait.
    (pytest-xdist's own ``loadgroup`` cannot be used: it renames test ids through a field
    pytest 9 no longer reads.)"""
    if config.getvalue("dist") != "loadfile":
        return None
    from xdist.scheduler import LoadFileScheduling

    class BrowserFilesTogether(LoadFileScheduling):
        def _split_scope(self, nodeid):
            path = nodeid.split("::", 1)[0]
            return "chromium" if is_browser_file(path) else path

    return BrowserFilesTogether(config, log)


def pytest_collection_modifyitems(config, items):
    """The long files first, longest first; each file's tests keep their order."""
    def weight(item):
        path = item.path.as_posix()
        return next((-w for name, w in LONG_FILES.items() if path.endswith("tests/" + name)), 0)
    items.sort(key=weight)             # stable: files stay whole, in their order otherwise
    browser_files_named(config, items)


def browser_files_named(config, items):
    """Every file that uses the ``chromium`` fixture is one ``BROWSER_FILES`` names, and the
    other way round (the scheduler above sees test ids only)."""
    uses = {item.path.relative_to(config.rootpath).as_posix()
            for item in items if "chromium" in item.fixturenames}
    named = {item.path.relative_to(config.rootpath).as_posix() for item in items
             if is_browser_file(item.path.relative_to(config.rootpath).as_posix())}
    if uses != named:
        raise pytest.UsageError(f"tests/conftest.py BROWSER_FILES: files that drive Chromium "
                                f"{sorted(uses - named)} are not named, files named do not "
                                f"{sorted(named - uses)}")


@pytest.fixture(autouse=True, scope="session")
def jit_cache(tmp_path_factory):
    """Compiled models go to a folder of this test run, not to the user's cache: one folder
    for all of the run's workers (pytest-xdist's share the parent of their base folders), so a
    model the two workers both compile is compiled once. The cache is made for processes that
    share it (atomic renames, a lock file per optimised build); tests that need a cold cache
    set their own."""
    import os
    mp = pytest.MonkeyPatch()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        folder = tmp_path_factory.getbasetemp().parent / "kinetwork-cache"
        folder.mkdir(mode=0o700, exist_ok=True)
    else:
        folder = tmp_path_factory.mktemp("kinetwork-cache")
    mp.setenv("KINETWORK_CACHE", str(folder))
    # a large function stays at its quick library: no optimised build in a background process
    # that outlives the test which started it (one 3-D 128-link right-hand side is ~35 s of
    # compiler time, unseen by the test's own accounting, the whole run long); the tiers are
    # tested where they are the subject (tests/solver/test_jit_tiers.py)
    mp.setenv("KINETWORK_JIT_LEVEL", "quick")
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
