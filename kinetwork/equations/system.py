"""System: the equations of a validated model as CasADi expressions and Functions.

A System is built once per model content (``Model.compile`` keeps it) and is not changed by
running it: whatever a run compiles or caches (C code, integrators) lives in
``kinetwork.solver``. Model parameters stay symbols, so one System serves every
parameter value.
"""

from __future__ import annotations

import functools
from collections.abc import Mapping

import casadi as ca
import numpy as np

from ..errors import ModelError
from . import junctions
from . import closing
from .closing import closer
from .assemble import assemble
from .initial import InitialEquations
from .loops import BAUMGARTE_RATE, formulate, newton
from .modes import close as close_modes, free_terms
from .pointwise import mapped, pointwise
from .regularity import OVERFLOW, check_mass_matrix, overflow_message  # noqa: F401
from .relations import find as find_relations

# mapped, pointwise, OVERFLOW and overflow_message are imported from here by the solver
__all__ = ["OVERFLOW", "System", "mapped", "overflow_message", "pointwise"]


class System:
    """The equations of a validated model, compiled once; parameters stay symbolic.

    Attributes
    ----------
    state_names : list of str
        Joint coordinates, then their speeds (``"shoulder.q"``, ..., ``"shoulder.qd"``),
        then the 1-D network's, the signal blocks' and the circuits' states.
    demoted_states : dict
        States index reduction took out (a capacitor of a capacitor loop: ``"C2.v"``), each
        with why.
    x0 : numpy.ndarray
        Initial state for the model's parameter values.
    signals : list of Signal
        What the probes record: name, unit, shape of each quantity.
    """

    def __init__(self, model, loops="projected", baumgarte_rate=None, topology=None,
                 partition=None, assembly=None):
        # partition, assembly: the same model with other independent coordinates (a run
        # re-partitions a loop where its partition turns singular), on the same assembly
        self.model = model
        self._compiled_as = (loops, baumgarte_rate)      # how a pickle compiles it again
        self.topology = topology if topology is not None else model.validate()
        values = model.parameter_values()
        self.asm = asm = assembly if assembly is not None else \
            assemble(model, self.topology, values)
        self.eq = eq = formulate(asm, self.topology, values, loops,
                                 BAUMGARTE_RATE if baumgarte_rate is None else baumgarte_rate,
                                 partition)
        if asm.junctions is not None:
            junctions.extend(eq, asm, self.topology)
        #: friction and stops: their holding forces solved, their events (``modes.py``)
        self.modes = close_modes(asm, eq, model)
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
        self.signals = [sig.described() for sig in asm.signals]
        self.probe_targets = _as_wired(model, {probe.name: target.path
                                               for probe, target in self.topology.probes})
        self.f_out, self.f_dependent, self.f_assembly_checks = _readouts(asm, eq, self.modes)
        #: f_dependent: the closure's Jacobian in the dependent speeds, of the full state
        #: (None: no loop whose partition can turn singular); f_assembly_checks: what stays
        #: positive away from the singular positions of assemblies that close their loops in
        #: closed form, of the full state (None: no assembly)
        self.dependent_names = eq.dependent_names or []
        checks = asm.placed.checks if asm.placed is not None else []
        #: (assembly, what is singular) of each check
        self.assembly_check_names = [(name, what) for _, name, what in checks]
        if self.formulation in ("tree", "hybrid") and self.speed_names and \
                not self.n_algebraic:
            check_mass_matrix(self)
        elif partition is None:  # initial values that contradict the loops: refused now
            self.initial_full_p(self.param_vector())
        self._z_last = None

    @property
    def signal_names(self) -> list[str]:
        return [sig.name for sig in self.signals]

    def __reduce__(self):
        """A System pickles as the file text of its model and how it was compiled;
        unpickling compiles it again (CasADi's expressions do not pickle; the equations are
        rebuilt from the model, in the receiving process, once)."""
        from ..graph.io import dumps
        model = self.model._source or self.model        # a flat model: what it expands
        try:
            text = dumps(model)
        except ModelError as exc:
            raise TypeError(f"cannot pickle the System of {model.name!r}: its model cannot "
                            f"be written as a file, which is how a System travels ({exc})") \
                from None
        return _system_from_text, (text, *self._compiled_as)

    def _fields_of(self, name):
        """The fields of a Problem about component ``name`` of the model (none if it is no
        component of it)."""
        comp = self.model.components.get(name)
        return {} if comp is None else self.model.fields(comp)

    def polish(self, X, p, t=None):
        """Full states X (n_points, n_states + n_algebraic) with the algebraic variables
        Newton-corrected onto the closure to machine precision (``closing.polish``)."""
        return closing.polish(self, X, p, t)

    @functools.cached_property
    def _f_polish(self):
        return ca.Function("polish", [ca.vertcat(self._x, self._z), self.asm.p, self.asm.t],
                           [newton(self.eq.alg, self._z)])

    @property
    def dof(self) -> int:
        """Degrees of freedom: speeds less the independent loop-closure equations and the
        prescribed joint speeds, plus the free rotors and sliding masses of the 1-D network."""
        free = sum(1 for g in self.topology.oned if g.kind == "free")
        return len(self.speed_names) - self.eq.loop_rows - self.eq.prescribed + free

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
        return self.constraint_residual_p(X, self.param_vector(params))

    def constraint_residual_p(self, X, p):
        """``constraint_residual`` for a parameter vector already checked."""
        return closing.closure_residual(self, X, p)

    def assembly_singular(self, times, X, p, margin=0.0):
        """(row, messages): the first row of full states X at which an assembly that closes
        its loop in closed form is at (or near) a singular position (``closing``)."""
        return closing.assembly_singular(self, times, X, p, margin)

    @functools.cached_property
    def _f_residual(self):
        return ca.Function("residual", [ca.vertcat(self._x, self._z), self.asm.p],
                           [ca.norm_inf(self.eq.residual)])

    # -- parameters -----------------------------------------------------------------------
    def param_vector(self, params: Mapping[str, float] | None = None) -> np.ndarray:
        """Model parameters as the vector p, with ``params`` overrides checked."""
        missing = [k for k in self.param_names if k not in self.model.parameters]
        if missing:             # taken out of the model after it was compiled
            raise ModelError(f"model {self.model.name!r} has no parameter "
                             f"{', '.join(map(repr, missing[:5]))} any more, which its "
                             f"compiled System uses: compile the model again "
                             f"(model.compile()), or put the parameter back")
        values = self.model.parameter_values(params)
        if params:
            self.model.numeric_values(params)     # bounds of everything that depends on them
        p = np.array([values[k] for k in self.param_names], dtype=float)
        if self.initial_equations.solves_parameters():     # found from the start (initial.py)
            p = self.initial_equations.apply(p, self.eq.initial(p)[0])[1]
        return p

    @property
    def x0(self) -> np.ndarray:
        return self.initial_state()

    def initial_state(self, params: Mapping[str, float] | None = None) -> np.ndarray:
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
        x0 = self.initial_equations.apply(p, x0)[0]      # Model.initial, when it asks
        return np.asarray(x0, dtype=float), np.asarray(z0, dtype=float)

    @functools.cached_property
    def initial_equations(self):
        """The model's initial equations (``Model.initial``): a steady state, given
        derivatives, parameters solved from the start."""
        return InitialEquations(self)

    def initial_values(self, params=None):
        """What the model's initial equations solved for ``params``: {name: value} of the
        unknown states and parameters (``Model.set_initial``); empty without them."""
        from .initial import solved
        return solved(self, params)

    @property
    def n_states(self) -> int:
        return len(self.state_names)

    @property
    def demoted_states(self) -> dict[str, str]:
        """States that index reduction took out, by name, with why: a capacitor of a loop
        of capacitors, an inductor of a cut set of inductors, whose value a differentiated
        constraint fixes from the states kept (``state_names``) and the sources."""
        net = self.asm.net
        return dict(net.demoted) if net is not None else {}

    # -- numbers --------------------------------------------------------------------------
    def rhs(self, t: float, x: np.ndarray, params: Mapping[str, float] | None = None
            ) -> np.ndarray:
        """dx/dt of the ODE at (t, x), as numpy (n_states,).

        With loops (algebraic variables z), z is first solved from the closure: Newton from
        the last z solved, else followed from the assembled start on its branch
        (``closing.py``; a state where the loops cannot close is refused naming them).
        """
        x = self._vector(x, self.n_states, "x")
        p = self.param_vector(params)
        if not self.n_algebraic:
            return np.asarray(self.f_rhs(t, x, p)).ravel()
        closing = closer(self)
        z, ok = None, False
        if self._z_last is not None:
            z, _, ok = closing.newton(x, self._z_last, p)
        if not ok:
            z = closing.close(x, p, self.initial_full_p(p), where="x")
        self._z_last = np.asarray(z, dtype=float).ravel()
        return np.asarray(self.f_dae(t, x, z, p)[0]).ravel()

    @functools.cached_property
    def _f_mass(self):
        return ca.Function("M", [self.asm.q, self.asm.p], [self.asm.mass_matrix()])

    def mass_matrix(self, q: np.ndarray, params: Mapping[str, float] | None = None
                    ) -> np.ndarray:
        """Joint-space mass matrix M(q) of the tree, numpy (n, n)."""
        q = self._vector(q, len(self.coordinate_names), "q")
        return np.asarray(self._f_mass(q, self.param_vector(params)))

    def dynamics_terms(self, q: np.ndarray, qd: np.ndarray,
                       params: Mapping[str, float] | None = None, t: float = 0.0
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(M, V, G) as numpy with M qdd + V + G = 0, in the form of the seed paper.

        V holds the Coriolis and centripetal terms minus the generalized forces of the 1-D
        elements (so a shoulder spring-damper adds c*q + d*qd); G holds gravity. Friction
        there slides the way its speed goes (at rest it adds nothing: a stuck friction's
        holding force is a constraint force, not a term; ``modes.free_terms``).
        """
        f = self._f_terms
        M, V, G = f(t, self._vector(q, len(self.coordinate_names), "q"),
                    self._vector(qd, len(self.speed_names), "qd"),
                    self.param_vector(params))
        return np.asarray(M), np.asarray(V).ravel(), np.asarray(G).ravel()

    def equations(self) -> dict:
        """Symbolic M, V, G (CasADi SX) with their symbols: q, qd, p (parameters), t, and
        ``x``, the states of 1-D networks and signal blocks V depends on (a PID's
        integral), named in ``x_names``."""
        a = self.asm
        M, V, G = free_terms(a, a.terms())
        known = {ca.SX(v).name() for v in (a.q, a.u, a.p, a.t) for v in ca.vertsplit(v)}
        x = [v for v in ca.symvar(ca.veccat(M, V, G)) if v.name() not in known]
        return {"M": M, "V": V, "G": G, "q": a.q, "qd": a.u, "p": a.p, "t": a.t,
                "x": ca.vertcat(*x) if x else ca.SX(0, 1), "x_names": [v.name() for v in x],
                "param_names": list(a.param_names)}

    def outputs(self, t: np.ndarray, x: np.ndarray, params: Mapping[str, float] | None = None
                ) -> np.ndarray:
        """Probe signals at the given times and states (x: (n_points, n_states +
        n_algebraic)): differential states, then the algebraic variables of loops)."""
        return self.outputs_p(t, x, self.param_vector(params))

    def outputs_p(self, t, x, p, f_out=None):
        """Probe signals for a parameter vector already checked by ``param_vector``;
        ``f_out`` replaces the output Function (its compiled twin)."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        X = np.atleast_2d(np.asarray(x, dtype=float))
        out = np.empty((len(t), self.f_out.size1_out(0)))
        return self.outputs_into(t, X, p, out, f_out)

    def outputs_into(self, t, X, p, out, f_out=None):
        """The probe signals at times ``t`` (m,) and full states ``X`` (m, n_states +
        n_algebraic), written into ``out`` (m, values) and returned: ``pointwise``, through
        CasADi's buffer interface (a DM of 10^5 x 8 values took 0.5 s to convert)."""
        clock = self.eq.clock
        if clock is not None and len(t) and \
                np.max(np.abs(X[:, clock] - t)) > 1e-6 * (1 + np.max(np.abs(t))):
            # the state "time" starts at 0: a loop driven in time must start there too
            raise ModelError(f"{self.model.name!r}: a kinematic loop follows a prescribed "
                             f"motion in time, whose clock (the state 'time') starts at 0; "
                             f"simulate from t_start = 0")
        f = f_out or self.f_out
        if f.nnz_out(0) == 0:       # no probes: nothing to evaluate (the state grid of a
            out[...] = 0.0          # 128-link chain took 0.25 s to convert)
            return out
        if len(t):
            out[...] = pointwise(f, t[:, None], X, p)[0]
        return out

    @functools.cached_property
    def frame_sets(self):
        """The frame connection sets placed by the kinematic tree (topology indices, in
        order): the frames ``f_frames`` gives the poses of."""
        return sorted({*self.asm.place, *(self.asm.junctions.sets if self.asm.junctions
                                          else ())})

    @functools.cached_property
    def f_frames(self):
        """World poses of every set of ``frame_sets`` from the full state: a Function of
        (t, x, p) -> (12, n_sets), each column the origin (3) then the orientation R
        row-major (9). The very kinematics frame probes read (``Assembly.pose``), so an
        animation shows what the probes record."""
        a, eq = self.asm, self.eq
        columns = [ca.vertcat(pos, ca.vec(R.T)) for R, pos in map(a.pose, self.frame_sets)]
        poses = ca.horzcat(*columns) if columns else ca.SX(12, 0)
        coords = a.q if eq.q is None else eq.q
        return ca.Function("frame_poses", [a.t, ca.vertcat(eq.x, eq.z), a.p],
                           [ca.densify(ca.substitute(poses, a.q, ca.densify(coords)))])

    @functools.cached_property
    def relations(self):
        """Where the equations change their law (``relations.Relations``: time and state
        events, and the equations held between them), or None; found on first use."""
        return find_relations(self)

    @functools.cached_property
    def damped(self):
        """Whether a generalized force depends on the speeds (dampers): only then can the
        model be stiff in the sense of ``kinetwork.solver.driver.stiffness``."""
        return bool(ca.depends_on(self.asm.Q, self.asm.u)) if self.n_states else False

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

    def jacobian_function(self):
        """d(xdot)/dx as a CasADi Function of (t, x, p), for implicit methods (with loops:
        d(xdot, alg)/d(x, z) of (t, x, z, p))."""
        return self._f_jac

    @functools.cached_property
    def _f_jac(self):
        a = self.asm
        if self.n_algebraic:
            v = ca.vertcat(self._x, self._z)
            return ca.Function("jacobian", [a.t, self._x, self._z, a.p], [
                ca.densify(ca.jacobian(ca.vertcat(self.ode, self.eq.alg), v))])
        return ca.Function("jacobian", [a.t, self._x, a.p],
                           [ca.densify(ca.jacobian(self.ode, self._x))])

    @functools.cached_property
    def _f_terms(self):
        a = self.asm
        return ca.Function("terms", [a.t, a.q, a.u, a.p], list(free_terms(a, a.terms())))

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


def _readouts(asm, eq, modes):
    """The Functions that read the full state (differential, then algebraic): the probe
    signals, the closure's Jacobian in the dependent speeds and the assemblies' checks
    (None where there is nothing to read)."""
    # signals are written in the assembly's coordinates, speeds, their rates and the
    # multipliers; the formulation says what those are in the states (x, z)
    coords = asm.q if eq.q is None else eq.q
    values_in_states = ca.densify(ca.vertcat(coords, eq.u, eq.udot, eq.lam))
    kinematics = ca.vertcat(asm.q, asm.u, asm.udot, asm.lam)
    if modes is not None:      # what friction and stops hold with
        values_in_states = ca.vertcat(values_in_states, modes.F_solution)
        kinematics = ca.vertcat(kinematics, modes.F)
    outs = [ca.substitute(sig.flat(), kinematics, values_in_states) for sig in asm.signals]
    # dense: CasADi's buffer interface writes the values into a plain array
    f_out = ca.Function("outputs", [asm.t, ca.vertcat(eq.x, eq.z), asm.p],
                        [ca.densify(ca.vertcat(*outs)) if outs else ca.SX(0, 1)])
    jd = eq.dependent_jacobian
    f_dependent = None if jd is None or jd.numel() == 0 else ca.Function(
        "dependent_jacobian", [ca.vertcat(eq.x, eq.z), asm.p],
        [ca.densify(ca.substitute(jd, asm.q, ca.densify(coords)))])
    checks = asm.placed.checks if asm.placed is not None else []
    f_checks = None if not checks else ca.Function(
        "assembly_checks", [asm.t, ca.vertcat(eq.x, eq.z), asm.p],
        [ca.densify(ca.substitute(ca.vertcat(*[c for c, _, _ in checks]), asm.q,
                                  ca.densify(coords)))])
    return f_out, f_dependent, f_checks


def _system_from_text(text, loops, baumgarte_rate):
    """The System a pickle holds (``System.__reduce__``): its model read and compiled."""
    from ..graph.io import loads
    return loads(text).compile(loops=loops, baumgarte_rate=baumgarte_rate)
def _as_wired(model, targets):
    """{probe: the port it reads as the user wired it}: ``motor.p``, not the flat model's
    ``motor.Ra.p`` inside an aggregate or a subsystem (names the user never wrote);
    ``targets`` gives the flat model's, kept where the user's model does not say."""
    source = getattr(model, "_source", None)
    if source is None:
        return targets
    other_end = {}                     # a port -> the other end of its first connection
    for a, b in source.connections:
        a, b = str(getattr(a, "path", a)), str(getattr(b, "path", b))
        other_end.setdefault(a, b)
        other_end.setdefault(b, a)
    return {probe: other_end.get(f"{probe}.port", target)
            if probe in source.components else target for probe, target in targets.items()}
