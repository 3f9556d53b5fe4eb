"""Brent's root finder, as ``scipy.optimize.brentq`` finds roots: the same algorithm (Charles
Harris's ``brentq.c`` in SciPy: inverse quadratic or secant steps kept within the bracket,
bisection where they would crawl), the same arguments, answers and errors. It is here because
importing ``scipy.optimize`` for it costs 0.26 s of CPU (it brings scipy.linalg), a fifth of
the first run of a model with events in a new process; locating an event and a time event's
instant are its only users (``curves.py``, ``schedule.py``)."""

import math

import numpy as np

#: the least relative tolerance that makes sense in double precision (scipy's ``_rtol``)
RTOL = 4 * np.finfo(float).eps


def brentq(f, a, b, args=(), xtol=2e-12, rtol=RTOL, maxiter=100):
    """A root of ``f(x, *args)`` in [a, b], where f(a) and f(b) differ in sign, to within
    ``xtol + rtol * |x|``.

    Raises
    ------
    ValueError
        f(a) and f(b) of the same sign, a value NaN, or tolerances that cannot be met.
    RuntimeError
        No convergence in ``maxiter`` iterations.
    """
    if xtol <= 0:
        raise ValueError(f"xtol too small ({xtol:g} <= 0)")
    if rtol < RTOL:
        raise ValueError(f"rtol too small ({rtol:g} < {RTOL:g})")
    def value(x):
        v = float(f(x, *args))
        if math.isnan(v):
            raise ValueError(f"the function value at x={x!r} is NaN; the search cannot go on")
        return v
    xpre, xcur = float(a), float(b)
    fpre, fcur = value(xpre), value(xcur)
    # (the signs by products, as brentq.c: two values that tiny underflow to no sign)
    if fpre * fcur > 0:
        raise ValueError("f(a) and f(b) must have different signs")
    if fpre == 0:
        return xpre
    if fcur == 0:
        return xcur
    xblk = fblk = spre = scur = 0.0
    for _ in range(maxiter):
        if fpre * fcur < 0:
            xblk, fblk = xpre, fpre         # the bracket's other end
            spre = scur = xcur - xpre
        if abs(fblk) < abs(fcur):           # xcur the better of the two
            xpre, xcur, xblk = xcur, xblk, xcur
            fpre, fcur, fblk = fcur, fblk, fcur
        delta = (xtol + rtol * abs(xcur)) / 2
        sbis = (xblk - xcur) / 2
        if fcur == 0 or abs(sbis) < delta:
            return xcur
        if abs(spre) > delta and abs(fcur) < abs(fpre):
            if xpre == xblk:                # secant
                stry = -fcur * (xcur - xpre) / (fcur - fpre)
            else:                           # inverse quadratic
                dpre = (fpre - fcur) / (xpre - xcur)
                dblk = (fblk - fcur) / (xblk - xcur)
                stry = -fcur * (fblk * dblk - fpre * dpre) / (dblk * dpre * (fblk - fpre))
            if 2 * abs(stry) < min(abs(spre), 3 * abs(sbis) - delta):
                spre, scur = scur, stry     # a good short step
            else:
                spre = scur = sbis          # bisection
        else:
            spre = scur = sbis
        xpre, fpre = xcur, fcur
        xcur += scur if abs(scur) > delta else (delta if sbis > 0 else -delta)
        fcur = value(xcur)
    raise RuntimeError(f"brentq: no convergence after {maxiter} iterations (x = {xcur!r})")
