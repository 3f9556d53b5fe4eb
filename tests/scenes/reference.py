"""Independent references: the seed paper's closed-form double pendulum in plain numpy."""

import math

import numpy as np
from scipy.integrate import solve_ivp

PAPER = {"L1": 1.0, "L2": 1.0, "m1": 1.0, "m2": 1.0, "c": 1.0, "d": 1.0, "g": 9.8}


def seed_mvg(q, qd, L1, L2, m1, m2, c, d, g, sin=np.sin, cos=np.cos, array=np.array):
    """M, V, G of the seed paper (V with its two typos corrected), M qdd + V + G = 0.

    Numbers by default; pass ``sin=sympy.sin, cos=sympy.cos, array=sympy.Matrix`` (and
    symbols) for the closed forms themselves.
    """
    T1, T2 = q
    T1d, T2d = qd
    M = array([
        [L1 * L2 * m2 * cos(T2) + L2**2 * m2 / 4 + L1**2 * m1 / 4 + L1**2 * m2,
         L2**2 * m2 / 4 + L1 * L2 * m2 * cos(T2) / 2],
        [L2**2 * m2 / 4 + L1 * L2 * m2 * cos(T2) / 2, L2**2 * m2 / 4]])
    V = array([-L1 * L2 * m2 * T2d * sin(T2) * (T1d + T2d / 2) + c * T1 + d * T1d,
               L1 * L2 * m2 * T1d**2 * sin(T2) / 2])
    G = array([(sin(T1 + T2) * L2 * m2 / 2 + L1 * m1 * sin(T1) / 2 + L1 * m2 * sin(T1)) * g,
               sin(T1 + T2) * g * L2 * m2 / 2])
    return M, V, G


def seed_reference(t, x0=(0.05, 0.05, 0.0, 0.0), rtol=1e-13, atol=1e-14, method="DOP853",
                   **params):
    """States on ``t`` from the closed form, integrated tightly with DOP853 (or ``method``:
    Radau for the stiff variants)."""
    rhs = _seed_rhs(**{**PAPER, **params})
    sol = solve_ivp(rhs, (t[0], t[-1]), x0, method=method, t_eval=t, rtol=rtol, atol=atol)
    return sol.y.T


def _seed_rhs(L1, L2, m1, m2, c, d, g):
    """The closed form's right-hand side on Python floats with ``math`` (``seed_mvg``'s M, V,
    G, the 2x2 solve by Cramer's rule): numpy's small-array calls cost ten times the
    arithmetic, and the tight references call it ~10^5 times. ``seed_mvg`` stays the one
    statement of the equations: tests/scenes/test_reference.py checks the two agree."""
    def rhs(_, x):
        T1, T2, T1d, T2d = x.tolist()
        s1, s2, s12, c2 = math.sin(T1), math.sin(T2), math.sin(T1 + T2), math.cos(T2)
        m11 = L1 * L2 * m2 * c2 + L2**2 * m2 / 4 + L1**2 * m1 / 4 + L1**2 * m2
        m12 = L2**2 * m2 / 4 + L1 * L2 * m2 * c2 / 2
        m22 = L2**2 * m2 / 4
        b1 = -(-L1 * L2 * m2 * T2d * s2 * (T1d + T2d / 2) + c * T1 + d * T1d
               + (s12 * L2 * m2 / 2 + L1 * m1 * s1 / 2 + L1 * m2 * s1) * g)
        b2 = -(L1 * L2 * m2 * T1d**2 * s2 / 2 + s12 * g * L2 * m2 / 2)
        det = m11 * m22 - m12 * m12
        return np.array([T1d, T2d, (m22 * b1 - m12 * b2) / det, (m11 * b2 - m12 * b1) / det])
    return rhs


def seed_energy(X, c=PAPER["c"], **params):
    """Mechanical energy of the seed scene on states X (n, 4): kinetic from the closed-form M,
    gravity of the point masses at mid-link (angles from the downward vertical), shoulder
    spring c q1^2 / 2."""
    p = {**PAPER, "c": c, **params}
    q, qd = X[:, :2], X[:, 2:]
    T = np.array([0.5 * w @ seed_mvg(a, w, **p)[0] @ w for a, w in zip(q, qd)])
    m1, m2, L1, L2, g = p["m1"], p["m2"], p["L1"], p["L2"], p["g"]
    height1 = -L1 / 2 * np.cos(q[:, 0])
    height2 = -L1 * np.cos(q[:, 0]) - L2 / 2 * np.cos(q[:, 0] + q[:, 1])
    return T + g * (m1 * height1 + m2 * height2) + 0.5 * c * q[:, 0] ** 2
