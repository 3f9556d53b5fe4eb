"""MSL Rotational.Examples.CoupledClutches, two ways: wired in kinetwork as MSL wires it, and
written out by hand (four unit inertias in a row, three clutches between them) with an
event-located scipy integration that shares nothing with kinetwork's events.

The hand-written reference follows MSL's PartialFriction: a clutch is free while its normal
force fn <= 0 (no torque), else slides with the torque mu fn against its relative speed, or
is stuck while the torque holding it is within peak mu fn. At every restart the modes of the
clutches at rest are chosen together, as one consistent combination (each stuck one within
its limit, each sliding one accelerating the way it slides)."""

import itertools
import math

import numpy as np
from scipy.integrate import solve_ivp

import kinetwork as kn

MU, PEAK, FN_MAX, T2, T3, F1 = 0.5, 1.1, 20.0, 0.4, 0.9, 0.2
W0 = (10.0, 0.0, 0.0, 0.0)


def model():
    """The example with MSL's parameters: J1 starts at 10 rad/s, the torque 10 sin(2 pi 5 t)
    acts on it (its support fixed), clutch1 is pressed by 20 cos(2 pi 0.2 t), clutch2 from
    T2 = 0.4 s, clutch3 from T3 = 0.9 s."""
    rot, sig = kn.rotational, kn.signals
    m = kn.Model("CoupledClutches")
    for k in range(1, 5):
        m.add(rot.Inertia(f"J{k}", J=1.0, phi0=0.0, w0=W0[k - 1]))
    for k in range(1, 4):
        m.add(rot.Clutch(f"clutch{k}", mu=MU, peak=PEAK, fn_max=FN_MAX))
    m.add(rot.Torque("torque"))
    m.add(rot.Fixed("fixed"))
    m.add(sig.Sine("sin1", amplitude=10.0, f=5.0))
    m.add(sig.Sine("sin2", amplitude=1.0, f=F1, phase=math.pi / 2))
    m.add(sig.Step("step1", start_time=T2))
    m.add(sig.Step("step2", start_time=T3))
    for a, b in [("torque.flange", "J1.flange_a"), ("J1.flange_b", "clutch1.flange_a"),
                 ("clutch1.flange_b", "J2.flange_a"), ("J2.flange_b", "clutch2.flange_a"),
                 ("clutch2.flange_b", "J3.flange_a"), ("J3.flange_b", "clutch3.flange_a"),
                 ("clutch3.flange_b", "J4.flange_a"), ("sin1.y", "torque.u"),
                 ("sin2.y", "clutch1.u"), ("step1.y", "clutch2.u"), ("step2.y", "clutch3.u"),
                 ("fixed.flange", "torque.support")]:
        m.connect(a, b)
    return m


def _fn(t):
    return FN_MAX * np.array([math.cos(2 * math.pi * F1 * t), float(t >= T2), float(t >= T3)])


def _tau(t):
    return 10.0 * math.sin(2 * math.pi * 5.0 * t)


def _accelerations(t, w, modes):
    """Accelerations of the four inertias and the torque each clutch puts on the inertia
    before it (c_k; -c_k on the one after) for the given modes (None: free)."""
    fn = _fn(t)
    ext = np.array([_tau(t), 0.0, 0.0, 0.0])
    c = np.zeros(3)
    for k, m in enumerate(modes):
        if m in (1, -1):
            c[k] = m * MU * fn[k]
    groups, start = [], 0
    for k in range(3):
        if modes[k] != 0:
            groups.append(list(range(start, k + 1)))
            start = k + 1
    groups.append(list(range(start, 4)))
    a = np.zeros(4)
    for g in groups:
        load = sum(ext[i] for i in g)
        if g[0] > 0:
            load -= c[g[0] - 1]
        if g[-1] < 3:
            load += c[g[-1]]
        a[g] = load / len(g)
        for k in g[:-1]:                      # stuck clutch k inside: the left part's balance
            left = g[:g.index(k) + 1]
            c[k] = len(left) * a[g[0]] - sum(ext[i] for i in left) + (
                c[g[0] - 1] if g[0] > 0 else 0.0)
    return a, c


def _consistent(t, w, modes, at_rest):
    """Modes with the clutches at rest chosen together (fewest changes first)."""
    fn = _fn(t)
    options = [((0, 1, -1) if k in at_rest else (modes[k],)) for k in range(3)]
    for choice in sorted(itertools.product(*options),
                         key=lambda c: sum(a != b for a, b in zip(c, modes))):
        a, c = _accelerations(t, w, choice)
        ok = True
        for k in at_rest:
            rel = a[k + 1] - a[k]
            if choice[k] == 0 and abs(c[k]) > PEAK * MU * fn[k] * (1 + 1e-12):
                ok = False
            if choice[k] in (1, -1) and choice[k] * rel < -1e-12:
                ok = False
        if ok:
            return list(choice)
    raise RuntimeError(f"no consistent modes at t = {t}")


def reference(t_eval, rtol=1e-12, atol=1e-12):
    """(phi, w): the four inertias' angles and speeds at ``t_eval`` (rows), integrated by
    scipy's DOP853 between events located by solve_ivp."""
    t, x = 0.0, np.concatenate([np.zeros(4), W0])
    t_end = float(t_eval[-1])
    breaks = [T2, T3, 1.0 / (4 * F1)]                 # steps, and clutch1's fn reaching 0
    out_t, out_x = [], []
    modes = [None, None, None]
    while t < t_end - 1e-15:
        fn = _fn(t + 1e-13)
        w = x[4:]
        modes = [None if fn[k] <= 0 else modes[k] for k in range(3)]
        for k in range(3):
            if modes[k] is None and fn[k] > 0:
                rel = w[k + 1] - w[k]
                modes[k] = 0 if abs(rel) < 1e-9 else int(np.sign(rel))
        at_rest = [k for k in range(3) if modes[k] is not None and abs(w[k + 1] - w[k]) < 1e-9]
        if at_rest:
            modes = _consistent(t + 1e-13, w, modes, at_rest)
            for k in at_rest:
                if modes[k] == 0:
                    x[4 + k + 1] = x[4 + k]           # exactly together
        stop = min([b for b in breaks if b > t + 1e-12] + [t_end])

        def rhs(s, y, modes=tuple(modes)):
            return np.concatenate([y[4:], _accelerations(s, y[4:], modes)[0]])
        events = []
        for k in range(3):
            if modes[k] in (1, -1):
                def slide(s, y, k=k):
                    return modes[k] * (y[5 + k] - y[4 + k])
                slide.terminal, slide.direction = True, -1
                events.append(slide)
            elif modes[k] == 0:
                def stick(s, y, k=k, modes=tuple(modes)):
                    c = _accelerations(s, y[4:], modes)[1]
                    return PEAK * MU * _fn(s)[k] - abs(c[k])
                stick.terminal, stick.direction = True, -1
                events.append(stick)
        inside = t_eval[(t_eval > t) & (t_eval <= stop)]
        sol = solve_ivp(rhs, (t, stop), x, method="DOP853", rtol=rtol, atol=atol,
                        events=events or None, dense_output=True)
        t_next = sol.t[-1]
        keep = inside[inside <= t_next]
        out_t += list(keep)
        out_x += list(sol.sol(keep).T) if len(keep) else []
        x = sol.y[:, -1].copy()
        for k, ev in zip([k for k in range(3) if modes[k] is not None], sol.t_events or []):
            if len(ev) and modes[k] == 0:            # the hold gave way: slide its way
                c = _accelerations(t_next, x[4:], modes)[1]
                modes[k] = 1 if c[k] > 0 else -1
        t = t_next
    X = np.array(out_x)
    if t_eval[0] == 0.0:
        X = np.vstack([np.concatenate([np.zeros(4), W0]), X])
    return X[:, :4], X[:, 4:]
