"""Linearisation: the state-space model dx = A dx + B du, dy = C dx + D du of a model at an
operating point, exact by CasADi's algorithmic differentiation.

With kinematic loops the states are the independent coordinates and speeds: the dependent
coordinates z follow from the closure g(x, z) = 0, so dz = -g_z^-1 (g_x dx + g_u du) enters
A, B, C and D (the implicit function theorem, at the closed operating point).
"""

import weakref

import casadi as ca
import numpy as np

from ..equations.modes import operating_modes
from ..errors import ModelError
from ..solver.plan import lifted_model
from .channels import output_channels, output_expression, plant

#: System -> {(input positions, output rows): the Jacobians' Function}
_JACOBIANS = weakref.WeakKeyDictionary()


class Linearization:
    """A linear state-space model with named, unit-carrying states, inputs and outputs.

    Attributes
    ----------
    A, B, C, D : numpy.ndarray
        dx/dt = A x + B u, y = C x + D u, in deviations from the operating point.
    state_names, input_names, output_names : list of str
    state_units, input_units, output_units : list of str
    t : float
        Time of the operating point [s].
    x, u, y : numpy.ndarray
        Operating state (differential states), inputs and outputs.
    """

    def __init__(self, A, B, C, D, states, inputs, outputs, t, x, u, y, plant=None):
        self.A, self.B, self.C, self.D = A, B, C, D
        self.state_names, self.state_units = states
        self.input_names, self.input_units = inputs
        self.output_names, self.output_units = outputs
        self.t, self.x, self.u, self.y = t, x, u, y
        self.plant = plant

    @property
    def eigenvalues(self):
        return np.linalg.eigvals(self.A)

    def frequency_response(self, omega):
        """H(j omega) = C (j omega I - A)^-1 B + D, complex (n_outputs, n_inputs, n_omega)."""
        omega = np.atleast_1d(np.asarray(omega, dtype=float))
        n = self.A.shape[0]
        out = np.empty((self.C.shape[0], self.B.shape[1], len(omega)), dtype=complex)
        for k, w in enumerate(omega):
            out[:, :, k] = self.C @ np.linalg.solve(1j * w * np.eye(n) - self.A, self.B) \
                + self.D if n else self.D
        return out

    def to_control(self):
        """The same model as a ``control.StateSpace`` (python-control). Names keep their
        order with "." written "_" ("motor.u" -> "motor_u"): python-control keeps the dot
        for its own paths (``sys.signal`` in ``interconnect``)."""
        try:
            import control
        except ImportError:
            raise ModelError("to_control needs python-control: pip install "
                             "'kinetwork[analysis]' (or pip install control)") from None
        return control.ss(self.A, self.B, self.C, self.D, states=_undotted(self.state_names),
                          inputs=_undotted(self.input_names),
                          outputs=_undotted(self.output_names))

    def text(self, digits=6):
        """A, B, C and D as labelled tables, the way ``kinetwork linearize`` prints them."""
        def table(title, M, rows, cols):
            if M.size == 0:
                return f"{title}: empty ({M.shape[0]} x {M.shape[1]})"
            width = max(digits + 8, *(len(c) for c in cols))
            head = " " * (max(map(len, rows)) + 2) + "".join(f"{c:>{width}}" for c in cols)
            lines = [f"{title}:", head]
            lines += [f"{r:<{max(map(len, rows)) + 2}}" +
                      "".join(f"{v:>{width}.{digits}g}" for v in row) for r, row in zip(rows, M)]
            return "\n".join(lines)
        s = [f"{n} [{u}]" if u else n for n, u in zip(self.state_names, self.state_units)]
        i = [f"{n} [{u}]" if u else n for n, u in zip(self.input_names, self.input_units)]
        o = [f"{n} [{u}]" if u else n for n, u in zip(self.output_names, self.output_units)]
        return "\n\n".join([table("A", self.A, s, self.state_names),
                            table("B", self.B, s, i),
                            table("C", self.C, o, self.state_names),
                            table("D", self.D, o, i)])

    def __repr__(self):
        return (f"<Linearization at t = {self.t:g} s: {self.A.shape[0]} states, "
                f"{self.B.shape[1]} inputs, {self.C.shape[0]} outputs>")


def linearize(model, at=None, inputs=(), outputs=None, params=None):
    """Linearise ``model`` at an operating point, exactly (CasADi's derivatives).

    Parameters
    ----------
    model : Model or System
    at : None, float, array, dict or Equilibrium
        The operating point: None, the initial state; a time [s], the state a simulation
        (the model's settings) reaches then; a state vector or {state name: value} (the other
        states initial); an Equilibrium from ``kn.equilibrium`` (its inputs too).
    inputs : list of str
        Open signal inputs (``"motor.u"``: a Torque's or Force's u, a force's f1) or
        ``signals.Input`` blocks by name; at their operating values (what they replace).
    outputs : list of str, optional
        Probe quantities (``"probe1.angle"``, ``"probe.position[1]"``; a vector's name for
        all its entries) or state names; default: every probe quantity.
    params : dict, optional
        Parameter values: model parameters, or component parameters by path
        (``"spring.c"``, lifted to model parameters once, see ``kn.simulate``); numbers, or
        numbers with a unit.

    Returns
    -------
    Linearization
        A, B, C, D with named states, inputs and outputs and their units.
    """
    # at an Equilibrium: its inputs, and the parameters it solved for
    params = {**(params or {}), **(getattr(at, "params", None) or {})}
    model, aliases = lifted_model(model, list(params))
    params = {aliases.get(k, k): v for k, v in params.items()}
    pl = plant(model, inputs)
    s = pl.system
    input_values = getattr(at, "inputs", None) or {}
    p = pl.param_vector(params, {k: v for k, v in input_values.items() if k in pl.inputs},
                        t=_time_of(at))
    t, X = pl.operating_state(at, p)
    if t != _time_of(at):
        p = pl.param_vector(params, t=t)
    X = operating_modes(s, t, X, p)         # friction and stops: in the modes there
    names, units, rows = output_channels(s, outputs)
    A, B, C, D, y = _matrices(s, tuple(pl.input_index), tuple(rows), t, X, p)
    if s.modes is not None:                 # a mode stays what it is under a perturbation
        A, C = A.copy(), C.copy()
        A[:, s.modes.mode_index] = 0.0
        C[:, s.modes.mode_index] = 0.0
    return Linearization(A, B, C, D, (list(s.state_names), list(s.state_units)),
                         (list(pl.inputs), list(pl.input_units)), (names, units), t,
                         X[:s.n_states], np.array([p[k] for k in pl.input_index]), y, pl)


def _undotted(names):
    """Names without dots for python-control; its own numbering where that would merge
    two (None)."""
    out = [n.replace(".", "_") for n in names]
    return out if len(set(out)) == len(out) else len(out)


def _time_of(at):
    if isinstance(at, (int, float)) and not isinstance(at, bool):
        return float(at)
    return float(getattr(at, "t", 0.0))


def _matrices(system, index, rows, t, X, p):
    """A, B, C, D and the outputs y at (t, X, p), eliminating the algebraic variables."""
    f = jacobians(system, index, rows)
    Fx, Fz, Fu, Gx, Gz, Gu, Yx, Yz, Yu, y = (np.asarray(v, dtype=float).reshape(v.shape)
                                            for v in f(t, X, p))
    if system.n_algebraic:
        try:
            # z = z(x, u) on the closure: dz = -Gz^-1 (Gx dx + Gu du)
            Zx, Zu = np.linalg.solve(Gz, -Gx), np.linalg.solve(Gz, -Gu)
        except np.linalg.LinAlgError:
            raise ModelError("the loops are singular at the operating point (their closure "
                             "does not determine the dependent coordinates): linearise at "
                             "another state") from None
        Fx, Fu = Fx + Fz @ Zx, Fu + Fz @ Zu
        Yx, Yu = Yx + Yz @ Zx, Yu + Yz @ Zu
    for name, M in (("A", Fx), ("B", Fu), ("C", Yx), ("D", Yu)):
        if not np.all(np.isfinite(M)):
            raise ModelError(f"{name} is not finite at the operating point (a division by "
                             f"zero or an overflow there): linearise at another state")
    return Fx, Fu, Yx, Yu, y.ravel()


def jacobians(system, index, rows):
    """The Function (t, X, p) -> the derivatives of the rates F, the closure G and the
    outputs Y with respect to x, z and the inputs u = p[index], and Y itself."""
    cache = _JACOBIANS.setdefault(system, {})
    key = (index, rows)
    if key not in cache:
        cache[key] = _build(system, list(index), list(rows))
    return cache[key]


def _build(system, index, rows):
    eq, a = system.eq, system.asm
    x, z, p, t = eq.x, eq.z, a.p, a.t
    X = ca.vertcat(x, z)
    u = ca.vertcat(*[p[k] for k in index]) if index else ca.SX(0, 1)
    y = output_expression(system, rows, t, X, p)
    out = []
    for e in (eq.ode, eq.alg, y):
        out += [ca.densify(ca.jacobian(e, v)) for v in (x, z, u)]
    return ca.Function("linearization", [t, X, p], out + [ca.densify(y)])
