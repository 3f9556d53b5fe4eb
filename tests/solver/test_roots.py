"""kinetwork's Brent root finder against scipy.optimize.brentq, the one it stands in for:
the same roots (to the tolerance asked), about as many evaluations, the same refusals."""

import math

import numpy as np
import pytest
from scipy.optimize import brentq as scipy_brentq

from kinetwork.solver.roots import RTOL, brentq

TIGHT = dict(xtol=1e-15, rtol=RTOL, maxiter=200)
CASES = [
    (lambda x: x ** 3 - 2 * x - 5, 2.0, 3.0),
    (lambda x: math.cos(x) - x, 0.0, 1.0),
    (lambda x: math.exp(x) - 1e6, 0.0, 20.0),
    (lambda x: math.tanh(50 * (x - 0.3)), -1.0, 1.0),          # steep
    (lambda x: (x - 0.5) ** 3, 0.0, 1.2),                      # a triple root
    (lambda x: x - 1e-9, -1.0, 1.0),
    (lambda x: 1.0 if x > 0.123456789 else -1.0, 0.0, 1.0),     # a jump: bisection
    (lambda x: math.sin(x), 3.0, 4.0),
    (lambda x: x * x - 1e-20, 0.0, 1.0),
]


def counted(f):
    calls = []

    def g(x, *args):
        calls.append(x)
        return f(x, *args)
    return g, calls


def outcome(f, a, b, **opts):
    """(root or the exception's type, the points f was called at)."""
    g, calls = counted(f)
    try:
        found = (scipy_brentq if opts.pop("scipy", False) else brentq)(g, a, b, **opts)
    except (ValueError, RuntimeError) as exc:
        found = type(exc)
    return found, calls


@pytest.mark.parametrize("case", range(len(CASES)))
def test_the_roots_of_scipys_brentq(case):
    f, a, b = CASES[case]
    for opts in (TIGHT, {}, {"maxiter": 20}):
        (x, mine), (y, theirs) = outcome(f, a, b, **opts), outcome(f, a, b, scipy=True, **opts)
        if isinstance(y, type):                 # scipy gave up: so does this one
            assert x is y, (x, y)
            continue
        tol = opts.get("xtol", 2e-12) + opts.get("rtol", RTOL) * abs(y)
        assert abs(x - y) <= 2 * tol, (x, y)
        assert len(mine) <= len(theirs) + 2, (len(mine), len(theirs))


def test_args_and_refusals():
    assert brentq(lambda x, c: x - c, 0.0, 1.0, args=(0.25,), **TIGHT) == pytest.approx(0.25,
                                                                                        abs=1e-15)
    assert brentq(lambda x: x, 0.0, 1.0) == 0.0                   # a root at an end
    with pytest.raises(ValueError, match="different signs"):
        brentq(lambda x: x * x + 1, -1.0, 1.0)
    with pytest.raises(ValueError, match="NaN"):
        brentq(lambda x: math.nan if x > 0.1 else -1.0, 0.0, 1.0)
    with pytest.raises(ValueError, match="rtol"):
        brentq(lambda x: x, -1.0, 1.0, rtol=1e-17)
    with pytest.raises(RuntimeError, match="convergence"):
        brentq(lambda x: 1.0 if x > np.pi / 10 else -1.0, 0.0, 1.0, xtol=1e-15, maxiter=3)
