"""Initial conditions as equations: MSL's InitSpringConstant (the spring constant that holds a
pendulum still at its start) on a rotational spring and on a line spring, against the closed
forms of their moment balance; an equilibrium solved for the angle (scipy's brentq on the same
balance); a DC motor started in its steady run from given derivatives (the closed-form
operating point); refusals; the file form."""

import json

import numpy as np
import pytest
import scipy.optimize

import kinetwork as kn
from kinetwork.equations.initial import solved

G, MASS, ARM = 9.81, 2.0, 0.8


def _pendulum(q0=-0.3, c=100.0, phi_rel0=0.0):
    m = kn.Model("isc", parameters={"c": c})
    for comp in (kn.multibody.Ground("ground", gravity=[0, -G, 0]),
                 kn.multibody.Revolute("rev", axis=[0, 0, 1], q0=q0),
                 kn.multibody.RigidBody("bob", mass=MASS, r_cm=[ARM, 0, 0], inertia=[0, 0, 0]),
                 kn.rotational.Spring("spring", c="c", phi_rel0=phi_rel0),
                 kn.Probe("p", quantities=["angle", "speed"])):
        m.add(comp)
    for a, b in [("ground.frame", "rev.frame_a"), ("rev.frame_b", "bob.frame_a"),
                 ("spring.flange_a", "rev.support"), ("spring.flange_b", "rev.axis"),
                 ("p.port", "rev.axis")]:
        m.connect(a, b)
    return m


def test_init_spring_constant_on_a_rotational_spring():
    m = _pendulum()
    m.set_initial(steady=True, fixed=["rev.q"], solve=["c"])
    c = MASS * G * ARM * np.cos(0.3) / 0.3          # c (0 - q0) = m g l cos q0
    assert solved(m.compile()) == pytest.approx({"c": c, "rev.qd": 0.0}, rel=1e-12, abs=1e-12)
    assert m.compile().initial_values({"c": 10.0})["c"] == pytest.approx(c, rel=1e-12)
    res = kn.simulate(m, t_end=1.0, n_points=5, rtol=1e-10, atol=1e-12, jit=False)
    assert np.max(abs(res["p.angle"] + 0.3)) < 1e-9 and np.max(abs(res["p.speed"])) < 1e-8
    # the same from a given derivative: no acceleration at the start, c the unknown
    m.set_initial(derivatives={"rev.qd": 0}, solve=["c"])
    assert solved(m.compile())["c"] == pytest.approx(c, rel=1e-12)


def test_init_spring_constant_on_a_line_spring_as_msl():
    """MSL's Examples.Elementary.InitSpringConstant: a spring from a world point to the tip of
    a pendulum; the constant found keeps it at rest."""
    q0, h, s0 = 0.2, 0.7, 0.1
    m = kn.Model("line", parameters={"c": 50.0})
    for comp in (kn.multibody.Ground("ground", gravity=[0, -G, 0]),
                 kn.multibody.Revolute("rev", axis=[0, 0, 1], q0=q0),
                 kn.multibody.FixedTranslation("rod", r=[ARM, 0, 0]),
                 kn.multibody.RigidBody("bob", mass=MASS, inertia=[0, 0, 0]),
                 kn.multibody.FixedTranslation("anchor", r=[ARM, h, 0]),
                 kn.multibody.Spring("spring", c="c", s_unstretched=s0),
                 kn.Probe("p", quantities=["angle"])):
        m.add(comp)
    for a, b in [("ground.frame", "rev.frame_a"), ("rev.frame_b", "rod.frame_a"),
                 ("rod.frame_b", "bob.frame_a"), ("ground.frame", "anchor.frame_a"),
                 ("anchor.frame_b", "spring.frame_a"), ("rod.frame_b", "spring.frame_b"),
                 ("p.port", "rev.axis")]:
        m.connect(a, b)
    m.set_initial(steady=True, fixed=["rev.q"], solve=["c"])
    tip = ARM * np.array([np.cos(q0), np.sin(q0)])
    d = np.array([ARM, h]) - tip
    length = np.hypot(*d)
    moment = (length - s0) / length * (tip[0] * d[1] - tip[1] * d[0])   # per unit c
    c = MASS * G * tip[0] / moment
    assert solved(m.compile())["c"] == pytest.approx(c, rel=1e-12)
    res = kn.simulate(m, t_end=0.5, n_points=3, rtol=1e-10, atol=1e-12, jit=False)
    assert np.max(abs(res["p.angle"] - q0)) < 1e-9


def test_steady_state_solves_the_angle():
    m = _pendulum(q0=0.0, c=40.0)
    m.set_initial(steady=True)
    q = solved(m.compile())["rev.q"]
    ref = scipy.optimize.brentq(lambda q: -40.0 * q - MASS * G * ARM * np.cos(q), -2, 0,
                                xtol=1e-15)
    assert q == pytest.approx(ref, abs=1e-12)
    assert kn.simulate(m, t_end=0.5, n_points=3, jit=False)["p.angle"] == pytest.approx([ref] * 3,
                                                                             abs=1e-9)


def test_dc_motor_started_in_its_steady_run():
    """Given derivatives on electrical and mechanical states: no change of current and
    speed, both unknown: i = d w / k, V = R i + k w."""
    R, L, k, J, d, V = 1.2, 0.05, 0.3, 2e-3, 0.01, 12.0
    m = kn.Model("run")
    E = kn.electrical
    for comp in (E.Ground("g"), E.VoltageSource("src", V=V),
                 E.DCMotor("motor", R=R, L=L, k=k, J=J), kn.rotational.Damper("friction", d=d),
                 kn.rotational.Fixed("housing"), kn.Probe("pw", quantities=["speed"])):
        m.add(comp)
    for a, b in [("src.p", "motor.p"), ("motor.n", "src.n"), ("g.p", "src.n"),
                 ("motor.flange", "friction.flange_b"), ("friction.flange_a", "housing.flange"),
                 ("motor.support", "housing.flange"), ("pw.port", "motor.flange")]:
        m.connect(a, b)
    m.set_initial(derivatives={"motor.La.i": 0, "motor.rotor.w": 0},
                  solve=["motor.La.i", "motor.rotor.w"])
    w = V * k / (R * d + k ** 2)
    assert solved(m.compile()) == pytest.approx({"motor.rotor.w": w, "motor.La.i": d * w / k},
                                                rel=1e-12)
    res = kn.simulate(m, t_end=0.5, n_points=3, rtol=1e-10, atol=1e-12, jit=False)
    assert res["pw.speed"] == pytest.approx([w] * 3, rel=1e-9)
    # a steady state of everything leaves the rotor's angle to nothing: refused by name
    m.set_initial(steady=True)
    with pytest.raises(kn.ModelError, match=r"do not determine motor.rotor.phi"):
        m.compile().x0


def test_initial_equations_that_cannot_hold_are_refused():
    m = _pendulum()
    m.set_initial(steady=True, solve=["c"])
    with pytest.raises(kn.ModelError, match=r"2 equation\(s\).*3 unknown\(s\)"):
        m.compile().x0
    m.set_initial(steady=True, fixed=["rev.q"], solve=["k"])
    with pytest.raises(kn.ModelError, match=r"initial.solve\[0\]: 'k' is neither"):
        m.compile().x0
    m.set_initial(derivatives={"rev.q": 0}, solve=["rev.qd"], steady=False)
    assert solved(m.compile())["rev.qd"] == 0.0
    # a spring that is unstretched at the start cannot hold the pendulum, whatever its c
    m = _pendulum(q0=-0.3, phi_rel0=-0.3)
    m.set_initial(steady=True, fixed=["rev.q"], solve=["c"])
    with pytest.raises(kn.ModelError, match=r"cannot satisfy der\(rev.q\) = 0, der\(rev.qd\)"):
        m.compile().x0
    with pytest.raises(kn.ModelError, match=r"initial.fixed: only with steady"):
        m.set_initial(fixed=["rev.q"])


def test_initial_in_files(tmp_path):
    m = _pendulum()
    m.set_initial(steady=True, fixed=["rev.q"], solve=["c"])
    path = tmp_path / "isc.json"
    m.save(path)
    text = path.read_text()
    assert json.loads(text)["initial"] == {"steady": True, "fixed": ["rev.q"], "solve": ["c"]}
    again = kn.load(path)
    again.save(tmp_path / "again.json")
    assert (tmp_path / "again.json").read_text() == text
    assert solved(again.compile())["c"] == pytest.approx(solved(m.compile())["c"], rel=1e-14)
    data = json.loads(text)
    data["initial"] = {"steady": "yes", "solv": ["c"]}
    with pytest.raises(kn.ModelError, match=r"initial.solv: unknown key.*solve") as err:
        kn.loads(json.dumps(data))
    assert any("initial.steady: must be true or false" in p for p in err.value.problems)


def test_msl_init_spring_constant_model_file():
    """models/init_spring_constant.json, MSL's example part for part: its documentation's
    c = 49.05 N/m (m g r_CM over the spring's stretch, 1 * 9.81 * 0.5 / 0.1), and at rest."""
    path = __import__("pathlib").Path(__file__).resolve().parents[2] / "models" / \
        "init_spring_constant.json"
    model = kn.load(path)
    assert solved(model.compile())["c"] == pytest.approx(9.81 * 0.5 / 0.1, rel=1e-12)
    res = kn.simulate(model, t_end=1.0, n_points=11, rtol=1e-10, atol=1e-12, jit=False)
    assert np.max(abs(res["angle.angle"])) < 1e-9


def _held_rotor(phi0, w0=None):
    """A unit rotor on a spring (c = 50) to the ground, held by a BearingFriction of
    0.5 N*m (peak 1)."""
    rot = kn.rotational
    m = kn.Model("held_rotor")
    m.add(rot.Inertia("J", J=1.0, phi0=phi0, w0=w0))
    m.add(rot.Spring("spring", c=50.0))
    m.add(rot.Fixed("ground"))
    m.add(rot.BearingFriction("bearing", tau_c=0.5))
    m.connect("spring.flange_a", "ground.flange")
    m.connect("spring.flange_b", "J.flange_a")
    m.connect("bearing.flange", "J.flange_b")
    m.set_initial(derivatives={"J.w": 0}, solve=["J.phi"])
    return m


def test_a_start_the_friction_cannot_hold_is_refused():
    """At rest at phi = 1 the spring pulls 50 N*m: the bearing (0.5 N*m) cannot hold, so
    der(J.w) = 0 is no start there (the run would begin at -49.5 rad/s^2)."""
    with pytest.raises(kn.ModelError, match=r"initial: the start solved for \(J.phi = 1\) "
                                            r"keeps der\(J.w\) = 0 only with a friction stuck "
                                            r"where it cannot hold: bearing: at rest there, it "
                                            r"would have to hold 50 beyond its static limit "
                                            r"0.5"):
        _held_rotor(1.0).compile().initial_state()


def test_a_start_the_friction_holds_stays_and_a_sliding_one_is_solved_with_its_law():
    held = _held_rotor(0.005)                    # the spring pulls 0.25 N*m: it holds
    res = kn.simulate(held, t_end=0.2, n_points=3, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(res["J.phi"], 0.005, atol=1e-12)
    # sliding forward at 1 rad/s: der(w) = -50 phi - 0.5 = 0 at phi = -0.01
    sliding = _held_rotor(0.3, w0=1.0).compile()
    x0 = dict(zip(sliding.state_names, sliding.initial_state()))
    assert x0["J.phi"] == pytest.approx(-0.01, abs=1e-12)
    assert sliding.rhs(0.0, sliding.initial_state())[sliding.state_names.index("J.w")] == \
        pytest.approx(0.0, abs=1e-9)


def test_what_the_solver_prints_on_a_failed_start_is_captured_and_summarised(capfd):
    """A start Newton cannot find (the pendulum's length solved for an acceleration gravity
    cannot give: NaN on the way) is refused with CasADi's warnings summarised in the error;
    nothing reaches the terminal."""
    mb = kn.multibody
    m = kn.Model("pendulum", parameters={"L": 1.0})
    m.add(mb.Ground("ground"))
    m.add(mb.Revolute("j", q0=0.3))
    m.add(mb.RigidBody("bob", mass=1.0, r_cm=["L", 0, 0]))
    m.connect("ground.frame", "j.frame_a")
    m.connect("j.frame_b", "bob.frame_a")
    m.set_initial(derivatives={"j.qd": 1.0}, solve=["L"])
    capfd.readouterr()
    with pytest.raises(kn.ModelError, match=r"initial: the model cannot satisfy der\(j.qd\) = 1 "
                                            r"with L as unknowns: .*\(the solver said \d+ lines?:"
                                            r" initial:g failed: NaN detected"):
        m.compile().initial_state()
    out, err = capfd.readouterr()
    assert out == "" and err == ""
