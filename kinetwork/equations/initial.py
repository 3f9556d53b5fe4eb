"""Initial conditions as equations: the start that ``Model.initial`` asks for (a steady
state, given derivatives, parameters solved from the start; see ``kinetwork.graph.initial``).

The equations are rows of the System's own right-hand side at t = 0, f(0, x, p) = d, with the
unknown states and parameters of ``initial`` put in as the unknowns w: r(w) = 0, square, solved
by CasADi's Newton rootfinder from the given start and the parameters' values (its Jacobian
by CasADi's AD). A structurally singular system (an unknown that no equation reads: a free
rotor's angle in a steady state, a parameter the start does not depend on) is refused before
any iteration, naming the unknowns left undetermined (a maximum matching, networkx); one
Newton cannot solve, or solves only to a residual above the tolerance, is refused naming the
equations it could not satisfy.
"""

import json

import casadi as ca
import numpy as np

from ..errors import ModelError
from ..util import quiet, suggest, summary
from .matching import maximum_matching
from .modes import operating_modes

#: a residual above this (scaled by 1 + |d|) after Newton is no solution
RESIDUAL_TOL = 1e-8


class InitialEquations:
    """The initial equations of ``system``'s model, built once per ``initial`` block and
    solved once per parameter vector and given start."""

    def __init__(self, system):
        self.system = system
        self._built = {}              # spec (JSON) -> _Problem
        self._solved = {}             # (spec, p, x0) -> (x0, p)

    @property
    def spec(self):
        return getattr(self.system.model, "initial", None) or {}

    def solves_parameters(self):
        return any(n in self.system.param_names for n in self.spec.get("solve", []))

    def apply(self, p, x0):
        """(x0, p) with the unknowns of ``initial`` solved; unchanged without it."""
        spec = self.spec
        if not spec:
            return x0, p
        text = json.dumps(spec, sort_keys=True)
        p, x0 = np.asarray(p, dtype=float), np.asarray(x0, dtype=float)
        key = (text, p.tobytes(), x0.tobytes())
        if key not in self._solved:
            if text not in self._built:
                self._built[text] = _Problem(self.system, spec)
            self._solved[key] = self._built[text].solve(x0, p)
        return self._solved[key]


class _Problem:
    """r(w) = 0 for one ``initial`` block: the unknowns' places, the equations' rows."""

    def __init__(self, system, spec):
        if system.n_algebraic:
            raise ModelError("initial: initial equations are solved for models of ordinary "
                             "differential equations; this one has algebraic variables "
                             f"({', '.join(system.algebraic_names)}: kinematic or algebraic "
                             f"loops): give their start instead")
        self.system = system
        states, params = list(system.state_names), list(system.param_names)
        steady = spec.get("steady", False)
        problems = []

        def state(name, where):
            if name not in states:
                problems.append(f"{where}: no state {name!r}{suggest(name, states)}; states "
                                f"are {', '.join(states) or 'none'}")
                return None
            return states.index(name)
        fixed = {i for k, n in enumerate(spec.get("fixed", []))
                 if (i := state(n, f"initial.fixed[{k}]")) is not None}
        rows = {i: 0.0 for i in range(len(states))} if steady else {}
        for name, value in spec.get("derivatives", {}).items():
            i = state(name, f"initial.derivatives.{name}")
            if i is not None:
                rows[i] = float(value)
        self.x_unknown = [i for i in range(len(states)) if i not in fixed] if steady else []
        self.p_unknown = []
        for k, name in enumerate(spec.get("solve", [])):
            where = f"initial.solve[{k}]"
            if name in params:
                self.p_unknown.append(params.index(name))
            elif name in states and steady:
                problems.append(f"{where}: {name!r} is an unknown already (steady solves "
                                f"every state not fixed)")
            elif name in states:
                self.x_unknown.append(states.index(name))
            else:
                problems.append(f"{where}: {name!r} is neither a model parameter nor a "
                                f"state{suggest(name, params + states)}; parameters are "
                                f"{', '.join(params) or 'none'}")
        if problems:
            raise ModelError(problems)
        self.rows = sorted(rows)
        self.d = np.array([rows[i] for i in self.rows])
        unknowns = [states[i] for i in self.x_unknown] + [params[i] for i in self.p_unknown]
        equations = [f"der({states[i]}) = {rows[i]:g}" for i in self.rows]
        if len(unknowns) != len(equations):
            raise ModelError(
                f"initial: {len(equations)} equation(s) ({', '.join(equations) or 'none'}) "
                f"for {len(unknowns)} unknown(s) ({', '.join(unknowns) or 'none'}): they must "
                f"be as many; " + ("fix as many states as parameters are solved"
                                   if steady else "solve as many states and parameters as "
                                   "derivatives are given"))
        self.unknowns, self.equations = unknowns, equations
        x, p, t = system._x, system.asm.p, system.asm.t
        n = len(unknowns)
        w = ca.SX.sym("w", n)
        xs, ps = ca.vertsplit(ca.densify(x)) if x.numel() else [], \
            ca.vertsplit(ca.densify(p)) if p.numel() else []
        for k, i in enumerate(self.x_unknown):
            xs[i] = w[k]
        for k, i in enumerate(self.p_unknown):
            ps[i] = w[len(self.x_unknown) + k]
        f = ca.substitute(ca.SX(system.ode), t, ca.SX(0))
        r = ca.vertcat(*[f[i] for i in self.rows]) - ca.DM(self.d) if self.rows else \
            ca.SX(0, 1)
        known = ca.vertcat(x, p)
        r = ca.substitute(r, known, ca.vertcat(*xs, *ps))
        self._undetermined(r, w)
        self.residual = ca.Function("initial_residual", [w, known], [r])
        self.newton = ca.rootfinder("initial", "newton", self.residual,
                                    {"error_on_fail": True, "max_iter": 100})

    def _undetermined(self, r, w):
        """Refuse unknowns that a maximum matching of the Jacobian's pattern leaves out."""
        rows, cols = ca.jacobian(r, w).sparsity().get_triplet()
        matching = maximum_matching(len(self.equations), len(self.unknowns), zip(rows, cols))
        matched = set(matching.values())
        lost = [self.unknowns[j] for j in range(len(self.unknowns)) if j not in matched]
        if lost:
            idle = [self.equations[k] for k in range(len(self.equations))
                    if k not in matching]
            raise ModelError(f"initial: the equations do not determine {', '.join(lost)} "
                             f"(structurally singular: no equation left reads them; "
                             f"{', '.join(idle)} is one too many): fix those states, or "
                             f"solve something these equations depend on")

    def solve(self, x0, p):
        """(x0, p) with the unknowns solved; the modes of friction and stops as the run
        starts them, before and after (a stuck friction that cannot hold is refused: its
        start would not keep the derivatives asked)."""
        x0 = self._modes(x0, p, check=False)
        x0, p = self._newton(x0, p)
        moved = self._modes(x0, p, check=True)
        if not np.array_equal(moved, x0):       # the start found changed a mode: again
            x0, p = self._newton(moved, p)
            x0 = self._modes(x0, p, check=True)
        known = np.concatenate([x0, p])
        w = np.concatenate([x0[self.x_unknown], p[self.p_unknown]])
        left = np.asarray(self.residual(w, known), dtype=float).ravel()
        if not np.all(np.abs(left) <= RESIDUAL_TOL * (1 + np.abs(self.d))):
            raise ModelError(f"initial: the start solved for does not keep "
                             f"{', '.join(self.equations)} once its modes are those the run "
                             f"starts with (residual " + ", ".join(
                                 f"{e}: {v:.3g}" for e, v in zip(self.equations, left))
                             + "): give a start nearer one where they hold")
        return x0, p

    def _modes(self, x0, p, check):
        """x0 with the modes of friction and stops that its numbers give (``operating_modes``);
        with ``check``, a stuck friction beyond its static limit is refused."""
        system = self.system
        if system.modes is None:
            return x0
        try:
            return operating_modes(system, 0.0, x0, p, check=check)
        except ModelError as exc:
            shown = ", ".join(f"{system.state_names[i]} = {x0[i]:.6g}"
                              for i in self.x_unknown)
            raise ModelError(f"initial: the start solved for ({shown or 'as given'}) keeps "
                             f"{', '.join(self.equations)} only with a friction stuck where "
                             f"it cannot hold: {exc}") from None

    def _newton(self, x0, p):
        known = np.concatenate([x0, p])
        guess = np.concatenate([x0[self.x_unknown], p[self.p_unknown]])
        with quiet() as said:
            try:
                w = np.asarray(self.newton(guess, known), dtype=float).ravel()
            except RuntimeError:
                w = None
        if w is not None:
            left = np.asarray(self.residual(w, known), dtype=float).ravel()
        if w is None or not np.all(np.abs(left) <= RESIDUAL_TOL * (1 + np.abs(self.d))):
            where = "" if w is None else " (residual " + ", ".join(
                f"{e}: {v:.3g}" for e, v in zip(self.equations, left)) + ")"
            chatter = summary(said["text"])
            raise ModelError(f"initial: the model cannot satisfy {', '.join(self.equations)} "
                             f"with {', '.join(self.unknowns)} as unknowns: Newton from the "
                             f"given start and parameter values found no solution{where}; "
                             f"the equations may have none (a spring constant that does not "
                             f"act at the start), or start nearer one"
                             + (f" ({chatter})" if chatter else ""))
        x0, p = x0.copy(), p.copy()
        nx_ = len(self.x_unknown)
        x0[self.x_unknown] = w[:nx_]
        p[self.p_unknown] = w[nx_:]
        return x0, p


def solved(system, params=None):
    """The unknowns of the model's ``initial`` block as solved for ``params``: {name: value}
    (parameters and states), empty without initial equations (``System.initial_values``)."""
    p = np.array([system.model.parameter_values(params)[k] for k in system.param_names],
                 dtype=float)
    x0 = system.eq.initial(p)[0]
    ini = system.initial_equations
    x, q = ini.apply(p, x0)
    if not ini.spec:
        return {}
    problem = ini._built[json.dumps(ini.spec, sort_keys=True)]
    out = {system.state_names[i]: float(x[i]) for i in problem.x_unknown}
    out.update({system.param_names[i]: float(q[i]) for i in problem.p_unknown})
    return out
