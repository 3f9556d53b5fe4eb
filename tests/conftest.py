"""Fixtures of the whole test run. The scenes the tests build are in ``tests/scenes`` (a
package: ``from scenes import double_pendulum``), importable because pyproject.toml puts
``tests/`` on the path (``[tool.pytest.ini_options] pythonpath``)."""

import pytest

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
