"""Models the analysis tests share: the seed with a torque at the elbow, and the paper's
closed-form linearisation of it at rest (sympy on the paper's M, V, G)."""

import numpy as np
import sympy as sp

import kinetwork as kn
from scenes import double_pendulum
from scenes.reference import PAPER, seed_mvg


def seed_with_motor(tau="tau"):
    """The seed, a rotational.Torque ``motor`` on the elbow axis (tau: a model parameter,
    so a finite difference of the nonlinear model can push it), probes on both joints."""
    model = double_pendulum()
    model.set_parameter("tau", 0.0)
    model.add(kn.rotational.Torque("motor", tau=tau))
    model.connect("motor.flange", "elbow.axis")
    return model


def paper_pencil(**params):
    """(M, D, K) at rest (q = qd = 0) from the paper's closed forms: M qdd + D qd + K q = 0,
    with D = d(V)/d(qd) and K = d(V + G)/d(q), differentiated by sympy."""
    p = {**PAPER, **params}
    q, qd = sp.symbols("q1 q2"), sp.symbols("qd1 qd2")
    M, V, G = seed_mvg(q, qd, **p, sin=sp.sin, cos=sp.cos, array=sp.Matrix)
    rest = {s: 0 for s in (*q, *qd)}
    K = (V + G).jacobian(q).subs(rest)
    D = V.jacobian(qd).subs(rest)
    return tuple(np.array(m.subs(rest), dtype=float) for m in (M, D, K))


def paper_A(**params):
    """The first-order system matrix of the pencil, states (q1, q2, qd1, qd2)."""
    M, D, K = paper_pencil(**params)
    Minv = np.linalg.inv(M)
    return np.block([[np.zeros((2, 2)), np.eye(2)], [-Minv @ K, -Minv @ D]])
