"""sympy.physics.mechanics: Kane's equations derived symbolically, lambdified, scipy DOP853.

The textbook route: one ReferenceFrame per link, oriented relative to its parent by
``orient_axis`` about the joint axis (given in the parent's frame) through the relative angle
q_i, with the generalized speed u_i = qd_i as its angular velocity relative to the parent;
joint points and centres of mass located by the link's ``offset`` and ``r_cm``; one RigidBody
per link with its inertia dyadic about the centre of mass; gravity on each centre of mass; the
spring-damper torque -(k q + d u) on the link and its reaction on the parent. The numbers of
the spec go into the derivation as floats (no symbolic parameters), which is the cheapest way
to use sympy here. ``KanesMethod`` gives M(q) u' = F(q, u); both are lambdified into one
function with common subexpressions shared (``cse=True``) and u' comes from
``np.linalg.solve``.

The derivation grows fast with N, so ``build`` runs it in a spawned process and gives up
after ``timeout`` seconds with TimeoutError.

Tolerances: ``atol = rtol * 1e-2``, as for the pinocchio peer.
"""

import multiprocessing
import pickle
import queue
import time
import traceback

import numpy as np
import sympy as sm
from scipy.integrate import solve_ivp

NAME = "sympy+DOP853"
RTOLS = (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12)
TIGHTEST = {"method": "DOP853", "rtol": 1e-12}


def _plain(spec):
    """The spec's fields as lists of floats, picklable without importing ``scenes``."""
    names = ("offset", "axis", "mass", "r_cm", "inertia", "gravity", "stiffness", "damping")
    return {k: np.asarray(getattr(spec, k), dtype=float).tolist() for k in names}


def derive(data):
    """Kane's M(q) and F(q, u) of the chain in ``data`` (see ``_plain``).

    Returns
    -------
    q, u : list of Symbol
    M : Matrix (N, N)
    F : Matrix (N, 1)
    """
    from sympy.physics import mechanics as me

    n = len(data["mass"])
    q = me.dynamicsymbols(f"q0:{n}")
    u = me.dynamicsymbols(f"u0:{n}")
    ground = me.ReferenceFrame("N")
    origin = me.Point("O")
    origin.set_vel(ground, 0)

    def vector(frame, v):
        return sum((sm.Float(c) * e for c, e in zip(v, (frame.x, frame.y, frame.z)) if c),
                   me.Vector(0))

    gravity = vector(ground, data["gravity"])
    parent, joint = ground, origin
    bodies, loads = [], []
    for i in range(n):
        axis = vector(parent, data["axis"][i])
        frame = me.ReferenceFrame(f"A{i}")
        frame.orient_axis(parent, axis, q[i])
        frame.set_ang_vel(parent, u[i] * axis)
        cm = joint.locatenew(f"C{i}", vector(frame, data["r_cm"][i]))
        cm.v2pt_theory(joint, ground, frame)
        I = data["inertia"][i]
        dyadic = me.inertia(frame, I[0][0], I[1][1], I[2][2], I[0][1], I[1][2], I[0][2])
        mass = sm.Float(data["mass"][i])
        bodies.append(me.RigidBody(f"B{i}", cm, frame, mass, (dyadic, cm)))
        loads.append((cm, mass * gravity))
        k, d = data["stiffness"][i], data["damping"][i]
        if k or d:
            torque = -(sm.Float(k) * q[i] + sm.Float(d) * u[i]) * axis
            loads.append((frame, torque))
            if parent is not ground:
                loads.append((parent, -torque))
        nxt = joint.locatenew(f"P{i + 1}", vector(frame, data["offset"][i]))
        nxt.v2pt_theory(joint, ground, frame)
        parent, joint = frame, nxt

    kane = me.KanesMethod(ground, q_ind=q, u_ind=u,
                          kd_eqs=[qi.diff(me.dynamicsymbols._t) - ui for qi, ui in zip(q, u)])
    kane.kanes_equations(bodies, loads)
    qs, us = sm.symbols(f"q0:{n}"), sm.symbols(f"u0:{n}")
    plain = dict(zip(q, qs)) | dict(zip(u, us))
    return list(qs), list(us), kane.mass_matrix.xreplace(plain), kane.forcing.xreplace(plain)


def _derive_into(data, results):
    """Child process: derive, then send (seconds, pickled expressions) or the error back."""
    start = time.perf_counter()
    try:
        exprs = pickle.dumps(derive(data))
    except Exception:
        results.put((None, traceback.format_exc()))
    else:
        results.put((time.perf_counter() - start, exprs))


class Built:
    """The lambdified ``mf(q, u) -> (M, F)`` with the initial state and derivation timings."""

    def __init__(self, mf, n, x0, derive_s, lambdify_s):
        self.mf = mf
        self.n = n
        self.x0 = x0
        self.derive_s = derive_s
        self.lambdify_s = lambdify_s


def build(spec, timeout=600.0):
    """Derive the equations of ``spec`` in a spawned process and lambdify them here.

    Raises TimeoutError if the derivation takes longer than ``timeout`` seconds, RuntimeError
    with the child's traceback if it fails.
    """
    results = multiprocessing.get_context("spawn").Queue()
    child = multiprocessing.get_context("spawn").Process(
        target=_derive_into, args=(_plain(spec), results), daemon=True)
    child.start()
    try:
        derive_s, payload = results.get(timeout=timeout)
    except queue.Empty:
        raise TimeoutError(f"{NAME}: deriving the equations of the {spec.n}-link chain took "
                           f"longer than timeout = {timeout} s; gave up") from None
    finally:
        if child.is_alive():
            child.terminate()
        child.join()
    if derive_s is None:
        raise RuntimeError(f"{NAME}: the derivation failed:\n{payload}")
    q, u, M, F = pickle.loads(payload)
    start = time.perf_counter()
    mf = sm.lambdify([q, u], [M, F], modules="numpy", cse=True)
    lambdify_s = time.perf_counter() - start
    x0 = np.concatenate([spec.q0, spec.qd0]).astype(float)
    return Built(mf, spec.n, x0, derive_s, lambdify_s)


def run(built, t, **options):
    """Joint angles (len(t), N) from ``spec.q0``, ``spec.qd0`` at ``t[0]``; see ``trajectory``."""
    return trajectory(built, t, **options)[0]


def trajectory(built, t, method="DOP853", rtol=1e-8, atol=None):
    """Joint angles and rates, each (len(t), N), from ``spec.q0``, ``spec.qd0`` at ``t[0]``.

    ``atol`` defaults to ``rtol * 1e-2``. Raises RuntimeError if the integration fails.
    """
    n, mf = built.n, built.mf
    solve, concatenate = np.linalg.solve, np.concatenate

    def rhs(t, x):
        M, F = mf(x[:n], x[n:])
        return concatenate((x[n:], solve(M, F[:, 0])))

    t = np.asarray(t, dtype=float)
    sol = solve_ivp(rhs, (t[0], t[-1]), built.x0, method=method, t_eval=t, rtol=rtol,
                    atol=rtol * 1e-2 if atol is None else atol)
    if not sol.success:
        raise RuntimeError(f"{NAME} {method} rtol={rtol}: {sol.message}")
    return sol.y[:n].T, sol.y[n:].T


def variants():
    """DOP853 at rtol 1e-3 .. 1e-12."""
    return [{"method": "DOP853", "rtol": r} for r in RTOLS]
