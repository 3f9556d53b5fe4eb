"""System: a compiled model, its states, parameters and CasADi Functions."""

import functools

import casadi as ca
import numpy as np

from ..errors import ModelError
from . import jit as _jit
from .assemble import assemble
from .loops import BAUMGARTE_RATE, formulate, newton

#: Jacobians larger than this (instructions) are not compiled to C: Newton iterations use
#: finite differences of the compiled right-hand side instead (an N = 128 chain's exact
#: Jacobian is 2.5 million instructions, minutes of gcc)
JACOBIAN_JIT_LIMIT = 200_000


class System:
    """The equations of a validated model, compiled once; parameters stay symbolic.

    Attributes
    ----------
    state_names : list of str
        Joint coordinates, then their speeds (``"shoulder.q"``, ..., ``"shoulder.qd"``).
    x0 : numpy.ndarray
        Initial state for the model's parameter values.
    """

    def __init__(self, model, loops="partition", baumgarte_rate=None):
        self.model = model
        self.topology = model.validate()
        self.asm = asm = assemble(model, self.topology)
        self.eq = eq = formulate(asm, self.topology, model.parameter_values(), loops,
                                 BAUMGARTE_RATE if baumgarte_rate is None else baumgarte_rate)
        self.param_names = asm.param_names
        self.coordinate_names = asm.coordinate_names
        self.speed_names = asm.speed_names
        self.state_names, self.state_units = eq.state_names, eq.state_units
        #: dependent joint coordinates of a model with loops (solved, not integrated)
        self.algebraic_names, self.algebraic_units = eq.algebraic_names, eq.algebraic_units
        self._x, self._z = eq.x, eq.z
        self.ode = eq.ode
        # dense outputs: Function.buffer callers read plain column-major arrays
        self.f_rhs = ca.Function("rhs", [asm.t, eq.x, asm.p], [ca.densify(self.ode)],
                                 ["t", "x", "p"], ["xdot"]) if not self.n_algebraic else None
        self.f_dae = ca.Function("dae", [asm.t, eq.x, eq.z, asm.p],
                                 [ca.densify(eq.ode), ca.densify(eq.alg)],
                                 ["t", "x", "z", "p"], ["ode", "alg"])
        self.probe_targets = {probe.name: target.path for probe, target in self.topology.probes}
        self.signal_names = [name for name, _, _ in asm.signals]
        self.signal_units = {name: unit for name, unit, _ in asm.signals}
        self.signal_sizes = {name: expr.numel() for name, _, expr in asm.signals}
        coords = asm.q if eq.q is None else eq.q
        # dense: a structurally zero acceleration (a body with no inertia about an axis)
        # must still replace its symbol
        values = ca.densify(ca.vertcat(coords, eq.u, eq.udot, eq.lam))
        outs = [ca.substitute(expr, ca.vertcat(asm.q, asm.qd, asm.qdd_sym, asm.lam_sym), values)
                for _, _, expr in asm.signals]
        # outputs read the whole state: differential, then algebraic
        self.f_out = ca.Function("outputs", [asm.t, ca.vertcat(eq.x, eq.z), asm.p],
                                 [ca.vertcat(*outs) if outs else ca.SX(0, 1)])
        self._f_mass = None
        if self.formulation == "tree" and self.speed_names and not self.n_algebraic:
            self._check_mass_matrix()
        else:                  # initial values that contradict the loops: refused now
            self.initial_full_p(self.param_vector())
        self._f_terms = None
        self._f_jac = None
        self._f_residual = None
        self._z_last = None
        self._integrators = {}
        self._compiled = {}
        self.jit_stats = {}

    def _check_mass_matrix(self):
        """Refuse a mass matrix that is singular at the initial state (a joint that moves no
        mass or inertia: a chain of bodies with zero mass, a slider carrying nothing, a free
        body with no inertia about an axis), naming the joints it cannot accelerate, rather
        than integrating NaNs or, worse, zeros."""
        p = self.param_vector()
        x0 = self.initial_full_p(p)[0]
        # M column by column as inverse dynamics of unit accelerations (no speed, no
        # gravity): an O(n) expression, where CRBA's would be O(n^2) to build
        a, n = self.asm, len(self.speed_names)
        acc = ca.SX.sym("acc", n)
        f = ca.Function("M_columns", [a.q, acc, a.p], [a.mass_times(acc)])
        M = np.asarray(f.map(n)(x0[:len(self.coordinate_names)], np.eye(n), p))
        values, vectors = np.linalg.eigh((M + M.T) / 2)
        scale = max(np.max(np.abs(M)), 1.0)
        if values[0] > 1e-12 * scale:
            return
        null = vectors[:, values <= 1e-12 * scale]
        involved = [self.speed_names[i] for i in range(len(self.speed_names))
                    if np.max(np.abs(null[i])) > 1e-3]
        joints = list(dict.fromkeys(n.split(".")[0] for n in involved))
        raise ModelError(f"the mass matrix is singular at the initial state: "
                         f"{', '.join(joints)} move(s) no mass or inertia in the direction of "
                         f"{', '.join(involved)} (give the bodies they carry mass or inertia, "
                         f"or lock the joint)")

    def polish(self, X, p):
        """Full states X (n_points, n_states + n_algebraic) with the algebraic variables
        (dependent coordinates) Newton-corrected onto the closure to machine precision: the
        integrator solves them only to its tolerance."""
        if not self.n_algebraic or not len(X):
            return X
        key = ("polish", len(X))
        if key not in self._compiled:
            if "polish" not in self._compiled:
                self._compiled["polish"] = ca.Function(
                    "polish", [ca.vertcat(self._x, self._z), self.asm.p],
                    [newton(self.eq.alg, self._z)])
            self._compiled[key] = self._compiled["polish"].map(len(X))
        Z = np.asarray(self._compiled[key](np.asarray(X).T, p)).T
        out = np.array(X, dtype=float)
        ok = np.all(np.isfinite(Z), axis=1)
        out[ok, self.n_states:] = Z[ok]
        return out

    @property
    def dof(self):
        """Degrees of freedom: speeds less the independent loop-closure equations, plus the
        free rotors and sliding masses of the 1-D network."""
        free = sum(1 for g in self.topology.oned if g.kind == "free")
        return len(self.speed_names) - self.eq.loop_rows + free

    @property
    def n_algebraic(self):
        return len(self.algebraic_names)

    @property
    def formulation(self):
        """"tree" (no loops), "partition", "projected" or "baumgarte"; ``formulation_note``
        says why the state count is what it is."""
        return self.eq.formulation

    @property
    def formulation_note(self):
        return self.eq.note

    def constraint_residual(self, X, params=None):
        """Largest |closure residual| of the kept loop equations at each row of full states
        X (n_points, n_states + n_algebraic); zeros for a model without loops."""
        X = np.atleast_2d(np.asarray(X, dtype=float))
        if self.eq.residual is None:
            return np.zeros(len(X))
        if self._f_residual is None:
            self._f_residual = ca.Function("residual", [ca.vertcat(self._x, self._z),
                                                        self.asm.p],
                                           [ca.norm_inf(self.eq.residual)])
        out = self._f_residual.map(len(X))(X.T, self.param_vector(params))
        return np.asarray(out).ravel()

    # -- parameters -----------------------------------------------------------------------
    def param_vector(self, params=None):
        """Model parameters as the vector p, with ``params`` overrides checked."""
        values = self.model.parameter_values(params)
        if params:
            self.model.numeric_values(params)     # bounds of everything that depends on them
        return np.array([values[k] for k in self.param_names], dtype=float)

    @property
    def x0(self):
        return self.initial_state()

    def initial_state(self, params=None):
        """Initial state for the given parameter overrides."""
        return self.initial_state_p(self.param_vector(params))

    def initial_state_p(self, p):
        """Initial state for a parameter vector already checked by ``param_vector``."""
        return self.initial_full_p(p)[0]

    @property
    def z0(self):
        """Initial values of the algebraic variables (dependent coordinates of loops)."""
        return self.initial_full_p(self.param_vector())[1]

    def initial_full_p(self, p):
        """(x0, z0): consistent initial states and algebraic variables (loops closed)."""
        x0, z0 = self.eq.initial(np.asarray(p, dtype=float))
        return np.asarray(x0, dtype=float), np.asarray(z0, dtype=float)

    @property
    def n_states(self):
        return len(self.state_names)

    # -- numbers --------------------------------------------------------------------------
    def rhs(self, t, x, params=None):
        """dx/dt of the ODE at (t, x), as numpy (n_states,).

        With loops (algebraic variables z), z is first solved from the closure by Newton,
        starting from the last z solved (at first the initial one).
        """
        x = self._vector(x, self.n_states, "x")
        p = self.param_vector(params)
        if not self.n_algebraic:
            return np.asarray(self.f_rhs(t, x, p)).ravel()
        if "rootfinder" not in self._compiled:
            z, xp = ca.SX.sym("z", self.n_algebraic), ca.SX.sym("xp", self.n_states + p.size)
            alg = ca.Function("alg", [z, xp], [self.f_dae(0, xp[:self.n_states], z,
                                                          xp[self.n_states:])[1]])
            self._compiled["rootfinder"] = ca.rootfinder("closure", "newton", alg,
                                                         {"abstol": 1e-13})
        if self._z_last is None:
            self._z_last = self.initial_full_p(p)[1]
        try:
            z = np.asarray(self._compiled["rootfinder"](self._z_last, np.concatenate([x, p])))
        except RuntimeError:
            raise ModelError("the loops cannot close at this state x (Newton on the "
                             "dependent coordinates failed)") from None
        self._z_last = z.ravel()
        return np.asarray(self.f_dae(t, x, z, p)[0]).ravel()

    def mass_matrix(self, q, params=None):
        """Joint-space mass matrix M(q) of the tree, numpy (n, n)."""
        if self._f_mass is None:
            a = self.asm
            self._f_mass = ca.Function("M", [a.q, a.p], [a.mass_matrix()])
        q = self._vector(q, len(self.coordinate_names), "q")
        return np.asarray(self._f_mass(q, self.param_vector(params)))

    def dynamics_terms(self, q, qd, params=None, t=0.0):
        """(M, V, G) as numpy with M qdd + V + G = 0, in the form of the seed paper.

        V holds the Coriolis and centripetal terms minus the generalized forces of the 1-D
        elements (so a shoulder spring-damper adds c*q + d*qd); G holds gravity.
        """
        f = self._terms_function()
        M, V, G = f(t, self._vector(q, len(self.coordinate_names), "q"),
                    self._vector(qd, len(self.speed_names), "qd"),
                    self.param_vector(params))
        return np.asarray(M), np.asarray(V).ravel(), np.asarray(G).ravel()

    def equations(self):
        """Symbolic M, V, G (CasADi SX) with their symbols: q, qd, p (parameters), t."""
        a = self.asm
        M, V, G = a.terms()
        return {"M": M, "V": V, "G": G, "q": a.q, "qd": a.qd, "p": a.p, "t": a.t,
                "param_names": list(a.param_names)}

    def outputs(self, t, x, params=None):
        """Probe signals at the given times and states (x: (n_points, n_states +
        n_algebraic)): differential states, then the algebraic variables of loops)."""
        return self.outputs_p(t, x, self.param_vector(params))

    def outputs_p(self, t, x, p, jit=False):
        """Probe signals for a parameter vector already checked by ``param_vector``; with
        ``jit`` computed by compiled C."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        X = np.atleast_2d(np.asarray(x, dtype=float))
        jit = jit and bool(self.signal_names)
        key = ("outputs", len(t), jit)
        if key not in self._compiled:
            if jit and "outputs" not in self._compiled:
                self._compiled["outputs"] = _jit.external(self.f_out, False, self.jit_stats)
            self._compiled[key] = (self._compiled["outputs"] if jit else self.f_out).map(len(t))
        return np.asarray(self._compiled[key](t[None, :], X.T, p)).T

    @functools.cached_property
    def damped(self):
        """Whether a generalized force depends on the speeds (dampers): only then can the
        model be stiff in the sense of ``kinetwork.solver.integrate.stiffness``."""
        return bool(ca.depends_on(self.asm.Q, self.asm.qd)) if self.n_states else False

    # -- size -----------------------------------------------------------------------------
    def size(self):
        """What the model costs: states, algebraic variables, right-hand-side operations.

        ``operations`` counts the elementary operations of one right-hand-side evaluation
        (CasADi instructions that are not inputs, outputs or constants).
        """
        f = self.f_rhs or self.f_dae
        ops = sum(1 for k in range(f.n_instructions())
                  if f.instruction_id(k) not in (ca.OP_INPUT, ca.OP_OUTPUT, ca.OP_CONST,
                                                 ca.OP_PARAMETER))
        return {"states": self.n_states, "algebraic": self.n_algebraic,
                "parameters": len(self.param_names), "operations": ops,
                "formulation": self.formulation, "loop_equations": self.eq.loop_rows,
                "redundant_equations": self.eq.loop_redundant}

    # -- compiled code ----------------------------------------------------------------------
    def rhs_function(self, jit=False, jacobian=False):
        """The right-hand side as a CasADi Function of (t, x, p): SX, or compiled C with ``jit``.

        With ``jacobian`` the compiled library also holds the exact Jacobian, if it is small
        enough (``JACOBIAN_JIT_LIMIT``); otherwise derivatives are finite differences.
        """
        if not jit:
            return self.f_rhs
        jacobian = jacobian and self._jacobian_small()
        key = ("rhs", jacobian)
        if key not in self._compiled:
            self._compiled[key] = _jit.external(self.f_rhs, jacobian, self.jit_stats)
        return self._compiled[key]

    def jacobian_numeric_function(self, jit=False):
        """d(xdot)/dx as a Function of (t, x, p) for scipy's implicit methods, compiled with
        ``jit`` when small enough."""
        if not (jit and self._jacobian_small()):
            return self.jacobian_function()
        if "jac" not in self._compiled:
            self._compiled["jac"] = _jit.external(self.jacobian_function(), False, self.jit_stats)
        return self._compiled["jac"]

    def _jacobian_small(self):
        # a Jacobian costs about (operations x states): skip building one that cannot pass
        f = self.f_rhs or self.f_dae
        if f.n_instructions() * (self.n_states + self.n_algebraic) > 20 * JACOBIAN_JIT_LIMIT:
            return False
        return self.jacobian_function().n_instructions() <= JACOBIAN_JIT_LIMIT

    def dae(self, jit=False, jacobian=False):
        """The equations as the DAE Function CasADi's integrators take (t, x, z, p, u)."""
        t, x = ca.MX.sym("t"), ca.MX.sym("x", self.n_states)
        z = ca.MX.sym("z", self.n_algebraic)
        p, empty = ca.MX.sym("p", len(self.param_names)), ca.MX(0, 1)
        if self.n_algebraic:
            f = self.f_dae
            if jit:
                jacobian = jacobian and self._jacobian_small()
                key = ("dae", jacobian)
                if key not in self._compiled:
                    self._compiled[key] = _jit.external(self.f_dae, jacobian, self.jit_stats)
                f = self._compiled[key]
            ode, alg = f(t, x, z, p)
        else:
            ode, alg = self.rhs_function(jit, jacobian)(t, x, p), empty
        return ca.Function("dae", [t, x, z, p, ca.MX.sym("u", 0)],
                           [ode, alg, empty, empty], ca.dyn_in(), ca.dyn_out())

    def integrator(self, plugin, grid, options=None, cache=True, jit=False, jacobian=True):
        """A CasADi integrator over ``grid`` (outputs at grid[1:]), cached per settings.

        ``options`` go to CasADi (``reltol``, ``abstol``, ...). With ``jit`` the right-hand
        side is compiled C (``rhs_function``); ``jacobian`` says whether the method iterates
        with Newton and so needs the exact Jacobian.
        """
        key = (plugin, grid[0], grid[-1], len(grid), jit, jacobian,
               tuple(sorted((options or {}).items())))
        if cache and key in self._integrators:
            return self._integrators[key]
        dae = self.dae(True, jacobian) if jit else \
            {"x": self._x, "z": self._z, "p": self.asm.p, "t": self.asm.t, "ode": self.ode,
             "alg": self.eq.alg}
        opts = dict(options or {})
        integ = ca.integrator("simulate", plugin, dae, float(grid[0]),
                              [float(g) for g in grid[1:]], opts)
        if cache:
            self._integrators[key] = integ
        return integ

    def jacobian_function(self):
        """d(xdot)/dx as a CasADi Function of (t, x, p), for implicit methods (with loops:
        d(xdot, alg)/d(x, z) of (t, x, z, p))."""
        if self._f_jac is None:
            a = self.asm
            if self.n_algebraic:
                v = ca.vertcat(self._x, self._z)
                self._f_jac = ca.Function("jacobian", [a.t, self._x, self._z, a.p], [
                    ca.densify(ca.jacobian(ca.vertcat(self.ode, self.eq.alg), v))])
            else:
                self._f_jac = ca.Function("jacobian", [a.t, self._x, a.p],
                                          [ca.densify(ca.jacobian(self.ode, self._x))])
        return self._f_jac

    def numeric(self, f, p):
        """A fast Python callable ``(t, x) -> ndarray`` of a Function of (t, x, p).

        Uses ``Function.buffer``: ~0.5 us a call instead of ~16 us for a plain call, which is
        what scipy's integrators pay on every right-hand-side evaluation.
        """
        buf, trigger = f.buffer()
        t_in, x_in = np.zeros(1), np.zeros(self.n_states)
        p_in = np.array(p, dtype=float)
        shape = f.size_out(0)
        out = np.zeros(shape[0] * shape[1])          # dense, column-major like CasADi
        for i, arr in enumerate((t_in, x_in, p_in)):
            buf.set_arg(i, memoryview(arr))
        buf.set_res(0, memoryview(out))

        # CasADi keeps raw pointers: the buffer and every array must outlive the trigger
        def call(t, x, _keep=(buf, p_in)):
            t_in[0] = t
            x_in[:] = x
            trigger()
            return out.reshape(shape, order="F").copy() if shape[1] > 1 else out.copy()
        return call

    def _terms_function(self):
        if self._f_terms is None:
            a = self.asm
            self._f_terms = ca.Function("terms", [a.t, a.q, a.qd, a.p], list(a.terms()))
        return self._f_terms

    @staticmethod
    def _vector(v, n, what):
        arr = np.asarray(v, dtype=float).ravel()
        if arr.shape != (n,):
            raise ModelError(f"{what}: expected {n} values, got shape {np.shape(v)}")
        return arr

    def __repr__(self):
        alg = f", {self.n_algebraic} algebraic" if self.n_algebraic else ""
        return (f"<System {self.model.name!r}: {self.n_states} states{alg}, "
                f"{len(self.signal_names)} signals>")
