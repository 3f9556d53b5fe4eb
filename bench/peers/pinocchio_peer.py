"""Pinocchio's articulated-body algorithm (``pin.aba``) driven by scipy's ``solve_ivp``.

What a robotics user would write: a ``pin.Model`` built by hand from the chain, and a Python
right-hand side around ``pin.aba``. Joint ``i`` is a ``JointModelRevoluteUnaligned`` on
``spec.axis[i]``, placed at the parent's ``offset`` (the ground's origin for the first joint);
its body is ``pin.Inertia(mass, r_cm, inertia)``, CoM and inertia about it in the joint's
frame, as in ``tests/equations/test_pinocchio.py``. The spring-dampers enter as the joint torque
``tau = -(k q + d qd)``.

Tolerances: ``atol = rtol * 1e-2`` throughout (the angles are of order 0.1..1 rad).
"""

import numpy as np
import pinocchio as pin
from scipy.integrate import solve_ivp

NAME = "pinocchio+scipy"
RTOLS = (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12)
TIGHTEST = {"method": "DOP853", "rtol": 1e-12}


class Built:
    """A pinocchio model of the chain with its data, spring-damper gains and initial state."""

    def __init__(self, model, stiffness, damping, x0):
        self.model = model
        self.data = model.createData()
        self.stiffness = stiffness
        self.damping = damping
        self.x0 = x0
        self.n = model.nv


def build(spec):
    """The ``pin.Model`` of ``spec``; joint ``i + 1`` is link ``i``, q index ``i``."""
    model = pin.Model()
    model.gravity.linear = np.asarray(spec.gravity, dtype=float)
    parent, at = 0, np.zeros(3)
    for i in range(spec.n):
        joint = pin.JointModelRevoluteUnaligned(np.asarray(spec.axis[i], dtype=float))
        parent = model.addJoint(parent, joint, pin.SE3(np.eye(3), at), f"j{i}")
        body = pin.Inertia(float(spec.mass[i]), np.asarray(spec.r_cm[i], dtype=float),
                           np.asarray(spec.inertia[i], dtype=float))
        model.appendBodyToJoint(parent, body, pin.SE3.Identity())
        at = np.asarray(spec.offset[i], dtype=float)
    x0 = np.concatenate([spec.q0, spec.qd0]).astype(float)
    return Built(model, np.asarray(spec.stiffness, float), np.asarray(spec.damping, float), x0)


def rhs_function(built):
    """``f(t, x)`` for ``solve_ivp``, x = (q, qd): one ``pin.aba`` and a few small numpy ops.

    A fresh output array each call: scipy's RK methods keep the last returned derivative as
    the first stage of the next step, so a shared buffer would be overwritten under it.
    """
    model, data, n = built.model, built.data, built.n
    minus_k, d = -built.stiffness, built.damping
    aba, concatenate = pin.aba, np.concatenate
    if not (minus_k.any() or d.any()):
        tau = np.zeros(n)

        def rhs(t, x):
            v = x[n:]
            return concatenate((v, aba(model, data, x[:n], v, tau)))
    else:
        def rhs(t, x):
            q, v = x[:n], x[n:]
            return concatenate((v, aba(model, data, q, v, minus_k * q - d * v)))
    return rhs


def run(built, t, **options):
    """Joint angles (len(t), N) from ``spec.q0``, ``spec.qd0`` at ``t[0]``; see ``trajectory``."""
    return trajectory(built, t, **options)[0]


def trajectory(built, t, method="DOP853", rtol=1e-8, atol=None):
    """Joint angles and rates, each (len(t), N), from ``spec.q0``, ``spec.qd0`` at ``t[0]``.

    ``atol`` defaults to ``rtol * 1e-2``. Raises RuntimeError if the integration fails.
    """
    t = np.asarray(t, dtype=float)
    sol = solve_ivp(rhs_function(built), (t[0], t[-1]), built.x0, method=method, t_eval=t,
                    rtol=rtol, atol=rtol * 1e-2 if atol is None else atol)
    if not sol.success:
        raise RuntimeError(f"{NAME} {method} rtol={rtol}: {sol.message}")
    return sol.y[:built.n].T, sol.y[built.n:].T


def energy(built, q, qd):
    """Kinetic + gravitational potential + spring energy at each row of q, qd."""
    model, data = built.model, built.data
    q, qd = np.atleast_2d(q), np.atleast_2d(qd)
    return np.array([pin.computeKineticEnergy(model, data, qi, vi)
                     + pin.computePotentialEnergy(model, data, qi)
                     + 0.5 * built.stiffness @ qi**2 for qi, vi in zip(q, qd)])


def variants():
    """DOP853, RK45 and LSODA, each at rtol 1e-3 .. 1e-12."""
    return [{"method": m, "rtol": r} for m in ("DOP853", "RK45", "LSODA") for r in RTOLS]
