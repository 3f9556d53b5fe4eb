"""Massless junctions: frames that only line forces meet at, placed by their balance.

Where springs and dampers are connected in series with no body between them (MSL's
``Examples.Elementary.ThreeSprings``), the point they share carries no mass, so the forces on
it balance at every instant. Its position r_J (3 per junction) is then no state of the
mechanism but an algebraic variable fixed by that balance, sum of the line forces f_e e_e = 0,
with e_e the unit vector of each line and f_e its tension from the element's own ``law``.

A damper in series makes the junction first-order: the balance holds the damper's rate of
extension, not its length. Each line force with damping that ends at a junction therefore has
its length s_e as a state, with d(s_e)/dt = sd_e, and its rate sd_e as an algebraic variable;
the equation |r_b - r_a| - s_e = 0 ties the length to the junction's position. Its tension is
law(|r_b - r_a|, sd_e). A spring and a damper in series along one line is Maxwell's element:
c (s_1 - l) = d sd_2 at the junction.

So the residual R(y; q, s) = 0, y the junctions' positions and the dampers' rates, holds the
coordinates q and the damper lengths s only, never the speeds: y is a function of (q, s) and
its rate, which probes of the junction read, follows by the implicit-function theorem,
dy/dt = -R_y^-1 (R_q dq/dt + R_s sd). The generalized forces on the tree are J^T f of the
line forces' ends on tree frames, in (q, u, y): the model is a semi-explicit index-1 DAE that
IDAS integrates, as the dependent coordinates of loops and the nonlinear algebraic loops of
signals already are (Newton on y from its previous value at every step, and a Newton polish
of the outputs). That is why junctions are algebraic variables rather than an inner Newton in
every right-hand side: the driver and the formulations already carry algebraic variables,
start them consistently and polish them; nothing new is integrated. A probe on a junction
reads its position, velocity and acceleration (the rates through the implicit-function
theorem) and the forces there; its orientation is the world's, as line forces need none.

The start: each damper extends at the rate its two ends give it were the junctions at rest
(so a model that starts at rest starts with its dampers unloaded), and the junctions sit
where the forces then balance (a least-squares Newton from the mean of the frames around
them); each damper's length starts at its distance there. A series chain that starts at rest
and unloaded has no tension to hold its junction across the line (its balance is singular
there): start it stretched, or moving.
"""

from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from ..errors import ModelError
from ..spatial import line_length

#: a junction balance below this (N) at the start counts as balanced
BALANCED = 1e-9
#: the balance's Jacobian is singular at the start when its smallest singular value is below
#: this fraction of its largest (a junction no tension holds across its lines)
SINGULAR = 1e-10


@dataclass
class Line:
    """A line force with an end at a junction."""
    name: str
    sets: dict                  # port -> frame set
    force: dict                 # port -> force it applies there (world), in (q, y, s)
    length: ca.SX = None        # its length state (damped lines only)
    rate: ca.SX = None          # its rate of extension, an algebraic variable (damped only)
    distance: ca.SX = None      # |r_b - r_a| in (q, y)
    start_rate: ca.SX = None    # its rate of extension were the junctions at rest, (q, u, y)


@dataclass
class Junctions:
    """The massless junctions of a model and the line forces that meet at them."""
    sets: list                                  # junction frame sets
    names: list                                 # per junction: the name of its first port
    position: dict                              # set -> SX (3,) symbol
    lines: dict                                 # element name -> Line
    y: ca.SX = None                             # algebraic: positions, then damper rates
    s: ca.SX = None                             # states: lengths of the damped lines
    sd: ca.SX = None                            # their rates (part of y)
    residual: ca.SX = None                      # R(y; q, s)
    balance: ca.SX = None                       # the junctions' balances alone
    Q: ca.SX = None                             # generalized forces on the tree
    _ydot: ca.SX = field(default=None, repr=False)

    @property
    def elements(self):
        return set(self.lines)

    def ydot(self, q, qdot):
        """dy/dt by the implicit-function theorem (no accelerations in it)."""
        if self._ydot is None:
            R = self.residual
            rhs = ca.jtimes(R, q, qdot) + ca.jtimes(R, self.s, self.sd) if self.s.numel() \
                else ca.jtimes(R, q, qdot)
            self._ydot = -ca.solve(ca.jacobian(R, self.y), rhs)
        return self._ydot


def build(asm, topo, bound):
    """The Junctions of an assembled model (None without any): symbols, the forces of the
    line forces that end at junctions, their balance and their generalized forces."""
    if not topo.junctions:
        return None
    names = [next(p.path for p in topo.sets[s] if p.component.role != "probe")
             for s in topo.junctions]
    position = {s: ca.SX.sym(f"{name}.r", 3) for s, name in zip(topo.junctions, names)}
    J = Junctions(list(topo.junctions), names, position, {})
    balance = {s: ca.SX.zeros(3) for s in topo.junctions}
    lengths, rates, ties = [], [], []
    S, SD = ca.SX.sym("s"), ca.SX.sym("sd")
    Q = ca.SX.zeros(asm.u.shape[0])
    for comp in topo.forces:
        sets = {pn: topo.set_of[comp.port_ref(pn)] for pn, port in comp.ports.items()
                if port.domain == "frame"}
        if not any(s in position for s in sets.values()):
            continue
        law = bound[comp.name].law
        ends = {pn: position[s] if s in position else asm.pose(s)[1] for pn, s in sets.items()}
        d = ends["frame_b"] - ends["frame_a"]
        dist = line_length(d)
        line = Line(comp.name, sets, {}, distance=dist)
        moving = {pn: ca.SX.zeros(3) if s in position else asm.rate(ends[pn], False)
                  for pn, s in sets.items()}
        line.start_rate = ca.dot(d, moving["frame_b"] - moving["frame_a"]) / dist
        if ca.depends_on(ca.SX(law(S, SD)), SD):
            line.length, line.rate = ca.SX.sym(f"{comp.name}.s"), ca.SX.sym(f"{comp.name}.sd")
            lengths.append(line.length)
            rates.append(line.rate)
            ties.append(dist - line.length)
            tension = law(dist, line.rate)
        else:
            tension = law(dist, ca.SX(0))
        force = tension * d / dist
        line.force = {"frame_a": force, "frame_b": -force}
        for pn, s in sets.items():
            if s in position:
                balance[s] += line.force[pn]
            elif asm.u.shape[0]:
                Q += ca.jtimes(asm.rate(ends[pn], False), asm.u, line.force[pn], True)
        J.lines[comp.name] = line
    J.s = ca.vertcat(*lengths) if lengths else ca.SX(0, 1)
    J.sd = ca.vertcat(*rates) if rates else ca.SX(0, 1)
    J.y = ca.vertcat(*[position[s] for s in J.sets], J.sd)
    J.balance = ca.vertcat(*[balance[s] for s in J.sets])
    J.residual = ca.vertcat(J.balance, *ties)
    J.Q = Q
    return J


def extend(eq, asm, topo):
    """Add the junctions to the Equations of the formulation: the damper lengths to the
    states (their rates are algebraic), the positions and rates to the algebraic variables,
    the balance and the length ties to the algebraic equations; and start them."""
    J = asm.junctions
    q = asm.q if eq.q is None else eq.q
    lam = eq.lam if eq.lam is not None else ca.SX(0, 1)

    def in_states(e):
        return ca.substitute(e, ca.vertcat(asm.q, asm.u, asm.udot, asm.lam),
                             ca.densify(ca.vertcat(q, eq.u, eq.udot, lam)))
    x_before, z_before = eq.x, eq.z
    eq.x, eq.ode = ca.vertcat(eq.x, J.s), ca.vertcat(eq.ode, J.sd)
    eq.z, eq.alg = ca.vertcat(eq.z, J.y), ca.vertcat(eq.alg, in_states(J.residual))
    lines = [line for line in J.lines.values() if line.length is not None]
    eq.state_names = eq.state_names + [f"{line.name}.s" for line in lines]
    eq.state_units = eq.state_units + ["m"] * len(lines)
    eq.algebraic_names = eq.algebraic_names + [f"{n}.r[{i}]" for n in J.names
                                               for i in range(3)] + \
        [f"{line.name}.sd" for line in lines]
    eq.algebraic_units = eq.algebraic_units + ["m"] * (3 * len(J.sets)) + ["m/s"] * len(lines)
    damped = f"; the lengths of {', '.join(line.name for line in lines)} (damped, in series) " \
             f"are states" if lines else ""
    eq.note = ((eq.note + "; ") if eq.note else "") + (
        f"{len(J.sets)} massless junction(s) ({', '.join(J.names)}) placed by the balance of "
        f"their line forces: their positions are algebraic variables{damped}")
    mechanism = eq.initial
    known = ca.vertcat(x_before, z_before, asm.p)
    k = 3 * len(J.sets)
    pos = J.y[:k]
    # the start: each damper extends at the rate its ends give it with the junctions at
    # rest (unloaded when everything starts at rest), and the junctions balance
    start_rates = ca.vertcat(*[line.start_rate for line in lines])
    unloaded = in_states(ca.substitute(J.balance, J.sd, start_rates))
    f_balance = ca.Function("junction_start", [pos, known],
                            [unloaded, ca.jacobian(unloaded, pos)])
    ends = ca.vertcat(*[asm.pose(s)[1] for s in sorted({
        s for line in J.lines.values() for s in line.sets.values() if s not in J.position})])
    f_ends = ca.Function("junction_ends", [known], [in_states(ends)])
    f_lengths = ca.Function("junction_lengths", [pos, known],
                            [in_states(ca.vertcat(*[line.distance for line in lines])),
                             in_states(start_rates)])

    f_regular = ca.Function("junction_jacobian", [J.y, ca.vertcat(eq.x, z_before, asm.p)],
                            [ca.jacobian(in_states(J.residual), J.y)])

    def initial(p):
        x0, z0 = mechanism(p)
        kn = np.concatenate([x0, z0, p])
        guess = _guess(J, np.asarray(f_ends(kn), dtype=float).ravel(), topo)

        def fun(v):
            return np.asarray(f_balance(v, kn)[0], dtype=float).ravel()

        def jac(v):
            return np.asarray(f_balance(v, kn)[1], dtype=float)
        import scipy.optimize                # only models with junctions pay for it
        sol = scipy.optimize.least_squares(fun, guess, jac=jac, method="lm", xtol=1e-15,
                                           ftol=1e-15, gtol=1e-15)
        if not np.all(np.isfinite(sol.x)) or np.max(np.abs(fun(sol.x)), initial=0) > BALANCED:
            raise ModelError(f"massless junction(s) {', '.join(J.names)}: the line forces on "
                             f"them do not balance anywhere at the initial state (residual "
                             f"{np.max(np.abs(fun(sol.x))):.3g} N)")
        s0, sd0 = (np.asarray(v, dtype=float).ravel() for v in f_lengths(sol.x, kn))
        y0 = np.concatenate([sol.x, sd0])
        jac = np.asarray(f_regular(y0, np.concatenate([x0, s0, z0, p])), dtype=float)
        sv = np.linalg.svd(jac, compute_uv=False)
        if not sv.size or sv[-1] <= SINGULAR * max(sv[0], 1.0):
            raise ModelError(f"massless junction(s) {', '.join(J.names)}: the line forces on "
                             f"them carry no tension at the start, so nothing holds a junction "
                             f"across its lines (the balance is singular there); start them "
                             f"stretched or moving, or put a body at the junction")
        return np.concatenate([x0, s0]), np.concatenate([z0, y0])
    eq.initial = initial
    return eq


def _guess(J, ends, topo):
    """Start of the junctions' positions: each at the mean of the frames its line forces
    reach (junctions averaged with one another until they settle)."""
    placed = sorted({s for line in J.lines.values() for s in line.sets.values()
                     if s not in J.position})
    at = {s: ends[3 * i:3 * i + 3] for i, s in enumerate(placed)}
    mean = np.mean(list(at.values()), axis=0) if at else np.zeros(3)
    guess = {s: mean.copy() for s in J.sets}
    neighbours = {s: [] for s in J.sets}
    for line in J.lines.values():
        a, b = line.sets["frame_a"], line.sets["frame_b"]
        for x, y in ((a, b), (b, a)):
            if x in neighbours:
                neighbours[x].append(y)
    for _ in range(50):
        guess = {s: np.mean([guess[n] if n in guess else at[n] for n in neighbours[s]], axis=0)
                 for s in J.sets}
    return np.concatenate([guess[s] for s in J.sets])
