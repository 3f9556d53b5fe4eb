"""Conditions on the start that the start values of a loop's cut joint set.

A FreeMotion that closes a loop constrains nothing while the model runs, but its start values
say where frame_b starts relative to frame_a and how it moves (MSL's DoublePendulumInitTip
places a pendulum's tip that way). They become rows solved with the loop closures when the
start is assembled (``loops._Loops.close``: the joints of the loop without a q0 are the
unknowns, from their guesses) and, for the speeds, one linear least-squares problem in the
speeds not given (``speeds``). Rows that cannot all be met are refused, naming the start
values; redundant ones that agree (a planar pendulum's tip at z = 0) are fine.
"""

import warnings
from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from ..errors import AssemblyBranchWarning, ModelError
from ..spatial import vee
from . import loopclose

#: a start condition counts as met below this (m, m/s, rad/s, rotation-matrix entries)
MET = 1e-9


@dataclass
class StartRows:
    """The rows of every cut joint's start values: positions in (q, p), speeds in (q, u, p),
    each row labelled with its component and parameter (``"tip.r0"``)."""
    position: ca.SX
    speed: ca.SX
    position_labels: list = field(default_factory=list)
    speed_labels: list = field(default_factory=list)


def rows(asm, topo, bound):
    """The StartRows of the model's cut joints, or None when none has start values."""
    pos, spd, pos_labels, spd_labels = [], [], [], []
    for cut in topo.cuts:
        comp = bound[cut.component.name]
        if getattr(type(comp), "start_conditions", None) is None:
            continue
        Ra, pa, Rb, pb = asm.relative_poses(cut.set_a, cut.set_b)
        rel_R, rel_p = Ra.T @ Rb, Ra.T @ (pb - pa)
        rel_v = asm.rate(rel_p, accelerations=False)
        rel_w = vee(rel_R.T @ asm.rate(rel_R, accelerations=False))
        position, speed = comp.start_conditions(rel_R, rel_p, rel_v, rel_w)
        for out, labels, items in ((pos, pos_labels, position), (spd, spd_labels, speed)):
            for expr, key in items:
                out.append(expr)
                labels += [f"{comp.name}.{key}"] * expr.shape[0]
    if not pos and not spd:
        return None
    return StartRows(ca.vertcat(*pos) if pos else ca.SX(0, 1),
                     ca.vertcat(*spd) if spd else ca.SX(0, 1), pos_labels, spd_labels)


def unmet(labels, residual, what):
    """The ModelError of start conditions left unmet (the largest residual per value)."""
    worst = {}
    for label, r in zip(labels, np.abs(residual)):
        worst[label] = max(worst.get(label, 0.0), float(r))
    bad = {k: v for k, v in worst.items() if v > MET}
    listed = ", ".join(f"{k} (off by {v:.3g})" for k, v in bad.items())
    return ModelError(f"the start values {listed} cannot be met: no {what} of the joints "
                      f"without a given start puts the cut joint's frame_b there; check them "
                      f"against the mechanism, or give guesses (q0_guess) nearer a solution")


def speeds(loops, q, u0, p):
    """The start speeds ``u0`` with those not given solved so that the loops' velocity
    closure and the speed start conditions hold (least squares; refused when they cannot)."""
    asm = loops.asm
    if loops.f_speed is None:
        return u0
    r, A = (np.asarray(v, dtype=float) for v in loops.f_speed(q, u0, p))
    r = r.ravel()
    J = np.asarray(loops.f_J(q, p), dtype=float).reshape(-1, len(u0))
    free = [k for k in range(len(u0)) if not asm.u_given[k] and k not in asm.prescribed]
    M = np.vstack([J[:, free], A[:, free]])
    b = -np.concatenate([J @ u0, r])
    u = np.array(u0, dtype=float)
    if free:
        u[free] += np.linalg.lstsq(M, b, rcond=None)[0]
    left = np.asarray(loops.f_speed(q, u, p)[0], dtype=float).ravel()
    if np.max(np.abs(left), initial=0.0) > MET * (1 + np.max(np.abs(u), initial=0.0)):
        raise unmet(asm.start_rows.speed_labels, left, "set of start speeds")
    return u


def branch(loops, q, p):
    """Warn, per loop, where Newton from the guesses assembled the start on another branch
    than the guesses point to (AssemblyBranchWarning), naming the loop's joints with where
    they start and where the other assembly has them. The guesses point to another
    assembly when it lies at most NEARER as far from them in every distance a prismatic
    joint of the loop has (a piston: its stroke on one branch, outside it on the other), or,
    in a loop of angles only, in every angle; a guess midway between two branches points to
    neither. The start is not changed: the warning says what to give."""
    asm = loops.asm
    start = np.asarray(loops.f_start(p)[0], dtype=float).ravel()
    pattern = np.asarray(ca.DM(loops.f_jac.sparsity_out(0), 1))
    n_closure = loops.phi.shape[0]
    units = np.array(asm.coordinate_units)
    for i, (cut, _) in enumerate(asm.cuts):
        rows = [k for k, owner in enumerate(loops.owner) if owner == i]
        others = [k for k in range(n_closure) if loops.owner[k] != i]
        cols = [c for c in range(len(loops.free)) if pattern[rows, c].any()]
        if not cols or pattern[np.ix_(others, cols)].any():
            continue                      # no joint of its own, or shared with another loop
        free = [loops.free[c] for c in cols]
        angle = units[free] != "m"
        judged = ~angle if (~angle).any() else angle

        def off(z, free=free, angle=angle):
            d = z - start[free]
            return np.abs(np.where(angle, (d + np.pi) % (2 * np.pi) - np.pi, d))
        mine = off(q[free])
        if np.max(mine[judged], initial=0.0) <= 1e-6:
            continue                      # assembled at its guesses: nothing is nearer
        scale = np.where(angle, np.pi, max(1.0, np.max(np.abs(start[free]), initial=0.0)))
        rng = np.random.default_rng(0)
        nearest = None
        for _ in range(SEARCH_STARTS):
            trial = q.copy()
            trial[free] = start[free] + rng.uniform(-1, 1, len(free)) * scale
            found, r = loopclose.gauss_newton(loops, trial, p, rows, free)
            if not loopclose.closed(r):
                continue
            z = found[free]
            theirs = off(z)
            if np.all(theirs[judged] < NEARER * mine[judged]) and (
                    nearest is None or np.sum(theirs[judged]) < np.sum(nearest[0])):
                nearest = (theirs[judged], z)
        if nearest is None:
            continue
        names = asm.coordinate_names
        listed = ", ".join(
            f"{names[k]} = {q[k]:.6g}{' ' + units[k] if units[k] else ''} (other branch: "
            f"{z:.6g}, guess {start[k]:.6g})" for k, z in zip(free, nearest[1]))
        # the place is the joint judged farthest from its guess (a piston's prismatic)
        farthest = free[int(np.argmax(np.where(judged, mine, -1.0)))]
        warnings.warn(AssemblyBranchWarning(
            f"kinematic loop through {', '.join(cut.loop)}: Newton from the guesses "
            f"(q0_guess) assembled the start on another branch than the one they point to "
            f"({listed}): the start is the first; if the other is meant (a piston inside its "
            f"cylinder), give its values as q0_guess",
            component=names[farthest].rsplit(".", 1)[0], parameter="q0_guess",
            hint="give q0_guess on the branch meant"), stacklevel=2)


#: random starts of the search for other assemblies of a loop (Gauss-Newton from each)
SEARCH_STARTS = 12
#: another assembly this much nearer the guesses (as a fraction of the distance of the one
#: found), in every coordinate judged, is the one they point to
NEARER = 0.4
