"""An independent reference for constrained mechanisms: equations of motion with Lagrange
multipliers, written with sympy from the bodies' positions and orientations in the
coordinates, integrated by scipy's DOP853. Nothing of kinetwork is used.

Each body is (mass, inertia about its centre of mass in its own axes, orientation R(q) in
the world, centre of mass c(q) in the world). With the Jacobians of c and of the body's
angular velocity (in its own axes, from R^T dR/dt), the equations are

    M(q) q'' + h(q, q') = Q(q, q') + G(q)^T lambda,     G(q) q'' = -(dG/dt) q',

M = sum m Jc^T Jc + Jw^T I Jw, h their velocity terms and the gyroscopic one, Q gravity and
the forces given, G the constraints' Jacobian: solved for q'' and lambda at every step. The
constraints are held at position level by the start (solved by scipy's fsolve) and drift
only at the integrator's tolerance, which the tests check.
"""

import warnings

import casadi as ca
import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp
from scipy.optimize import fsolve


def rot(axis, angle):
    """Rotation by ``angle`` about the unit vector along ``axis`` (sympy, Rodrigues)."""
    n = sp.Matrix(axis) / sp.sqrt(sum(a**2 for a in axis))
    K = sp.Matrix([[0, -n[2], n[1]], [n[2], 0, -n[0]], [-n[1], n[0], 0]])
    return sp.eye(3) + sp.sin(angle) * K + (1 - sp.cos(angle)) * K * K


def unit(v):
    return v / sp.sqrt(v.dot(v))


class Mechanism:
    """Coordinates ``q`` (sympy symbols), bodies, constraints g(q) = 0 and extra generalized
    forces Q(q, qd); gravity along ``gravity`` (world).

    The scene is written in sympy; the derivatives (Jacobians, rates) are taken by CasADi's
    SX, a second symbolic engine with no part of kinetwork in it: sympy's own differentiation
    and common-subexpression pass took 40-120 s on a spatial four-bar, CasADi's takes
    milliseconds, with the same equations."""

    def __init__(self, q, bodies, constraints=(), forces=None, gravity=(0, -9.81, 0)):
        self.q = list(q)
        n = len(self.q)
        self.qd = sp.symbols(f"qd0:{n}")
        qv, qd = ca.SX.sym("q", n), ca.SX.sym("qd", n)
        sx = _to_sx(self.q + list(self.qd), ca.vertcat(qv, qd))
        g = ca.DM(gravity)
        M, h, Q = ca.SX(n, n), ca.SX(n, 1), ca.SX(n, 1)

        def rate(expr):
            return ca.reshape(ca.jtimes(ca.vec(expr), qv, qd), *expr.shape)
        for mass, inertia, R, c in bodies:
            I = ca.DM(np.array(sp.Matrix(inertia), dtype=float))
            R, c = sx(R), sx(c)
            Jc = ca.jacobian(c, qv)
            W = R.T @ rate(R)
            w = ca.vertcat(W[2, 1], W[0, 2], W[1, 0])           # body axes
            Jw = ca.jacobian(w, qd)
            M += mass * Jc.T @ Jc + Jw.T @ I @ Jw
            h += mass * Jc.T @ rate(Jc @ qd) + Jw.T @ (I @ rate(Jw @ qd)
                                                         + ca.cross(w, I @ w))
            Q += mass * Jc.T @ g
        if forces is not None:
            Q += sx(sp.Matrix(forces))
        phi = sx(sp.Matrix(list(constraints))) if constraints else ca.SX(0, 1)
        G = ca.jacobian(phi, qv)
        Gd = rate(G @ qd)
        self.f_M = ca.Function("M", [qv, qd], [M])
        self.f_rest = ca.Function("rest", [qv, qd], [Q - h])
        self.f_G = ca.Function("G", [qv, qd], [G])
        self.f_Gd = ca.Function("Gd", [qv, qd], [Gd])
        self.f_phi = ca.Function("phi", [qv], [phi])
        self.m = len(constraints)

    def accelerations(self, q, qd):
        M = np.array(self.f_M(q, qd), dtype=float)
        rest = np.array(self.f_rest(q, qd), dtype=float).ravel()
        n = len(q)
        if not self.m:
            return np.linalg.solve(M, rest)
        G = np.array(self.f_G(q, qd), dtype=float).reshape(self.m, n)
        Gd = np.array(self.f_Gd(q, qd), dtype=float).ravel()
        A = np.block([[M, -G.T], [G, np.zeros((self.m, self.m))]])
        return np.linalg.solve(A, np.concatenate([rest, -Gd]))[:n]

    def start(self, q_given, free, qd_given, qd_free):
        """Consistent start: the coordinates at indices ``free`` solved from the guesses in
        ``q_given`` so that g(q) = 0, and the speeds at ``qd_free`` so that G qd = 0."""
        q = np.array(q_given, dtype=float)

        def res(z):
            x = q.copy()
            x[free] = z
            return np.array(self.f_phi(x), dtype=float).ravel()
        with warnings.catch_warnings():
            # fsolve warns when it cannot better 1e-14; the residual is checked instead
            warnings.simplefilter("ignore", RuntimeWarning)
            q[free] = fsolve(res, q[free], xtol=1e-14)
        assert np.max(np.abs(res(q[free])), initial=0.0) < 1e-12
        qd = np.array(qd_given, dtype=float)
        if self.m:
            G = np.array(self.f_G(q, qd), dtype=float).reshape(self.m, len(q))
            known = [k for k in range(len(q)) if k not in qd_free]
            qd[qd_free] = np.linalg.solve(G[:, qd_free], -G[:, known] @ qd[known])
        return q, qd

    def solve(self, q0, qd0, t):
        n = len(q0)

        def rhs(_, y):
            return np.concatenate([y[n:], self.accelerations(y[:n], y[n:])])
        sol = solve_ivp(rhs, (t[0], t[-1]), np.concatenate([q0, qd0]), method="DOP853",
                        rtol=1e-12, atol=1e-12, t_eval=t)
        assert sol.success, sol.message
        return sol.y[:n].T, sol.y[n:].T

    def drift(self, Q):
        return max(np.max(np.abs(np.array(self.f_phi(q), dtype=float)), initial=0.0)
                   for q in Q)


def _to_sx(symbols, values):
    """A function taking a sympy matrix (or expression) in ``symbols`` to CasADi SX, the
    symbols replaced by the entries of ``values``."""
    functions = {"sin": ca.sin, "cos": ca.cos, "tan": ca.tan, "sqrt": ca.sqrt,
                 "atan2": ca.atan2, "exp": ca.exp, "log": ca.log, "Abs": ca.fabs}
    entries = [values[i] for i in range(values.shape[0])]

    def sx(expr):
        matrix = sp.Matrix(expr) if not isinstance(expr, sp.MatrixBase) else expr
        f = sp.lambdify(symbols, list(matrix), modules=[functions, "math"])
        out = f(*entries)
        return ca.reshape(ca.vertcat(*[ca.SX(v) for v in out]), matrix.shape[1],
                          matrix.shape[0]).T
    return sx
