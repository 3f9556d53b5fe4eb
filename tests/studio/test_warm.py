"""The studio's forkserver warm-up (``studio/warm.py``, ``jobs.PRELOAD``): a failure there is
swallowed (children still work, cold), so these tests are what notices one. It went unnoticed
when ``simulate`` moved to ``solver/plan.py``: every child started cold (CasADi's plugins,
kinetwork's first-use caches), and each studio run of EngineV6 imported scipy.optimize again."""

import importlib

import pytest

from kinetwork.studio import jobs, warm


def test_the_warm_up_runs_its_model_through_every_step():
    """check, compile, run, encode: each of them must work, or the children start cold."""
    warm.warm()


@pytest.mark.parametrize("name", jobs.PRELOAD)
def test_every_preloaded_module_imports(name):
    importlib.import_module(name)
