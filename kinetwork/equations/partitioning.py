"""The independent closure equations of the kinematic loops and the partition of the speeds.

Which closure rows are independent (pivoted QR), which speeds follow the closure (dependent)
and which the states keep (independent); at a configuration where the partition turns
singular, the partitions possible there and their quality (``partitions_at``, for the run's
loop watch). Each function takes the _Loops.
"""

import itertools
import math

import numpy as np

from ..errors import ModelError

#: singular values below this fraction of the largest mark redundant closure equations
RANK_TOL = 1e-8
#: a re-partition compares every choice of dependent speeds when there are at most this many
#: (a planar five-bar: 10); beyond, it takes the pivoted-QR choice
PARTITION_CHOICES = 200


def _pivoted_qr(a):
    """The QR factorisation of ``a`` with column pivoting (Businger-Golub: at each step the
    column of largest remaining norm, the first of equals): (|diagonal of R|, column order).

    numpy has no pivoted QR and scipy.linalg costs 0.3 s to import in every process that
    builds a loop; the matrices here are a few dozen rows and columns.
    """
    r = np.array(a, dtype=float)
    m, n = r.shape
    order = np.arange(n)
    diag = np.zeros(min(m, n))
    for k in range(min(m, n)):
        norms = np.sqrt(np.einsum("ij,ij->j", r[k:, k:], r[k:, k:]))
        j = k + int(np.argmax(norms))
        if j != k:
            r[:, [k, j]] = r[:, [j, k]]
            order[[k, j]] = order[[j, k]]
        diag[k] = norms[j - k]
        if diag[k] == 0.0:
            break                      # what remains is zero
        v = r[k:, k].copy()
        v[0] += math.copysign(diag[k], v[0])
        v /= np.linalg.norm(v)
        r[k:, k:] -= 2.0 * np.outer(v, v @ r[k:, k:])
    return diag, order


def choose(loops, J, loop_coords):
    """The independent closure rows (pivoted QR on J's rows) and the dependent speeds
    (pivoted QR on their columns, cut joints first, given coordinates last)."""
    asm = loops.asm
    names = loops.asm.coordinate_names
    if J.size == 0:
        return [], []
    s = np.linalg.svd(J, compute_uv=False)
    rank = int(np.sum(s > RANK_TOL * max(s[0], 1.0)))
    _, piv = _pivoted_qr(J.T)
    rows = sorted(piv[:rank].tolist())
    Jr = J[rows]
    # speeds that may be dependent: of regular loop coordinates; preference tiers
    cut_joints = {c.component.name for c, _ in asm.cuts}
    tiers = [[], [], []]
    for k in sorted(loop_coords):
        if not asm.regular[k]:
            continue
        speed = asm.speed_of[k]
        if speed in asm.prescribed:      # its motion is given: neither kind
            continue
        if asm.given[k] or asm.u_given[speed]:
            tiers[2].append(speed)
        elif names[k].rsplit(".", 1)[0] in cut_joints:
            tiers[0].append(speed)
        else:
            tiers[1].append(speed)
    dep = []
    basis = np.zeros((rank, 0))
    for tier in tiers:
        if len(dep) == rank or not tier:
            continue
        cols = Jr[:, tier]
        if basis.shape[1]:                 # what the chosen columns do not reach yet
            Qb, _ = np.linalg.qr(basis)
            cols = cols - Qb @ (Qb.T @ cols)
        diag, piv = _pivoted_qr(cols)
        for j, d in zip(piv, diag):
            if len(dep) == rank or d <= RANK_TOL * max(np.abs(Jr).max(), 1.0):
                break
            dep.append(tier[j])
            basis = np.column_stack([basis, Jr[:, tier[j]]])
    if len(dep) < rank:
        quaternion = sorted({n.rsplit(".", 1)[0] for k, n in enumerate(names)
                             if k in loop_coords and not asm.regular[k]})
        through = "; ".join(", ".join(c.loop) for c, _ in asm.cuts)
        driven = sorted({f"{m.joint} (by {m.source})" for m in asm.prescribed.values()
                         if m.coordinate in loop_coords})
        raise ModelError(
            f"kinematic loop through {through}: its closure fixes {rank} speeds but only "
            f"{len(dep)} joint angles or distances on the loop can follow it"
            + (f"; the ball or free joint(s) {', '.join(quaternion)} on the loop must be "
               f"the cut joint (mark one cut=True), or be replaced by a Universal joint"
               if quaternion else "")
            + (f"; the prescribed joint(s) {', '.join(driven)} cannot follow it: "
               f"their motions fight each other through the loop (drive fewer joints)"
               if driven else ""))
    return rows, sorted(dep)


def candidates(loops):
    """The speeds that may be dependent: of the regular coordinates on a loop, less the
    prescribed ones."""
    asm = loops.asm
    return sorted(asm.speed_of[k] for k in loops.loop_coords
                  if asm.regular[k] and asm.speed_of[k] not in asm.prescribed)


def partitions_at(loops, q, p):
    """The partitions possible at the configuration ``q``: (health, choices), or None
    where the closure has lost rank.

    ``health`` is the ratio of the smallest to the largest singular value of the kept
    closure rows' Jacobian in the candidate speeds: it goes to zero at a change point,
    where two branches of the mechanism's configurations cross (a rhombus folding
    flat) and no partition is regular. ``choices`` are (rows, dependent speeds,
    condition number of the Jacobian in them, quality): the rows by pivoted QR as at
    the start, every choice of as many candidate speeds as rows (or, beyond
    PARTITION_CHOICES of them, the pivoted-QR one); quality is the smallest singular
    value of the rows of the independent speeds in an orthonormal basis of the
    closure's null space (the tangent of the configurations): how well the independent
    coordinates describe the motion, through a change point too."""
    J = np.asarray(loops.f_J(q, p), dtype=float)
    if not np.all(np.isfinite(J)):
        return None
    s = np.linalg.svd(J, compute_uv=False)
    rank = int(np.sum(s > RANK_TOL * max(s[0], 1.0))) if s.size else 0
    if rank < len(loops.rows):
        return None
    _, piv = _pivoted_qr(J.T)
    rows = sorted(piv[:rank].tolist())
    cand = candidates(loops)
    Jc = J[rows][:, cand]
    _, sc, vt = np.linalg.svd(Jc)
    health = float(sc[-1] / sc[0]) if sc.size and sc[0] > 0 else 0.0
    N = vt[rank:].T                              # null space, one row per candidate
    if math.comb(len(cand), rank) <= PARTITION_CHOICES:
        choices = itertools.combinations(range(len(cand)), rank)
    else:
        _, piv = _pivoted_qr(Jc)
        choices = [sorted(piv[:rank].tolist())]
    out = []
    for dep in choices:
        ind = [j for j in range(len(cand)) if j not in dep]
        quality = np.linalg.svd(N[ind], compute_uv=False)[-1] if ind else 1.0
        out.append((rows, [cand[j] for j in dep], condition(Jc[:, list(dep)]),
                    float(quality)))
    return health, out


def condition(A):
    """The 2-norm condition number of a square matrix (inf when singular)."""
    if not A.size:
        return 1.0
    s = np.linalg.svd(A, compute_uv=False)
    return float(s[0] / s[-1]) if s[-1] > 0 else np.inf
