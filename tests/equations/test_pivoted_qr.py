"""The loops' pivoted QR (numpy, Businger-Golub) against LAPACK's dgeqp3 through scipy, and
a loop model built without importing scipy.linalg."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg

from kinetwork.equations.partitioning import _pivoted_qr

ROOT = Path(__file__).resolve().parents[2]


def _rank_deficient(rng, m, n, rank):
    return rng.standard_normal((m, rank)) @ rng.standard_normal((rank, n))


@pytest.mark.parametrize("shape, rank", [((4, 12), 4), ((12, 4), 4), ((6, 9), 3),
                                         ((9, 6), 5), ((24, 40), 16), ((1, 5), 1)])
def test_pivoted_qr_is_lapacks_within_the_rank(shape, rank):
    rng = np.random.default_rng(sum(shape) * 10 + rank)
    for _ in range(20):
        a = _rank_deficient(rng, *shape, rank)
        diag, order = _pivoted_qr(a)
        _, r, piv = scipy.linalg.qr(a, pivoting=True, mode="economic")
        want = np.abs(np.diag(r))
        assert sorted(order.tolist()) == list(range(shape[1]))
        assert order[:rank].tolist() == piv[:rank].tolist()   # integer column indices
        np.testing.assert_allclose(diag[:rank], want[:rank], rtol=1e-12)
        assert np.all(diag[rank:] <= 1e-12 * want[0])


def test_pivoted_qr_of_a_loop_jacobian_with_equal_columns_takes_the_first():
    # a planar four-bar's closure rows: two columns of equal norm, the first of them first
    a = np.array([[1.0, 0.0, 1.0, 0.5], [0.0, 1.0, 0.0, 0.5]])
    diag, order = _pivoted_qr(a)
    _, r, piv = scipy.linalg.qr(a, pivoting=True)
    assert order[:2].tolist() == piv[:2].tolist()
    np.testing.assert_allclose(diag, np.abs(np.diag(r)), rtol=1e-12, atol=1e-15)


def test_pivoted_qr_of_zero_and_empty_matrices():
    diag, order = _pivoted_qr(np.zeros((3, 4)))
    assert diag.tolist() == [0.0, 0.0, 0.0] and sorted(order.tolist()) == [0, 1, 2, 3]
    diag, order = _pivoted_qr(np.zeros((3, 0)))
    assert diag.size == 0 and order.size == 0


def test_a_loop_model_builds_without_scipy_linalg():
    code = ("import sys, kinetwork as kn; "
            "kn.load('models/engine_v6/EngineV6.json').compile(); "
            "print(sorted(m for m in sys.modules if m.startswith('scipy.linalg')))")
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True,
                          text=True, check=True)
    assert done.stdout.strip() == "[]", done.stdout
