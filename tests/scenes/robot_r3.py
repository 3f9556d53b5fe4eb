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
    m = kn.Model("Motor", parameters=dict(MOTOR), description=(
        "Modelica.Mechanics.MultiBody.Examples.Systems.RobotR3.Utilities.Motor, part for part: "
        "the reference current (port current_ref, through convert2 into the voltage source "
        "Vs) against the measured one (hall1, through convert1 into hall2) in the difference "
        "amplifier diff, integrated by OpI with C, amplified by the power stage (1 + Rp1/Rp2) "
        "into Ra, La and the EMF (k) turning the rotor Jmotor; the motor angle (phi) and "
        "speed (speed) measured on the EMF's flange. Ports: flange_motor, current_ref, "
        "motorAngle, motorSpeed. Starts at rest with no current, which is MSL's steady start "
        "(der(C.v) = der(La.i) = 0) for a zero reference."))
    for c in [E.VoltageSource("Vs"), E.IdealOpAmp("power"), E.IdealOpAmp("diff"),
              E.EMF("emf", k="k"), E.Inductor("La", L="250/(2*D*w)"), E.Resistor("Ra", R=250),
              E.Resistor("Rd2", R=100), E.Capacitor("C", C="0.004*D/w"), E.IdealOpAmp("OpI"),
              E.Resistor("Ri", R=10), E.Resistor("Rd1", R=100), E.Resistor("Rp1", R=200),
              E.Resistor("Rp2", R=50), E.Resistor("Rd4", R=100), E.VoltageSource("hall2"),
              E.Resistor("Rd3", R=100), E.CurrentSensor("hall1"),
              *[E.Ground(f"g{i}") for i in range(1, 6)],
              rot.AngleSensor("phi"), rot.SpeedSensor("speed"), rot.Inertia("Jmotor", J="J"),
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


def gear_type1():
    """Utilities.GearType1: bearing friction, gear elasticity and the ideal gear."""
    m = kn.Model("GearType1", parameters={"i": -105.0, "c": 43.0, "d": 0.005, "Rv0": 0.4,
                                          "Rv1": 0.13 / 160, "peak": 1.0}, description=(
        "Modelica.Mechanics.MultiBody.Examples.Systems.RobotR3.Utilities.GearType1: "
        "bearingFriction on the motor side (MSL's tau_pos = [0, Rv0; 1, Rv0 + Rv1]: Coulomb "
        "Rv0 and viscous Rv1, static peak*Rv0, with stiction), the gear's elasticity spring "
        "(c, d) and the IdealGear gear (ratio i). Ports: flange_a (motor), flange_b (joint)."))
    m.add(rot.BearingFriction("bearingFriction", tau_c="Rv0", d="Rv1", peak="peak"))
    m.add(rot.SpringDamper("spring", c="c", d="d"))
    m.add(rot.IdealGear("gear", ratio="i"))
    _wire(m, [("bearingFriction.flange", "spring.flange_a"),
              ("spring.flange_b", "gear.flange_a")])
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
              "Rv1": 0.13 / 160, "peak": 1.0, "c": 43.0, "cd": 0.005}
    m = kn.Model("AxisType1", parameters=params, description=(
        "Modelica.Mechanics.MultiBody.Examples.Systems.RobotR3.Utilities.AxisType1 (AxisType2 "
        "with GearType1): controller, motor and gear wired as MSL's, the axis bus as ports: "
        "flange (the gear's output), angle_ref, speed_ref. MSL's InitializeFlange and the "
        "sensors of the output flange that only feed the bus are left out; the axis starts at "
        "rest at angle 0, where MSL's references start it."))
    m.add(kn.Subsystem("controller", controller_def, params={
        "kp": "kp", "ks": "ks", "Ts": "Ts", "ratio": "ratio"}))
    m.add(kn.Subsystem("motor", motor_def, params={k: k for k in MOTOR}))
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


def write_models(folder=FOLDER):
    folder = pathlib.Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    for build in (motor, gear_type1, controller):
        model = build()
        model.save(folder / f"{model.name}.json")
    load = {n: kn.load(folder / f"{n}.json") for n in ("Motor", "GearType1", "Controller")}
    axis_type1(load["Motor"], load["GearType1"], load["Controller"]).save(
        folder / "AxisType1.json")
    one_axis(kn.load(folder / "AxisType1.json")).save(folder / "OneAxis.json")
    return folder


if __name__ == "__main__":
    print("wrote", write_models())
