"""A translational Mass of length L, as MSL's: s is its centre, flange_a at s - L/2 and
flange_b at s + L/2. MSL's Translational.Examples.InitialConditions (its first system, at
rest by construction), a mass on a spring oscillating about the rest its length sets
(closed form), a mass on a prismatic joint's axis (the spring sees the far flange), a
Position moving a mass's flange_b, and two masses in a row sharing one state."""

import numpy as np
import pytest

import kinetwork as kn

T = kn.translational
TOL = dict(rtol=1e-10, atol=1e-12, jit=False)


def _model(parts, wires, name="m"):
    m = kn.Model(name)
    for c in parts:
        m.add(c)
    for a, b in wires:
        m.connect(a, b)
    return m


def test_msl_initial_conditions_first_system_stays_at_rest():
    """fixed2 at 1 m, s2 of 2 m unstretched, m3 of 3 m, sd2 of 4 m, m4 of 5 m: MSL's
    documentation adds them up to m3.s = 4.5 and m4.s = 12.5, where nothing moves."""
    m = _model([T.Fixed("fixed2", s0=1.0), T.Spring("s2", c=1e3, s_rel0=2.0),
                T.Mass("m3", m=1.0, L=3.0, s0=4.5, v0=0.0),
                T.SpringDamper("sd2", c=111.0, d=1.0, s_rel0=4.0),
                T.Mass("m4", m=1.0, L=5.0, s0=12.5, v0=0.0),
                kn.Probe("a3", quantities=["position", "force"]),
                kn.Probe("b4", quantities=["position"])],
               [("s2.flange_a", "fixed2.flange"), ("m4.flange_a", "sd2.flange_b"),
                ("sd2.flange_a", "m3.flange_b"), ("m3.flange_a", "s2.flange_b"),
                ("a3.port", "m3.flange_a"), ("b4.port", "m4.flange_b")], "InitialConditions")
    system = m.compile()
    assert system.state_names == ["m3.s", "m3.v", "m4.s", "m4.v"]
    assert np.allclose(system.x0, [4.5, 0, 12.5, 0])
    res = kn.simulate(m, t_end=5.0, n_points=51, **TOL)
    assert np.max(abs(res["a3.position"] - 3.0)) < 1e-12       # 4.5 - 3/2
    assert np.max(abs(res["b4.position"] - 15.0)) < 1e-12      # 12.5 + 5/2
    assert np.max(abs(res.states[:, [0, 2]] - [4.5, 12.5])) < 1e-12
    assert np.max(abs(res["a3.force"])) < 1e-9


def test_a_mass_on_a_spring_oscillates_about_the_rest_its_length_sets():
    """Spring from a Fixed at 2 m (unstretched 1 m) to flange_b of a mass of length 1 m: at
    rest its centre is at 2 - 1 - 0.5 = 0.5 m; started at 0.8 m, s = 0.5 + 0.3 cos(w t)."""
    m = _model([T.Fixed("wall", s0=2.0), T.Spring("k", c=400.0, s_rel0=1.0),
                T.Mass("mass", m=4.0, L=1.0, s0=0.8), kn.Probe("pa", quantities=["position"])],
               [("mass.flange_b", "k.flange_a"), ("k.flange_b", "wall.flange"),
                ("pa.port", "mass.flange_a")])
    res = kn.simulate(m, t_end=2.0, n_points=41, **TOL)
    s = 0.5 + 0.3 * np.cos(10.0 * res.t)
    assert np.max(abs(res.states[:, 0] - s)) < 1e-8
    assert np.max(abs(res["pa.position"] - (s - 0.5))) < 1e-8


def test_a_mass_on_a_joint_axis_carries_its_length_to_what_it_is_wired_to():
    """A prismatic joint's axis at flange_b of a 0.4 m mass; a spring from a Fixed at 0 to
    its flange_a (unstretched 0): the joint rests at q = 0.4 m and, started 0.1 m beyond,
    oscillates with the mass and the body as one inertia."""
    mb = kn.multibody
    m = _model([mb.Ground("ground", gravity=[0, 0, 0]),
                mb.Prismatic("slide", axis=[1, 0, 0], q0=0.5),
                mb.RigidBody("body", mass=1.0, inertia=[0, 0, 0]),
                T.Mass("mass", m=3.0, L=0.4), T.Spring("k", c=16.0),
                T.Fixed("anchor", s0=0.0), kn.Probe("pa", quantities=["position"])],
               [("ground.frame", "slide.frame_a"), ("slide.frame_b", "body.frame_a"),
                ("slide.axis", "mass.flange_b"), ("mass.flange_a", "k.flange_b"),
                ("k.flange_a", "anchor.flange"), ("pa.port", "mass.flange_a")])
    res = kn.simulate(m, t_end=2.0, n_points=41, **TOL)
    q = 0.4 + 0.1 * np.cos(2.0 * res.t)
    assert res.state_names[0] == "slide.q"
    assert np.max(abs(res.states[:, 0] - q)) < 1e-8
    assert np.max(abs(res["pa.position"] - (q - 0.4))) < 1e-8


def test_a_position_source_on_flange_b_places_flange_a_a_length_behind():
    m = _model([T.Position("drive", s_ref="sin(t)"), T.Mass("mass", m=2.0, L=0.6),
                kn.Probe("pa", quantities=["position", "force"])],
               [("drive.flange", "mass.flange_b"), ("pa.port", "mass.flange_a")])
    res = kn.simulate(m, t_end=1.0, n_points=11, **TOL)
    assert np.max(abs(res["pa.position"] - (np.sin(res.t) - 0.6))) < 1e-12


@pytest.mark.parametrize("order, b2", [(("m1", "m2"), 2.5), (("m2", "m1"), 1.0)])
def test_masses_in_a_row_are_one_state_at_the_first_centre(order, b2):
    """m1 (L = 1) then m2 (L = 2) flange to flange, pushed by 3 N: one rigid group, its
    state the centre of the first mass placed, at 0: m2.flange_b is 2.5 m ahead of m1's
    centre, 1 m ahead of m2's."""
    parts = {"m1": T.Mass("m1", m=1.0, L=1.0), "m2": T.Mass("m2", m=2.0, L=2.0)}
    m = _model([parts[order[0]], parts[order[1]], T.Force("push", f=3.0),
                kn.Probe("b2", quantities=["position"])],
               [("m1.flange_b", "m2.flange_a"), ("push.flange", "m1.flange_a"),
                ("b2.port", "m2.flange_b")])
    system = m.compile()
    assert system.state_names == [f"{order[0]}.s", f"{order[0]}.v"]
    res = kn.simulate(m, t_end=1.0, n_points=11, **TOL)
    assert np.max(abs(res["b2.position"] - (b2 + 0.5 * res.t ** 2))) < 1e-10
