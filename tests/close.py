"""Comparisons of numbers that two routes compute alike: equal to within rounding, never bit
for bit (another CPU or BLAS changes the last digits of what numpy computes, and a file written
on one machine holds the last digits of that machine)."""

import json
import math
import pathlib

import numpy as np

#: two computations of the same equations agree to this, relative to their scale
RTOL = 1e-12


def assert_same_numbers(a, b, rtol=RTOL):
    """``a`` and ``b`` equal to within ``rtol`` of the larger magnitude in either (an absolute
    floor at that scale, so values that pass through zero are compared by their scale); NaN
    where the other has NaN (a run that stopped: no value after)."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    assert a.shape == b.shape, (a.shape, b.shape)
    scale = max(np.nanmax(np.abs(a), initial=0.0), np.nanmax(np.abs(b), initial=0.0), 1e-300)
    np.testing.assert_allclose(a, b, rtol=rtol, atol=rtol * scale)


def same_json(a, b, rtol=RTOL, where="$"):
    """The first place where two JSON values differ (numbers within ``rtol``), or None."""
    if isinstance(a, bool) or isinstance(b, bool) or not (
            isinstance(a, (int, float)) and isinstance(b, (int, float))):
        if type(a) is not type(b):
            return f"{where}: {a!r} against {b!r}"
        if isinstance(a, dict):
            if list(a) != list(b):
                return f"{where}: keys {list(a)} against {list(b)}"
            return next((d for k in a if (d := same_json(a[k], b[k], rtol, f"{where}.{k}"))),
                        None)
        if isinstance(a, list):
            if len(a) != len(b):
                return f"{where}: {len(a)} items against {len(b)}"
            return next((d for i, (x, y) in enumerate(zip(a, b))
                         if (d := same_json(x, y, rtol, f"{where}[{i}]"))), None)
        return None if a == b else f"{where}: {a!r} against {b!r}"
    if math.isclose(a, b, rel_tol=rtol, abs_tol=rtol):
        return None
    return f"{where}: {a!r} against {b!r}"


def assert_same_json_file(path_a, path_b, rtol=RTOL):
    """Two JSON files hold the same document, numbers equal to within ``rtol``."""
    a, b = (json.loads(pathlib.Path(p).read_text()) for p in (path_a, path_b))
    difference = same_json(a, b, rtol)
    assert difference is None, f"{path_a} and {path_b} differ at {difference}"
