"""Elements with modes (friction with stiction, elastic gaps, hard stops): what they hold with,
and the functions their events read.

Each such element (``components/friction.py``) puts a force F_i into the network besides its
law, and a mode state. Once the formulation has the speeds' rates in the states, the
relative acceleration of each element is affine in the forces F, so the conditions

    held_i * a_rel_i + (1 - held_i) * F_i = 0

(a held element keeps its flanges together, any other holds with nothing) are one small
linear system in F, solved symbolically: one compiled system serves every combination of
modes, and a stuck friction is exactly stuck. The driver (``solver/events.py``) reads
the indicators and numbers of ``f_values`` and applies impulses with ``f_response``.
"""

from dataclasses import dataclass

import casadi as ca
import numpy as np

from ..errors import ModelError

#: columns of ``Modes.f_values``: the indicator, the relative position and speed, the holding
#: force, the element's two numbers (a static limit, a restitution), and the relative
#: acceleration (which way an element at rest starts to slide: ``solver/events.py``),
#: and the indicator's rate along the motion (an indicator that dips to zero and back between
#: two sampled points has a minimum there: ``solver/events.py`` looks for it)
COLUMNS = ("indicator", "rel", "w_rel", "force", "value0", "value1", "a_rel", "rate")


@dataclass
class Modes:
    """The elements with modes of a System, and their compiled functions."""
    comps: list                 # the model's components, in order
    mode_index: list            # index of each one's mode in the state vector
    F: ca.SX                    # the symbols of their holding forces ...
    F_solution: ca.SX           # ... and what they are, in (t, x, p)
    f_values: ca.Function       # (t, x, p) -> (k, len(COLUMNS))
    f_response: ca.Function     # (t, x, p) -> (d a_rel / d F (k, k), d xdot / d F (n, k))


def close(asm, eq, model):
    """Solve the holding forces of ``asm``'s elements with modes into ``eq`` (changed in
    place) and return their Modes, or None when the model has none."""
    net = asm.net
    if net is None or not net.hybrid:
        return None
    names = [h.comp.name for h in net.hybrid]
    if eq.z.numel():
        raise ModelError(f"{', '.join(names)}: friction and stops are handled by events, which "
                         f"need the equations as ODEs; this model has algebraic variables "
                         f"({', '.join(eq.algebraic_names)}): compile it with "
                         f"loops='projected' (the default)", component=names[0])
    q = asm.q if eq.q is None else eq.q
    lam = eq.lam if eq.lam is not None else ca.SX(0, 1)

    def in_states(e):
        return ca.substitute(ca.SX(e), ca.vertcat(asm.q, asm.u, asm.udot, asm.lam),
                             ca.densify(ca.vertcat(q, eq.u, eq.udot, lam)))

    def at(d, ref):
        return ca.SX(0) if ref is None else ca.SX(d.get(ref, 0))

    F = ca.vertcat(*[h.F for h in net.hybrid])
    rel = [at(net.pos, h.b) - at(net.pos, h.a) for h in net.hybrid]
    w_rel = [at(net.vel, h.b) - at(net.vel, h.a) for h in net.hybrid]
    a_rel = in_states(ca.vertcat(*[at(net.acc, h.b) - at(net.acc, h.a) for h in net.hybrid]))
    held = ca.vertcat(*[ca.SX(h.bound.held(h.mode)) for h in net.hybrid])
    residual = held * a_rel + (1 - held) * F
    A = ca.jacobian(residual, F)
    if ca.depends_on(A, F):
        raise ModelError(f"{', '.join(names)}: the relative accelerations are not linear in "
                         f"the friction and stop forces")
    b = ca.substitute(residual, F, ca.SX.zeros(F.shape[0]))
    solution = -b / A if F.shape[0] == 1 else -ca.solve(A, b)

    rows = []
    for i, h in enumerate(net.hybrid):
        u = net.signal.get(h.u) if h.u is not None else None
        values = tuple(ca.SX(v) for v in h.bound.values(asm.t, u))
        power = at(net.flow, h.a) * at(net.vel, h.a)      # into the element at flange a
        g = h.bound.indicator(h.mode, rel[i], w_rel[i], F[i], values, power)
        rows.append(ca.horzcat(g, rel[i], w_rel[i], F[i], *values))
    table = ca.substitute(ca.horzcat(in_states(ca.vertcat(*rows)), a_rel), F, solution)
    zero = ca.SX.zeros(F.shape[0])
    response = [ca.substitute(ca.jacobian(a_rel, F), F, zero),
                ca.substitute(ca.jacobian(eq.ode, F), F, zero)]

    for key in ("ode", "alg", "udot", "lam", "u"):
        value = getattr(eq, key)
        if value is not None:
            setattr(eq, key, ca.substitute(value, F, solution))
    g = table[:, 0]
    rate = ca.jtimes(g, eq.x, ca.densify(eq.ode)) + ca.jacobian(g, asm.t)
    table = ca.horzcat(table, rate)
    args = [asm.t, eq.x, asm.p]
    return Modes([h.comp for h in net.hybrid],
                 [eq.state_names.index(f"{n}.mode") for n in names], F, solution,
                 ca.Function("mode_values", args, [ca.densify(table)]),
                 ca.Function("mode_response", args, [ca.densify(r) for r in response]))


def free_terms(asm, exprs):
    """``exprs`` (the seed's M, V, G of ``asm``) with every element with modes in the law
    that the state itself gives: no holding force (a stuck friction's, a resting stop's is a
    constraint force, not a term), a friction sliding the way its relative speed goes (the
    sign of it: at rest it adds nothing), an elastic gap in contact while closed, a stop free.
    A gear with losses, whose mode is which flange drives, has no such law: refused."""
    net = asm.net
    if net is None or not net.hybrid:
        return exprs

    def at(d, ref):
        return ca.SX(0) if ref is None else ca.SX(d.get(ref, 0))

    modes = []
    for h in net.hybrid:
        free = getattr(h.bound, "free_mode", None)
        if free is None:
            raise ModelError(f"{h.comp.name}: its mode (which flange drives) is not a function "
                             f"of the state, so M, V, G cannot show it: give it eta = 1 to see "
                             f"the equations", component=h.comp.name)
        modes.append(free(at(net.pos, h.b) - at(net.pos, h.a),
                          at(net.vel, h.b) - at(net.vel, h.a)))
    symbols = ca.vertcat(*[h.mode for h in net.hybrid], *[h.F for h in net.hybrid])
    values = ca.vertcat(*modes, ca.SX.zeros(len(net.hybrid)))
    return tuple(ca.substitute(ca.SX(e), symbols, values) for e in exprs)


#: relative speeds below this count as at rest at an operating point (an equilibrium's speeds
#: are zero to its tolerance)
AT_REST = 1e-8


def operating_modes(system, t, X, p, check=True):
    """The full state ``X`` (numpy) with the modes that its numbers give, for analyses at one
    point (``kn.linearize``, ``kn.equilibrium``): a friction slides the way its relative speed
    goes, or at rest is stuck, and with ``check`` its holding force must be within its static
    limit (else a ModelError naming it: no smooth model holds there); an elastic gap is in
    contact while closed. Stops and gears keep the modes ``X`` gives."""
    modes = system.modes
    if modes is None:
        return X
    X = np.array(X, dtype=float)
    n = system.n_states
    x = X[:n]
    table = np.asarray(modes.f_values(t, x, p)).reshape(len(modes.comps), -1)
    for i, comp in enumerate(modes.comps):
        k = modes.mode_index[i]
        if getattr(type(comp), "disengaged", None) and comp.disengaged(table[i, 4:6]):
            x[k] = comp.FREE                 # a clutch or brake with no normal force
        elif getattr(type(comp), "at_rest_modes", None):
            w = table[i, 2]
            x[k] = 0 if abs(w) <= AT_REST else np.sign(w)
        elif getattr(type(comp), "state_mode", False) and table[i, 0] < 0:
            x[k] = 1 - x[k]                 # a gap closed and open by its numbers alone
    if check:
        table = np.asarray(modes.f_values(t, x, p)).reshape(len(modes.comps), -1)
        for i, comp in enumerate(modes.comps):
            if getattr(type(comp), "at_rest_modes", None) and x[modes.mode_index[i]] == 0 \
                    and table[i, 0] < 0:
                raise ModelError(f"{comp.name}: at rest there, it would have to hold "
                                 f"{abs(table[i, 3]):.6g} beyond its static limit "
                                 f"{table[i, 4]:.6g}, so it slides, and friction is not smooth "
                                 f"at zero speed: take a point where it holds or slides",
                                 component=comp.name)
    X[:n] = x
    return X
