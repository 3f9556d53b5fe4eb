"""The second half of the docs' pages against the installed wheel (see
``test_docs_installed.py``; a file of its own so that the other test worker runs it)."""

import pytest
from installed_wheel import installed
from test_docs_installed import run_part


@pytest.fixture(scope="module")
def wheel_and_python(tmp_path_factory):
    return installed(tmp_path_factory)


def test_the_second_half_of_the_docs_runs_against_the_installed_wheel(wheel_and_python,
                                                                      tmp_path):
    run_part(wheel_and_python, tmp_path, 1)
