"""1-D networks and signal blocks against closed forms written by hand from the seed's M, V,
G (``bench/reference.py``): rotors behind gears, flexible couplings, series elements, and the
PID-controlled arm; and the ill-posed networks, each refused with its components named."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import kinetwork as kn
from scenes import SEED_PARAMS, double_pendulum, drives
from scenes.reference import seed_mvg

rot, sig, mb = kn.rotational, kn.signals, kn.multibody
P = {k: SEED_PARAMS[k] for k in ("L1", "L2", "m1", "m2", "c", "d", "g")}


def _seed(x, extra_inertia=(0.0, 0.0), tau=(0.0, 0.0)):
    """Accelerations of the seed with ``extra_inertia`` on M's diagonal and joint torques."""
    M, V, G = (np.asarray(a, dtype=float) for a in seed_mvg(x[:2], x[2:], **P))
    return np.linalg.solve(M + np.diag(extra_inertia), np.asarray(tau) - V.ravel() - G.ravel())


def _rotor(model, joint, J, ratios, tau=None):
    """A rotor J behind a chain of gears on ``joint``'s axis, optionally driven by ``tau``."""
    model.add(rot.Inertia(f"rotor_{joint}", J=J))
    previous = f"rotor_{joint}.flange_b"
    for i, n in enumerate(ratios):
        model.add(rot.IdealGear(f"gear_{joint}{i}", ratio=n))
        model.connect(previous, f"gear_{joint}{i}.flange_a")
        previous = f"gear_{joint}{i}.flange_b"
    model.connect(previous, f"{joint}.axis")
    if tau is not None:
        model.add(rot.Torque(f"motor_{joint}", tau=tau))
        model.connect(f"motor_{joint}.flange", f"rotor_{joint}.flange_a")


@pytest.mark.parametrize("joint, ratios", [("elbow", [12.0]), ("shoulder", [3.0, -4.0])])
def test_rotor_behind_gears_adds_J_n_squared_and_no_state(joint, ratios):
    J, tau = 0.02, 0.7
    model = double_pendulum(q0=(0.6, -0.3))
    _rotor(model, joint, J, ratios, tau)
    system = model.compile()
    assert system.state_names == ["shoulder.q", "elbow.q", "shoulder.qd", "elbow.qd"]
    n = np.prod(ratios)
    k = 0 if joint == "shoulder" else 1
    extra, torque = np.zeros(2), np.zeros(2)
    extra[k], torque[k] = J * n * n, n * tau
    rng = np.random.default_rng(3)
    for _ in range(5):
        x = rng.uniform(-2, 2, 4)
        assert np.allclose(system.rhs(0.0, x)[2:], _seed(x, extra, torque), rtol=1e-10,
                           atol=1e-10)
    assert np.allclose(system.mass_matrix([0.6, -0.3]),
                       seed_mvg([0.6, -0.3], [0, 0], **P)[0] + np.diag(extra), atol=1e-12)


def test_gear_flows_follow_the_ratio():
    """Probes on both gear flanges: flange_b carries -ratio times flange_a's torque; the
    joint axis feels the motor torque times the ratio less the rotor's inertia."""
    J, n, tau = 0.02, 12.0, 0.7
    model = double_pendulum(q0=(0.6, -0.3))
    _rotor(model, "elbow", J, [n], tau)
    for port in ("gear_elbow0.flange_a", "gear_elbow0.flange_b"):
        name = port.replace(".", "_")
        model.add(kn.Probe(name, quantities=["torque", "acceleration"]))
        model.connect(f"{name}.port", port)
    res = kn.simulate(model, t_end=1.0, n_points=11, rtol=1e-10, atol=1e-12)
    ta, tb = res["gear_elbow0_flange_a.torque"], res["gear_elbow0_flange_b.torque"]
    assert np.allclose(tb, -n * ta, atol=1e-12)
    # the rotor: J * (n * qdd_elbow) = tau + (flow into the rotor at flange_b) = tau - ta
    acc_rotor = res["gear_elbow0_flange_a.acceleration"]
    assert np.allclose(acc_rotor, n * res["probe2.acceleration"], atol=1e-12)
    assert np.allclose(J * acc_rotor, tau - ta, atol=1e-10)


def test_flexible_coupling_gives_the_rotor_its_own_state():
    """drive_train: hinge with a load, and a rotor behind a spring-damper coupling and a gear;
    against the two-body equations written by hand."""
    model = drives.drive_train()
    system = model.compile()
    assert system.state_names == ["hinge.q", "hinge.qd", "rotor.phi", "rotor.w"]
    c, d, J, n, tau = 200.0, 0.5, 0.01, 10.0, 0.5
    m, r, I, g = 2.0, 0.5, 0.01, 9.81

    def rhs(t, x):
        q, qd, phi, w = x
        twist = c * (q * n - phi) + d * (qd * n - w)      # coupling: flange_b - flange_a
        qdd = (-n * twist - m * g * r * np.cos(q)) / (I + m * r * r)
        return [qd, qdd, w, (tau + twist) / J]
    t = np.linspace(0, 3, 301)
    ref = solve_ivp(rhs, (0, 3), [0, 0, 0, 0], t_eval=t, rtol=1e-12, atol=1e-12,
                    method="DOP853").y.T
    res = kn.simulate(system, t_end=3.0, n_points=301, rtol=1e-11, atol=1e-12)
    assert np.max(np.abs(res.states - ref)) < 1e-7


def test_maxwell_element_and_springs_in_series():
    """A spring in series with a damper (a massless node: one first-order state) and two
    springs in series (no state: the node is solved), on a 1-DOF rotor."""
    def build(series):
        model = kn.Model("series")
        model.add(mb.Ground("ground", gravity=[0, 0, 0]))
        model.add(mb.Revolute("hinge", q0=0.4, qd0=0.0))
        model.add(mb.RigidBody("body", mass=1.0, inertia=[0, 0, 0.5]))
        model.connect("ground.frame", "hinge.frame_a")
        model.connect("hinge.frame_b", "body.frame_a")
        model.add(rot.Spring("s1", c=30.0))
        second = rot.Damper("s2", d=2.0) if series == "maxwell" else rot.Spring("s2", c=20.0)
        model.add(second)
        for a, b in [("s1.flange_a", "hinge.support"), ("s1.flange_b", "s2.flange_a"),
                     ("s2.flange_b", "hinge.axis")]:
            model.connect(a, b)
        return model.compile()
    maxwell = build("maxwell")
    assert maxwell.state_names == ["hinge.q", "hinge.qd", "s1.flange_b.phi"]

    def rhs(t, x):                      # node at p: c p = d (qd - pd)
        q, qd, p = x
        return [qd, -30.0 * p / 0.5, (-30.0 * p + 2.0 * qd) / 2.0]
    t = np.linspace(0, 3, 61)
    ref = solve_ivp(rhs, (0, 3), [0.4, 0, 0], t_eval=t, rtol=1e-12, atol=1e-12).y.T
    res = kn.simulate(maxwell, t_end=3, n_points=61, rtol=1e-11, atol=1e-12)
    assert np.max(np.abs(res.states - ref)) < 1e-8
    springs = build("springs")
    assert springs.state_names == ["hinge.q", "hinge.qd"]
    c_eq = 30.0 * 20.0 / 50.0
    assert np.allclose(springs.rhs(0, [0.4, 0.1]), [0.1, -c_eq * 0.4 / 0.5], atol=1e-12)


def _pid_reference(t_eval, drive, step, sine):
    """The arm under two PID loops, written from the seed's closed form by hand."""
    d = drive
    n, J = d["n"], d["J_m"]

    def refs(t):
        return (step["height"] if t >= step["start_time"] else 0.0,
                sine["amplitude"] * np.sin(2 * np.pi * sine["f"] * t))

    def rhs(t, x):
        q, qd, states = x[:2], x[2:4], x[4:].reshape(2, 2)
        out, rates = np.zeros(2), np.zeros(4)
        for j in range(2):
            e = refs(t)[j] - q[j]
            integral, filt = states[j]
            unlimited = d["k"] * (e + integral + d["Nd"] * (e - filt))
            y = min(max(unlimited, -d["y_max"]), d["y_max"])
            out[j] = y
            rates[2 * j] = (e + (y - unlimited) / (d["k"] * 0.9)) / d["Ti"]
            rates[2 * j + 1] = (e - filt) * d["Nd"] / d["Td"]
        qdd = _seed(np.concatenate([q, qd]), (J * n * n, J * n * n), n * out)
        return np.concatenate([qd, qdd, rates])
    x0 = np.array([0.05, 0.05, 0, 0, 0, 0, 0, 0])
    ts = step["start_time"]
    out = []
    for span, piece in (((0.0, ts), t_eval[t_eval < ts]),       # restart at the step: no
                        ((ts, t_eval[-1]), t_eval[t_eval >= ts])):  # error across it
        sol = solve_ivp(rhs, span, x0, t_eval=piece, rtol=1e-12, atol=1e-12,
                        method="DOP853", dense_output=True)
        out.append(sol.y.T)
        x0 = sol.sol(span[1])
    return np.vstack(out)


def test_pid_controlled_arm_agrees_with_the_closed_loop_closed_form():
    model = drives.arm_pid()
    system = model.compile()
    assert system.state_names[:4] == ["shoulder.q", "elbow.q", "shoulder.qd", "elbow.qd"]
    assert system.n_states == 8                       # rotors add nothing, PIDs two each
    t = np.linspace(0.0, 6.0, 601)
    res = kn.simulate(system, rtol=1e-11, atol=1e-12)
    ref = _pid_reference(t, drives.DRIVE, drives.STEP, drives.SINE)
    assert np.max(np.abs(res.states[:, :4] - ref[:, :4])) < 1e-6
    # and it does what the model says: the shoulder settles within 1e-3 rad by t = 2 s
    late = res.t >= 2.0
    assert np.max(np.abs(res["probe1.angle"][late] - 0.5)) < 1e-3
    assert np.max(np.abs(res["command_shoulder.value"])) == pytest.approx(3.0)   # saturates


def test_signal_blocks_against_their_formulas():
    model = kn.Model("blocks")                  # signals only: no Ground needed
    blocks = [sig.Constant("c", k=2.0), sig.Ramp("ramp", height=3.0, duration=2.0,
                                                   start_time=1.0),
              sig.Sine("sine", amplitude=2.0, f=0.5, phase=0.3, offset=1.0),
              sig.Gain("gain", k=-1.5), sig.Add("add", k1=2.0, k2=-1.0),
              sig.Product("prod"), sig.Limiter("lim", u_max=1.0),
              sig.Table("table", table=[[0, 0], [1, 2], [3, -2]]),
              sig.Integrator("integ", k=2.0, y_start=1.0), sig.FirstOrder("lag", k=2.0, T=0.5),
              sig.Sum("sum")]
    for b in blocks:
        model.add(b)
    wires = [("sine.y", "gain.u"), ("c.y", "add.u1"), ("ramp.y", "add.u2"),
             ("sine.y", "prod.u1"), ("ramp.y", "prod.u2"), ("sine.y", "lim.u"),
             ("c.y", "integ.u"), ("c.y", "lag.u"), ("sine.y", "sum.u1"), ("c.y", "sum.u3")]
    for a, b in wires:
        model.connect(a, b)
    for b in blocks:
        model.add(kn.Probe(f"p_{b.name}", quantities=["value"]))
        model.connect(f"p_{b.name}.port", f"{b.name}.y")
    res = kn.simulate(model, t_end=4.0, n_points=81, rtol=1e-12, atol=1e-12)
    t = res.t
    ramp = 3.0 * np.clip((t - 1.0) / 2.0, 0, 1)
    sine = 1.0 + 2.0 * np.sin(np.pi * t + 0.3)
    expected = {"c": 2.0 + 0 * t, "ramp": ramp, "sine": sine, "gain": -1.5 * sine,
                "add": 4.0 - ramp, "prod": sine * ramp, "lim": np.clip(sine, -1, 1),
                "table": np.interp(t, [0, 1, 3], [0, 2, -2]) + np.where(
                    t > 3, -2.0 * (t - 3), 0), "integ": 1.0 + 4.0 * t,
                "lag": 4.0 * (1 - np.exp(-t / 0.5)), "sum": sine + 2.0}
    for name, value in expected.items():
        assert np.allclose(res[f"p_{name}.value"], value, atol=1e-8), name


ILL_POSED = [
    ("singular signal loop", lambda m: (m.add(sig.Gain("g1", k=1.0)),
                                        m.add(sig.Gain("g2", k=1.0)),
                                        m.connect("g1.y", "g2.u"), m.connect("g2.y", "g1.u")),
     r"algebraic loop through g1, g2: its outputs are not determined"),
    ("loop through the mechanics", lambda m: (
        m.add(rot.AccSensor("acc")), m.add(sig.Gain("fb", k=0.1)), m.add(rot.Torque("push")),
        m.connect("acc.flange", "elbow.axis"), m.connect("acc.y", "fb.u"),
        m.connect("fb.y", "push.u"), m.connect("push.flange", "elbow.axis")),
     r"algebraic loop through acc, fb and the mechanics"),
    ("two outputs", lambda m: (m.add(sig.Constant("a", k=1.0)), m.add(sig.Constant("b", k=2.0)),
                               m.add(sig.Gain("g", k=1.0)), m.connect("a.y", "g.u"),
                               m.connect("b.y", "g.u")),
     r"signal outputs a.y, b.y are wired together"),
    ("input left open", lambda m: m.add(sig.Gain("g", k=1.0)), r"port g.u \(signal_in\) is not"),
    ("inputs without an output", lambda m: (m.add(sig.Gain("g1", k=1.0)),
                                            m.add(sig.Gain("g2", k=1.0)),
                                            m.connect("g1.u", "g2.u")),
     r"signal inputs g1.u, g2.u are wired to each other but to no output"),
    ("gear between two joints", lambda m: (m.add(rot.IdealGear("gear", ratio=2.0)),
                                           m.connect("gear.flange_a", "shoulder.axis"),
                                           m.connect("gear.flange_b", "elbow.axis")),
     r"rigidly ties joint flange shoulder.axis to elbow.axis \(through gear\)"),
    ("gears in a ring", lambda m: (m.add(rot.IdealGear("g1", ratio=2.0)),
                                   m.add(rot.IdealGear("g2", ratio=3.0)),
                                   m.add(rot.Inertia("rotor", J=1.0)),
                                   m.connect("g1.flange_a", "rotor.flange_a"),
                                   m.connect("g2.flange_a", "rotor.flange_a"),
                                   m.connect("g1.flange_b", "g2.flange_b")),
     r"rigid 1-D elements g1, g2 form a closed loop"),
    ("torques on a bare flange", lambda m: (m.add(rot.Torque("t1", tau=1.0)),
                                            m.add(rot.Torque("t2", tau=1.0)),
                                            m.connect("t1.flange", "t2.flange")),
     r"\{t1.flange, t2.flange\} has no defined rotational position"),
    ("a free rotor without inertia", lambda m: (m.add(rot.Inertia("rotor", J=0.0)),
                                                m.add(rot.Spring("shaft", c=1.0)),
                                                m.connect("rotor.flange_b", "shaft.flange_a"),
                                                m.connect("shaft.flange_b", "elbow.axis")),
     r"the inertia of rotor is zero and nothing holds the flange"),
    ("a gear of ratio 0", lambda m: (m.add(rot.IdealGear("gear", ratio=0.0)),
                                     m.connect("gear.flange_b", "elbow.axis")),
     r"gear.ratio = 0.0: must not be 0"),
    ("a PID with Ti = 0", lambda m: m.add(sig.PID("pid", Ti=0.0)), r"pid.Ti = 0.0 s: must be > 0"),
    ("acceleration of a massless flange", lambda m: (
        m.add(rot.Spring("s", c=1.0)), m.add(rot.Damper("d", d=1.0)),
        m.add(kn.Probe("pa", quantities=["acceleration"])),
        m.connect("s.flange_a", "shoulder.axis"), m.connect("s.flange_b", "d.flange_a"),
        m.connect("d.flange_b", "elbow.axis"), m.connect("pa.port", "s.flange_b")),
     r"the acceleration of s.flange_b is not available"),
    ("two motions on one rotor", lambda m: (m.add(rot.Position("a", phi_ref="sin(t)")),
                                            m.add(rot.Position("b", phi_ref="t")),
                                            m.add(rot.Inertia("r", J=1.0)),
                                            m.connect("a.flange", "r.flange_a"),
                                            m.connect("b.flange", "r.flange_b")),
     r"rigidly ties prescribed motion a.flange to b.flange \(through r\): one rigid group"),
    ("two motions on a joint", lambda m: (m.add(rot.Position("a", phi_ref="sin(t)")),
                                          m.add(rot.Speed("b", w_ref="1")),
                                          m.connect("a.flange", "elbow.axis"),
                                          m.connect("b.flange", "elbow.axis")),
     r"joint flange elbow.axis is driven by 2 prescribed motions \(a.flange, b.flange\); "
     r"a joint follows one motion"),
    ("a joint locked to a Fixed", lambda m: (m.add(rot.Fixed("lock")),
                                             m.connect("lock.flange", "elbow.axis")),
     r"rigidly ties joint flange elbow.axis to lock.flange: this locks or couples joints"),
]


@pytest.mark.parametrize("what, edit, message", ILL_POSED, ids=[w for w, _, _ in ILL_POSED])
def test_ill_posed_networks_are_refused_by_name(what, edit, message):
    model = double_pendulum()
    with pytest.raises(kn.ModelError, match=message):     # when built, or when compiled
        edit(model)
        model.compile()


def test_prescribed_motion_drives_a_rotor_through_a_spring():
    """A Position source turns a flange at sin(t); a spring to the elbow drives the arm;
    the source's flange carries the spring torque."""
    model = double_pendulum(q0=(0.0, 0.0))
    model.add(rot.Position("drive", phi_ref="sin(t)"))
    model.add(rot.Spring("shaft", c=5.0))
    model.connect("drive.flange", "shaft.flange_a")
    model.connect("shaft.flange_b", "elbow.axis")
    model.add(kn.Probe("p", quantities=["angle", "speed", "acceleration", "torque"]))
    model.connect("p.port", "drive.flange")
    system = model.compile()
    res = kn.simulate(system, t_end=2.0, n_points=21, rtol=1e-11, atol=1e-12)
    t = res.t
    assert np.allclose(res["p.angle"], np.sin(t)) and np.allclose(res["p.speed"], np.cos(t))
    assert np.allclose(res["p.acceleration"], -np.sin(t))
    # the spring pulls the driven flange towards the elbow's angle
    assert np.allclose(res["p.torque"], 5.0 * (res["probe2.angle"] - np.sin(t)), atol=1e-10)
    x = np.array([0.2, -0.1, 0.3, 0.4])
    tau = 5.0 * (np.sin(0.7) - x[1])
    assert np.allclose(system.rhs(0.7, x)[2:], _seed(x, tau=(0.0, tau)), atol=1e-10)


def test_computed_torque_from_the_models_own_dynamics_leaves_a_linear_error():
    """arm_computed_torque: InverseDynamics blocks evaluate the model's M, V, G (spring-damper
    included) at the measured state, so each error e = r - q obeys e'' + kd e' + kp e = 0
    exactly: at kp = 100, kd = 20 it is (e0 + (e0' + 10 e0) t) exp(-10 t)."""
    system = drives.arm_computed_torque().compile()
    assert system.n_states == 4                    # the controller has no state of its own
    res = kn.simulate(system)
    t, w = res.t, np.pi
    for joint, probe in (("shoulder", "probe1"), ("elbow", "probe2")):
        amp, phase = drives.SINES[joint]
        e0, ed0 = amp * np.sin(phase) - 0.05, amp * w * np.cos(phase)
        expected = (e0 + (ed0 + 10 * e0) * t) * np.exp(-10 * t)
        assert np.max(np.abs(amp * np.sin(w * t + phase) - res[f"{probe}.angle"]
                             - expected)) < 1e-8, joint
        assert np.allclose(res[f"error_{joint}.value"], expected, atol=1e-8)


def test_inverse_dynamics_needs_a_joint_of_the_model():
    model = double_pendulum()
    model.add(sig.Constant("a", k=1.0))
    model.add(sig.InverseDynamics("inv", joint="link1"))
    model.connect("a.y", "inv.a1")
    with pytest.raises(kn.ModelError, match="'link1' is not a joint with one degree"):
        model.compile()


def test_linear_algebraic_loop_of_signals_is_solved():
    """y = 3 - 0.5 y through an Add and a Gain: solved symbolically, y = 2, no state."""
    model = double_pendulum()
    model.add(sig.Constant("c", k=3.0))
    model.add(sig.Add("add", k2=-0.5))
    model.add(sig.Gain("same", k=1.0))
    for a, b in [("c.y", "add.u1"), ("add.y", "same.u"), ("same.y", "add.u2")]:
        model.connect(a, b)
    model.add(kn.Probe("p", quantities=["value"]))
    model.connect("p.port", "add.y")
    system = model.compile()
    assert system.n_states == 4
    res = kn.simulate(system, t_end=0.1, n_points=3)
    assert np.allclose(res["p.value"], 2.0, atol=1e-14)


def test_a_pure_1d_drive_train_needs_no_ground():
    """Two rotors and a shaft, torque on one: the twist oscillates at sqrt(c (1/J1 + 1/J2))
    about its mean, and the total momentum grows at the torque (no multibody at all)."""
    model = kn.Model("shaft")
    model.add(rot.Torque("motor", tau=2.0))
    model.add(rot.Inertia("r1", J=0.5))
    model.add(rot.Spring("shaft", c=100.0))
    model.add(rot.Inertia("r2", J=2.0))
    for a, b in [("motor.flange", "r1.flange_a"), ("r1.flange_b", "shaft.flange_a"),
                 ("shaft.flange_b", "r2.flange_a")]:
        model.connect(a, b)
    system = model.compile()
    assert system.state_names == ["r1.phi", "r1.w", "r2.phi", "r2.w"]
    res = kn.simulate(system, t_end=2.0, n_points=201, rtol=1e-11, atol=1e-12)
    t = res.t
    w1, w2 = res.states[:, 1], res.states[:, 3]
    assert np.allclose(0.5 * w1 + 2.0 * w2, 2.0 * t, atol=1e-9)
    # relative motion: mu x'' = -c x + (J2/(J1+J2)) tau, x = phi1 - phi2, mu = J1 J2/(J1+J2)
    omega = np.sqrt(100.0 / 0.4)                # mu = 0.5 * 2 / 2.5 = 0.4
    x_mean = 2.0 * (2.0 / 2.5) / 100.0
    x = res.states[:, 0] - res.states[:, 2]
    assert np.allclose(x, x_mean * (1 - np.cos(omega * t)), atol=1e-9)


def test_nonlinear_algebraic_loop_is_kept_for_idas():
    """y = 3 - 0.5 lim(y) with lim clipping at 1: the loop's outputs become algebraic
    variables (y = 2.5, lim = 1), solved by IDAS beside an ODE that integrates y."""
    model = double_pendulum()
    for block in (sig.Constant("c", k=3.0), sig.Add("add", k2=-0.5),
                  sig.Limiter("lim", u_max=1.0), sig.Integrator("integ")):
        model.add(block)
    for a, b in [("c.y", "add.u1"), ("lim.y", "add.u2"), ("add.y", "lim.u"),
                 ("add.y", "integ.u")]:
        model.connect(a, b)
    system = model.compile()
    assert system.algebraic_names == ["add.y", "lim.y"]
    res = kn.simulate(system, t_end=2.0, n_points=21)
    assert res.method == "idas"
    assert np.allclose(res["add.y"], 2.5) and np.allclose(res["lim.y"], 1.0)
    assert np.allclose(res["integ.x"], 2.5 * res.t, atol=1e-6)
    # and the mechanism is unchanged: the seed's own closed form
    X = res.states[:, :4]
    rates = np.array([_seed(x) for x in X])
    assert np.allclose(np.array([system.rhs(0.0, x)[2:4] for x in
                                 res.states[:, :system.n_states]]), rates, atol=1e-10)
