"""Relations: where the equations of a System change their law, found in the equations
themselves, and the equations with each held at a value between events.

Modelica's semantics, read off the compiled expressions (so every source of them counts: an
``if_else`` in a user's expression, a Step or a KinematicPTP, the breakpoints of a Table,
CasADi's own ``pw_lin``):

- a relation ``a < b`` or ``a <= b`` (CasADi's OP_LT, OP_LE; ``a > b`` is ``b < a``) is an
  event where it changes: a *time event* when it reads time alone (its instants are known in
  advance), a *state event* when it reads the states (its instants are located as the
  integration goes);
- on time alone, the kinked and stepped operations are events too: ``fmin``, ``fmax``,
  ``fabs``, ``sign``, ``floor``, ``ceil``, ``fmod`` (a Ramp, a limited time signal, a Pulse).
  On the states these are taken literally, as Modelica's ``abs`` and ``sign`` are: a kink the
  integrator's error control follows;
- relations on parameters alone are constant over a run, and ``==``, ``!=`` hold at single
  instants of a real number: none of these is an event. Nor is anything built by ``noEvent``
  (``kinetwork.expr.literal_functions``), which uses none of the operations above.

In the equations the integrators see, each event node is replaced by a value ``r`` held
between events (``Relations.ode``, parameters ``[p; r]``): a relation by its truth, ``fmin`` and
``fmax`` by which argument they take, ``fabs`` and ``sign`` by the sign, ``floor`` and
``ceil`` by their integer, ``fmod`` by its quotient's integer part. Between events the
equations are smooth (each branch continued past its region, as in Modelica: guard a branch
that cannot be, a square root of a gap, with ``noEvent``), and an event is where a held value
is no longer the node's own (``f_select``).
"""

from dataclasses import dataclass

import casadi as ca
import numpy as np

from ..components.tables import interpolant_knots
from ..errors import ModelError

#: Jacobians larger than this (instructions) are not compiled to C: Newton iterations use
#: finite differences of the compiled right-hand side instead (an N = 128 chain's exact
#: Jacobian is 2.5 million instructions, minutes of gcc). The solver's rule
#: (``solver.compiled``), here so that a kept System can hold its Jacobian's count
JACOBIAN_JIT_LIMIT = 200_000
RELATIONS = (ca.OP_LT, ca.OP_LE)
#: events on time alone (on the states these are taken literally)
TIME_ONLY = (ca.OP_FMIN, ca.OP_FMAX, ca.OP_FABS, ca.OP_SIGN, ca.OP_FLOOR, ca.OP_CEIL,
             ca.OP_FMOD)
#: nodes whose events are where an argument crosses a whole number, not zero
LEVELS = (ca.OP_FLOOR, ca.OP_CEIL, ca.OP_FMOD)
NAMES = {ca.OP_LT: "<", ca.OP_LE: "<=", ca.OP_FMIN: "min", ca.OP_FMAX: "max",
         ca.OP_FABS: "abs", ca.OP_SIGN: "sign", ca.OP_FLOOR: "floor", ca.OP_CEIL: "ceil",
         ca.OP_FMOD: "fmod"}
# what a value depends on, as bits
_T, _X, _MODE, _Z = 1, 2, 4, 8


@dataclass
class Relations:
    """The event nodes of a System's equations and the equations with them held.

    Attributes
    ----------
    ops : list of int
        The CasADi operation of each node.
    time, state : numpy.ndarray
        Indices of the nodes on time alone, and of the relations on the states.
    affine : numpy.ndarray of bool
        Per time node: its indicator is affine in t (its instants are found in closed form).
    tables : list
        The long Tables read in time, whose knots are time events of no node (their
        interpolants', ``kinetwork.components.tables.interpolant_knots``): per table,
        (the Function (t, p) -> (its argument, that argument's time derivative), whether
        that argument is affine in t, the knots, increasing).
    reading : list
        Each node's arguments as written, and the names of what they may read (``text``).
    ode, alg : casadi.SX
        The equations in (t, x, z, [p; r]), each node held at r.
    p : casadi.SX
        The parameters of those equations: the model's, then r.
    f_select : casadi.Function
        (t, [x; z], [p; r]) -> (n,): the value each node takes there, the others held at r.
    f_state : casadi.Function
        (t, [x; z], [p; r]) -> (k, 2): each state relation's indicator g (the relation
        holds where g > 0, ``<=``: g >= 0) and its rate along the held equations.
    f_level : casadi.Function
        (t, [x; z], [p; r]) -> (k,): the indicators g alone, without the equations their
        rates read (what locating a crossing evaluates, many times).
    f_time : casadi.Function
        (t, p) -> (k, 2): each time node's indicator (a relation, min, max: zero where it
        switches; abs, sign: its argument; floor, ceil, fmod: the argument whose whole
        numbers it switches at) and its time derivative, in the equations as they are.
    """
    ops: list
    time: np.ndarray
    state: np.ndarray
    affine: np.ndarray
    tables: list
    reading: list
    ode: ca.SX
    alg: ca.SX
    p: ca.SX
    f_select: ca.Function
    f_state: ca.Function
    f_level: ca.Function
    f_time: ca.Function

    @property
    def n(self):
        return len(self.ops)

    def text(self, i):
        """Node i in words, for messages: what it compares or takes, and what it reads."""
        texts = self.__dict__.setdefault("_texts", {})
        if i not in texts:
            texts[i] = self._text(i)
        return texts[i]

    def _text(self, i):
        args, names, symbols = self.reading[i]
        reads = [n for n, s in zip(names, symbols) if any(ca.depends_on(a, s) for a in args)]
        shown = " and ".join(_short(a) for a in args)
        where = f" (reads {', '.join(reads[:4])}{', ...' if len(reads) > 4 else ''})" \
            if reads else ""
        return f"{NAMES[self.ops[i]]} of {shown}{where}"

    @property
    def f_rhs(self):
        return self._functions()[0]

    @property
    def f_dae(self):
        return self._functions()[1]

    def _functions(self):
        if not hasattr(self, "_made"):
            t, x, z = self._symbols
            self._made = (
                ca.Function("rhs_held", [t, x, self.p], [ca.densify(self.ode)],
                            ["t", "x", "p"], ["xdot"]) if not z.numel() else None,
                ca.Function("dae_held", [t, x, z, self.p],
                            [ca.densify(self.ode), ca.densify(self.alg)],
                            ["t", "x", "z", "p"], ["ode", "alg"]))
        return self._made

    def jacobian_function(self):
        """d(xdot)/dx of the held equations, as ``System.jacobian_function``."""
        if not hasattr(self, "_jac"):
            self._jac = self._jacobian()
        return self._jac

    def _jacobian(self):
        """``jacobian_function``'s Function, built (not kept)."""
        t, x, z = self._symbols
        if z.numel():
            v = ca.vertcat(x, z)
            return ca.Function("jacobian_held", [t, x, z, self.p], [ca.densify(
                ca.jacobian(ca.vertcat(self.ode, self.alg), v))])
        return ca.Function("jacobian_held", [t, x, self.p],
                           [ca.densify(ca.jacobian(self.ode, x))])

    def jacobian_instructions(self, most=JACOBIAN_JIT_LIMIT):
        """``jacobian_instructions`` of the held equations: the instructions of
        ``jacobian_function``, or None when surely more than ``most``. Counted once per
        ``most`` and kept with the Relations, so with a kept System (``stored._found_first``)
        the count is read back, not the Function (EngineV6: 18 ms to build, 23 to read)."""
        counts = self.__dict__.setdefault("_jacobian_instructions", {})
        if most not in counts:
            t, x, z = self._symbols
            f = self._made[1] if hasattr(self, "_made") else ca.Function(
                "held", [t, x, z, self.p], [self.ode, self.alg])
            counts[most] = jacobian_instructions(
                f, x.numel() + z.numel(),
                lambda: self._jac if hasattr(self, "_jac") else self._jacobian(), most)
        return counts[most]


def jacobian_instructions(f, variables, jacobian, most=JACOBIAN_JIT_LIMIT):
    """The instructions of the Jacobian ``jacobian()`` builds of the equations ``f`` in its
    ``variables``, or None when it surely has more than ``most``: when ``f``'s instructions
    times the variables exceed 20 ``most`` it is not built (a 1024-link chain's would take
    GBs). Whether the solver compiles a Jacobian (``solver.compiled``)."""
    if f.n_instructions() * variables > 20 * most:
        return None
    return jacobian().n_instructions()


def find(system):
    """The Relations of ``system``'s equations, or None when they have no event node."""
    eq, asm = system.eq, system.asm
    t, x, z, p = asm.t, eq.x, eq.z, asm.p
    ode, alg = ca.densify(eq.ode), ca.densify(eq.alg)
    f = ca.Function("equations", [t, x, z, p], [ode, alg])
    n_ins = f.n_instructions()
    ids = [f.instruction_id(k) for k in range(n_ins)]
    if not set(ids) & {*RELATIONS, *TIME_ONLY, ca.OP_CALL}:
        return None
    # one node per distinct expression: a relation the equations compute twice (a gas force
    # read in two equations) is one event, located once, not two (EngineV6: 36 relations on
    # the states become 18, and its equations half as many operations)
    both = ca.cse(ca.vertcat(ode, alg))
    ode, alg = both[:ode.numel()], both[ode.numel():]
    f = ca.Function("equations", [t, x, z, p], [ode, alg])
    n_ins = f.n_instructions()
    ids = [f.instruction_id(k) for k in range(n_ins)]
    modes = set(system.modes.mode_index) if system.modes is not None else set()
    inputs = [ca.vertsplit(v) if v.numel() else [] for v in (t, x, z, p)]

    def origin(i, nz):
        if i == 0:
            return _T
        if i == 1:
            return _MODE if nz in modes else _X
        return _Z if i == 2 else 0

    expressions = ca.vertsplit(f.instructions_sx())       # (indexing one by one: O(n) each)
    held = {}              # work slot -> its expression rebuilt with the nodes held
    flags = {}             # work slot -> what it depends on
    nodes = []             # (op, kind, rebuilt arguments, original arguments)
    r_all = []             # the held values' symbols, one per node
    tables = []            # (argument, knots) of each long Table read in time
    outputs = [list(ca.vertsplit(ode)), list(ca.vertsplit(alg))]
    for k, op in enumerate(ids):
        ins_k, outs_k = f.instruction_input(k), f.instruction_output(k)
        if op == ca.OP_CONST:
            flags[outs_k[0]] = 0
            held.pop(outs_k[0], None)
            continue
        if op == ca.OP_INPUT:
            flags[outs_k[0]] = origin(*ins_k)
            held.pop(outs_k[0], None)
            continue
        if op == ca.OP_OUTPUT:
            if ins_k[0] in held:
                outputs[outs_k[0]][outs_k[1]] = held[ins_k[0]]
            continue
        flag = 0
        for slot in ins_k:
            flag |= flags.get(slot, 0)
        if op == ca.OP_CALL:
            if flag == _T:                  # a Table read in time: its knots are events
                e = expressions[k]
                knots = interpolant_knots(e.which_function().name())
                if knots is not None:
                    tables.append((e.dep(0), knots))
            if any(slot in held for slot in ins_k):
                raise ModelError("a function of the equations (a table of more than "
                                 "Table.expression_rows rows) reads a value that changes at "
                                 "events (a relation, or a time signal with a kink): wrap "
                                 "that in noEvent(...)")
            for slot in outs_k:
                flags[slot] = flag
                held.pop(slot, None)
            continue
        kind = _kind(op, flag)
        out = outs_k[0]
        flags[out] = flag
        if kind is None and not any(slot in held for slot in ins_k):
            held.pop(out, None)             # as it is
            continue
        e = expressions[k]
        original = [e.dep(j) for j in range(len(ins_k))]
        args = [held.get(slot, original[j]) for j, slot in enumerate(ins_k)]
        if kind is not None:
            r = ca.SX.sym(f"r{len(nodes)}")
            nodes.append((op, kind, args, original))
            r_all.append(r)
            held[out] = _held(op, args, r)
        else:
            held[out] = ca.SX.binary(op, *args) if len(args) == 2 else ca.SX.unary(op, *args)
    if not nodes and not tables:
        return None
    r = ca.vertcat(*r_all) if r_all else ca.SX(0, 1)
    ode_h, alg_h = (ca.vertcat(*o) if o else ca.SX(0, 1) for o in outputs)
    pr = ca.vertcat(p, r)
    time = np.array([i for i, n in enumerate(nodes) if n[1] == "time"], dtype=int)
    state = np.array([i for i, n in enumerate(nodes) if n[1] == "state"], dtype=int)
    select = ca.vertcat(*[_select(op, args) for op, _, args, _ in nodes])
    g_state = ca.vertcat(*[_indicator(nodes[i][0], nodes[i][2]) for i in state]) \
        if len(state) else ca.SX(0, 1)
    rate = ca.jacobian(g_state, t) + ca.jtimes(g_state, x, ode_h) if len(state) else g_state
    g_time = ca.vertcat(*[_indicator(nodes[i][0], nodes[i][3]) for i in time]) \
        if len(time) else ca.SX(0, 1)
    d_time = ca.jacobian(g_time, t)
    # affine in t: no event node inside it (held, it reads none of r) and its derivative
    # constant (no curve)
    held_time = [_indicator(nodes[i][0], nodes[i][2]) for i in time]
    affine = np.array([not ca.depends_on(d_time[j], t) and not ca.depends_on(held_time[j], r)
                       for j in range(len(time))], dtype=bool)
    names = ["t"] + list(system.state_names) + list(system.algebraic_names)
    symbols = [t] + list(inputs[1]) + list(inputs[2])
    out = Relations(
        ops=[n[0] for n in nodes], time=time, state=state, affine=affine,
        tables=[(ca.Function("table_argument", [t, p], [a, ca.jacobian(a, t)]),
                 not ca.depends_on(ca.jacobian(a, t), t), np.asarray(knots, dtype=float))
                for a, knots in tables],
        reading=[(n[3], names, symbols) for n in nodes],
        ode=ode_h, alg=alg_h, p=pr,
        f_select=ca.Function("relation_values", [t, ca.vertcat(x, z), pr],
                             [ca.densify(select)]),
        f_state=ca.Function("relation_indicators", [t, ca.vertcat(x, z), pr],
                            [ca.densify(ca.horzcat(g_state, rate))]),
        f_level=ca.Function("relation_levels", [t, ca.vertcat(x, z), pr],
                            [ca.densify(g_state)]),
        f_time=ca.Function("time_indicators", [t, p],
                           [ca.densify(ca.horzcat(g_time, d_time))]))
    out._symbols = (t, x, z)
    return out


def _kind(op, flag):
    """"time", "state" or None (taken as it is) for a node of ``op`` reading ``flag``."""
    if op in RELATIONS:
        if flag & (_X | _Z):
            return "state"
        if flag & _MODE:
            return None         # changes only at the events of friction and stops
        return "time" if flag & _T else None
    if op in TIME_ONLY and flag & _T and not flag & (_X | _Z | _MODE):
        return "time"
    return None


def _held(op, args, r):
    """The node of ``op`` on ``args`` with its branch held at ``r``."""
    if op in (ca.OP_FMIN, ca.OP_FMAX):
        a, b = args
        return a + r * (b - a)
    if op == ca.OP_FABS:
        return r * args[0]
    if op == ca.OP_FMOD:
        a, b = args
        return a - r * b
    return r


def _select(op, args):
    """The value r that holds the node of ``op`` on ``args`` as it is here."""
    if op == ca.OP_FMIN:
        return args[1] < args[0]
    if op == ca.OP_FMAX:
        return args[1] > args[0]
    if op in (ca.OP_FABS, ca.OP_SIGN):
        return ca.sign(args[0])
    if op == ca.OP_FMOD:
        a, b = args
        quotient = (a - ca.fmod(a, b)) / b
        return ca.sign(quotient) * ca.floor(ca.fabs(quotient) + 0.5)
    return ca.SX.binary(op, *args) if len(args) == 2 else ca.SX.unary(op, *args)


def _indicator(op, args):
    """Zero where the node of ``op`` switches (a level: where it crosses a whole number):
    for a relation, positive where it holds."""
    if op in (ca.OP_LT, ca.OP_LE, ca.OP_FMAX):
        return args[1] - args[0]
    if op == ca.OP_FMIN:
        return args[0] - args[1]
    if op == ca.OP_FMOD:
        return args[0] / args[1]
    return args[0]


def _short(e):
    text = str(e)
    return text if len(text) <= 60 else text[:57] + "..."
