"""Structural analysis of a system of equations in CasADi SX: the matching of equations to
unknowns, the Dulmage-Mendelsohn parts that name a singular system, Pantelides' index
reduction with Mattsson and Söderlind's dummy derivatives (the block-lower-triangular solve
of what is left is ``blocks.py``).

A differential-algebraic system is written as residuals in algebraic unknowns y, state
candidates x and their derivatives x' (each x' an unknown of its own, the state's rate
equation one of the residuals), and knowns: time, parameters and symbols whose time
derivatives the caller gives. It is of index 1 when the residuals can be solved for y and
x' with x known. When they cannot, a constraint among the states is hidden in them (a
capacitor across a voltage source: v_C = V(t)); Pantelides' algorithm (1988) finds, by
augmenting paths in the bipartite graph of equations and highest derivatives, the smallest
sets of equations to differentiate, CasADi's AD differentiates them, and the dummy
derivatives (Mattsson and Söderlind 1993) pick which states the differentiated equations
fix: their derivatives become algebraic unknowns ("dummies") and the states themselves are
solved from the original equations, so the system stays square, of index 1, on the
constraint manifold, and no equation is dropped. Among the states a choice is possible
for (the capacitors of a loop), ``priority`` says which to keep.

Every choice is made in index order, so the same system gives the same reduction, the same
states and the same messages in every run.
"""

from dataclasses import dataclass, field

import casadi as ca
import numpy as np

#: differentiations of one equation beyond which a system is refused (circuits need one,
#: a circuit that constrains a mechanism two)
MAX_DIFFERENTIATIONS = 3
#: a column whose part independent of the columns before it is below this fraction of its
#: norm is taken as dependent (the choice of dummy derivatives)
RANK_TOL = 1e-9


class Singular(Exception):
    """A structurally singular system: ``equations`` (indices) over-determine the unknowns
    they read and ``unknowns`` (indices) are left undetermined (the Dulmage-Mendelsohn
    parts, the same for every maximum matching)."""

    def __init__(self, equations, unknowns, reason=""):
        super().__init__(reason)
        self.equations, self.unknowns, self.reason = equations, unknowns, reason


def incidence(expressions, symbols):
    """For each expression, the sorted indices of the ``symbols`` it depends on (the
    sparsity of its Jacobian: a term that cancels is no dependence)."""
    if not expressions:
        return []
    out = [[] for _ in expressions]
    if not symbols:
        return out
    jac = ca.jacobian(ca.vertcat(*expressions), ca.vertcat(*symbols))
    for i, j in zip(*jac.sparsity().get_triplet()):
        out[i].append(j)
    return [sorted(c) for c in out]


def augment(root, candidates, owner, colored_eqs, colored_vars):
    """An augmenting path from equation ``root`` (iterative depth-first search, unknowns in
    index order): True and ``owner`` (unknown -> equation) updated, or False with what the
    search visited coloured (Pantelides' colouring)."""
    def free(e):
        return next((v for v in candidates(e) if v not in owner), None)
    colored_eqs.add(root)
    f = free(root)
    if f is not None:
        owner[f] = root
        return True
    stack, via = [(root, iter(candidates(root)))], []
    while stack:
        _, it = stack[-1]
        for v in it:
            if v in colored_vars:
                continue
            colored_vars.add(v)
            nxt = owner[v]
            colored_eqs.add(nxt)
            via.append(v)
            f = free(nxt)
            if f is not None:
                owner[f] = nxt
                for (e, _), var in zip(stack, via):
                    owner[var] = e
                return True
            stack.append((nxt, iter(candidates(nxt))))
            break
        else:
            stack.pop()
            if via:
                via.pop()
    return False


def match(inc, allowed=None):
    """A maximum matching of equations (rows of ``inc``) to unknowns: unknown -> equation."""
    owner = {}
    for k, row in enumerate(inc):
        augment(k, lambda e: [v for v in inc[e] if allowed is None or allowed(v)], owner,
                set(), set())
    return owner


def singular_parts(inc, n_unknowns, owner):
    """The over-determined equations and the under-determined unknowns of a maximum
    matching ``owner`` (Dulmage-Mendelsohn: what alternating paths reach from an unmatched
    equation, and from an unmatched unknown), both sorted."""
    matched_eq = {e: v for v, e in owner.items()}
    readers = [[] for _ in range(n_unknowns)]
    for e, row in enumerate(inc):
        for v in row:
            readers[v].append(e)
    over = _alternating([e for e in range(len(inc)) if e not in matched_eq], inc, owner)
    under = _alternating([v for v in range(n_unknowns) if v not in owner], readers, matched_eq)
    return sorted(over), sorted(under)


def _alternating(starts, neighbours, partner):
    """What alternating paths reach from ``starts``: a node, its ``neighbours`` on the other
    side, the node each of those is matched to (``partner``), and so on."""
    reached, seen, todo = set(), set(), list(starts)
    while todo:
        a = todo.pop()
        if a in reached:
            continue
        reached.add(a)
        for b in neighbours[a]:
            if b not in seen and b in partner:
                seen.add(b)
                todo.append(partner[b])
    return reached


@dataclass
class Reduced:
    """An index-1 system from ``reduce_index``: ``equations`` in ``unknowns`` (square),
    with ``states`` (indices of the candidates kept) known; ``demoted`` are the candidates
    whose values the differentiated constraints fix (now among the unknowns, their
    derivatives too); ``differentiated[k]`` how often original equation k was."""
    equations: list
    unknowns: list
    states: list
    demoted: list
    differentiated: dict = field(default_factory=dict)
    #: for each equation of ``equations``, the original equation it is (a derivative of)
    origin: list = field(default_factory=list)
    #: for each unknown of ``unknowns``, (index of y or x it is, times differentiated)
    base: list = field(default_factory=list)
    #: the original equations of each constraint found (one per failed augmenting path)
    constraints: list = field(default_factory=list)


def reduce_index(equations, algebraic, states, rates, knowns, t, priority, sample,
                 constants=()):
    """Pantelides and dummy derivatives on F(x', x, y, knowns, t) = 0.

    Parameters
    ----------
    equations : list of SX
        The residuals, as many as ``algebraic`` and ``states`` together (the rate
        equations x' - f = 0 among them).
    algebraic, states, rates : list of SX
        The unknowns y, the state candidates x and their derivatives x' (symbols).
    knowns : list of (SX, SX or None)
        Symbols the residuals read besides t and their time derivatives (symbols the caller
        resolves; None: not differentiable, a ``Singular`` when a constraint needs it).
    t : SX
        Time.
    constants : SX
        Symbols constant in time (the parameters).
    priority : list
        A sortable key per state candidate: where the constraints leave a choice, the
        candidates of larger key stay states.
    sample : callable
        ``sample(expr)``: a numeric value of a Jacobian at generic values of its symbols
        (the parameters at their values); the ranks that pick the dummies are taken there.

    Returns
    -------
    Reduced
    """
    n_y, n_x = len(algebraic), len(states)
    var = list(algebraic) + list(states) + list(rates)
    der = [None] * len(var)                 # index of the derivative variable
    integ = [None] * len(var)               # index of the variable this derives
    for i in range(n_x):
        der[n_y + i], integ[n_y + n_x + i] = n_y + n_x + i, n_y + i
    eqs = list(equations)
    eq_der, eq_integ = [None] * len(eqs), [None] * len(eqs)
    inc = incidence(eqs, var)
    _check_regular(inc, n_y, n_x, len(eqs))

    timeless = {s.element_hash() for s in ca.symvar(ca.vertcat(
        t, *var, *[k for k, _ in knowns], ca.SX(constants)))}

    def base(v):
        return _last(integ, v)

    def differentiate(e):
        expr = eqs[e]
        vs = inc[e]
        stray = [s.name() for s in ca.symvar(expr) if s.element_hash() not in timeless]
        if stray:
            raise Singular([_last(eq_integ, e)], [], f"it reads {', '.join(stray)}, whose time "
                           f"derivative is not known")
        d = ca.jacobian(expr, t)
        if vs:
            d += ca.jtimes(expr, ca.vertcat(*[var[v] for v in vs]),
                           ca.vertcat(*[var[der[v]] for v in vs]))
        for (sym, dsym) in knowns:
            if ca.depends_on(expr, sym):
                if dsym is None:
                    raise Singular([_last(eq_integ, e)], [],
                                   f"it needs the time derivative of {sym.name()}")
                d += ca.jacobian(expr, sym) * dsym
        eqs.append(ca.simplify(d))
        eq_der.append(None)
        eq_integ.append(e)
        eq_der[e] = len(eqs) - 1
        inc.append(incidence([eqs[-1]], var)[0])
        return len(eqs) - 1

    def new_derivative(v):
        var.append(ca.SX.sym(f"der_{var[v].name()}"))
        timeless.add(var[-1].element_hash())
        der.append(None)
        integ.append(v)
        der[v] = len(var) - 1
        return der[v]

    def level(e):
        n = 0
        while eq_integ[e] is not None:
            e, n = eq_integ[e], n + 1
        return n

    owner, constraints = {}, []
    for k in range(len(equations)):
        e = k
        while True:
            ceq, cvar = set(), set()
            if augment(e, lambda q: [v for v in inc[q] if der[v] is None], owner, ceq, cvar):
                break
            if level(e) >= MAX_DIFFERENTIATIONS:
                raise Singular(sorted({_last(eq_integ, q) for q in ceq}),
                               sorted({base(v) for v in cvar}),
                               f"differentiated {MAX_DIFFERENTIATIONS} times without "
                               f"finding its unknowns")
            constraints.append(sorted({_last(eq_integ, q) for q in ceq}))
            for v in sorted(cvar):
                new_derivative(v)
            for q in sorted(ceq):
                differentiate(q)
            for v in sorted(cvar):
                owner[der[v]] = eq_der[owner[v]]
            e = eq_der[e]
    try:
        dummies = _dummies(eqs, var, eq_der, eq_integ, der, integ, n_y, priority, sample)
    except Singular as exc:
        raise Singular(sorted({_last(eq_integ, q) for q in exc.equations}), [],
                       exc.reason) from None
    kept = [v for v in range(len(var)) if der[v] is not None and der[v] not in dummies]
    extra = [v for v in kept if not n_y <= v < n_y + n_x]
    if extra:
        raise Singular([], sorted({base(v) for v in extra}),
                       "its constraints leave a choice only among unknowns that are no "
                       "states (a potential or a current), which kinetwork does not take as "
                       "states")
    unknowns = [v for v in range(len(var)) if v not in kept]
    if len(unknowns) != len(eqs):
        raise Singular(sorted(set(range(len(equations)))), [],
                       "the reduced system is not square")

    def order(v):
        n = 0
        while integ[v] is not None:
            v, n = integ[v], n + 1
        return v, n
    return Reduced(eqs, [var[v] for v in unknowns], [v - n_y for v in kept],
                   [i for i in range(n_x) if der[n_y + i] in dummies],
                   {k: level(_last(eq_der, k)) for k in range(len(equations))
                    if eq_der[k] is not None},
                   [_last(eq_integ, e) for e in range(len(eqs))],
                   [order(v) for v in unknowns], constraints)


def _last(links, k):
    """Follow ``links`` (derivative or antiderivative indices) from ``k`` to its end."""
    while links[k] is not None:
        k = links[k]
    return k


def _check_regular(inc, n_y, n_x, n_eqs):
    """The system is structurally regular when its equations match its unknown functions
    (y and x, a state and its derivative being one function): otherwise no differentiation
    helps (two voltage sources in parallel) and Pantelides' algorithm would not end."""
    def function(v):
        return v if v < n_y + n_x else v - n_x
    rows = [sorted({function(v) for v in row}) for row in inc]
    owner = match(rows)
    if len(owner) < n_eqs or n_eqs != n_y + n_x:
        over, under = singular_parts(rows, n_y + n_x, owner)
        raise Singular(over, under)


def _dummies(eqs, var, eq_der, eq_integ, der, integ, n_y, priority, sample):
    """Mattsson-Söderlind: level by level from the highest derivatives, as many dummy
    derivatives as differentiated equations, chosen among the derivatives of the variables
    those equations fix so that their Jacobian is regular; derivatives of algebraic
    unknowns first, then of states of the lowest ``priority``."""
    rows = [e for e in range(len(eqs)) if eq_der[e] is None and eq_integ[e] is not None]
    cols = [v for v in range(len(var)) if der[v] is None and integ[v] is not None]
    chosen_all = set()
    while rows:
        read = set().union(*incidence([eqs[e] for e in rows], [var[v] for v in cols]))
        cols = sorted((v for k, v in enumerate(cols) if k in read),
                      key=lambda v: _rank_key(v, integ, n_y, priority))
        jac = sample(ca.jacobian(ca.vertcat(*[eqs[e] for e in rows]),
                                 ca.vertcat(*[var[v] for v in cols]))) if cols else None
        chosen = [cols[c] for c in _independent(jac, len(rows))] if cols else []
        if len(chosen) < len(rows):
            raise Singular(sorted(rows), [], "its differentiated equations are singular")
        chosen_all.update(chosen)
        rows = [eq_integ[e] for e in rows if eq_integ[eq_integ[e]] is not None]
        cols = [integ[v] for v in chosen if integ[integ[v]] is not None]
    return chosen_all


def _independent(jac, wanted):
    """Indices of the first columns of ``jac``, in order, that are linearly independent of
    those before them, up to ``wanted`` of them (Gram-Schmidt, twice for round-off)."""
    basis, out = [], []
    for c in range(jac.shape[1]):
        v = np.array(jac[:, c], dtype=float)
        norm = np.linalg.norm(v)
        if norm == 0:
            continue
        for _ in range(2):
            for q in basis:
                v -= (q @ v) * q
        if np.linalg.norm(v) > RANK_TOL * max(1.0, norm):
            basis.append(v / np.linalg.norm(v))
            out.append(c)
            if len(out) == wanted:
                break
    return out


def _rank_key(v, integ, n_y, priority):
    """Order in which derivatives are taken as dummies: those of algebraic unknowns and the
    second and higher derivatives first (a state is the variable itself, not its derivative
    introduced by a rate equation x' = u), then first derivatives of state candidates by
    ``priority``, lowest first."""
    base, order = v, 0
    while integ[base] is not None:
        base, order = integ[base], order + 1
    if base < n_y or order > 1:
        return (0, 0, base)
    return (1, priority[base - n_y], -base)
