"""Massless junctions: line forces meeting at a frame with no body (issue 15, item 4).

The junction is placed by the balance of its line forces (algebraic), or, with a damper in
series, through the damper's length as a state. Checked against closed forms of the 1-D
special cases (two springs in series are one spring of c1 c2 / (c1 + c2); a spring and a
damper in series are Maxwell's element) and against an independently written scipy
reference of MSL's ThreeSprings that solves the junction with scipy.optimize inside the
right-hand side.
"""

import pathlib

import numpy as np
import pytest
import scipy.integrate
import scipy.linalg
import scipy.optimize

import kinetwork as kn

G = 9.81
MODELS = pathlib.Path(__file__).resolve().parents[2] / "models"


def series(lower, c1=40.0, m=1.0, l1=0.2, q0=0.8, qd0=0.0):
    """A body on a vertical slider hanging from the ground by spring ``upper`` (c1, l1) and
    ``lower`` in series; the junction between them has no body."""
    model = kn.Model("series")
    model.add(kn.multibody.Ground("ground", gravity=[0, -G, 0]))
    model.add(kn.multibody.Prismatic("slider", axis=[0, -1, 0], q0=q0, qd0=qd0))
    model.add(kn.multibody.RigidBody("mass", mass=m, inertia=[0.01, 0.01, 0.01]))
    model.add(kn.multibody.Spring("upper", c=c1, s_unstretched=l1))
    model.add(lower)
    model.add(kn.Probe("junction", quantities=["position", "velocity", "acceleration",
                                                "force"]))
    for a, b in [("ground.frame", "slider.frame_a"), ("slider.frame_b", "mass.frame_a"),
                 ("ground.frame", "upper.frame_a"), ("upper.frame_b", "lower.frame_a"),
                 ("lower.frame_b", "mass.frame_a"), ("junction.port", "upper.frame_b")]:
        model.connect(a, b)
    return model


def test_two_springs_in_series_are_one_spring_of_the_series_stiffness():
    c1, c2, l1, l2, m, x0 = 40.0, 60.0, 0.2, 0.3, 1.0, 0.8
    model = series(kn.multibody.Spring("lower", c=c2, s_unstretched=l2), c1, m, l1, x0)
    system = model.compile()
    # no state for the junction: its position is an algebraic variable
    assert system.state_names == ["slider.q", "slider.qd"]
    assert system.algebraic_names == [f"upper.frame_b.r[{i}]" for i in range(3)]
    res = kn.simulate(system, t_end=1.5, n_points=31, rtol=1e-11, atol=1e-12)
    c = c1 * c2 / (c1 + c2)
    w = np.sqrt(c / m)
    x_eq = l1 + l2 + m * G / c
    t = res.t
    x = x_eq + (x0 - x_eq) * np.cos(w * t)
    v = -(x0 - x_eq) * w * np.sin(w * t)
    a = -(x0 - x_eq) * w**2 * np.cos(w * t)
    np.testing.assert_allclose(res.states[:, 0], x, atol=1e-8)
    tension = c * (x - l1 - l2)
    assert tension.min() > 0          # the line stays taut: the junction is determined
    # the junction sits where the upper spring carries the tension; it moves c / c1 as fast
    zero = np.zeros_like(t)
    np.testing.assert_allclose(res["junction.position"],
                               np.c_[zero, -(l1 + tension / c1), zero], atol=1e-8)
    np.testing.assert_allclose(res["junction.velocity"], np.c_[zero, -c * v / c1, zero],
                               atol=1e-7)
    np.testing.assert_allclose(res["junction.acceleration"], np.c_[zero, -c * a / c1, zero],
                               atol=1e-6)
    # the flow into the upper spring at the junction: the lower one pulls it down by T
    np.testing.assert_allclose(res["junction.force"], np.c_[zero, -tension, zero], atol=1e-7)


def test_spring_and_damper_in_series_are_maxwells_element():
    """Maxwell's element: T = c1 (s1 - l1) = d sd2; with the body, dx/dt = v,
    dv/dt = g - T/m, dT/dt = c1 (v - T/d), a linear system solved in closed form by the
    matrix exponential. The body starts moving at v0 with the junction at rest, so the
    damper starts with tension d v0 (here m g / 2) and the line stays taut."""
    c1, d, l1, m, x0 = 40.0, 3.0, 0.2, 1.0, 0.8
    v0 = 0.5 * m * G / d
    model = series(kn.multibody.Damper("lower", d=d), c1, m, l1, x0, v0)
    system = model.compile()
    # the damper's length is the state the junction adds; its rate is algebraic
    assert system.state_names == ["slider.q", "slider.qd", "lower.s"]
    assert system.algebraic_names[-1] == "lower.sd"
    res = kn.simulate(system, t_end=2.0, n_points=41, rtol=1e-11, atol=1e-12)
    A = np.array([[0, 1, 0, 0], [0, 0, -1 / m, G], [0, c1, -c1 / d, 0], [0, 0, 0, 0]])
    start = np.array([x0, v0, d * v0, 1.0])
    ref = np.array([scipy.linalg.expm(A * t) @ start for t in res.t])
    x, v, T = ref[:, 0], ref[:, 1], ref[:, 2]
    assert T.min() > 0
    np.testing.assert_allclose(res.states[:, 0], x, atol=1e-8)
    np.testing.assert_allclose(res.states[:, 1], v, atol=1e-8)
    s1 = l1 + T / c1
    np.testing.assert_allclose(res.states[:, 2], x - s1, atol=1e-8)       # damper length
    np.testing.assert_allclose(res["junction.position"][:, 1], -s1, atol=1e-8)
    # the junction moves as the upper spring stretches: dT/dt / c1
    np.testing.assert_allclose(res["junction.velocity"][:, 1], -(v - T / d), atol=1e-7)
    np.testing.assert_allclose(res["junction.force"][:, 1], -T, atol=1e-7)


# -- MSL ThreeSprings against an independent scipy reference -------------------------------
ANCHORS = (np.array([0.3, 0.0, 0.0]), np.array([0.0, 0.0, 0.3]))     # bar1, bar2 ends
C1, C2, C3, L0 = 20.0, 40.0, 20.0, 0.1
MASS, R_CM, INERTIA = 0.8, np.array([0.0, -0.2, 0.0]), 0.1


def _pull(c, frm, to):
    """Force of a spring (c, L0) on the end at ``frm`` whose other end is at ``to``."""
    d = to - frm
    s = np.linalg.norm(d)
    return c * (s - L0) * d / s


def _junction(r, guess):
    """Where the three springs balance: scipy's root finder, from the previous solution."""
    def balance(j):
        return (_pull(C1, j, ANCHORS[0]) + _pull(C3, j, ANCHORS[1]) + _pull(C2, j, r))
    sol = scipy.optimize.root(balance, guess, method="hybr", options={"xtol": 1e-14})
    assert np.max(np.abs(balance(sol.x))) < 1e-10
    return sol.x


def three_springs_reference(t_eval, guess):
    """A free rigid body (Newton-Euler about its centre of mass: isotropic inertia, so
    I dw/dt = moment) pulled at frame_a by spring2 from the junction, under gravity."""
    memo = {"j": np.asarray(guess, dtype=float)}

    def rhs(t, y):
        c, v, R, w = y[:3], y[3:6], y[6:15].reshape(3, 3), y[15:]
        r = c - R @ R_CM                                   # frame_a's origin
        memo["j"] = _junction(r, memo["j"])
        f = _pull(C2, r, memo["j"])
        acc = f / MASS + np.array([0.0, -G, 0.0])
        alpha = np.cross(r - c, f) / INERTIA
        Rdot = np.cross(w[:, None], R, axis=0)             # [w]x R, column by column
        return np.concatenate([v, acc, Rdot.ravel(), alpha])
    r0 = np.array([0.5, -0.3, 0.0])
    y0 = np.concatenate([r0 + R_CM, np.zeros(3), np.eye(3).ravel(), np.zeros(3)])
    sol = scipy.integrate.solve_ivp(rhs, (0, t_eval[-1]), y0, method="DOP853", t_eval=t_eval,
                                    rtol=1e-11, atol=1e-12)
    assert sol.success
    out = []
    for y in sol.y.T:
        c, v, R, w = y[:3], y[3:6], y[6:15].reshape(3, 3), y[15:]
        r = c - R @ R_CM
        rdot = v + np.cross(w, r - c)
        memo["j"] = j = _junction(r, memo["j"])
        # the junction's velocity: a central difference of its balance along frame_a's path
        h = 1e-6
        jdot = (_junction(r + h * rdot, j) - _junction(r - h * rdot, j)) / (2 * h)
        out.append(np.concatenate([r, j, jdot]))
    return np.array(out)


def test_msl_three_springs_matches_an_independent_scipy_reference():
    model = kn.load(MODELS / "three_springs.json")
    system = model.compile()
    assert len(system.state_names) == 13 and system.n_algebraic == 3
    res = kn.simulate(system, t_end=1.5, n_points=16, rtol=1e-11, atol=1e-12, jit=False)
    ref = three_springs_reference(res.t, system.z0)
    np.testing.assert_allclose(res["body1_frame.position"], ref[:, :3], atol=1e-7)
    np.testing.assert_allclose(res["junction.position"], ref[:, 3:6], atol=1e-7)
    # what spring2 takes at the junction: minus its pull on it, towards body1
    pulls = np.array([_pull(C2, j, r) for r, j in zip(ref[:, :3], ref[:, 3:6])])
    np.testing.assert_allclose(res["junction.force"], -pulls, atol=1e-6)
    # the junction's velocity (the implicit-function theorem in kinetwork)
    np.testing.assert_allclose(res["junction.velocity"], ref[:, 6:], atol=1e-6)
    # the start: the junction balanced where MSL's r_rel_0 guess of spring1 points near
    assert np.linalg.norm(system.z0 - (ANCHORS[0] + [-0.2, -0.2, 0.2])) < 0.3


def test_junction_energy_is_conserved():
    """Nothing dissipates in ThreeSprings: kinetic + gravity + the three springs' energy
    stays constant, the junction's springs included (a check of its generalized forces)."""
    model = kn.load(MODELS / "three_springs.json")
    res = kn.simulate(model, t_end=1.0, n_points=11, rtol=1e-11, atol=1e-12, jit=False)
    X = res.states
    r, quat, v, w = X[:, 0:3], X[:, 3:7], X[:, 7:10], X[:, 10:13]
    j = res["junction.position"]
    energy = []
    for k in range(len(res.t)):
        a, b, c, d = quat[k]
        R = np.array([[a*a+b*b-c*c-d*d, 2*(b*c-a*d), 2*(b*d+a*c)],
                      [2*(b*c+a*d), a*a-b*b+c*c-d*d, 2*(c*d-a*b)],
                      [2*(b*d-a*c), 2*(c*d+a*b), a*a-b*b-c*c+d*d]])
        vc = v[k] + R @ np.cross(w[k], R_CM)      # the centre of mass; w is in frame_b
        cm = r[k] + R @ R_CM
        springs = sum(0.5 * cc * (np.linalg.norm(p - j[k]) - L0)**2
                      for cc, p in ((C1, ANCHORS[0]), (C3, ANCHORS[1]), (C2, r[k])))
        energy.append(0.5 * MASS * vc @ vc + 0.5 * INERTIA * w[k] @ w[k] + MASS * G * cm[1]
                      + springs)
    energy = np.array(energy)
    assert np.ptp(energy) < 1e-9          # of about 2.4 J


# -- refusals ---------------------------------------------------------------------------------
def _hanging(extra):
    model = kn.Model("refused")
    model.add(kn.multibody.Ground("ground"))
    model.add(kn.multibody.Prismatic("slider", axis=[0, -1, 0], q0=0.5))
    model.add(kn.multibody.RigidBody("mass", mass=1.0))
    model.connect("ground.frame", "slider.frame_a")
    model.connect("slider.frame_b", "mass.frame_a")
    extra(model)
    return model


def test_a_spring_end_nothing_holds_is_refused_by_name():
    def one(model):
        model.add(kn.multibody.Spring("loose", c=10.0))
        model.connect("ground.frame", "loose.frame_a")
        model.add(kn.Probe("p", quantities=["position"]))
        model.connect("p.port", "loose.frame_b")
    with pytest.raises(kn.ModelError, match=r"port loose.frame_b \(frame\) is not connected"):
        _hanging(one).compile()


def test_a_force_at_a_junction_and_a_point_mass_there_are_refused_by_name():
    def force(model):
        model.add(kn.multibody.Spring("s1", c=10.0))
        model.add(kn.multibody.Force("push", f=[0, 1, 0]))
        model.connect("ground.frame", "s1.frame_a")
        model.connect("s1.frame_b", "push.frame_b")
        model.connect("push.frame_a", "mass.frame_a")
    with pytest.raises(kn.ModelError, match=r"push.*massless junction.*only line forces"):
        _hanging(force).compile()

    def heavy(model):
        model.add(kn.multibody.Spring("s1", c=10.0, mass=0.2))
        model.add(kn.multibody.Spring("s2", c=10.0))
        model.connect("ground.frame", "s1.frame_a")
        model.connect("s1.frame_b", "s2.frame_a")
        model.connect("s2.frame_b", "mass.frame_a")
    with pytest.raises(kn.ModelError, match=r"s1.*mass.*massless junction"):
        _hanging(heavy).compile()


def test_junctions_that_reach_no_placed_frame_are_refused():
    def ring(model):
        model.add(kn.multibody.Spring("s1", c=10.0))
        model.add(kn.multibody.Spring("s2", c=10.0))
        model.connect("s1.frame_a", "s2.frame_a")
        model.connect("s1.frame_b", "s2.frame_b")
    with pytest.raises(kn.ModelError, match=r"reach no frame"):
        _hanging(ring).compile()


def test_a_slack_series_chain_at_the_start_is_refused_by_name():
    """A spring and damper in series starting at rest carry no tension: nothing holds their
    junction across the line, so the balance is singular there."""
    model = series(kn.multibody.Damper("lower", d=3.0))
    with pytest.raises(kn.ModelError, match=r"junction\(s\) upper.frame_b: .* no tension"):
        model.compile()
