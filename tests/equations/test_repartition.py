"""Loops through singular configurations (issue 15, item 6): where the partition of the speeds
turns singular, the run re-partitions and goes on.

Two scenes, each against a reference that knows nothing of partitions:

- a triple rocker (a non-Grashof four-bar) released from rest with its crank as the
  independent coordinate: the crank cannot go round, so the motion passes the crank's dead
  points, where the crank partition is singular (the coupler and the rocker in line). The
  reference is the same mechanism in absolute link angles with Lagrange multipliers (an
  index-1 DAE with Baumgarte stabilisation, scipy's DOP853 at 1e-12); energy is conserved;
- Multibody.jl's five-revolute planar loop (``models/five_revolute_loop.json``): an equal-sided
  rhombus hung from one corner that folds flat (a change point: all four links in line, where
  no partition is regular) about twice a second. Its configurations stay a rhombus, so two
  link angles describe it with no closure at all: the reference is that two-coordinate
  Lagrangian, integrated by DOP853.
"""

import pathlib

import numpy as np
import pytest
from close import assert_same_numbers
from scenes import fourbar
from scipy.integrate import solve_ivp

import kinetwork as kn

MODELS = pathlib.Path(__file__).resolve().parents[2] / "models"
G = 9.81


def e(a):
    return np.array([np.cos(a), np.sin(a)])


def de(a):
    return np.array([-np.sin(a), np.cos(a)])


def wrap(a):
    return (a + np.pi) % (2 * np.pi) - np.pi


# -- the triple rocker ------------------------------------------------------------------------
ROCKER = {"a": 1.0, "b": 0.9, "c": 0.7, "d": 1.3}      # 0.7 + 1.3 > 1.0 + 0.9: non-Grashof
MASS = {"a": 1.0, "b": 0.8, "c": 0.6}


def triple_rocker(q0=1.2):
    """Crank A at the origin (q0 given: the independent coordinate), coupler, rocker D at
    (d, 0), the loop cut at C; slender links with their mass at mid-length."""
    m = kn.Model("triple_rocker")
    m.add(kn.multibody.Ground("ground", gravity=[0, -G, 0]))
    m.add(kn.multibody.FixedTranslation("base", r=[ROCKER["d"], 0, 0]))
    for name, key in (("crank", "a"), ("coupler", "b"), ("rocker", "c")):
        length, mass = ROCKER[key], MASS[key]
        m.add(kn.multibody.BodyShape(name, r=[length, 0, 0], mass=mass,
                                     r_cm=[length / 2, 0, 0],
                                     inertia=[0, 0, mass * length ** 2 / 12]))
    m.add(kn.multibody.Revolute("A", q0=q0))
    m.add(kn.multibody.Revolute("B", q0_guess=-1.0))
    m.add(kn.multibody.Revolute("D", q0_guess=2.0))
    m.add(kn.multibody.Revolute("C", cut=True))
    for joint in "ABD":
        m.add(kn.Probe(f"p{joint}", quantities=["angle", "speed"]))
        m.connect(f"p{joint}.port", f"{joint}.axis")
    for a, b in [("ground.frame", "A.frame_a"), ("A.frame_b", "crank.frame_a"),
                 ("crank.frame_b", "B.frame_a"), ("B.frame_b", "coupler.frame_a"),
                 ("coupler.frame_b", "C.frame_a"), ("C.frame_b", "rocker.frame_b"),
                 ("ground.frame", "base.frame_a"), ("base.frame_b", "D.frame_a"),
                 ("D.frame_b", "rocker.frame_a")]:
        m.connect(a, b)
    return m


def rocker_links(th, w):
    """Centre-of-mass Jacobians (in the absolute angles of crank, coupler, rocker) and
    velocity-product accelerations of the three links."""
    a, b, c = ROCKER["a"], ROCKER["b"], ROCKER["c"]
    z = np.zeros(2)
    J = [np.column_stack([a / 2 * de(th[0]), z, z]),
         np.column_stack([a * de(th[0]), b / 2 * de(th[1]), z]),
         np.column_stack([z, z, c / 2 * de(th[2])])]
    acc = [-a / 2 * e(th[0]) * w[0] ** 2,
           -a * e(th[0]) * w[0] ** 2 - b / 2 * e(th[1]) * w[1] ** 2,
           -c / 2 * e(th[2]) * w[2] ** 2]
    pos = [a / 2 * e(th[0]), a * e(th[0]) + b / 2 * e(th[1]),
           np.array([ROCKER["d"], 0]) + c / 2 * e(th[2])]
    return J, acc, pos


def rocker_reference(y0, t, rate=20.0):
    """Absolute angles with Lagrange multipliers: [M A^T; A 0] [th''; lam] = [-h; gamma]."""
    a, b, c, d = ROCKER["a"], ROCKER["b"], ROCKER["c"], ROCKER["d"]
    masses = [MASS[k] for k in "abc"]
    inertia = np.diag([m * L ** 2 / 12 for m, L in zip(masses, (a, b, c))])

    def rhs(_, y):
        th, w = y[:3], y[3:]
        J, acc, _ = rocker_links(th, w)
        M, h = inertia.copy(), np.zeros(3)
        for Ji, ai, m in zip(J, acc, masses):
            M += m * Ji.T @ Ji
            h += m * Ji.T @ (ai + np.array([0, G]))
        A = np.column_stack([a * de(th[0]), b * de(th[1]), -c * de(th[2])])
        phi = a * e(th[0]) + b * e(th[1]) - c * e(th[2]) - np.array([d, 0])
        gamma = a * e(th[0]) * w[0] ** 2 + b * e(th[1]) * w[1] ** 2 - \
            c * e(th[2]) * w[2] ** 2 - 2 * rate * (A @ w) - rate ** 2 * phi
        K = np.block([[M, A.T], [A, np.zeros((2, 2))]])
        return np.concatenate([w, np.linalg.solve(K, np.concatenate([-h, gamma]))[:3]])
    sol = solve_ivp(rhs, (t[0], t[-1]), y0, method="DOP853", rtol=1e-12, atol=1e-12, t_eval=t)
    return sol.y.T


def rocker_energy(th, w):
    masses = [MASS[k] for k in "abc"]
    lengths = [ROCKER[k] for k in "abc"]
    J, _, pos = rocker_links(th, w)
    E = sum(m * L ** 2 / 24 * wi ** 2 for m, L, wi in zip(masses, lengths, w))
    return E + sum(0.5 * m * (Ji @ w) @ (Ji @ w) + m * G * p[1]
                   for Ji, p, m in zip(J, pos, masses))


@pytest.fixture(scope="module")
def rocker_run():
    return kn.simulate(triple_rocker(), t_end=1.5, n_points=151, rtol=1e-10, atol=1e-10,
                       jit=False)


def test_the_fixed_partition_stops_at_the_crank_dead_point():
    """What happens with the fixed partition (``repartition=False``, as before): the crank
    reaches its dead point at t ~ 1.14 s and the run stops there, by name."""
    with pytest.raises(kn.SimulationError) as info:
        kn.simulate(triple_rocker(), t_end=1.5, n_points=151, jit=False, repartition=False)
    assert "dead point" in info.value.reason and 1.1 < info.value.t_reached < 1.2


def test_a_triple_rocker_runs_past_its_crank_dead_points(rocker_run):
    res = rocker_run
    # it re-partitioned at the dead points, and says so
    assert res.stats["repartitions"] >= 2 and len(res.stats["repartition_times"]) == \
        res.stats["repartitions"]
    assert 1.05 < res.stats["repartition_times"][0] < 1.15
    parts = res.stats["partitions"]
    assert parts[0]["dependent"] == ["B.qd", "D.qd", "C.qd"] and "A.qd" in parts[1]["dependent"]
    # the loop stays closed, the states are the model's own (crank angle and speed)
    system = res.system
    assert res.state_names == system.state_names + system.algebraic_names
    assert np.max(system.constraint_residual(res.states)) < 1e-10
    # the crank reached its limit (it cannot go round) and turned back
    crank = res["pA.angle"]
    assert crank.min() < -1.5 and crank[-1] > crank.min() + 1.0
    # against the Lagrange-multiplier reference in absolute angles
    th = np.column_stack([crank, crank + res["pB.angle"], res["pD.angle"]])
    w = np.column_stack([res["pA.speed"], res["pA.speed"] + res["pB.speed"], res["pD.speed"]])
    ref = rocker_reference(np.concatenate([th[0], w[0]]), res.t)
    assert np.max(np.abs(wrap(ref[:, :3] - th))) < 1e-6
    assert np.max(np.abs(ref[:, 3:] - w)) < 5e-5          # up to ~10 rad/s there
    # undamped: the energy is conserved through the dead points
    energy = np.array([rocker_energy(a, b) for a, b in zip(th, w)])
    assert np.ptp(energy) < 1e-7 * abs(energy[0]) + 1e-6


@pytest.mark.parametrize("loops", ["partition", "baumgarte"])
def test_the_other_formulations_re_partition_too(loops, rocker_run):
    """rocker_run is the default (projected); the partition's DAE and the Baumgarte ODE
    re-partition at the same dead points."""
    res = kn.simulate(triple_rocker().compile(loops=loops), t_end=1.3, n_points=131,
                      rtol=1e-10, atol=1e-10, jit=False)
    assert res.stats["repartitions"] >= 1
    closed = 1e-6 if loops == "baumgarte" else 1e-10    # Baumgarte keeps it small only
    assert np.max(res.system.constraint_residual(res.states)) < closed
    assert np.max(np.abs(wrap(res["pA.angle"] - rocker_run["pA.angle"][:131]))) < 1e-5


def test_a_loop_that_stays_regular_runs_as_before():
    """The default path is unchanged where no partition nears a singular configuration: a
    Grashof four-bar gives the same numbers, to rounding, with and without re-partitioning."""
    system = fourbar(theta0=1.0, thetad0=2.0).compile()
    a = kn.simulate(system, t_end=2.0, n_points=201, jit=False)
    b = kn.simulate(system, t_end=2.0, n_points=201, jit=False, repartition=False)
    assert a.stats["repartitions"] == 0 and a.stats["repartition_times"] == []
    assert_same_numbers(a.states, b.states)
    for name in a.signal_names:
        assert_same_numbers(a[name], b[name])


# -- Multibody.jl's five-revolute loop --------------------------------------------------------
def rhombus_reference(y0, t, l=1.5, m=1.0, inertia=0.001, g=9.80665, d=0.1):
    """The rhombus O-A-B-C in the absolute angles th1 (link 1, O to A) and th2 (link 2, A to
    B): link 3 runs B to C along -e(th1), link 4 C to O along -e(th2), so the loop is closed
    by construction. Lagrange's equations of the four links, the dampers on j1 (= th1) and
    j2 (= th2 - th1 - pi/2)."""
    cm = [(l / 2, 0), (l, l / 2), (l / 2, l), (0, l / 2)]       # in e(th1), e(th2)
    spin = [(1, 0), (0, 1), (1, 0), (0, 1)]

    def rhs(_, y):
        th, w = y[:2], y[2:]
        M, h = np.zeros((2, 2)), np.zeros(2)
        for (c1, c2), s in zip(cm, spin):
            J = np.column_stack([c1 * de(th[0]), c2 * de(th[1])])
            acc = -c1 * e(th[0]) * w[0] ** 2 - c2 * e(th[1]) * w[1] ** 2
            M += m * J.T @ J + inertia * np.outer(s, s)
            h += m * J.T @ (acc + np.array([0, g]))
        rel = w[1] - w[0]
        Q = np.array([-d * w[0] + d * rel, -d * rel])
        return np.concatenate([w, np.linalg.solve(M, Q - h)])
    sol = solve_ivp(rhs, (t[0], t[-1]), y0, method="DOP853", rtol=1e-11, atol=1e-11, t_eval=t)
    return sol.y.T


def test_the_five_revolute_loop_runs_through_its_folds():
    model = kn.load(MODELS / "five_revolute_loop.json")
    with pytest.raises(kn.SimulationError) as info:          # before: stuck at the fold
        kn.simulate(model, t_end=2.0, n_points=201, jit=False, repartition=False)
    assert 1.0 < info.value.t_reached < 1.1
    res = kn.simulate(model, t_end=1.6, n_points=161, rtol=1e-8, atol=1e-8, jit=False)
    assert res.t[-1] == 1.6 and res.stats["repartitions"] >= 2
    assert np.max(res.system.constraint_residual(res.states)) < 1e-10
    # the folds crossed were flat: the links (nearly) in line, j2 near -pi/2 (mod 2 pi)
    j2 = res["probe2.angle"]
    assert np.min(np.abs(wrap(j2 + np.pi / 2))) < 0.05
    # still a rhombus after them (the branch it was on): j3 = -j2
    j3 = res["probe3.angle"]
    assert np.max(np.abs(wrap(j3 + j2))) < 1e-9
    th1, th2 = res["probe1.angle"], res["probe1.angle"] + j2 + np.pi / 2
    w1, w2 = res["probe1.speed"], res["probe1.speed"] + res["probe2.speed"]
    ref = rhombus_reference([th1[0], th2[0], w1[0], w2[0]], res.t)
    early = res.t <= 1.0                                      # before the first fold
    assert np.max(np.abs(wrap(ref[early, 0] - th1[early]))) < 5e-5   # IDAS at 1e-8
    assert np.max(np.abs(wrap(ref[:, 0] - th1))) < 1e-3
    assert np.max(np.abs(wrap(ref[:, 1] - th2))) < 1e-3


def test_a_loop_with_time_events_re_partitions_with_its_relations():
    # a torque of 1e-12 N m from 1.2 to 1.25 s (after the first dead point): two time events
    # met by a re-partitioned System, whose relations the run reads again at the switch
    m = triple_rocker()
    m.add(kn.rotational.Torque("kick", tau="if_else(t < 1.2, 0, if_else(t < 1.25, 1e-12, 0))"))
    m.connect("kick.flange", "A.axis")
    res = kn.simulate(m, t_end=1.5, n_points=151, rtol=1e-10, atol=1e-10, jit=False)
    assert res.stats["repartitions"] >= 2 and res.stats["time_events"] == 2
    assert res.stats["repartition_times"][0] < 1.2
    crank = res["pA.angle"]
    th = np.column_stack([crank, crank + res["pB.angle"], res["pD.angle"]])
    ref = rocker_reference(np.concatenate([th[0], [res["pA.speed"][0],
                                                   res["pA.speed"][0] + res["pB.speed"][0],
                                                   res["pD.speed"][0]]]), res.t)
    assert np.max(np.abs(wrap(ref[:, :3] - th))) < 1e-6
