"""Recursive Newton-Euler algorithms over a kinematic tree, in CasADi SX.

Spatial vectors are 6-vectors [angular; linear] in body coordinates (Featherstone's
convention). ``Body.R, Body.p`` place a body in its parent: a point with body coordinates x
sits at ``R @ x + p`` in the parent's. Gravity enters as an upward acceleration of the world
(a0 = [0; -g]), so bodies feel it as inertia. Every function is O(number of bodies) except
``crba``, which fills the n x n mass matrix.

Each body's step of a pass is one call of a small SX Function on that body's expressions
(``_steps``), not a few dozen calls of CasADi's matrix operations from Python: those cost
~50 us each whatever their size (the wrapper checks every argument's shape), and were 80 %
of building a 512-link chain (11.6 s; 3.8 s of CPU now, most of it elsewhere). Evaluating an SX Function on SX arguments
expands it, folding the zeros and ones of the arguments, so the expressions are the same
operations as before.
"""

import functools
from dataclasses import dataclass, field

import casadi as ca

from ..spatial import skew, vee

ZERO6 = ca.SX.zeros(6, 1)


@dataclass
class Body:
    """One moving body of the tree: the part carried by one joint with degrees of freedom."""
    name: str
    parent: int          # index of the parent body, -1 for the world
    R: ca.SX             # 3x3, body axes in parent coordinates (depends on q)
    p: ca.SX             # 3x1, body origin in parent coordinates (depends on q)
    S: ca.SX             # 6 x dof motion subspace, body coordinates
    cJ: ca.SX            # 6x1 velocity-product acceleration of the joint (S-dot qd)
    inertia: ca.SX       # 6x6 spatial inertia about the body origin, body coordinates
    speeds: list         # positions of this joint's speeds in u
    X: ca.SX = field(init=False)     # parent-to-body motion transform, built once

    def __post_init__(self):
        self.X = transform(self.R, self.p)


def transform(R, p):
    """Plücker transform of motion vectors from parent to body coordinates."""
    if isinstance(R, ca.SX) and R.shape == (3, 3) and p.shape == (3, 1):
        return _steps("transform")(R, p)
    return _transform(R, p)


def _transform(R, p):
    Rt = R.T
    return ca.blockcat([[Rt, ca.SX.zeros(3, 3)], [-Rt @ skew(p), Rt]])


def crm(v):
    """Spatial cross product for motion vectors (v x)."""
    w, u = skew(v[:3]), skew(v[3:])
    return ca.blockcat([[w, ca.SX.zeros(3, 3)], [u, w]])


def crf(v):
    """Spatial cross product for force vectors (v x*) = -crm(v)^T."""
    return -crm(v).T


def spatial_inertia(mass, com, inertia_cm):
    """Spatial inertia about a frame origin of a body with ``com`` and ``inertia_cm`` there."""
    if all(isinstance(v, ca.SX) for v in (mass, com, inertia_cm)) and mass.shape == (1, 1) \
            and com.shape == (3, 1) and inertia_cm.shape == (3, 3):
        return _steps("inertia")(mass, com, inertia_cm)
    return _spatial_inertia(mass, com, inertia_cm)


def _spatial_inertia(mass, com, inertia_cm):
    c = skew(com)
    return ca.blockcat([[inertia_cm + mass * (c @ c.T), mass * c],
                        [mass * c.T, mass * ca.SX.eye(3)]])


def _solve(D, b):
    """D^-1 b for the small dof x dof joint-space inertia of one joint."""
    return b / D if D.shape == (1, 1) else ca.solve(D, b)


@functools.lru_cache(maxsize=None)
def _steps(name):
    """The SX Function of one body's step ``name``, for joints of one degree of freedom
    (revolute, prismatic, screw: nearly every body). Written with the very operations the
    general code of ``aba`` and ``rnea`` uses, in the same order."""
    sym = ca.SX.sym
    X, I, IA, IAp = sym("X", 6, 6), sym("I", 6, 6), sym("IA", 6, 6), sym("IAp", 6, 6)
    v_p, a_p, S, cJ = sym("v_p", 6), sym("a_p", 6), sym("S", 6), sym("cJ", 6)
    c, pA, pAp, f, fp, U = sym("c", 6), sym("pA", 6), sym("pAp", 6), sym("f", 6), \
        sym("fp", 6), sym("U", 6)
    qd, qdd, tau, arm, D, u = (sym(n) for n in ("qd", "qdd", "tau", "arm", "D", "u"))
    if name == "transform":
        R, p = sym("R", 3, 3), sym("p", 3)
        return ca.Function(name, [R, p], [_transform(R, p)])
    if name == "inertia":
        m, com, Ic = sym("m"), sym("com", 3), sym("Ic", 3, 3)
        return ca.Function(name, [m, com, Ic], [_spatial_inertia(m, com, Ic)])
    if name == "aba_out":          # outward: velocity, bias acceleration and force
        vJ = S @ qd
        v = X @ v_p + vJ
        return ca.Function(name, [X, v_p, S, qd, cJ, I],
                           [v, crm(v) @ vJ + cJ, crf(v) @ (I @ v)])
    if name in ("aba_in", "aba_in_root"):   # inward: articulated inertia into the parent's
        U_ = IA @ S
        D_ = S.T @ U_ + arm
        u_ = tau - S.T @ pA
        outs = [U_, D_, u_]
        if name == "aba_in":
            Ia = IA - U_ @ _solve(D_, U_.T)
            pa = pA + Ia @ c + U_ @ _solve(D_, u_)
            outs += [IAp + X.T @ Ia @ X, pAp + X.T @ pa]
        return ca.Function(name, [IA, pA, S, c, tau, arm, X, IAp, pAp], outs)
    if name == "aba_acc":          # outward again: the joint's and the body's accelerations
        ap = X @ a_p + c
        qdd_ = _solve(D, u - U.T @ ap)
        return ca.Function(name, [X, a_p, c, D, u, U, S], [qdd_, ap + S @ qdd_])
    if name == "rnea_out":
        vJ = S @ qd
        v = X @ v_p + vJ
        a = X @ a_p + S @ qdd + crm(v) @ vJ + cJ
        return ca.Function(name, [X, v_p, a_p, S, qd, qdd, cJ, I],
                           [v, a, I @ a + crf(v) @ (I @ v)])
    if name == "rnea_in":
        return ca.Function(name, [S, f, X, fp], [S.T @ f, fp + X.T @ f])
    raise KeyError(name)


def aba(bodies, qd, tau, a0, armature=None, known=None):
    """Articulated-body algorithm: joint accelerations qdd, O(n) in the number of bodies.

    ``armature`` (one per speed) is 1-D inertia rigidly geared to a joint coordinate (a
    motor's rotor): it adds to D, the joint-space inertia of its joint, and nowhere else.
    ``known`` (speed index -> acceleration) makes it Featherstone's hybrid dynamics: those
    speeds' rates are given (prescribed motions) and pass their bodies' articulated inertia
    whole to the parent; ``tau`` of them is not used.
    """
    known = known or {}
    n = len(bodies)
    X = [b.X for b in bodies]
    v, c, IA, pA = [None] * n, [None] * n, [None] * n, [None] * n
    free, S, given = [None] * n, [None] * n, [None] * n
    for k, b in enumerate(bodies):
        free[k] = [s for s in b.speeds if s not in known]
        if len(b.speeds) == 1 and free[k]:        # one free speed: one call (``_steps``)
            v[k], c[k], pA[k] = _steps("aba_out").call(
                [X[k], v[b.parent] if b.parent >= 0 else ZERO6, b.S, qd[b.speeds[0]],
                 b.cJ, b.inertia])
            S[k], given[k], IA[k] = b.S, [], b.inertia
            continue
        vJ = b.S @ qd[b.speeds]
        v[k] = (X[k] @ v[b.parent] if b.parent >= 0 else ZERO6) + vJ
        c[k] = crm(v[k]) @ vJ + b.cJ
        cols = [b.speeds.index(s) for s in free[k]]
        S[k] = b.S if len(cols) == len(b.speeds) else (b.S[:, cols] if cols
                                                           else ca.SX(6, 0))
        given[k] = [b.speeds.index(s) for s in b.speeds if s in known]
        if given[k]:             # the prescribed part of the joint's motion acts as a bias
            c[k] = c[k] + b.S[:, given[k]] @ ca.vertcat(*[known[b.speeds[i]]
                                                          for i in given[k]])
        IA[k] = b.inertia
        pA[k] = crf(v[k]) @ (b.inertia @ v[k])
    U, D, u = [None] * n, [None] * n, [None] * n
    for k in reversed(range(n)):
        b = bodies[k]
        if len(b.speeds) == 1 and free[k]:
            s_ = b.speeds[0]
            step = _steps("aba_in" if b.parent >= 0 else "aba_in_root")
            out = step.call([IA[k], pA[k], S[k], c[k], tau[s_],
                             0 if armature is None else armature[s_], X[k],
                             *((IA[b.parent], pA[b.parent]) if b.parent >= 0 else (0, 0))])
            U[k], D[k], u[k] = out[:3]
            if b.parent >= 0:
                IA[b.parent], pA[b.parent] = out[3:]
            continue
        if free[k]:
            U[k] = IA[k] @ S[k]
            D[k] = S[k].T @ U[k]
            if armature is not None:
                D[k] = D[k] + ca.diag(armature[free[k]])
            u[k] = tau[free[k]] - S[k].T @ pA[k]
        if b.parent >= 0:
            if free[k]:
                Ia = IA[k] - U[k] @ _solve(D[k], U[k].T)
                pa = pA[k] + Ia @ c[k] + U[k] @ _solve(D[k], u[k])
            else:
                Ia, pa = IA[k], pA[k] + IA[k] @ c[k]
            IA[b.parent] = IA[b.parent] + X[k].T @ Ia @ X[k]
            pA[b.parent] = pA[b.parent] + X[k].T @ pa
    qdd = ca.SX.zeros(qd.shape[0], 1)
    a = [None] * n
    for k, b in enumerate(bodies):
        if len(b.speeds) == 1 and free[k]:
            qdd[b.speeds[0]], a[k] = _steps("aba_acc").call(
                [X[k], a[b.parent] if b.parent >= 0 else a0, c[k], D[k], u[k], U[k], S[k]])
            continue
        ap = X[k] @ (a[b.parent] if b.parent >= 0 else a0) + c[k]
        a[k] = ap
        if free[k]:
            qdd_k = _solve(D[k], u[k] - U[k].T @ ap)
            qdd[free[k]] = qdd_k
            a[k] = ap + S[k] @ qdd_k
    for s, value in known.items():
        qdd[s] = value
    return qdd


def crba(bodies, n_q, armature=None):
    """Composite-rigid-body algorithm: the joint-space mass matrix M(q) (plus ``armature``
    on the diagonal)."""
    X = [b.X for b in bodies]
    IC = [b.inertia for b in bodies]
    for k in reversed(range(len(bodies))):
        parent = bodies[k].parent
        if parent >= 0:
            IC[parent] = IC[parent] + X[k].T @ IC[k] @ X[k]
    M = ca.SX.zeros(n_q, n_q)
    for k, b in enumerate(bodies):
        F = IC[k] @ b.S
        M[b.speeds, b.speeds] = b.S.T @ F
        j = k
        while bodies[j].parent >= 0:
            F = X[j].T @ F
            j = bodies[j].parent
            block = F.T @ bodies[j].S
            M[b.speeds, bodies[j].speeds] = block
            M[bodies[j].speeds, b.speeds] = block.T
    return M if armature is None else M + ca.diag(armature)


def rnea(bodies, qd, qdd, a0, armature=None):
    """Inverse dynamics: generalized forces that produce qdd at (q, qd) (outward, inward),
    with ``armature`` times qdd on each speed."""
    n = len(bodies)
    X = [b.X for b in bodies]
    v, a, f = [None] * n, [None] * n, [None] * n
    for k, b in enumerate(bodies):
        if len(b.speeds) == 1:                    # one call (``_steps``)
            parent = b.parent >= 0
            v[k], a[k], f[k] = _steps("rnea_out").call(
                [X[k], v[b.parent] if parent else ZERO6, a[b.parent] if parent else a0, b.S,
                 qd[b.speeds[0]], qdd[b.speeds[0]], b.cJ, b.inertia])
            continue
        vJ = b.S @ qd[b.speeds]
        v[k] = (X[k] @ v[b.parent] if b.parent >= 0 else ZERO6) + vJ
        a[k] = (X[k] @ a[b.parent] if b.parent >= 0 else X[k] @ a0) \
            + b.S @ qdd[b.speeds] + crm(v[k]) @ vJ + b.cJ
        f[k] = b.inertia @ a[k] + crf(v[k]) @ (b.inertia @ v[k])
    tau = ca.SX.zeros(qd.shape[0], 1)
    for k in reversed(range(n)):
        b = bodies[k]
        if len(b.speeds) == 1 and b.parent >= 0:
            tau[b.speeds[0]], f[b.parent] = _steps("rnea_in").call(
                [b.S, f[k], X[k], f[b.parent]])
            continue
        tau[b.speeds] = b.S.T @ f[k]
        if b.parent >= 0:
            f[b.parent] = f[b.parent] + X[k].T @ f[k]
    return tau if armature is None else tau + armature * qdd


def motion_subspace(comp, qj, uj, Re, re):
    """Spatial velocity of the moved frame relative to the fixed one per unit joint speed,
    in the moved frame's axes (6 x dof), from the rate of the joint's transform (Re, re)."""
    qdot = comp.rate(qj, uj)
    w = vee(Re.T @ ca.reshape(ca.jtimes(ca.vec(Re), qj, qdot), 3, 3))
    return ca.jacobian(ca.vertcat(w, Re.T @ ca.jtimes(re, qj, qdot)), uj)
