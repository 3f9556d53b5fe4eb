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

from . import jit as _jit
from ..equations.newton_euler import rnea
from ..equations.system import pointwise
from .compiled import JACOBIAN_JIT_LIMIT


class Midpoint:
    """The compiled step of one system; ``run`` integrates on an output grid.

    Each step starts Newton from the explicit predictor v = qd + h/2 qdd (qd = M^-1 p, qdd by
    the articulated-body algorithm), and records the residual it leaves: a step that did not
    converge (a step too large for the motion) is reported by ``run``, not raised inside CasADi.
    """

    def __init__(self, system, jit=None):
        """``jit``: None, or the options of ``jit.external`` (compile the step to C)."""
        a = system.asm
        n = len(a.coordinate_names)
        zero, w = ca.SX.zeros(n), ca.SX.sym("w", n)
        a_grav = ca.vertcat(ca.SX.zeros(3), -a.gravity)
        # M(q) w by RNEA with no speed and no gravity; M(q) qd and its rate by differentiation
        Mw = a.mass_times(w)
        Mqd = ca.substitute(Mw, w, a.u)
        Mdot_qd = ca.substitute(ca.jtimes(Mw, a.q, a.u), w, a.u)
        fp = Mdot_qd - rnea(a.bodies, a.u, zero, a_grav) + a.Q
        f_Mqd = ca.Function("Mqd", [a.q, a.u, a.p], [Mqd])
        f_fp = ca.Function("fp", [a.t, a.q, a.u, a.p], [fp])
        f_qdd = ca.Function("qdd", [a.t, a.q, a.u, a.p], [a.udot_tree])
        # qd = M(q)^-1 p by the articulated-body algorithm (p as the joint forces, no speed,
        # no gravity): O(n), no mass matrix
        f_vel = ca.Function("velocity", [a.q, w, a.p], [a.solve_mass(w)])

        v, q0, p0 = ca.SX.sym("v", n), ca.SX.sym("q0", n), ca.SX.sym("p0", n)
        t0, h, par = ca.SX.sym("t0"), ca.SX.sym("h"), ca.SX.sym("par", a.p.shape[0])
        args = ca.vertcat(q0, p0, t0, h, par)
        qm = q0 + h / 2 * v
        r = 2 * f_Mqd(qm, v, par) - 2 * p0 - h * f_fp(t0 + h / 2, qm, v, par)
        residual = ca.Function("midpoint_residual", [v, args], [r])
        qd0 = f_vel(q0, p0, par)
        predict = ca.Function("midpoint_predict", [args], [qd0 + h / 2 * f_qdd(t0, q0, qd0, par)])
        advance = ca.Function("midpoint_advance", [v, args],
                              [ca.vertcat(q0 + h * v, 2 * f_Mqd(qm, v, par) - p0, t0 + h),
                               ca.norm_inf(r) / (1 + ca.norm_inf(p0))])
        # one step on the state z = (q, p, t, worst relative residual so far)
        if n <= UNROLLED:
            # a few Newton iterations written out: one SX function per step, compiled whole
            z, hh, pp = ca.SX.sym("z", 2 * n + 2), ca.SX.sym("h"), ca.SX.sym("p", a.p.shape[0])
            here = ca.vertcat(z[:2 * n + 1], hh, pp)
            jac = ca.Function("midpoint_jacobian", [v, args], [ca.jacobian(r, v)])
            vk = predict(here)
            for _ in range(NEWTON_ITERATIONS):
                vk = vk - ca.solve(jac(vk, here), residual(vk, here))
            nxt, miss = advance(vk, here)
            self._step = ca.Function("step", [z, hh, pp],
                                     [ca.vertcat(nxt, ca.fmax(z[-1], miss))])
            if jit:
                self._step = _jit.external(self._step, **jit)
        else:
            # CasADi's Newton rootfinder, its residual compiled with its Jacobian if small
            if jit:
                if residual.jacobian().n_instructions() <= JACOBIAN_JIT_LIMIT:
                    residual = _jit.external(residual, True, **jit)
                predict, advance = (_jit.external(f, **jit)
                                    for f in (predict, advance))
            solve = ca.rootfinder("midpoint", "newton", residual,
                                  {"abstol": 1e-12, "abstolStep": 1e-14, "max_iter": 30,
                                   "error_on_fail": False, "show_eval_warnings": False})
            z = ca.MX.sym("z", 2 * n + 2)
            hh, pp = ca.MX.sym("h"), ca.MX.sym("p", a.p.shape[0])
            here = ca.vertcat(z[:2 * n + 1], hh, pp)
            nxt, miss = advance(solve(predict(here), here), here)
            self._step = ca.Function("step", [z, hh, pp],
                                     [ca.vertcat(nxt, ca.fmax(z[-1], miss))])
        self._runs = {}
        self.n = n
        self._momenta = f_Mqd
        self._velocity = f_vel

    def trajectory(self, m, n_out):
        """``n_out`` output intervals of ``m`` steps each, as one CasADi call."""
        key = (m, n_out)
        if key not in self._runs:
            steps = self._step.mapaccum("steps", m)
            z, h = ca.MX.sym("z", 2 * self.n + 2), ca.MX.sym("h")
            p = ca.MX.sym("p", self._step.size1_in(2))
            interval = ca.Function("interval", [z, h, p], [steps(z, h, p)[:, -1]])
            self._runs[key] = interval.mapaccum("outputs", n_out)
        return self._runs[key]

    def run(self, grid, x0, p, m):
        """States (q, qd) on ``grid`` from ``x0``, in ``m`` equal steps per output interval.

        Returns (X, failure, stats): when a step's Newton iteration does not converge, the
        states up to the output time before it and the reason.
        """
        n = self.n
        h = float(grid[1] - grid[0]) / m
        q0, qd0 = x0[:n], x0[n:]
        z0 = np.concatenate([q0, np.asarray(self._momenta(q0, qd0, p)).ravel(), [grid[0], 0.0]])
        with np.errstate(invalid="ignore"):
            Z = np.vstack([z0, np.asarray(self.trajectory(m, len(grid) - 1)(z0, h, p)).T])
            bad = ~np.all(np.isfinite(Z), axis=1) | (Z[:, -1] > CONVERGED)
        failure = None
        if bad.any():          # the worst residual only grows: keep what came before
            Z = Z[:int(np.argmax(bad))]
            failure = (f"the midpoint rule's Newton iteration did not converge with steps of "
                       f"{h:g} s (the motion changes too much within a step): take a smaller "
                       f"step")
        qd = pointwise(self._velocity, Z[:, :n], Z[:, n:2 * n], p)[0]
        X = np.hstack([Z[:, :n], qd])
        return X, failure, {"steps": (len(Z) - 1) * m, "step": h,
                            "residual": float(Z[-1, -1])}


#: largest residual of a step's equations, relative to the momenta, counted as converged
CONVERGED = 1e-9
#: up to this many coordinates the Newton iterations are written out in SX (a symbolic n x n
#: solve per iteration); beyond, CasADi's rootfinder iterates numerically
UNROLLED = 12
#: Newton iterations from the explicit predictor (error O(h^3)): quadratic convergence takes
#: it to round-off in two or three; a step that needs more than five is reported by the
#: residual check
NEWTON_ITERATIONS = 5
