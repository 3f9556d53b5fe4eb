"""MSL's RobotR3 (``Modelica.Mechanics.MultiBody.Examples.Systems.RobotR3``) as subsystem
definitions in ``models/robot_r3``, wired part for part as MSL's Utilities: Motor (the
current controller of three op-amps, Ra, La, EMF, rotor, hall sensors), GearType1 (bearing
friction with stiction on the motor side, gear elasticity, ideal gear), Controller (P on the
motor angle, PI on the motor speed, references through the gear ratio), AxisType1 (the three
together), and OneAxis (one axis turning a load inertia along a KinematicPTP path).

``python tests/scenes/robot_r3.py`` writes the files."""

import math
import pathlib

import kinetwork as kn

ROOT = pathlib.Path(__file__).resolve().parents[2]
FOLDER = ROOT / "models" / "robot_r3"
E, rot, sig = kn.electrical, kn.rotational, kn.signals

#: RobotR3.OneAxis: its axis (AxisType1 with these values), load and path
ONE_AXIS = {"mLoad": 15.0, "kp": 5.0, "ks": 0.5, "Ts": 0.05, "startAngle": 0.0,
            "endAngle": 120.0, "refSpeedMax": 3.0, "refAccMax": 10.0}
AXIS1 = {"w": 5500.0, "ratio": 210.0, "c": 8.0, "cd": 0.01, "Rv0": 0.5, "Rv1": 0.1 / 130}
#: Motor's defaults (MSL: J = 0.0013, k = 1.1616, w = 4590, D = 0.6)
MOTOR = {"J": 0.0013, "k": 1.1616, "w": 4590.0, "D": 0.6}


def _wire(model, pairs):
    for a, b in pairs:
        model.connect(a, b)


def motor():
    """Utilities.Motor: the motor of one axis with its current controller."""
    m = kn.Model("Motor", parameters={**MOTOR, "phi0": 0.0}, description=(
        "Modelica.Mechanics.MultiBody.Examples.Systems.RobotR3.Utilities.Motor, part for part: "
        "the reference current (port current_ref, through convert2 into the voltage source "
        "Vs) against the measured one (hall1, through convert1 into hall2) in the difference "
        "amplifier diff, integrated by OpI with C, amplified by the power stage (1 + Rp1/Rp2) "
        "into Ra, La and the EMF (k) turning the rotor Jmotor; the motor angle (phi) and "
        "speed (speed) measured on the EMF's flange. Ports: flange_motor, current_ref, "
        "motorAngle, motorSpeed. Starts at rest at angle phi0 with no current, which is MSL's "
        "steady start (der(C.v) = der(La.i) = 0) for a zero reference."))
    for c in [E.VoltageSource("Vs"), E.IdealOpAmp("power"), E.IdealOpAmp("diff"),
              E.EMF("emf", k="k"), E.Inductor("La", L="250/(2*D*w)"), E.Resistor("Ra", R=250),
              E.Resistor("Rd2", R=100), E.Capacitor("C", C="0.004*D/w"), E.IdealOpAmp("OpI"),
              E.Resistor("Ri", R=10), E.Resistor("Rd1", R=100), E.Resistor("Rp1", R=200),
              E.Resistor("Rp2", R=50), E.Resistor("Rd4", R=100), E.VoltageSource("hall2"),
              E.Resistor("Rd3", R=100), E.CurrentSensor("hall1"),
              *[E.Ground(f"g{i}") for i in range(1, 6)],
              rot.AngleSensor("phi"), rot.SpeedSensor("speed"),
              rot.Inertia("Jmotor", J="J", phi0="phi0"),
              sig.Gain("convert1", k=1.0), sig.Gain("convert2", k=1.0),
              kn.Probe("current", quantities=["value"])]:
        m.add(c)
    _wire(m, [("La.n", "emf.p"), ("Ra.n", "La.p"), ("Rd2.n", "diff.n1"), ("C.n", "OpI.p2"),
              ("OpI.p2", "power.p1"), ("Vs.p", "Rd2.p"), ("diff.n1", "Rd1.p"),
              ("Rd1.n", "diff.p2"), ("diff.p2", "Ri.p"), ("Ri.n", "OpI.n1"), ("OpI.n1", "C.p"),
              ("power.n1", "Rp1.p"), ("power.p2", "Rp1.n"), ("Rp1.p", "Rp2.p"),
              ("power.p2", "Ra.p"), ("Rd3.p", "hall2.p"), ("Rd3.n", "diff.p1"),
              ("Rd3.n", "Rd4.p"), ("Vs.n", "g1.p"), ("g2.p", "hall2.n"), ("Rd4.n", "g3.p"),
              ("g3.p", "OpI.p1"), ("g5.p", "Rp2.n"), ("emf.n", "hall1.p"), ("hall1.n", "g4.p"),
              ("emf.flange", "phi.flange"), ("emf.flange", "speed.flange"),
              ("OpI.n2", "power.n2"), ("OpI.p1", "OpI.n2"), ("OpI.p1", "diff.n2"),
              ("hall1.y", "convert1.u"), ("convert1.y", "hall2.u"), ("convert2.y", "Vs.u"),
              ("emf.flange", "Jmotor.flange_a"), ("current.port", "hall1.y")])
    for port, ref in [("flange_motor", "Jmotor.flange_b"), ("current_ref", "convert2.u"),
                      ("motorAngle", "phi.y"), ("motorSpeed", "speed.y")]:
        m.expose(port, ref)
    return m


def smooth_friction(m, name, flange, w_s):
    """In place of BearingFriction ``name``: its law regularised, -(Rv0 tanh(w / w_s) +
    Rv1 w), an Expression of the flange's speed driving a Torque (for bench/study_robot.py)."""
    m.add(rot.SpeedSensor(f"{name}_w"))
    m.add(sig.Expression(f"{name}_law", expression=f"-(Rv0*tanh(w/{w_s!r}) + Rv1*w)",
                         names=["w"]))
    m.add(rot.Torque(name))
    _wire(m, [(f"{name}_w.flange", flange), (f"{name}_w.y", f"{name}_law.u1"),
              (f"{name}_law.y", f"{name}.u"), (f"{name}.flange", flange)])


def gear_type1(w_s=None):
    """Utilities.GearType1: bearing friction, gear elasticity and the ideal gear (``w_s``: the
    friction regularised by tanh at that speed instead)."""
    m = kn.Model("GearType1", parameters={"i": -105.0, "c": 43.0, "d": 0.005, "Rv0": 0.4,
                                          "Rv1": 0.13 / 160, "peak": 1.0}, description=(
        "Modelica.Mechanics.MultiBody.Examples.Systems.RobotR3.Utilities.GearType1: "
        "bearingFriction on the motor side (MSL's tau_pos = [0, Rv0; 1, Rv0 + Rv1]: Coulomb "
        "Rv0 and viscous Rv1, static peak*Rv0, with stiction), the gear's elasticity spring "
        "(c, d) and the IdealGear gear (ratio i). Ports: flange_a (motor), flange_b (joint)."))
    m.add(rot.SpringDamper("spring", c="c", d="d"))
    m.add(rot.IdealGear("gear", ratio="i"))
    m.connect("spring.flange_b", "gear.flange_a")
    if w_s is None:
        m.add(rot.BearingFriction("bearingFriction", tau_c="Rv0", d="Rv1", peak="peak"))
        m.connect("bearingFriction.flange", "spring.flange_a")
    else:
        smooth_friction(m, "bearingFriction", "spring.flange_a", w_s)
    m.expose("flange_a", "spring.flange_a")
    m.expose("flange_b", "gear.flange_b")
    return m


def controller():
    """Utilities.Controller: P on the motor angle, PI on the motor speed."""
    m = kn.Model("Controller", parameters={"kp": 10.0, "ks": 1.0, "Ts": 0.01, "ratio": 1.0},
                 description=(
        "Modelica.Mechanics.MultiBody.Examples.Systems.RobotR3.Utilities.Controller: the "
        "references of the gear output scaled to the motor by the gear ratio (gain1, gain2), "
        "P (kp) on the motor-angle error (feedback1), add3 = gain2 + P - motorSpeed (two Adds "
        "here), and MSL's Continuous.PI (k = ks, T = Ts: y = ks (u + x), x' = u / Ts) as the "
        "integrator PI_x and the sum PI. Ports: angle_ref, speed_ref, motorAngle, motorSpeed, "
        "current_ref."))
    for c in [sig.Gain("gain1", k="ratio"), sig.Add("feedback1", k2=-1.0), sig.Gain("P", k="kp"),
              sig.Gain("gain2", k="ratio"), sig.Add("add3a"), sig.Add("add3", k2=-1.0),
              sig.Integrator("PI_x", k="1/Ts"), sig.Add("PI", k1="ks", k2="ks")]:
        m.add(c)
    _wire(m, [("gain1.y", "feedback1.u1"), ("feedback1.y", "P.u"), ("gain2.y", "add3a.u1"),
              ("P.y", "add3a.u2"), ("add3a.y", "add3.u1"), ("add3.y", "PI_x.u"),
              ("add3.y", "PI.u1"), ("PI_x.y", "PI.u2")])
    for port, ref in [("angle_ref", "gain1.u"), ("speed_ref", "gain2.u"),
                      ("motorAngle", "feedback1.u2"), ("motorSpeed", "add3.u2"),
                      ("current_ref", "PI.y")]:
        m.expose(port, ref)
    return m


def axis_type1(motor_def, gear_def, controller_def):
    """Utilities.AxisType1: controller, motor and GearType1."""
    params = {"kp": 10.0, "ks": 1.0, "Ts": 0.01, **MOTOR, "ratio": -105.0, "Rv0": 0.4,
              "Rv1": 0.13 / 160, "peak": 1.0, "c": 43.0, "cd": 0.005, "q_start": 0.0}
    m = kn.Model("AxisType1", parameters=params, description=(
        "Modelica.Mechanics.MultiBody.Examples.Systems.RobotR3.Utilities.AxisType1 (AxisType2 "
        "with GearType1): controller, motor and gear wired as MSL's, the axis bus as ports: "
        "flange (the gear's output), angle_ref, speed_ref. MSL's InitializeFlange and the "
        "sensors of the output flange that only feed the bus are left out; the motor starts at "
        "rest at ratio q_start, the spring relaxed, for a joint starting at q_start (as "
        "InitializeFlange puts it on its reference)."))
    m.add(kn.Subsystem("controller", controller_def, params={
        "kp": "kp", "ks": "ks", "Ts": "Ts", "ratio": "ratio"}))
    m.add(kn.Subsystem("motor", motor_def, params={**{k: k for k in MOTOR},
                                                   "phi0": "ratio*q_start"}))
    m.add(kn.Subsystem("gear", gear_def, params={
        "i": "ratio", "c": "c", "d": "cd", "Rv0": "Rv0", "Rv1": "Rv1", "peak": "peak"}))
    _wire(m, [("motor.flange_motor", "gear.flange_a"),
              ("controller.current_ref", "motor.current_ref"),
              ("motor.motorAngle", "controller.motorAngle"),
              ("motor.motorSpeed", "controller.motorSpeed")])
    m.expose("flange", "gear.flange_b")
    m.expose("angle_ref", "controller.angle_ref")
    m.expose("speed_ref", "controller.speed_ref")
    return m


def ptp(name, quantity, q_begin, q_end, qd_max, qdd_max, axis=1):
    return sig.KinematicPTP(name, q_begin=q_begin, q_end=q_end, qd_max=qd_max,
                            qdd_max=qdd_max, axis=axis, quantity=quantity)


def one_axis(axis_def):
    """RobotR3.OneAxis."""
    p = ONE_AXIS
    m = kn.Model("OneAxis", description=(
        "Modelica.Mechanics.MultiBody.Examples.Systems.RobotR3.OneAxis: one axis of the r3 "
        "robot (AxisType1.json: Controller, Motor, GearType1 with stiction) turning a load "
        "inertia J = 1.3 mLoad (mLoad = 15 kg) from 0 to 120 deg along PathPlanning1's "
        "KinematicPTP (speed 3 rad/s, acceleration 10 rad/s^2), kp = 5, ks = 0.5, Ts = 0.05, "
        "w = 5500, ratio 210, c = 8, cd = 0.01, Rv0 = 0.5, Rv1 = 0.1/130; StopTime 1.6 s. "
        "Reproduces MSL's oneAxisPlot.mos figure: the load angle (probe load_angle) and the "
        "motor current (axis.motor.current), checked against an independent event-driven "
        "scipy model of the drive in tests/scenes/test_robot_r3.py."))
    path = {"q_begin": [math.radians(p["startAngle"])], "q_end": [math.radians(p["endAngle"])],
            "qd_max": [p["refSpeedMax"]], "qdd_max": [p["refAccMax"]]}
    m.add(ptp("path_q", "q", **path))
    m.add(ptp("path_qd", "qd", **path))
    m.add(kn.Subsystem("axis", axis_def, params={
        **AXIS1, "kp": p["kp"], "ks": p["ks"], "Ts": p["Ts"]}))
    m.add(rot.Inertia("load", J=1.3 * p["mLoad"], phi0=0.0, w0=0.0))
    m.add(kn.Probe("load_angle", quantities=["angle", "speed"]))
    _wire(m, [("path_q.y", "axis.angle_ref"), ("path_qd.y", "axis.speed_ref"),
              ("axis.flange", "load.flange_a"), ("load_angle.port", "load.flange_b")])
    m.simulation = {"t_end": 1.6, "n_points": 161, "method": "auto", "rtol": 1e-8,
                  "atol": 1e-10}
    return m


def gear_type2(w_s=None):
    """Utilities.GearType2: the ideal gear, bearing friction on the joint side (``w_s``: the
    friction regularised by tanh at that speed instead)."""
    m = kn.Model("GearType2", parameters={"i": -99.0, "Rv0": 21.8, "Rv1": 9.8,
                                          "peak": 26.7 / 21.8}, description=(
        "Modelica.Mechanics.MultiBody.Examples.Systems.RobotR3.Utilities.GearType2: the "
        "IdealGear gear (ratio i) and, on its output, bearingFriction (Coulomb Rv0, viscous "
        "Rv1, static peak*Rv0, with stiction). Ports: flange_a (motor), flange_b (joint)."))
    m.add(rot.IdealGear("gear", ratio="i"))
    if w_s is None:
        m.add(rot.BearingFriction("bearingFriction", tau_c="Rv0", d="Rv1", peak="peak"))
        m.connect("gear.flange_b", "bearingFriction.flange")
    else:
        smooth_friction(m, "bearingFriction", "gear.flange_b", w_s)
    m.expose("flange_a", "gear.flange_a")
    m.expose("flange_b", "gear.flange_b")
    return m


def axis_type2(motor_def, gear_def, controller_def):
    """Utilities.AxisType2: controller, motor and GearType2."""
    params = {"kp": 10.0, "ks": 1.0, "Ts": 0.01, **MOTOR, "ratio": -105.0, "Rv0": 0.4,
              "Rv1": 0.13 / 160, "peak": 1.0, "q_start": 0.0}
    m = kn.Model("AxisType2", parameters=params, description=(
        "Modelica.Mechanics.MultiBody.Examples.Systems.RobotR3.Utilities.AxisType2: "
        "controller, motor and GearType2 (no elasticity: the motor's rotor is geared rigidly "
        "to the joint) wired as MSL's, the axis bus as ports: flange, angle_ref, speed_ref. "
        "The motor starts at ratio q_start, where the joint it is geared to starts."))
    m.add(kn.Subsystem("controller", controller_def, params={
        "kp": "kp", "ks": "ks", "Ts": "Ts", "ratio": "ratio"}))
    m.add(kn.Subsystem("motor", motor_def, params={**{k: k for k in MOTOR},
                                                   "phi0": "ratio*q_start"}))
    m.add(kn.Subsystem("gear", gear_def, params={
        "i": "ratio", "Rv0": "Rv0", "Rv1": "Rv1", "peak": "peak"}))
    _wire(m, [("motor.flange_motor", "gear.flange_a"),
              ("controller.current_ref", "motor.current_ref"),
              ("motor.motorAngle", "controller.motorAngle"),
              ("motor.motorSpeed", "controller.motorSpeed")])
    m.expose("flange", "gear.flange_b")
    m.expose("angle_ref", "controller.angle_ref")
    m.expose("speed_ref", "controller.speed_ref")
    return m


#: MechanicalStructure.mo: (joint axis, body r, r_CM, m, [I_11, I_22, I_33, I_21]) per link
#: b0 .. b6 (BodyShape's inertia defaults to 0.001 on the diagonal). b1's I_11 and I_33
#: (0.001 in MSL) are 0 here: b1 turns about y alone, so they never act, and MSL's values
#: break the triangle inequality (kinetwork warns of such idealised bodies)
BODIES = [
    (None, [0, 0.351, 0], [0, 0, 0], 1.0, [0.001, 0.001, 0.001, 0.0]),
    ([0, 1, 0], [0, 0.324, 0.3], [0, 0, 0], 1.0, [0.0, 1.16, 0.0, 0.0]),
    ([1, 0, 0], [0, 0.65, 0], [0.172, 0.205, 0], 56.5, [2.58, 0.64, 2.73, -0.46]),
    ([1, 0, 0], [0, 0.414, -0.155], [0.064, -0.034, 0], 26.4, [0.279, 0.245, 0.413, -0.070]),
    ([0, 1, 0], [0, 0.186, 0], [0, 0, 0], 28.7, [1.67, 0.081, 1.67, 0.0]),
    ([1, 0, 0], [0, 0.125, 0], [0, 0, 0], 5.2, [1.25, 0.81, 1.53, 0.0]),
    ([0, 1, 0], [0, 0, 0], [0.05, 0.05, 0.05], 0.5, [0.001, 0.001, 0.001, 0.0]),
]
#: FullRobot.mo: load, start and end angles [deg], reference limits, and the axes' values
FULL = {"mLoad": 15.0, "rLoad": [0.1, 0.25, 0.1], "g": 9.81,
        "start": [-60, 20, 90, 0, -110, 0], "end": [60, -70, -35, 45, 110, 45],
        "speed": [3, 1.5, 5, 3.1, 3.1, 4.1], "acc": [15, 15, 15, 60, 60, 60]}
AXES = [
    {"w": 4590, "ratio": -105, "c": 43, "cd": 0.005, "Rv0": 0.4, "Rv1": 0.13 / 160},
    {"w": 5500, "ratio": 210, "c": 8, "cd": 0.01, "Rv0": 0.5, "Rv1": 0.1 / 130},
    {"w": 5500, "ratio": 60, "c": 58, "cd": 0.04, "Rv0": 0.7, "Rv1": 0.2 / 130},
    {"k": 0.2365, "w": 6250, "D": 0.55, "J": 1.6e-4, "ratio": -99, "Rv0": 21.8, "Rv1": 9.8,
     "peak": 26.7 / 21.8},
    {"k": 0.2608, "w": 6250, "D": 0.55, "J": 1.8e-4, "ratio": 79.2, "Rv0": 30.1, "Rv1": 0.03,
     "peak": 39.6 / 30.1},
    {"k": 0.0842, "w": 7400, "D": 0.27, "J": 4.3e-5, "ratio": -99, "Rv0": 10.9, "Rv1": 3.92,
     "peak": 16.8 / 10.9},
]


def mechanical_structure():
    """Utilities.MechanicalStructure: the r3 robot's six revolutes and seven bodies + load."""
    mb = kn.multibody
    m = kn.Model("MechanicalStructure", parameters={
        "mLoad": 15.0, "rLoad_x": 0.0, "rLoad_y": 0.25, "rLoad_z": 0.0, "g": 9.81,
        **{f"q{k}_start": 0.0 for k in range(1, 7)}},
        description=(
        "Modelica.Mechanics.MultiBody.Examples.Systems.RobotR3.Utilities.MechanicalStructure: "
        "world (gravity g along -y), b0 .. b6 as BodyShape (r, r_CM, m and inertia from MSL; "
        "b1's I_11 and I_33 are 0, not 0.001: b1 turns about y alone), "
        "revolutes r1 .. r6 (axes y, x, x, y, x, y) and the load (mLoad at rLoad from b6). "
        "Ports: axis1 .. axis6 (the joints' flanges); the joints start at rest at qk_start."))
    m.add(mb.Ground("world", gravity=[0, "-g", 0]))
    prev = "world.frame"
    for k, (axis, r, r_cm, mass, (i11, i22, i33, i21)) in enumerate(BODIES):
        if axis is not None:
            m.add(mb.Revolute(f"r{k}", axis=axis, q0=f"q{k}_start", qd0=0.0))
            m.connect(prev, f"r{k}.frame_a")
            prev = f"r{k}.frame_b"
        m.add(mb.BodyShape(f"b{k}", r=r, r_cm=r_cm, mass=mass,
                           inertia=[[i11, i21, 0], [i21, i22, 0], [0, 0, i33]]))
        m.connect(prev, f"b{k}.frame_a")
        prev = f"b{k}.frame_b"
    m.add(mb.BodyShape("load", r=[0, 0, 0], r_cm=["rLoad_x", "rLoad_y", "rLoad_z"],
                       mass="mLoad", inertia=[0.001, 0.001, 0.001]))
    m.connect(prev, "load.frame_a")
    m.add(kn.Probe("tool", quantities=["position"]))
    m.connect("tool.port", "load.frame_a")
    for k in range(1, 7):
        m.expose(f"axis{k}", f"r{k}.axis")
    return m


def full_robot(mechanics_def, axis1_def, axis2_def):
    """RobotR3.FullRobot: PathPlanning6's KinematicPTP, six axes, the mechanics."""
    f = FULL
    m = kn.Model("FullRobot", description=(
        "Modelica.Mechanics.MultiBody.Examples.Systems.RobotR3.FullRobot: the r3 robot "
        "(MechanicalStructure.json, mLoad = 15 kg at rLoad = {0.1, 0.25, 0.1}) driven by six "
        "axes, AxisType1 (elastic GearType1, stiction on the motor side) on joints 1-3 and "
        "AxisType2 (GearType2, stiction on the joint side) on joints 4-6, with MSL's motor, "
        "gear and controller values, along PathPlanning6's KinematicPTP (the six axes "
        "synchronised) from (-60, 20, 90, 0, -110, 0) deg to (60, -70, -35, 45, 110, 45) deg; "
        "StopTime 2 s. Reproduces MSL's fullRobotPlot.mos figure (axis 3: joint angle, probe "
        "joint3, and motor current axis3.motor.current) and the six joint angles "
        "(probes joint1 .. joint6). The start differs from MSL's initial equations: the joints "
        "start at rest on their references with relaxed springs and no motor current (MSL "
        "starts every motor in steady state holding the robot), so the arm first settles "
        "under gravity."))
    path = {"q_begin": [math.radians(a) for a in f["start"]],
            "q_end": [math.radians(a) for a in f["end"]], "qd_max": f["speed"],
            "qdd_max": f["acc"]}
    rl = f["rLoad"]
    m.add(kn.Subsystem("mechanics", mechanics_def, params={
        "mLoad": f["mLoad"], "rLoad_x": rl[0], "rLoad_y": rl[1], "rLoad_z": rl[2],
        "g": f["g"], **{f"q{k + 1}_start": path["q_begin"][k] for k in range(6)}}))
    for k, values in enumerate(AXES):
        n = k + 1
        m.add(ptp(f"path_q{n}", "q", axis=n, **path))
        m.add(ptp(f"path_qd{n}", "qd", axis=n, **path))
        params = {**values, "kp": 5.0, "ks": 0.5, "Ts": 0.05, "q_start": path["q_begin"][k]}
        m.add(kn.Subsystem(f"axis{n}", axis1_def if k < 3 else axis2_def, params=params))
        m.add(kn.Probe(f"joint{n}", quantities=["angle", "speed"]))
        _wire(m, [(f"path_q{n}.y", f"axis{n}.angle_ref"), (f"path_qd{n}.y", f"axis{n}.speed_ref"),
                  (f"axis{n}.flange", f"mechanics.axis{n}"),
                  (f"joint{n}.port", f"mechanics.axis{n}")])
    m.simulation = {"t_end": 2.0, "n_points": 201, "method": "auto", "rtol": 1e-6,
                    "atol": 1e-8}
    return m


def full_robot_regularised(w_s, folder=FOLDER):
    """FullRobot with every bearing friction regularised by tanh at speed ``w_s`` (motor side
    on axes 1-3, joint side on 4-6): the scene that needs no events."""
    motor_def, controller_def = kn.load(folder / "Motor.json"), kn.load(folder / "Controller.json")
    return full_robot(kn.load(folder / "MechanicalStructure.json"),
                      axis_type1(motor_def, gear_type1(w_s), controller_def),
                      axis_type2(motor_def, gear_type2(w_s), controller_def))


def write_models(folder=FOLDER):
    folder = pathlib.Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    for build in (motor, gear_type1, gear_type2, controller, mechanical_structure):
        model = build()
        model.save(folder / f"{model.name}.json")
    load = {n: kn.load(folder / f"{n}.json") for n in (
        "Motor", "GearType1", "GearType2", "Controller", "MechanicalStructure")}
    axis_type1(load["Motor"], load["GearType1"], load["Controller"]).save(
        folder / "AxisType1.json")
    axis_type2(load["Motor"], load["GearType2"], load["Controller"]).save(
        folder / "AxisType2.json")
    one_axis(kn.load(folder / "AxisType1.json")).save(folder / "OneAxis.json")
    full_robot(load["MechanicalStructure"], kn.load(folder / "AxisType1.json"),
               kn.load(folder / "AxisType2.json")).save(folder / "FullRobot.json")
    return folder


if __name__ == "__main__":
    print("wrote", write_models())
