"""The scenes of issue 5 (drives, gears, sensors, feedback) as kinetwork models.

``python tests/scenes/drives.py`` writes ``models/arm_pid.json``, ``models/drive_train.json``
and ``models/arm_computed_torque.json`` from these builders; the tests compare them with
closed-loop simulations written directly from the seed's closed-form M, V, G.

arm_pid      the seed's arm, each joint driven by a motor (rotor inertia J_m) through a gearbox
             (ratio n), under PID control of the joint angle: the shoulder follows a step, the
             elbow a sine
drive_train  a motor torque drives a rotor, which drives a pendulum through a flexible coupling
             (a rotational spring-damper) and a gearbox: the rotor has a state of its own
arm_computed_torque  the seed's arm under computed-torque control built from its own
             dynamics (InverseDynamics blocks)
"""

import pathlib

import kinetwork as kn

ROOT = pathlib.Path(__file__).resolve().parents[2]
SEED_FILE = ROOT / "models" / "double_pendulum.json"

#: motor, gearbox and controller of each joint of ``arm_pid``
DRIVE = {"J_m": 2e-4, "n": 50.0, "k": 20.0, "Ti": 0.2, "Td": 0.05, "Nd": 10.0, "y_max": 3.0}
#: the references: a step of the shoulder, a sine of the elbow
STEP = {"height": 0.5, "start_time": 0.5}
SINE = {"amplitude": 0.3, "f": 0.5}


def _seed_copy(name, simulation, description):
    """The seed model of ``models/double_pendulum.json``, renamed, to build on."""
    model = kn.loads(SEED_FILE.read_text())
    model.name, model.description = name, description
    model.simulation = {**simulation, "method": "auto"}
    return model


def arm_pid(drive=None, step=None, sine=None):
    """The seed model with two PID-controlled geared motors (parameters of ``DRIVE``)."""
    d = {**DRIVE, **(drive or {})}
    model = _seed_copy("arm_pid", {"t_end": 6.0, "n_points": 601, "rtol": 1e-8,
                                   "atol": 1e-10}, (
        "The seed's 2-DOF arm, each joint driven by a motor (rotor inertia J_m) through a "
        "gearbox of ratio n, under PID control of the joint angle (motor torque limited to "
        "y_max, back-calculation anti-windup): the shoulder follows a step of 0.5 rad at "
        "t = 0.5 s, the elbow a sine of 0.3 rad at 0.5 Hz. The rotors cost no state: each "
        "adds J_m n^2 to its joint's inertia. The shoulder settles within 1e-3 rad of the "
        "step by t = 2 s."))
    for name, value in d.items():
        model.set_parameter(name, value)
    rot, sig = kn.rotational, kn.signals
    refs = {"shoulder": sig.Step("ref_shoulder", **{**STEP, **(step or {})}),
            "elbow": sig.Sine("ref_elbow", **{**SINE, **(sine or {})})}
    for joint, ref in refs.items():
        model.add(ref)
        model.add(rot.Inertia(f"rotor_{joint}", J="J_m"))
        model.add(rot.IdealGear(f"gear_{joint}", ratio="n"))
        model.add(rot.Torque(f"motor_{joint}"))
        model.add(rot.AngleSensor(f"angle_{joint}"))
        model.add(sig.PID(f"pid_{joint}", k="k", Ti="Ti", Td="Td", Nd="Nd", y_max="y_max"))
        for a, b in [(f"motor_{joint}.flange", f"rotor_{joint}.flange_a"),
                     (f"rotor_{joint}.flange_b", f"gear_{joint}.flange_a"),
                     (f"gear_{joint}.flange_b", f"{joint}.axis"),
                     (f"angle_{joint}.flange", f"{joint}.axis"),
                     (f"{ref.name}.y", f"pid_{joint}.u_s"),
                     (f"angle_{joint}.y", f"pid_{joint}.u_m"),
                     (f"pid_{joint}.y", f"motor_{joint}.u")]:
            model.connect(a, b)
        model.add(kn.Probe(f"command_{joint}", quantities=["value"]))
        model.connect(f"command_{joint}.port", f"pid_{joint}.y")
        model.add(kn.Probe(f"reference_{joint}", quantities=["value"]))
        model.connect(f"reference_{joint}.port", f"{ref.name}.y")
    return model


def drive_train(c=200.0, d=0.5, J_rotor=0.01, n=10.0, tau=0.5):
    """A motor torque ``tau`` on a rotor, a flexible coupling (c, d) to a gearbox (ratio n)
    on a pendulum's revolute: 4 + 2 states (the rotor's angle and speed)."""
    mb, rot = kn.multibody, kn.rotational
    model = kn.Model("drive_train", parameters={"c": c, "d": d, "J_rotor": J_rotor, "n": n,
                                                "tau": tau},
                     description="A motor drives a pendulum through a flexible coupling (a "
                                 "rotational spring-damper) and a gearbox: the rotor has an "
                                 "angle and a speed of its own, the coupling twists.",
                     simulation={"t_end": 10.0, "n_points": 1001, "method": "auto",
                                 "rtol": 1e-8, "atol": 1e-10})
    model.add(mb.Ground("ground", gravity=[0, -9.81, 0]))
    model.add(mb.Revolute("hinge"))
    model.add(mb.FixedTranslation("arm", r=[0.5, 0, 0]))
    model.add(mb.RigidBody("load", mass=2.0, r_cm=[0.5, 0, 0], inertia=[0, 0, 0.01]))
    model.add(rot.Torque("motor", tau="tau"))
    model.add(rot.Inertia("rotor", J="J_rotor"))
    model.add(rot.SpringDamper("coupling", c="c", d="d"))
    model.add(rot.IdealGear("gear", ratio="n"))
    model.add(kn.Probe("rotor_probe", quantities=["angle", "speed"]))
    model.add(kn.Probe("twist", quantities=["torque"]))
    model.add(kn.Probe("joint", quantities=["angle", "speed", "torque"]))
    for a, b in [("ground.frame", "hinge.frame_a"), ("hinge.frame_b", "arm.frame_a"),
                 ("hinge.frame_b", "load.frame_a"), ("motor.flange", "rotor.flange_a"),
                 ("rotor.flange_b", "coupling.flange_a"), ("coupling.flange_b", "gear.flange_a"),
                 ("gear.flange_b", "hinge.axis"), ("rotor_probe.port", "rotor.flange_b"),
                 ("twist.port", "coupling.flange_b"), ("joint.port", "hinge.axis")]:
        model.connect(a, b)
    return model


#: the computed-torque references: per joint (amplitude, phase) of a 0.5 Hz sine
SINES = {"shoulder": (0.4, 0.0), "elbow": (0.3, 0.5)}


def arm_computed_torque(kp=100.0, kd=20.0, f=0.5):
    """The seed's arm under computed-torque control built from its own dynamics: per joint,
    the commanded acceleration r'' + kd (r' - q') + kp (r - q) goes into InverseDynamics
    blocks (the model's M, V, G at the measured state), whose outputs drive the joints."""
    model = _seed_copy("arm_computed_torque", {"t_end": 4.0, "n_points": 401, "rtol": 1e-9,
                                               "atol": 1e-11}, (
        "The seed's arm under computed-torque control: each joint's commanded acceleration "
        "r'' + kd (r' - q') + kp (r - q) feeds InverseDynamics blocks, which evaluate the "
        "model's own M(q) a + V(q, q') + G(q) (the shoulder spring-damper included). With "
        "the model exact, each tracking error obeys e'' + kd e' + kp e = 0: critically "
        "damped at kp = 100, kd = 20."))
    model.set_parameter("kp", kp)
    model.set_parameter("kd", kd)
    rot, sig = kn.rotational, kn.signals
    w = 2 * 3.141592653589793 * f
    for i, (joint, (amp, phase)) in enumerate(SINES.items()):
        for name, a, shift in (("r", amp, 0.0), ("rd", amp * w, 1.5707963267948966),
                               ("rdd", amp * w * w, 3.141592653589793)):
            model.add(sig.Sine(f"{name}_{joint}", amplitude=a, f=f, phase=phase + shift))
        model.add(rot.AngleSensor(f"q_{joint}"))
        model.add(rot.SpeedSensor(f"qd_{joint}"))
        model.add(sig.Add(f"e_{joint}", k2=-1.0))
        model.add(sig.Add(f"ed_{joint}", k2=-1.0))
        model.add(sig.Gain(f"kp_{joint}", k="kp"))
        model.add(sig.Gain(f"kd_{joint}", k="kd"))
        model.add(sig.Sum(f"a_{joint}"))
        model.add(sig.InverseDynamics(f"inverse_{joint}", joint=joint))
        model.add(rot.Torque(f"motor_{joint}"))
        for a, b in [(f"q_{joint}.flange", f"{joint}.axis"),
                     (f"qd_{joint}.flange", f"{joint}.axis"),
                     (f"r_{joint}.y", f"e_{joint}.u1"), (f"q_{joint}.y", f"e_{joint}.u2"),
                     (f"rd_{joint}.y", f"ed_{joint}.u1"), (f"qd_{joint}.y", f"ed_{joint}.u2"),
                     (f"e_{joint}.y", f"kp_{joint}.u"), (f"ed_{joint}.y", f"kd_{joint}.u"),
                     (f"rdd_{joint}.y", f"a_{joint}.u1"), (f"kp_{joint}.y", f"a_{joint}.u2"),
                     (f"kd_{joint}.y", f"a_{joint}.u3"),
                     (f"inverse_{joint}.y", f"motor_{joint}.u"),
                     (f"motor_{joint}.flange", f"{joint}.axis")]:
            model.connect(a, b)
        model.add(kn.Probe(f"error_{joint}", quantities=["value"]))
        model.connect(f"error_{joint}.port", f"e_{joint}.y")
    for joint in SINES:
        for i, other in enumerate(SINES):
            model.connect(f"a_{other}.y", f"inverse_{joint}.a{i + 1}")
    return model


def axis_definition():
    """One drive axis of ``arm_pid`` as a subsystem definition ("Axis", as MSL's RobotR3
    places one AxisType per joint): a motor torque on a rotor (J_m), a gearbox (ratio n) to
    the joint, the joint angle measured and PID-controlled (torque limited to y_max). Ports:
    ``flange`` (to the joint's axis), ``reference`` (the set point signal)."""
    rot, sig = kn.rotational, kn.signals
    axis = kn.Model("Axis", parameters=dict(DRIVE), description=(
        "A geared drive axis under PID control of the angle of its flange: motor torque "
        "(limited to y_max, back-calculation anti-windup) on a rotor of inertia J_m, a "
        "gearbox of ratio n to the flange, the flange angle measured. Ports: flange (to a "
        "joint's axis) and reference (the set point)."))
    axis.add(rot.Torque("motor"))
    axis.add(rot.Inertia("rotor", J="J_m"))
    axis.add(rot.IdealGear("gear", ratio="n"))
    axis.add(rot.AngleSensor("angle"))
    axis.add(sig.PID("pid", k="k", Ti="Ti", Td="Td", Nd="Nd", y_max="y_max"))
    axis.add(kn.Probe("command", quantities=["value"]))
    for a, b in [("motor.flange", "rotor.flange_a"), ("rotor.flange_b", "gear.flange_a"),
                 ("angle.flange", "gear.flange_b"), ("angle.y", "pid.u_m"),
                 ("pid.y", "motor.u"), ("command.port", "pid.y")]:
        axis.connect(a, b)
    axis.expose("flange", "gear.flange_b")
    axis.expose("reference", "pid.u_s")
    return axis


def arm_axes(axis=None, drive=None):
    """``arm_pid`` with each joint's drive one instance of :func:`axis_definition` (or
    ``axis``), fed from the model's parameters: ``shoulder_axis``, ``elbow_axis``."""
    d = {**DRIVE, **(drive or {})}
    model = _seed_copy("arm_axes", {"t_end": 6.0, "n_points": 601, "rtol": 1e-8,
                                    "atol": 1e-10}, (
        "The seed's 2-DOF arm with one Axis subsystem (Axis.json: geared motor under PID "
        "control of the joint angle) on each joint: the shoulder follows a step of 0.5 rad "
        "at t = 0.5 s, the elbow a sine of 0.3 rad at 0.5 Hz. The same scene as arm_pid.json, "
        "written flat there."))
    for name, value in d.items():
        model.set_parameter(name, value)
    axis = axis or axis_definition()
    refs = {"shoulder": kn.signals.Step("ref_shoulder", **STEP),
            "elbow": kn.signals.Sine("ref_elbow", **SINE)}
    for joint, ref in refs.items():
        model.add(ref)
        model.add(kn.Subsystem(f"{joint}_axis", axis, params={k: k for k in DRIVE}))
        model.connect(f"{joint}_axis.flange", f"{joint}.axis")
        model.connect(f"{ref.name}.y", f"{joint}_axis.reference")
        model.add(kn.Probe(f"reference_{joint}", quantities=["value"]))
        model.connect(f"reference_{joint}.port", f"{ref.name}.y")
    return model


def write_robot(folder):
    """``folder``/Axis.json and ``folder``/arm_axes.json placing it on each joint (the
    example in ``models/robot``)."""
    folder = pathlib.Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    axis_definition().save(folder / "Axis.json")
    arm_axes(kn.load(folder / "Axis.json")).save(folder / "arm_axes.json")
    return folder / "arm_axes.json"


FILES = {"arm_pid": arm_pid, "drive_train": drive_train,
         "arm_computed_torque": arm_computed_torque}


if __name__ == "__main__":
    for name, build in FILES.items():
        path = ROOT / "models" / f"{name}.json"
        build().save(path)
        print("wrote", path)
    print("wrote", write_robot(ROOT / "models" / "robot"))
