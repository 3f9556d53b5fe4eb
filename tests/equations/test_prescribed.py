"""Prescribed motion on joint axes (rotational / translational Position, Speed, Accelerate
wired to a joint's axis): the joint follows the motion, costs no state, the other joints move
freely and the drive torque is a probe quantity. Checked against independent references:
the seed paper's closed-form M, V, G with the shoulder's angle given (scipy's solve_ivp), a
driven cart pendulum written by hand, the four-bar's closed-form closure and energy balance
(``reference_loops``), and the sources' filters simulated by scipy.signal.lsim."""

import numpy as np
import pytest
from scipy import signal
from scipy.integrate import cumulative_simpson, solve_ivp

import kinetwork as kn
from close import assert_same_numbers
from scenes import double_pendulum, fourbar
from scenes import reference_loops as ref
from scenes.reference import PAPER, seed_mvg

rot, tr, sig, mb = kn.rotational, kn.translational, kn.signals, kn.multibody
TOL = {"rtol": 1e-11, "atol": 1e-12}
T_END, N = 5.0, 101
#: the shoulder's prescribed angle 0.5 sin(2 t), with its rates
SHOULDER = (lambda t: 0.5 * np.sin(2 * t), lambda t: np.cos(2 * t),
            lambda t: -2 * np.sin(2 * t))
#: Modelica's Bessel filter of Position (exact=false), phi_ref / (1 + af s/wc + bf s^2/wc^2)
AF, BF = 1.3617, 0.6180


def driven_arm(source, q2=0.3, probe_source=True):
    """The seed's arm (spring-damper at the shoulder) with ``source`` on the shoulder axis;
    a probe on the source's flange too."""
    model = double_pendulum(q0=(None, q2))
    model.add(source)
    model.connect(f"{source.name}.flange", "shoulder.axis")
    if probe_source:
        model.add(kn.Probe("drive_probe", quantities=["angle", "torque"]))
        model.connect("drive_probe.port", f"{source.name}.flange")
    return model


def elbow_reference(t, q1, q2=0.3):
    """Elbow angle and speed from the paper's closed form with the shoulder given:
    M21 q1'' + M22 q2'' + V2 + G2 = 0; and the torque the shoulder needs, row 1
    (M11 q1'' + M12 q2'' + V1 + G1, the spring-damper in V1)."""
    a, ad, add = q1

    def accel(tk, y):
        M, V, G = seed_mvg((a(tk), y[0]), (ad(tk), y[1]), **PAPER)
        return (-(V[1] + G[1]) - M[1, 0] * add(tk)) / M[1, 1]

    sol = solve_ivp(lambda tk, y: [y[1], accel(tk, y)], (t[0], t[-1]), [q2, 0.0],
                    t_eval=t, method="DOP853", rtol=1e-13, atol=1e-14)
    tau = []
    for tk, y in zip(t, sol.y.T):
        M, V, G = seed_mvg((a(tk), y[0]), (ad(tk), y[1]), **PAPER)
        tau.append(M[0, 0] * add(tk) + M[0, 1] * accel(tk, y) + V[0] + G[0])
    return sol.y[0], np.array(tau)


@pytest.fixture(scope="module")
def shoulder_run():
    model = driven_arm(rot.Position("drive", phi_ref="0.5*sin(2*t)"))
    system = model.compile()
    return system, kn.simulate(system, t_end=T_END, n_points=N, **TOL)


def test_a_prescribed_shoulder_costs_no_state(shoulder_run):
    system, _ = shoulder_run
    assert system.state_names == ["elbow.q", "elbow.qd"]
    assert system.formulation == "hybrid" and system.dof == 1
    assert "shoulder by drive" in system.formulation_note


def test_the_elbow_swings_freely_under_the_prescribed_shoulder(shoulder_run):
    _, res = shoulder_run
    t = res.t
    elbow, _ = elbow_reference(t, SHOULDER)
    assert np.max(np.abs(res["probe2.angle"] - elbow)) < 1e-8
    for quantity, exact in zip(("angle", "speed", "acceleration"), SHOULDER):
        assert np.max(np.abs(res[f"probe1.{quantity}"] - exact(t))) < 1e-12, quantity


def test_the_drive_torque_is_row_one_of_the_closed_form(shoulder_run):
    """The source's flange takes the flow into the source, -(M11 q1'' + M12 q2'' + V1 + G1);
    the shoulder's axis the torque its 1-D elements apply together (drive and spring-damper:
    the row without the spring-damper)."""
    _, res = shoulder_run
    t = res.t
    _, tau = elbow_reference(t, SHOULDER)
    assert np.max(np.abs(res["drive_probe.torque"] + tau)) < 1e-8
    spring = PAPER["c"] * SHOULDER[0](t) + PAPER["d"] * SHOULDER[1](t)
    assert np.max(np.abs(res["probe1.torque"] - (tau - spring))) < 1e-8


@pytest.mark.parametrize("source, states", [
    (rot.Speed("drive", w_ref="cos(2*t)"), ["drive.phi"]),
    (rot.Accelerate("drive", a_ref="-2*sin(2*t)", w0=1.0), ["drive.phi", "drive.w"]),
    (rot.Position("drive"), []),              # the reference from a Sine block, exactly
], ids=["Speed", "Accelerate", "Position from a signal"])
def test_speed_accelerate_and_signals_give_the_same_motion(source, states):
    model = driven_arm(source)
    if source.type_name == "rotational.Position":
        model.add(sig.Sine("sine", amplitude=0.5, f=1 / np.pi))
        model.connect("sine.y", "drive.u")
    system = model.compile()
    assert system.state_names == ["elbow.q", "elbow.qd"] + states
    res = kn.simulate(system, t_end=T_END, n_points=N, **TOL)
    elbow, tau = elbow_reference(res.t, SHOULDER)
    assert np.max(np.abs(res["probe1.angle"] - SHOULDER[0](res.t))) < 1e-8
    assert np.max(np.abs(res["probe2.angle"] - elbow)) < 1e-8
    assert np.max(np.abs(res["drive_probe.torque"] + tau)) < 1e-7


def test_a_position_through_a_gear_and_a_rotor():
    """Position -> rotor (J) -> IdealGear (ratio n) -> shoulder: the shoulder turns by the
    reference / n, the rotor's inertia folds into the joint (J n^2, no state), and the source
    gives (row 1 + J n^2 q1'') / n."""
    n, J = 10.0, 0.01
    model = double_pendulum(q0=(None, 0.3))
    model.add(rot.Position("drive", phi_ref="5*sin(2*t)"))
    model.add(rot.Inertia("rotor", J=J))
    model.add(rot.IdealGear("gear", ratio=n))
    model.add(kn.Probe("drive_probe", quantities=["angle", "torque"]))
    for a, b in (("drive.flange", "rotor.flange_a"), ("rotor.flange_b", "gear.flange_a"),
                 ("gear.flange_b", "shoulder.axis"), ("drive_probe.port", "drive.flange")):
        model.connect(a, b)
    system = model.compile()
    assert system.state_names == ["elbow.q", "elbow.qd"]
    res = kn.simulate(system, t_end=T_END, n_points=N, **TOL)
    t = res.t
    elbow, tau = elbow_reference(t, SHOULDER)
    assert np.max(np.abs(res["probe1.angle"] - SHOULDER[0](t))) < 1e-12
    assert np.max(np.abs(res["drive_probe.angle"] - n * SHOULDER[0](t))) < 1e-11
    assert np.max(np.abs(res["probe2.angle"] - elbow)) < 1e-8
    need = tau + J * n ** 2 * SHOULDER[2](t)
    assert np.max(np.abs(res["drive_probe.torque"] + need / n)) < 1e-8


def cart_pendulum(motion):
    """A cart on a Prismatic along x (mass 2), a pendulum (point mass 0.5 at L = 0.8) on a
    Revolute on the cart; ``motion`` drives the cart's axis."""
    m = kn.Model("cart", parameters={"M": 2.0, "m": 0.5, "L": 0.8, "g": 9.81})
    m.add(mb.Ground("ground", gravity=[0, "-g", 0]))
    m.add(mb.Prismatic("cart", axis=[1, 0, 0]))
    m.add(mb.RigidBody("cart_mass", mass="M"))
    m.add(mb.Revolute("pivot", axis=[0, 0, 1], q0=0.4))
    m.add(mb.RigidBody("bob", mass="m", r_cm=[0, "-L", 0]))
    m.add(motion)
    m.add(kn.Probe("cart_probe", quantities=["position", "velocity", "acceleration", "force"]))
    m.add(kn.Probe("source_probe", quantities=["force"]))
    m.add(kn.Probe("angle", quantities=["angle"]))
    for a, b in (("ground.frame", "cart.frame_a"), ("cart.frame_b", "cart_mass.frame_a"),
                 ("cart.frame_b", "pivot.frame_a"), ("pivot.frame_b", "bob.frame_a"),
                 (f"{motion.name}.flange", "cart.axis"), ("cart_probe.port", "cart.axis"),
                 ("source_probe.port", f"{motion.name}.flange"), ("angle.port", "pivot.axis")):
        m.connect(a, b)
    return m


@pytest.mark.parametrize("motion", [
    tr.Position("drive", s_ref="0.3*sin(3*t)"),
    tr.Speed("drive", v_ref="0.9*cos(3*t)"),
    tr.Accelerate("drive", a_ref="-2.7*sin(3*t)", v0=0.9),
], ids=["Position", "Speed", "Accelerate"])
def test_a_driven_cart_swings_its_pendulum(motion):
    """m L^2 th'' + m L cos(th) s'' + m g L sin(th) = 0 with s = 0.3 sin(3 t); the force the
    cart needs is (M + m) s'' + m L (cos(th) th'' - sin(th) th'^2)."""
    M, m_, L, g = 2.0, 0.5, 0.8, 9.81
    s = (lambda t: 0.3 * np.sin(3 * t), lambda t: 0.9 * np.cos(3 * t),
         lambda t: -2.7 * np.sin(3 * t))

    def thdd(t, th, thd):
        return -(np.cos(th) * s[2](t) + g * np.sin(th)) / L

    system = cart_pendulum(motion).compile()
    assert "cart.q" not in system.state_names and system.dof == 1
    res = kn.simulate(system, t_end=T_END, n_points=N, **TOL)
    t = res.t
    sol = solve_ivp(lambda tk, y: [y[1], thdd(tk, *y)], (0, T_END), [0.4, 0.0], t_eval=t,
                    method="DOP853", rtol=1e-13, atol=1e-14)
    th, thd = sol.y
    force = (M + m_) * s[2](t) + m_ * L * (np.cos(th) * thdd(t, th, thd)
                                           - np.sin(th) * thd ** 2)
    assert np.max(np.abs(res["angle.angle"] - th)) < 1e-8
    assert np.max(np.abs(res["cart_probe.position"] - s[0](t))) < 1e-8
    assert np.max(np.abs(res["cart_probe.force"] - force)) < 1e-7
    assert np.max(np.abs(res["source_probe.force"] + force)) < 1e-7


def driven_fourbar(source):
    """The four-bar of ``reference_loops`` with its crank A moved by ``source``."""
    model = fourbar(theta0=1.0)
    model.components["A"].set_param("q0", None)
    model.components["A"].set_param("qd0", None)
    model.add(source)
    model.add(kn.Probe("drive_probe", quantities=["torque"]))
    model.connect(f"{source.name}.flange", "A.axis")
    model.connect("drive_probe.port", f"{source.name}.flange")
    return model


#: the crank's angle 1 + 2 t + 0.3 sin(3 t) (it turns round), with its rates
CRANK = (lambda t: 1 + 2 * t + 0.3 * np.sin(3 * t), lambda t: 2 + 0.9 * np.cos(3 * t),
         lambda t: -2.7 * np.sin(3 * t))


@pytest.mark.parametrize("formulation", ["partition", "projected", "baumgarte"])
@pytest.mark.parametrize("source, states", [
    (rot.Position("drive", phi_ref="1 + 2*t + 0.3*sin(3*t)"), ["time"]),
    (rot.Speed("drive", w_ref="2 + 0.9*cos(3*t)", phi0=1.0), ["drive.phi"]),
], ids=["Position", "Speed"])
def test_a_fourbar_driven_at_its_crank(source, states, formulation):
    """No degree of freedom is left: the rocker follows the closed-form closure, and the
    crank's torque puts in the power the linkage's energy takes, tau theta' = dE/dt (the
    reference's reduced Lagrangian: m(theta) theta' theta'' + m'(theta) theta'^3 / 2 +
    V'(theta) theta'). An exact Position in a loop makes time a state, so the closure reads
    the states alone."""
    system = driven_fourbar(source).compile(loops=formulation)
    assert system.dof == 0
    assert system.state_names[-len(states):] == states
    assert not any(n.startswith("A.") for n in system.state_names + system.algebraic_names)
    res = kn.simulate(system, t_end=3.0, n_points=241, **TOL)
    t = res.t
    theta, thetad, thetadd = (f(t) for f in CRANK)
    _, psi = ref.fourbar_closure(theta)
    rocker = np.angle(np.exp(1j * (res["rocker_probe.angle"] - psi)))
    assert np.max(np.abs(rocker)) < 1e-9
    assert np.max(np.abs(res["crank_probe.angle"] - theta)) < 1e-9
    kin = ref.fourbar_kinematics(theta)
    power = kin["mass"] * thetad * thetadd + 0.5 * kin["mass_p"] * thetad ** 3 \
        + kin["Vg_p"] * thetad
    power_in = -res["drive_probe.torque"] * thetad
    assert np.max(np.abs(power_in - power)) < 1e-7
    # the work it does (Simpson's rule on the output grid) is the energy the linkage gains
    energy = ref.fourbar_energy(theta, thetad)
    work = cumulative_simpson(power_in, x=t, initial=0.0)
    assert np.max(np.abs(energy - energy[0] - work)) < 1e-4 * np.ptp(energy)


def test_a_loop_driven_in_time_starts_at_zero():
    model = driven_fourbar(rot.Position("drive", phi_ref="1 + 2*t"))
    with pytest.raises(kn.ModelError, match="clock .* starts at 0; simulate from t_start = 0"):
        kn.simulate(model, t_start=1.0, t_end=2.0, n_points=3)


def bessel(wc):
    """The Position filter as a state space: states (phi, w), outputs (phi, w, a)."""
    A = [[0, 1], [-wc ** 2 / BF, -AF * wc / BF]]
    B = [[0], [wc ** 2 / BF]]
    C = [[1, 0], [0, 1], A[1]]
    return signal.StateSpace(A, B, C, [[0], [0], B[1]])


def first_order(wc):
    """The Speed filter: states (phi, w), w' = (r - w) wc; outputs (phi, w, a)."""
    A = [[0, 1], [0, -wc]]
    return signal.StateSpace(A, [[0], [wc]], [[1, 0], [0, 1], [0, -wc]], [[0], [0], [wc]])


TABLE = [[0.0, 0.1], [1.0, 0.5], [2.0, 0.5], [3.0, -0.2]]


@pytest.mark.parametrize("cls, f_crit, filt, x0", [
    (rot.Position, 2.0, bessel, lambda r0: [r0, 0.0]),     # starts at rest on the reference
    (rot.Speed, 3.0, first_order, lambda r0: [0.0, r0]),   # from phi0, at the reference
], ids=["Position", "Speed"])
def test_a_table_reference_through_the_filter(cls, f_crit, filt, x0):
    """exact=False: a signals.Table (linear, kinks at whole seconds) filtered by the
    source's own states; the joint's angle, speed and acceleration are the filter's, as
    scipy.signal.lsim gives them (exact for a piecewise linear input sampled at its kinks)."""
    model = driven_arm(cls("drive", exact=False, f_crit=f_crit))
    model.add(sig.Table("plan", table=TABLE))
    model.connect("plan.y", "drive.u")
    system = model.compile()
    assert system.state_names == ["elbow.q", "elbow.qd", "drive.phi", "drive.w"]
    res = kn.simulate(system, t_end=3.0, n_points=301, **TOL)
    t = res.t
    r = np.interp(t, *np.transpose(TABLE))
    _, y, _ = signal.lsim(filt(2 * np.pi * f_crit), r, t, X0=x0(r[0]))
    for k, quantity in enumerate(("angle", "speed", "acceleration")):
        assert np.max(np.abs(res[f"probe1.{quantity}"] - y[:, k])) < 1e-8 * (1 + 10 * k)


def test_exact_differentiation_needs_a_reference_in_time():
    """A shoulder following the elbow's measured angle: exactly it is an algebraic loop
    through the mechanics and is refused; filtered it runs, starting on the elbow's angle."""
    def follower(exact):
        model = driven_arm(rot.Position("drive", exact=exact, f_crit=5.0), probe_source=False)
        model.add(rot.AngleSensor("sensor"))
        model.connect("sensor.flange", "elbow.axis")
        model.connect("sensor.y", "drive.u")
        return model
    with pytest.raises(kn.ModelError, match="exact=True differentiates the reference "
                                            "exactly.*set exact=False") as caught:
        follower(True).compile()
    assert (caught.value.problems[0].component, caught.value.problems[0].parameter) == \
        ("drive", "exact")
    res = kn.simulate(follower(False), t_end=1.0, n_points=11, **TOL)
    assert res["probe1.angle"][0] == pytest.approx(0.3) and np.all(np.isfinite(res.states))


REFUSED = [
    ("two sources on one joint",
     lambda m: (m.add(rot.Position("a", phi_ref="sin(t)")), m.add(rot.Speed("b", w_ref="1")),
                m.connect("a.flange", "shoulder.axis"), m.connect("b.flange", "shoulder.axis")),
     r"joint flange shoulder.axis is driven by 2 prescribed motions \(a.flange, b.flange\)"),
    ("two sources through a gear",
     lambda m: (m.add(rot.Position("a", phi_ref="sin(t)")), m.add(rot.Position("b", phi_ref="t")),
                m.add(rot.IdealGear("gear", ratio=3.0)), m.connect("a.flange", "shoulder.axis"),
                m.connect("gear.flange_b", "shoulder.axis"), m.connect("b.flange", "gear.flange_a")),
     r"is driven by 2 prescribed motions \(a.flange, b.flange\) \(through gear\); a joint "
     r"follows one motion"),
    ("a q0 the motion contradicts",
     lambda m: (m.add(rot.Position("a", phi_ref="0.2 + sin(t)")),
                m.connect("a.flange", "elbow.axis")),
     r"elbow.q0 = 0.3: elbow is moved by a, which gives its coordinate at t = 0 as 0.2"),
    ("no reference",
     lambda m: (m.add(rot.Position("a")), m.connect("a.flange", "shoulder.axis")),
     r"a.phi_ref: no reference: give phi_ref .* or wire a signal to a.u"),
    ("two references",
     lambda m: (m.add(rot.Position("a", phi_ref="t")), m.add(sig.Constant("k", k=1.0)),
                m.connect("k.y", "a.u"), m.connect("a.flange", "shoulder.axis")),
     r"a.phi_ref: a.u is wired too"),
    ("a support on a moving flange",
     lambda m: (m.add(rot.Position("a", phi_ref="t")), m.connect("a.flange", "shoulder.axis"),
                m.connect("a.support", "elbow.axis")),
     r"a.support is wired to a flange that moves \(joint\); the reaction of a prescribed "
     r"motion rests on a free rotor \(an inertia\) or in the world"),
]


@pytest.mark.parametrize("what, edit, message", REFUSED, ids=[w for w, _, _ in REFUSED])
def test_what_cannot_be_prescribed_is_refused_by_name(what, edit, message):
    model = double_pendulum(q0=(None, 0.3))
    edit(model)
    with pytest.raises(kn.ModelError, match=message):
        model.compile()


def test_the_joints_left_free_must_carry_mass():
    """The mass matrix of the joints a motion leaves free is checked at the start: an elbow
    carrying nothing is refused by name, but a driven joint may carry nothing."""
    massless_elbow = driven_arm(rot.Position("drive", phi_ref="sin(t)"))
    massless_elbow.set_parameter("m2", 0.0)
    with pytest.raises(kn.ModelError, match="singular at the initial state: elbow move"):
        massless_elbow.compile()
    driven_elbow = double_pendulum(q0=(0.3, None), m2=0.0)
    driven_elbow.add(rot.Position("drive", phi_ref="sin(t)"))
    driven_elbow.connect("drive.flange", "elbow.axis")
    assert driven_elbow.compile().state_names == ["shoulder.q", "shoulder.qd"]


def test_two_motions_fighting_through_a_loop_are_refused():
    _, psi = ref.fourbar_closure(1.0)
    model = driven_fourbar(rot.Position("drive", phi_ref="1 + t"))
    model.add(rot.Position("rocker_drive", phi_ref=float(psi)))
    model.connect("rocker_drive.flange", "D.axis")
    with pytest.raises(kn.ModelError, match=r"the prescribed joint\(s\) A \(by drive\), D "
                                            r"\(by rocker_drive\) cannot follow it"):
        model.compile()


def test_a_driven_model_saves_and_loads(tmp_path):
    model = driven_arm(rot.Position("drive", exact=False, f_crit=4.0))
    model.add(sig.Table("plan", table=TABLE))
    model.connect("plan.y", "drive.u")
    path = tmp_path / "driven.json"
    model.save(path)
    again = kn.load(path)
    assert again.components["drive"].exact is False
    a = kn.simulate(model, t_end=1.0, n_points=11, **TOL)
    b = kn.simulate(again, t_end=1.0, n_points=11, **TOL)
    assert_same_numbers(a.states, b.states)


def test_midpoint_refuses_a_prescribed_joint_saying_why():
    model = kn.Model("driven")
    model.add(kn.multibody.Ground("ground", gravity=[0, -9.81, 0]))
    model.add(kn.multibody.Revolute("j1"))
    model.add(kn.multibody.FixedTranslation("l1", r=[1, 0, 0]))
    model.add(kn.multibody.RigidBody("b1", mass=1.0))
    model.add(kn.rotational.Position("drive", phi_ref="0.5*sin(2*t)"))
    for a, b in [("ground.frame", "j1.frame_a"), ("j1.frame_b", "l1.frame_a"),
                 ("l1.frame_b", "b1.frame_a"), ("drive.flange", "j1.axis")]:
        model.connect(a, b)
    with pytest.raises(kn.ModelError, match="motion is prescribed"):
        kn.simulate(model, t_end=1, method="midpoint")
