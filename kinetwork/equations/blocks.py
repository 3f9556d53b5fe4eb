"""The block-lower-triangular solve of a square system of equations in CasADi SX, as a
Modelica tool's back end does it: the strongly connected components of the matched
dependency graph (Tarjan), in topological order, each solved in turn; a linear block
symbolically (a large one by sparse elimination, whose expressions grow with the fill, not
with the cube of its size), a nonlinear one torn, its tearing unknowns left to the
integrator as algebraic variables.
"""

from dataclasses import dataclass

import casadi as ca
import networkx as nx

from .structure import Singular, incidence, match, singular_parts


@dataclass
class Solved:
    """The block-lower-triangular solve of a square system: ``values[j]``, unknown j in the
    knowns (and in ``kept``); ``kept`` and ``residuals``, the unknowns and equations of
    nonlinear blocks left to the integrator as algebraic variables (what tearing leaves of
    each block); ``sizes`` the blocks' sizes, largest first."""
    values: list
    kept: list
    residuals: list
    sizes: list
    nonlinear: int = 0


def solve_blocks(equations, unknowns, regular, sample=None):
    """Solve ``equations`` for ``unknowns`` block by block (Tarjan's strongly connected
    components of the matched dependency graph, in topological order): a linear block
    symbolically, a nonlinear block torn (the unknowns it reads nonlinearly stay unknowns,
    the rest are solved from them).

    ``regular(matrix)`` says whether a block's matrix is regular at the parameters' values;
    a block where it is not, or a system that is not structurally regular, raises
    ``Singular`` naming the equations. ``sample(matrix)``, numbers of a matrix at generic
    values of its symbols, lets a large linear block be solved by sparse elimination (its
    pivots chosen on those numbers) rather than by a dense symbolic factorisation, whose
    expressions grow as the cube of the block.
    """
    n = len(unknowns)
    inc = incidence(equations, unknowns)
    owner = match(inc)
    if len(owner) < n or len(equations) != n:
        raise Singular(*singular_parts(inc, n, owner))
    assigned = {e: v for v, e in owner.items()}
    dep = nx.DiGraph()
    dep.add_nodes_from(range(n))
    for e, row in enumerate(inc):
        for v in row:
            if assigned[e] != v:
                dep.add_edge(owner[v], e)        # equation e needs what owner[v] gives
    dag = nx.condensation(dep)
    out = Solved([None] * n, [], [], sorted((len(dag.nodes[c]["members"]) for c in dag),
                                            reverse=True))
    for c in nx.lexicographical_topological_sort(dag, key=lambda c: min(
            dag.nodes[c]["members"])):
        block = sorted(dag.nodes[c]["members"])
        zs = [assigned[e] for e in block]
        res = ca.vertcat(*[equations[e] for e in block])
        # the unknowns solved before that the block reads, their values put in
        before = sorted({v for e in block for v in inc[e]} - set(zs))
        if before:
            res = ca.substitute(res, ca.vertcat(*[unknowns[j] for j in before]),
                                ca.vertcat(*[out.values[j] for j in before]))
        zb = ca.vertcat(*[unknowns[j] for j in zs])
        a = ca.jacobian(res, zb)
        if not ca.depends_on(a, zb):
            large = sample is not None and len(zs) > SMALL_BLOCK
            if not large and not regular(a):    # a large one: its elimination checks
                raise Singular(block, [], "singular at the parameters' values")
            try:
                solved = _linear(a, res, zb, sample)
            except Singular:
                raise Singular(block, [], "singular at the parameters' values") from None
        else:
            out.nonlinear += 1
            solved = _tear(res, zb, a, regular, out)
        for k, j in enumerate(zs):
            out.values[j] = solved[k]
    return out


def _linear(a, res, z, sample=None):
    """z from res(z) = a z + res(0) = 0."""
    rest = ca.substitute(res, z, ca.SX.zeros(z.shape[0]))
    if z.shape[0] == 1:
        return -rest / a
    if sample is None or z.shape[0] <= SMALL_BLOCK:
        return -ca.solve(a, rest)
    return -sparse_solve(a, rest, sample(a))


#: a linear block up to this size is solved by CasADi's dense symbolic solve
SMALL_BLOCK = 4
#: a pivot at least this fraction of its column's largest entry keeps elimination stable
PIVOT_THRESHOLD = 0.1


def sparse_solve(a, b, numbers):
    """x with a x = b for a square SX matrix ``a``: Gaussian elimination in Markowitz's
    order (the pivot that makes the least fill among those of at least PIVOT_THRESHOLD of
    their column's largest, on ``numbers``, the matrix's values at generic symbols): the
    expressions grow with the fill, a few entries per row for a circuit, not with the cube
    of the size."""
    n = a.shape[0]
    rows = [{} for _ in range(n)]
    vals = [{} for _ in range(n)]
    readers = [set() for _ in range(n)]
    for i, j in zip(*a.sparsity().get_triplet()):
        rows[i][j], vals[i][j] = a[i, j], float(numbers[i, j])
        readers[j].add(i)
    rhs = [b[i] for i in range(n)]
    free_rows, free_cols, order = set(range(n)), set(range(n)), []
    # below this a pivot is round-off of a cancellation (a loop of zero resistances)
    tiny = 1e-12 * max((abs(v) for row in vals for v in row.values()), default=0.0)
    for _ in range(n):
        best = None
        for c in sorted(free_cols):
            cand = [r for r in readers[c] if r in free_rows]
            big = max((abs(vals[r][c]) for r in cand), default=0.0)
            for r in sorted(cand):
                v = abs(vals[r][c])
                if v > tiny and v >= PIVOT_THRESHOLD * big:
                    cost = (len(rows[r]) - 1) * (len(cand) - 1)
                    if best is None or cost < best[0]:
                        best = (cost, r, c)
        if best is None:
            raise Singular(sorted(free_rows), sorted(free_cols), "singular at the "
                           "parameters' values")
        _, r, c = best
        free_rows.discard(r)
        free_cols.discard(c)
        order.append((r, c))
        for i in sorted(readers[c] & free_rows):
            f, fv = rows[i][c] / rows[r][c], vals[i][c] / vals[r][c]
            for j in rows[r]:
                if j != c:
                    rows[i][j] = rows[i].get(j, 0) - f * rows[r][j]
                    vals[i][j] = vals[i].get(j, 0.0) - fv * vals[r][j]
                    readers[j].add(i)
            del rows[i][c], vals[i][c]
            readers[c].discard(i)
            rhs[i] = rhs[i] - f * rhs[r]
    x = [None] * n
    for r, c in reversed(order):
        x[c] = (rhs[r] - sum((rows[r][j] * x[j] for j in rows[r] if j != c), ca.SX(0))) \
            / rows[r][c]
    return ca.vertcat(*x)


def _tear(res, zb, a, regular, out):
    """A nonlinear block: the unknowns whose Jacobian columns depend on the block's unknowns
    (read nonlinearly) tear it; the others, whose columns are constant, are solved from as
    many of its equations (a matching, regular at the parameters' values), and the
    equations left are the residuals in the tearing unknowns, which stay unknowns. Where no
    such split exists the whole block stays."""
    m = zb.shape[0]
    tear = [j for j in range(m) if ca.depends_on(a[:, j], zb)]
    rest = [j for j in range(m) if j not in tear]
    if rest:
        rows = [[c for c, j in enumerate(rest) if ca.depends_on(res[i], zb[j])]
                for i in range(m)]
        owner = match(rows)
        solving = [owner.get(c) for c in range(len(rest))]
        if None not in solving and regular(a[solving, rest]):
            zn = zb[rest]
            xn = _linear(a[solving, rest], res[solving], zn)
            values = ca.SX(zb)
            values[rest] = xn
            out.kept += [zb[j] for j in tear]
            out.residuals += [ca.substitute(res[i], zn, xn) for i in range(m)
                              if i not in solving]
            return values
    out.kept += [zb[j] for j in range(m)]
    out.residuals += [res[i] for i in range(m)]
    return zb
