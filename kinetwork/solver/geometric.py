"""The implicit midpoint rule in canonical coordinates: a symplectic, fixed-step integrator.

Explicit Runge-Kutta and multistep methods let the energy of an undamped mechanism drift over
long runs; a symplectic method keeps its error bounded for as long as one cares to integrate.
The implicit midpoint rule is symplectic for a Hamiltonian system written in canonical
coordinates (q, p), with p = M(q) qd the generalized momenta, so that is where it is applied:

    q1 = q0 + h v,    p1 = p0 + h f_p(t + h/2, qm, v),    qm = q0 + h v / 2,

where v = M(qm)^-1 (p0 + p1) / 2 is the midpoint velocity and f_p = dp/dt = M' qd - (C qd + g)
+ Q is the rate of the momenta (M' qd by forward differentiation of M(q) qd, C qd + g by the
recursive Newton-Euler algorithm, Q the generalized forces of the 1-D elements, damping
included as a non-conservative force). The unknown of each step is v alone (n values): its
residual ``2 M(qm) v - 2 p0 - h f_p`` is solved by CasADi's Newton rootfinder with the exact
Jacobian. Every piece is O(n) per evaluation (no mass matrix is formed in the step).
"""

import casadi as ca
import numpy as np

from .newton_euler import crba, rnea
from .system import JACOBIAN_JIT_LIMIT


class Midpoint:
    """The compiled step of one system; ``run`` integrates on an output grid.

    Each step starts Newton from the explicit predictor v = qd + h/2 qdd (qd = M^-1 p, qdd by
    the articulated-body algorithm), and records the residual it leaves: a step that did not
    converge (a step too large for the motion) is reported by ``run``, not raised inside CasADi.
    """

    def __init__(self, system, jit=False):
        a = system.asm
        n = len(a.coordinate_names)
        zero, w = ca.SX.zeros(n), ca.SX.sym("w", n)
        a_grav = ca.vertcat(ca.SX.zeros(3), -a.gravity)
        # M(q) w by RNEA with no speed and no gravity; M(q) qd and its rate by differentiation
        Mw = ca.substitute(rnea(a.bodies, zero, w, ca.SX.zeros(6)), a.qd, zero)
        Mqd = ca.substitute(Mw, w, a.qd)
        Mdot_qd = ca.substitute(ca.jtimes(Mw, a.q, a.qd), w, a.qd)
        fp = Mdot_qd - rnea(a.bodies, a.qd, zero, a_grav) + a.Q
        f_Mqd = ca.Function("Mqd", [a.q, a.qd, a.p], [Mqd])
        f_fp = ca.Function("fp", [a.t, a.q, a.qd, a.p], [fp])
        f_qdd = ca.Function("qdd", [a.t, a.q, a.qd, a.p], [a.qdd])
        f_M = ca.Function("M", [a.q, a.p], [crba(a.bodies, n)])

        v, q0, p0 = ca.SX.sym("v", n), ca.SX.sym("q0", n), ca.SX.sym("p0", n)
        t0, h, par = ca.SX.sym("t0"), ca.SX.sym("h"), ca.SX.sym("par", a.p.shape[0])
        qm = q0 + h / 2 * v
        residual = ca.Function("midpoint_residual", [v, ca.vertcat(q0, p0, t0, h, par)],
                               [2 * f_Mqd(qm, v, par) - 2 * p0 - h * f_fp(t0 + h / 2, qm, v, par)])
        if jit and residual.jacobian().n_instructions() <= JACOBIAN_JIT_LIMIT:
            from . import jit as _jit
            residual = _jit.external(residual, jacobian=True, stats=system.jit_stats)
        solve = ca.rootfinder("midpoint", "newton", residual,
                              {"abstol": 1e-12, "abstolStep": 1e-14, "max_iter": 30,
                               "error_on_fail": False, "show_eval_warnings": False})

        # one step on the state z = (q, p, t, worst relative residual so far)
        z = ca.MX.sym("z", 2 * n + 2)
        hh, pp = ca.MX.sym("h"), ca.MX.sym("p", a.p.shape[0])
        q, p, t = z[:n], z[n:2 * n], z[2 * n]
        qd = ca.solve(f_M(q, pp), p, "qr")
        guess = qd + hh / 2 * f_qdd(t, q, qd, pp)
        args = ca.vertcat(q, p, t, hh, pp)
        v1 = solve(guess, args)
        p1 = 2 * f_Mqd(q + hh / 2 * v1, v1, pp) - p
        miss = ca.norm_inf(residual(v1, args)) / (1 + ca.norm_inf(p))
        self._step = ca.Function("step", [z, hh, pp],
                                 [ca.vertcat(q + hh * v1, p1, t + hh, ca.fmax(z[-1], miss))])
        self._intervals = {}
        self.n = n
        self._momenta = f_Mqd
        zz = ca.MX.sym("z", 2 * n)
        self._velocity = ca.Function("velocity", [zz, pp],
                                     [ca.solve(f_M(zz[:n], pp), zz[n:], "qr")])

    def interval(self, m):
        """m steps at once, as one CasADi call."""
        if m not in self._intervals:
            steps = self._step.mapaccum("steps", m)
            z, h = ca.MX.sym("z", 2 * self.n + 2), ca.MX.sym("h")
            p = ca.MX.sym("p", self._step.size1_in(2))
            self._intervals[m] = ca.Function("interval", [z, h, p], [steps(z, h, p)[:, -1]])
        return self._intervals[m]

    def run(self, grid, x0, p, step):
        """States (q, qd) on ``grid`` from ``x0``; steps of at most ``step`` seconds.

        Returns (X, failure, stats): when a step's Newton iteration does not converge, the
        states up to the output time before it and the reason.
        """
        n = self.n
        dt = float(grid[1] - grid[0])
        m = max(1, int(np.ceil(dt / step * (1 - 1e-12))))
        h = dt / m
        interval = self.interval(m)
        q0, qd0 = x0[:n], x0[n:]
        z = np.concatenate([q0, np.asarray(self._momenta(q0, qd0, p)).ravel(), [grid[0], 0.0]])
        Z = [z]
        failure = None
        for _ in range(len(grid) - 1):
            z = np.asarray(interval(z, h, p)).ravel()
            if not np.all(np.isfinite(z)) or z[-1] > CONVERGED:
                failure = (f"the midpoint rule's Newton iteration did not converge with steps "
                           f"of {h:g} s (the motion changes too much within a step): take a "
                           f"smaller step")
                break
            Z.append(z)
        Z = np.array(Z)
        qd = np.asarray(self._velocity.map(len(Z))(Z[:, :2 * n].T, p)).T
        X = np.hstack([Z[:, :n], qd])
        return X, failure, {"steps": (len(Z) - 1) * m, "step": h,
                            "residual": float(Z[-1, -1])}


#: largest residual of a step's equations, relative to the momenta, counted as converged
CONVERGED = 1e-9
