"""The electrical library against closed forms and an independent scipy reference: RL and RC
circuits, a current source into an RC, a current loop closed through a sensor, a DC motor
with an inertia load (the linear second-order response, by the matrix exponential), and a DC
motor driving a pendulum's revolute joint (solve_ivp of the hand-written equations)."""

import numpy as np
import pytest
import scipy.integrate
import scipy.linalg

from close import assert_same_numbers

import kinetwork as kn

E = kn.electrical
TOL = dict(rtol=1e-10, atol=1e-12, jit=False)   # accuracy, not compiled code, is tested here


def _rl(v="V"):
    m = kn.Model("rl", parameters={"R": 2.0, "L": 0.5, "V": 3.0})
    m.add(E.Ground("g"))
    m.add(E.VoltageSource("src", V=v))
    m.add(E.Resistor("r", R="R"))
    m.add(E.Inductor("l", L="L"))
    m.add(kn.Probe("pl", quantities=["current", "voltage"]))
    m.connect("src.p", "r.p"); m.connect("r.n", "l.p"); m.connect("l.n", "src.n")
    m.connect("g.p", "src.n"); m.connect("pl.port", "l.p")
    return m


def test_rl_circuit_step_and_sine_match_closed_forms():
    m = _rl()
    res = kn.simulate(m, t_end=1.0, n_points=21, **TOL, params={"R": 4.0})
    assert res.state_names == ["l.i"]
    # what `kinetwork validate --compile` says of it: 3 nodes, 7 pins, every block scalar
    # (10 of the potentials and currents, 1 of the inductor's rate)
    assert "circuits: 3 node potentials and 7 pin currents in 11 blocks solved symbolically, " \
        "1 states" in m.compile().asm.net.summary(m.validate())
    tau = 0.5 / 4.0
    assert np.max(abs(res["pl.current"] - 3 / 4 * (1 - np.exp(-res.t / tau)))) < 1e-8
    # the voltage across the inductor (its pin p's potential; n is grounded): V e^(-t/tau)
    assert np.max(abs(res["pl.voltage"] - 3 * np.exp(-res.t / tau))) < 1e-8
    # a source in time: V = sin(w t); i(t) from the convolution, in closed form
    res = kn.simulate(_rl("sin(5*t)"), t_end=1.0, n_points=21, **TOL)
    R, L, w, t = 2.0, 0.5, 5.0, res.t
    a = R / L
    i = (a * np.sin(w * t) - w * np.cos(w * t) + w * np.exp(-a * t)) / (L * (a ** 2 + w ** 2))
    assert np.max(abs(res["pl.current"] - i)) < 1e-8


def test_rc_circuit_with_sensors_matches_closed_form():
    m = kn.Model("rc", parameters={"R": 1e3, "C": 1e-4})
    for c in (E.Ground("g"), E.VoltageSource("src", V=10.0), E.Resistor("r", R="R"),
              E.Capacitor("c", C="C", v0=2.0), E.CurrentSensor("am"), E.VoltageSensor("vm"),
              kn.Probe("pv", quantities=["value"]), kn.Probe("pa", quantities=["value"])):
        m.add(c)
    for a, b in [("src.p", "am.p"), ("am.n", "r.p"), ("r.n", "c.p"), ("c.n", "src.n"),
                 ("g.p", "src.n"), ("vm.p", "c.p"), ("vm.n", "c.n"), ("pv.port", "vm.y"),
                 ("pa.port", "am.y")]:
        m.connect(a, b)
    res = kn.simulate(m, t_end=0.3, n_points=31, **TOL)
    assert res.state_names == ["c.v"]
    tau = 0.1
    v = 10 - 8 * np.exp(-res.t / tau)
    assert np.max(abs(res["pv.value"] - v)) < 1e-8
    assert np.max(abs(res["pa.value"] - 8 / 1e3 * np.exp(-res.t / tau))) < 1e-11


def test_current_source_into_parallel_rc():
    """MSL's convention: I flows into p, through the source, out of n; with n on the RC
    and p grounded the RC charges to I R."""
    m = kn.Model("irc")
    for c in (E.Ground("g"), E.CurrentSource("src", I=0.2), E.Resistor("r", R=50.0),
              E.Capacitor("c", C=1e-3), kn.Probe("pc", quantities=["voltage"])):
        m.add(c)
    for a, b in [("src.n", "r.p"), ("r.p", "c.p"), ("r.n", "c.n"), ("c.n", "src.p"),
                 ("g.p", "src.p"), ("pc.port", "c.p")]:
        m.connect(a, b)
    res = kn.simulate(m, t_end=0.2, n_points=21, **TOL)
    assert np.max(abs(res["pc.voltage"] - 10 * (1 - np.exp(-res.t / 0.05)))) < 1e-8


def test_current_loop_through_a_sensor():
    """A signal-driven source fed back from a current sensor: through the inductor (a state)
    it is no algebraic loop: L di/dt = -R i + K (I_ref - i)."""
    m = kn.Model("loop", parameters={"K": 8.0})
    for c in (E.Ground("g"), E.VoltageSource("src"), E.Resistor("r", R=2.0),
              E.Inductor("l", L=0.5), E.CurrentSensor("am"), kn.signals.Constant("ref", k=1.0),
              kn.signals.Add("err", k2=-1.0), kn.signals.Gain("ctl", k="K"),
              kn.Probe("pa", quantities=["value"])):
        m.add(c)
    for a, b in [("src.p", "am.p"), ("am.n", "r.p"), ("r.n", "l.p"), ("l.n", "src.n"),
                 ("g.p", "src.n"), ("ref.y", "err.u1"), ("am.y", "err.u2"),
                 ("err.y", "ctl.u"), ("ctl.y", "src.u"), ("pa.port", "am.y")]:
        m.connect(a, b)
    res = kn.simulate(m, t_end=0.5, n_points=11, **TOL)
    i = 8 / 10 * (1 - np.exp(-10 / 0.5 * res.t))
    assert np.max(abs(res["pa.value"] - i)) < 1e-8


def test_resistive_feedback_is_an_algebraic_loop_solved_symbolically():
    """Without the inductor the same loop is algebraic: i = K (1 - i) / R."""
    m = kn.Model("loop")
    for c in (E.Ground("g"), E.VoltageSource("src"), E.Resistor("r", R=2.0),
              E.CurrentSensor("am"), kn.signals.Constant("ref", k=1.0),
              kn.signals.Add("err", k2=-1.0), kn.signals.Gain("ctl", k=8.0),
              kn.signals.Integrator("acc"), kn.Probe("pa", quantities=["value"])):
        m.add(c)
    for a, b in [("src.p", "am.p"), ("am.n", "r.p"), ("r.n", "src.n"), ("g.p", "src.n"),
                 ("ref.y", "err.u1"), ("am.y", "err.u2"), ("err.y", "ctl.u"),
                 ("ctl.y", "src.u"), ("am.y", "acc.u"), ("pa.port", "am.y")]:
        m.connect(a, b)
    res = kn.simulate(m, t_end=0.5, n_points=3, **TOL)
    assert np.allclose(res["pa.value"], 8 / 10, rtol=1e-12)
    assert np.allclose(res.states[:, 0], 0.8 * res.t, rtol=1e-9)


def _motor_params():
    return {"R": 1.2, "L": 0.05, "k": 0.3, "J": 2e-3}


def test_dc_motor_with_inertia_load_matches_the_second_order_closed_form():
    p = _motor_params()
    m = kn.Model("drive", parameters={"V": 12.0, "JL": 8e-3})
    for c in (E.Ground("g"), E.VoltageSource("src", V="V"),
              E.DCMotor("motor", R=p["R"], L=p["L"], k=p["k"], J=p["J"]),
              kn.rotational.Inertia("load", J="JL"),
              kn.Probe("pw", quantities=["speed"]), kn.Probe("pi", quantities=["current"])):
        m.add(c)
    for a, b in [("src.p", "motor.p"), ("motor.n", "src.n"), ("g.p", "src.n"),
                 ("motor.flange", "load.flange_a"), ("pw.port", "load.flange_b"),
                 ("pi.port", "motor.p")]:
        m.connect(a, b)
    res = kn.simulate(m, t_end=0.5, n_points=26, **TOL)
    assert sorted(res.state_names) == ["motor.La.i", "motor.rotor.phi", "motor.rotor.w"]
    # x = (i, w): x' = A x + b V from rest: x(t) = A^-1 (e^(At) - I) b V
    J = p["J"] + 8e-3
    A = np.array([[-p["R"] / p["L"], -p["k"] / p["L"]], [p["k"] / J, 0.0]])
    b = np.array([1 / p["L"], 0.0]) * 12.0
    x = np.array([np.linalg.solve(A, (scipy.linalg.expm(A * t) - np.eye(2)) @ b)
                  for t in res.t])
    assert np.max(abs(res["pi.current"] - x[:, 0])) < 1e-7
    assert np.max(abs(res["pw.speed"] - x[:, 1])) < 1e-7
    assert abs(res["pw.speed"][-1] - 12.0 / p["k"]) < 0.2      # towards the no-load speed


def test_dc_motor_wired_from_parts_equals_the_aggregate():
    """MSL's wiring by hand (R, L, EMF, rotor) gives the very states of DCMotor."""
    p = _motor_params()
    m = kn.Model("parts")
    for c in (E.Ground("g"), E.VoltageSource("src", V="10*sin(20*t)"),
              E.Resistor("Ra", R=p["R"]), E.Inductor("La", L=p["L"]), E.EMF("emf", k=p["k"]),
              kn.rotational.Inertia("rotor", J=p["J"]),
              kn.rotational.Damper("d", d=0.01), kn.rotational.Fixed("housing"),
              kn.Probe("pw", quantities=["speed", "torque"])):
        m.add(c)
    for a, b in [("src.p", "Ra.p"), ("Ra.n", "La.p"), ("La.n", "emf.p"), ("emf.n", "src.n"),
                 ("g.p", "src.n"), ("emf.flange", "rotor.flange_a"),
                 ("rotor.flange_b", "d.flange_b"), ("d.flange_a", "housing.flange"),
                 ("emf.support", "housing.flange"), ("pw.port", "emf.flange")]:
        m.connect(a, b)
    agg = kn.Model("agg")
    for c in (E.Ground("g"), E.VoltageSource("src", V="10*sin(20*t)"),
              E.DCMotor("motor", R=p["R"], L=p["L"], k=p["k"], J=p["J"]),
              kn.rotational.Damper("d", d=0.01), kn.rotational.Fixed("housing"),
              kn.Probe("pw", quantities=["speed"])):
        agg.add(c)
    for a, b in [("src.p", "motor.p"), ("motor.n", "src.n"), ("g.p", "src.n"),
                 ("motor.flange", "d.flange_b"), ("d.flange_a", "housing.flange"),
                 ("motor.support", "housing.flange"), ("pw.port", "motor.flange")]:
        agg.connect(a, b)
    r1 = kn.simulate(m, t_end=0.3, n_points=7, **TOL)
    r2 = kn.simulate(agg, t_end=0.3, n_points=7, **TOL)
    assert np.max(abs(r1["pw.speed"] - r2["pw.speed"])) < 1e-9
    # the torque into the EMF at its flange is -k i (MSL's flange.tau = -k*i)
    i = r1.states[:, r1.state_names.index("La.i")]
    assert np.max(abs(r1["pw.torque"] + p["k"] * i)) < 1e-9


def test_dc_motor_driving_a_revolute_joint_matches_scipy():
    p = _motor_params()
    mass, arm, g, V = 0.5, 0.3, 9.81, 6.0
    m = kn.Model("motor_arm")
    for c in (kn.multibody.Ground("ground", gravity=[0, -g, 0]),
              kn.multibody.Revolute("joint", axis=[0, 0, 1], q0=0.2),
              kn.multibody.RigidBody("bob", mass=mass, r_cm=[arm, 0, 0], inertia=[0, 0, 0]),
              E.Ground("g"), E.VoltageSource("src", V=V),
              E.DCMotor("motor", R=p["R"], L=p["L"], k=p["k"], J=p["J"]),
              kn.Probe("pq", quantities=["angle", "speed"])):
        m.add(c)
    for a, b in [("ground.frame", "joint.frame_a"), ("joint.frame_b", "bob.frame_a"),
                 ("src.p", "motor.p"), ("motor.n", "src.n"), ("g.p", "src.n"),
                 ("motor.flange", "joint.axis"), ("motor.support", "joint.support"),
                 ("pq.port", "joint.axis")]:
        m.connect(a, b)
    res = kn.simulate(m, t_end=1.0, n_points=11, **TOL)
    # the rotor rides on the joint axis: no state of its own, its inertia the joint's armature
    assert sorted(res.state_names) == ["joint.q", "joint.qd", "motor.La.i"]

    def rhs(t, x):
        q, w, i = x
        inertia = mass * arm ** 2 + p["J"]
        return [w, (p["k"] * i - mass * g * arm * np.cos(q)) / inertia,
                (V - p["R"] * i - p["k"] * w) / p["L"]]
    ref = scipy.integrate.solve_ivp(rhs, (0, 1.0), [0.2, 0.0, 0.0], method="DOP853",
                                    t_eval=res.t, rtol=1e-11, atol=1e-12)
    assert np.max(abs(res["pq.angle"] - ref.y[0])) < 1e-7
    assert np.max(abs(res["pq.speed"] - ref.y[1])) < 1e-6


def _circuit(*parts, wires):
    m = kn.Model("bad")
    for c in parts:
        m.add(c)
    for a, b in wires:
        m.connect(a, b)
    return m


def test_circuits_that_cannot_be_solved_are_refused_by_name():
    no_ground = _circuit(E.VoltageSource("src", V=1.0), E.Resistor("r", R=1.0),
                         wires=[("src.p", "r.p"), ("r.n", "src.n")])
    with pytest.raises(kn.ModelError, match="src, r has no electrical.Ground|r, src has no") \
            as caught:
        no_ground.compile()
    # each refusal's place as data (the studio marks the block from the fields)
    assert caught.value.problems[0].component == "r"
    parallel = _circuit(E.Ground("g"), E.VoltageSource("a", V=1.0), E.VoltageSource("b", V=2.0),
                        E.Resistor("r", R=1.0),
                        wires=[("a.p", "b.p"), ("a.n", "b.n"), ("g.p", "a.n"), ("r.p", "a.p"),
                               ("r.n", "a.n")])
    with pytest.raises(kn.ModelError, match="equations of a, b, g constrain their unknowns "
                                            "twice.*structurally singular") as caught:
        parallel.compile()
    assert caught.value.problems[0].component == "a"
    silent = _circuit(E.Ground("g"), E.VoltageSource("src"), E.Resistor("r", R=1.0),
                      wires=[("src.p", "r.p"), ("r.n", "src.n"), ("g.p", "src.n")])
    with pytest.raises(kn.ModelError, match=r"src.*V: no value") as caught:
        silent.compile()
    assert (caught.value.problems[0].component, caught.value.problems[0].parameter) == \
        ("src", "V")
    shorted = _circuit(E.Ground("g"), E.VoltageSource("src", V=1.0), E.Resistor("r", R=0.0),
                       wires=[("src.p", "r.p"), ("r.n", "src.n"), ("g.p", "src.n")])
    with pytest.raises(kn.ModelError, match="singular"):
        shorted.compile()


def test_a_circuit_saves_and_loads(tmp_path):
    m = _rl()
    m.save(tmp_path / "rl.json")
    again = kn.load(tmp_path / "rl.json")
    r1 = kn.simulate(m, t_end=0.2, n_points=3, jit=False)
    r2 = kn.simulate(again, t_end=0.2, n_points=3, jit=False)
    assert_same_numbers(r1["pl.current"], r2["pl.current"])


def test_inverting_amplifier_of_an_ideal_op_amp():
    """v_out = -R2/R1 v_in; the op-amp's output drives a load resistor."""
    m = kn.Model("amp")
    for c in (E.Ground("g"), E.VoltageSource("src", V="2*sin(3*t)"), E.Resistor("r1", R=1e3),
              E.Resistor("r2", R=4.7e3), E.Resistor("load", R=100.0), E.IdealOpAmp("op"),
              E.VoltageSensor("vm"), kn.Probe("pv", quantities=["value"])):
        m.add(c)
    for a, b in [("src.n", "g.p"), ("src.p", "r1.p"), ("r1.n", "op.n1"), ("op.n1", "r2.p"),
                 ("r2.n", "op.p2"), ("op.p1", "g.p"), ("op.n2", "g.p"), ("op.p2", "load.p"),
                 ("load.n", "g.p"), ("vm.p", "op.p2"), ("vm.n", "g.p"), ("pv.port", "vm.y")]:
        m.connect(a, b)
    res = kn.simulate(m, t_end=1.0, n_points=11, method="rk45", jit=False)
    assert np.max(abs(res["pv.value"] + 4.7 * 2 * np.sin(3 * res.t))) < 1e-12


def msl_robot_motor(J_load=0.3):
    """MSL's RobotR3 motor (Modelica.Mechanics.MultiBody.Examples.Systems.RobotR3.Utilities
    .Motor) wired part for part: a current controller of three ideal op-amps (difference
    amplifier, integrator, power stage) driving Ra, La and the EMF, the current fed back
    through hall1 and hall2; the shaft turns a load inertia. Started as MSL starts it, in
    steady state: der(C.v) = 0, der(La.i) = 0."""
    J, k, w, D = 0.0013, 1.1616, 4590.0, 0.6
    m = kn.Model("motor")
    parts = [E.VoltageSource("Vs"), E.IdealOpAmp("power"), E.IdealOpAmp("diff"),
             E.EMF("emf", k=k), E.Inductor("La", L=250 / (2 * D * w)), E.Resistor("Ra", R=250),
             E.Resistor("Rd2", R=100), E.Capacitor("C", C=0.004 * D / w), E.IdealOpAmp("OpI"),
             E.Resistor("Ri", R=10), E.Resistor("Rd1", R=100), E.Resistor("Rp1", R=200),
             E.Resistor("Rp2", R=50), E.Resistor("Rd4", R=100), E.VoltageSource("hall2"),
             E.Resistor("Rd3", R=100), E.CurrentSensor("hall1"),
             *[E.Ground(f"g{i}") for i in range(1, 6)],
             kn.rotational.Inertia("Jmotor", J=J), kn.rotational.Inertia("load", J=J_load),
             kn.signals.Gain("convert1", k=1.0), kn.signals.Gain("convert2", k=1.0),
             kn.signals.Sine("current_ref", amplitude=1.0, f=20.0, offset=0.5),
             kn.Probe("pw", quantities=["speed"]), kn.Probe("pi", quantities=["value"])]
    for c in parts:
        m.add(c)
    for a, b in [("La.n", "emf.p"), ("Ra.n", "La.p"), ("Rd2.n", "diff.n1"), ("C.n", "OpI.p2"),
                 ("OpI.p2", "power.p1"), ("Vs.p", "Rd2.p"), ("diff.n1", "Rd1.p"),
                 ("Rd1.n", "diff.p2"), ("diff.p2", "Ri.p"), ("Ri.n", "OpI.n1"),
                 ("OpI.n1", "C.p"), ("power.n1", "Rp1.p"), ("power.p2", "Rp1.n"),
                 ("Rp1.p", "Rp2.p"), ("power.p2", "Ra.p"), ("Rd3.p", "hall2.p"),
                 ("Rd3.n", "diff.p1"), ("Rd3.n", "Rd4.p"), ("Vs.n", "g1.p"), ("g2.p", "hall2.n"),
                 ("Rd4.n", "g3.p"), ("g3.p", "OpI.p1"), ("g5.p", "Rp2.n"), ("emf.n", "hall1.p"),
                 ("hall1.n", "g4.p"), ("OpI.n2", "power.n2"), ("OpI.p1", "OpI.n2"),
                 ("OpI.p1", "diff.n2"), ("hall1.y", "convert1.u"), ("convert1.y", "hall2.u"),
                 ("current_ref.y", "convert2.u"), ("convert2.y", "Vs.u"),
                 ("emf.flange", "Jmotor.flange_a"), ("Jmotor.flange_b", "load.flange_a"),
                 ("pw.port", "load.flange_b"), ("pi.port", "hall1.y")]:
        m.connect(a, b)
    m.set_initial(derivatives={"C.v": 0, "La.i": 0}, solve=["C.v", "La.i"])
    return m, dict(J=J + J_load, k=k, La=250 / (2 * D * w), Ra=250.0, C=0.004 * D / w, Ri=10.0)


def test_msl_robot_motor_against_its_circuit_by_nodal_analysis():
    """By hand: the difference amplifier gives i - i_ref, the op-amp integrator
    dv_C/dt = (i - i_ref) / (Ri C) at its virtual ground, the power stage 5 (-v_C) (gain
    1 + Rp1/Rp2), so La di/dt = -5 v_C - Ra i - k w and J dw/dt = k i."""
    m, p = msl_robot_motor()
    system = m.compile()
    # only the inductor's current, the capacitor's voltage and the load's motion are states
    assert sorted(system.state_names) == ["C.v", "Jmotor.phi", "Jmotor.w", "La.i"]
    # MSL's steady start: the current on its reference (0.5 A at t = 0), the power stage
    # holding Ra i against no back EMF
    x0 = dict(zip(system.state_names, system.x0))
    assert x0["La.i"] == pytest.approx(0.5, rel=1e-10)
    assert x0["C.v"] == pytest.approx(-p["Ra"] * 0.5 / 5, rel=1e-10)
    res = kn.simulate(system, t_end=0.05, n_points=11, **TOL)
    # x = (i, v_C, w) is linear, x' = A x + b(t) with i_ref = 0.5 + sin(W t): the state
    # augmented with (sin, cos, 1) evolves by one matrix exponential, the closed form
    W, rc = 2 * np.pi * 20, p["Ri"] * p["C"]
    M = np.zeros((6, 6))
    M[:3, :3] = [[-p["Ra"] / p["La"], -5 / p["La"], -p["k"] / p["La"]], [1 / rc, 0, 0],
                 [p["k"] / p["J"], 0, 0]]
    M[1, 3], M[1, 5] = -1 / rc, -0.5 / rc            # - i_ref / (Ri C)
    M[3, 4], M[4, 3] = W, -W                          # (sin, cos)' = (W cos, -W sin)
    z0 = np.array([0.5, -25.0, 0.0, 0.0, 1.0, 1.0])
    ref = np.array([scipy.linalg.expm(M * t) @ z0 for t in res.t]).T
    assert np.max(abs(res["pi.value"] - ref[0])) < 1e-7
    assert np.max(abs(res["pw.speed"] - ref[2])) < 1e-7


def test_probes_on_an_aggregate_name_its_ports_not_its_insides():
    # a DC motor is a resistor, inductor, EMF and rotor inside: a probe wired to motor.p and
    # one to motor.flange are titled so in results and plots, never motor.Ra.p
    import matplotlib
    matplotlib.use("Agg")
    m = kn.Model("drive")
    m.add(E.Ground("gnd"))
    m.add(E.VoltageSource("src", V=12.0))
    m.add(E.DCMotor("motor", R=1.0, L=0.01, k=0.1, J=0.01))
    m.add(kn.Probe("pm", quantities=["voltage"]))
    m.add(kn.Probe("ps", quantities=["speed"]))
    for a, b in [("src.p", "motor.p"), ("src.n", "gnd.p"), ("motor.n", "gnd.p"),
                 ("pm.port", "motor.p"), ("ps.port", "motor.flange")]:
        m.connect(a, b)
    res = kn.simulate(m, t_end=0.05, n_points=3, **TOL)
    assert res.probe_targets == {"pm": "motor.p", "ps": "motor.flange"}
    titles = [ax.get_title() for ax in kn.plot(res).axes]
    assert titles == ["pm (motor.p): voltage", "ps (motor.flange): speed"]
