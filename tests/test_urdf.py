"""URDF import (``kn.from_urdf``, ``kinetwork import``) against Pinocchio's own URDF parser.

Each robot in ``tests/data`` is read twice: by kinetwork and by ``pin.buildModelFromUrdf``
(urdfdom, an independent parser and an independent dynamics code). The joint-space mass
matrix and the forward dynamics (``pin.crba``, ``pin.aba``) must agree to 1e-9 at random
states, with random joint torques applied through 1-D sources on the joints' flanges and the
URDF's viscous damping and sliding Coulomb friction (which ``pin.aba`` leaves out) added to
Pinocchio's torques; within the joints' limits, where their end stops are free.

Conventions mapped (kinetwork.components.multibody): a 1-DOF joint's q and qd are
Pinocchio's, but for a continuous joint, whose angle Pinocchio keeps as (cos q, sin q). A
FreeMotion has r and a quaternion [w, x, y, z], speeds v = dr/dt in frame_a axes and w in
frame_b axes; Pinocchio's free flyer has [r, x, y, z, w] and the body velocity [R^T v, w], so
v_pin = T u with T = diag(R^T, 1) and d(R^T v)/dt = R^T v' - w x R^T v. A Planar joint has
(x, y, angle) and their rates; Pinocchio's planar (x, y, cos, sin) and the velocity in the
moving frame, mapped the same way in 2-D. Mass matrices compare as
T^T M_pin T (the same kinetic energy).
"""

import importlib.metadata
import json
import pathlib
import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin
import pytest

import kinetwork as kn
from kinetwork import urdf
from kinetwork.cli import main

DATA = pathlib.Path(__file__).parent / "data"
#: (robot, floating): the fixed-base ones free as well where a free base is worth a check
ROBOTS = [("planar_arm", False), ("industrial_arm", False), ("industrial_arm", True),
          ("gantry", False), ("floating_base", True), ("puck", False)]
RTOL = 1e-9


# ---------------------------------------------------------------------------------------------
# kinetwork's states and Pinocchio's (q, v)
# ---------------------------------------------------------------------------------------------

def rot2(angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s], [s, c]])


def quat_R(quat):
    """Rotation of the normalised quaternion [w, x, y, z]."""
    w, x, y, z = np.asarray(quat) / np.linalg.norm(quat)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


class Pair:
    """A URDF robot in both libraries, and the maps between their coordinates."""

    def __init__(self, name, floating=False, gravity=None, limits=True):
        path = name if isinstance(name, pathlib.Path) else DATA / f"{name}.urdf"
        kwargs = {} if gravity is None else {"gravity": gravity}
        self.model = kn.from_urdf(path, floating=floating, limits=limits, **kwargs)
        self.pmodel = (pin.buildModelFromUrdf(str(path), pin.JointModelFreeFlyer())
                       if floating else pin.buildModelFromUrdf(str(path)))
        if gravity is not None:
            self.pmodel.gravity.linear = np.asarray(gravity, dtype=float)
        info = self.model.layout["ground"]["urdf"]
        self.damping, self.friction = {}, {}
        # a 1-D source on every 1-DOF joint, its torque or force a model parameter
        for joint in list(self.model.components.values()):
            if getattr(joint, "role", "") != "joint" or joint.dof != 1:
                continue
            lib = kn.rotational.Torque if joint.domain == "rotational" else kn.translational.Force
            key = "tau" if joint.domain == "rotational" else "f"
            self.model.set_parameter(f"u_{joint.name}", 0.0)
            drive = self.model.add(lib(f"drive_{joint.name}", **{key: f"u_{joint.name}"}))
            self.model.connect(drive.flange, joint.axis)
            dynamics = self.model.layout[joint.name]["urdf"].get("dynamics", {})
            self.damping[joint.name] = dynamics.get("damping", 0.0)
            self.friction[joint.name] = dynamics.get("friction", 0.0)
        self.system = self.model.compile()
        coords, speeds = self.system.coordinate_names, self.system.speed_names
        # the joints' end stops add their modes (0: free, as no stop is active here)
        self.n_modes = self.system.n_states - len(coords) - len(speeds)
        assert self.system.state_names[:len(coords) + len(speeds)] == coords + speeds
        assert all(n.endswith(("_limits.mode", "_friction.mode"))
                   for n in self.system.state_names[len(coords) + len(speeds):])
        self.joints = []              # (pin joint, component, coordinate and speed indices)
        for jid in range(1, self.pmodel.njoints):
            jname = self.pmodel.names[jid]
            comp = info["base"] if jname == "root_joint" else info["joints"][jname]
            qi = [i for i, n in enumerate(coords) if n.startswith(comp + ".")]
            ui = [i for i, n in enumerate(speeds) if n.startswith(comp + ".")]
            joint = self.pmodel.joints[jid]
            assert (len(qi), len(ui)) == {4: (3, 3), 2: (1, 1)}.get(joint.nq,
                                                                    (joint.nq, joint.nv))
            self.joints.append((joint, comp, qi, ui))
        assert sum(len(j[3]) for j in self.joints) == len(speeds) == self.pmodel.nv
        self.nq, self.nu = len(coords), len(speeds)
        self.ranges = {}
        for comp in (c for c in self.model.components if c.endswith("_limits")):
            stop = self.model.components[comp]
            low, high = [v for k, v in stop.given.items() if k.endswith(("_min", "_max"))]
            self.ranges[comp[:-len("_limits")]] = (low, high)

    def random_state(self, rng):
        q, u = np.zeros(self.nq), rng.uniform(-2.0, 2.0, self.nu)
        for joint, comp, qi, ui in self.joints:
            kind = type(self.model.components[comp]).__name__
            if kind == "FreeMotion":
                q[qi] = np.concatenate([rng.uniform(-1, 1, 3), rng.normal(size=4)])
                q[qi[3:]] /= np.linalg.norm(q[qi[3:]])
            elif comp in self.ranges:      # within its end stops: none of them active
                q[qi] = rng.uniform(*self.ranges[comp])
            elif kind == "Prismatic":
                q[qi] = rng.uniform(-0.3, 0.5)
            else:
                q[qi] = rng.uniform(-np.pi, np.pi, len(qi))
        return q, u

    def state(self, q, u):
        """kinetwork's state: q, u and the modes of the end stops (0: free) and of the joint
        frictions (sliding the way the joint turns: +-1)."""
        speed = {comp: u[ui[0]] for _, comp, _, ui in self.joints if len(ui) == 1}
        modes = [np.sign(speed[name[:-len("_friction.mode")]])
                 if name.endswith("_friction.mode") else 0.0
                 for name in self.system.state_names[self.nq + self.nu:]]
        return np.concatenate([q, u, modes])

    def to_pin(self, q, u):
        """Pinocchio's (q, v) and T with v = T u."""
        q_pin, T = np.zeros(self.pmodel.nq), np.zeros((self.pmodel.nv, self.nu))
        for joint, comp, qi, ui in self.joints:
            iq, iv = joint.idx_q, joint.idx_v
            block = np.eye(joint.nv)
            if joint.nq == 7:          # free flyer: [r, x y z w]; [R^T v, w]
                r, quat = q[qi[:3]], q[qi[3:]] / np.linalg.norm(q[qi[3:]])
                q_pin[iq:iq + 7] = np.concatenate([r, quat[1:], quat[:1]])
                block[:3, :3] = quat_R(quat).T
            elif joint.nq == 4:        # planar: [x, y, cos, sin]; [R2^T (x', y'), angle']
                x, y, phi = q[qi]
                q_pin[iq:iq + 4] = [x, y, np.cos(phi), np.sin(phi)]
                block[:2, :2] = rot2(phi).T
            elif joint.nq == 2:        # unbounded revolute (URDF continuous): [cos, sin]
                q_pin[iq:iq + 2] = [np.cos(q[qi[0]]), np.sin(q[qi[0]])]
            else:
                q_pin[iq] = q[qi[0]]
            T[iv:iv + joint.nv, ui] = block
        return q_pin, T @ u, T

    def udot(self, q, u, a):
        """kinetwork's speed rates from Pinocchio's a = d(T u)/dt."""
        out = np.zeros(self.nu)
        for joint, comp, qi, ui in self.joints:
            aj, uj = a[joint.idx_v:joint.idx_v + joint.nv], u[ui]
            if joint.nq == 7:          # d/dt(R^T v) = R^T v' - w x R^T v
                R = quat_R(q[qi[3:]])
                out[ui] = np.concatenate([R @ (aj[:3] + np.cross(uj[3:], R.T @ uj[:3])), aj[3:]])
            elif joint.nq == 4:
                R2 = rot2(q[qi[2]])
                v_l = R2.T @ uj[:2]
                out[ui] = np.concatenate([R2 @ (aj[:2] + uj[2] * np.array([-v_l[1], v_l[0]])),
                                          aj[2:]])
            else:
                out[ui] = aj
        return out

    def pin_acceleration(self, q, u, udot):
        """Pinocchio's a = d(T u)/dt from kinetwork's speed rates (``udot``'s inverse)."""
        a = np.zeros(self.pmodel.nv)
        for joint, comp, qi, ui in self.joints:
            uj, rj = u[ui], udot[ui]
            if joint.nq == 7:
                R = quat_R(q[qi[3:]])
                aj = np.concatenate([R.T @ rj[:3] - np.cross(uj[3:], R.T @ uj[:3]), rj[3:]])
            elif joint.nq == 4:
                R2 = rot2(q[qi[2]])
                v_l = R2.T @ uj[:2]
                aj = np.concatenate([R2.T @ rj[:2] - uj[2] * np.array([-v_l[1], v_l[0]]),
                                     rj[2:]])
            else:
                aj = rj
            a[joint.idx_v:joint.idx_v + joint.nv] = aj
        return a

    def compare(self, q, u, drive):
        """(relative error of M, of the speed rates) against crba and aba."""
        q_pin, v_pin, T = self.to_pin(q, u)
        data = self.pmodel.createData()
        M_pin = pin.crba(self.pmodel, data, q_pin).copy()
        M_ref = T.T @ (np.triu(M_pin) + np.triu(M_pin, 1).T) @ T
        M = np.asarray(self.system.mass_matrix(q), dtype=float)
        tau = np.zeros(self.pmodel.nv)
        params = {}
        for joint, comp, qi, ui in self.joints:
            if comp in self.damping:
                params[f"u_{comp}"] = drive[ui[0]]
                tau[joint.idx_v] = (drive[ui[0]] - self.damping[comp] * u[ui[0]]
                                    - self.friction[comp] * np.sign(u[ui[0]]))
        a = pin.aba(self.pmodel, self.pmodel.createData(), q_pin, v_pin, tau).copy()
        ref = self.udot(q, u, a)
        dx = np.asarray(self.system.rhs(0.0, self.state(q, u), params=params),
                        dtype=float).ravel()
        e_M = np.abs(M - M_ref).max() / np.abs(M_ref).max()
        e_a = np.abs(dx[self.nq:self.nq + self.nu] - ref).max() / max(1.0, np.abs(ref).max())
        return e_M, e_a


@pytest.fixture(scope="module", params=ROBOTS, ids=[f"{r}{'-floating' * f}" for r, f in ROBOTS])
def pair(request):
    return Pair(*request.param)


def test_agrees_with_pinocchio(pair):
    """M(q) and the accelerations at random states, torques and forces, to 1e-9."""
    rng = np.random.default_rng(15)
    for k in range(6):
        q, u = pair.random_state(rng)
        drive = rng.uniform(-20.0, 20.0, pair.nu)
        e_M, e_a = pair.compare(q, u, drive)
        assert e_M < RTOL, f"mass matrix, state {k}: relative error {e_M:.2e}"
        assert e_a < RTOL, f"accelerations, state {k}: relative error {e_a:.2e}"


def test_gravity_option():
    """A gravity other than URDF's default, in both libraries."""
    pair = Pair("gantry", gravity=(1.5, -2.0, -9.0))
    assert pair.model.components["ground"].gravity == [1.5, -2.0, -9.0]
    q, u = pair.random_state(np.random.default_rng(3))
    e_M, e_a = pair.compare(q, u, np.zeros(pair.nu))
    assert e_M < RTOL and e_a < RTOL


# ---------------------------------------------------------------------------------------------
# What the model keeps: names, limits, visuals, probes
# ---------------------------------------------------------------------------------------------

def test_names_are_sanitized_and_mapped():
    """Joints are named first, then links, each clash getting _2; the map is kept."""
    model = kn.from_urdf(DATA / "gantry.urdf")
    info = model.layout["ground"]["urdf"]
    assert info["robot"] == "gantry robot" and model.name == "gantry robot"
    assert info["joints"] == {"carriage": "carriage", "bracket bolt": "bracket_bolt_origin",
                              "slew-joint": "slew_joint", "ram_joint": "ram_joint",
                              "gripper_mount": "gripper_mount_origin"}
    assert info["links"]["rail"] == "ground.frame"
    assert info["links"]["carriage"] == "carriage.frame_b"
    assert info["links"]["2nd gripper"] == "gripper_mount_origin.frame_b"
    # the link bodies (a visual's massless shape body has no entry of its own)
    bodies = {model.layout[c.name]["urdf"]["link"]: c.name for c in model.components.values()
              if c.role == "body" and "urdf" in model.layout.get(c.name, {})
              and not model.layout[c.name]["urdf"].get("visual")}
    assert bodies == {"rail": "rail", "carriage": "carriage_2", "bracket-A": "bracket_A",
                      "slew": "slew", "ram": "ram", "2nd gripper": "_2nd_gripper"}
    assert kn.from_urdf(DATA / "gantry.urdf", name="g").name == "g"


def test_limits_and_dynamics_are_kept_as_data():
    model = kn.from_urdf(DATA / "planar_arm.urdf")
    shoulder = model.layout["shoulder"]["urdf"]
    assert shoulder == {"joint": "shoulder", "type": "revolute",
                        "limit": {"lower": -2.8, "upper": 2.8, "effort": 40.0, "velocity": 3.0},
                        "dynamics": {"damping": 0.5, "friction": 0.1}}
    assert model.layout["elbow"]["urdf"]["limit"] == {"effort": 20.0, "velocity": 4.0}
    # the damping is physics (a Damper on the joint), the friction only data
    assert model.components["shoulder_damper"].d == 0.5
    assert [type(c).__name__ for c in model.components.values()].count("Damper") == 1


def test_visuals():
    model = kn.from_urdf(DATA / "planar_arm.urdf")
    visuals = model.layout["ground"]["urdf"]["visuals"]
    assert [(v["link"], v["kind"], v["color"]) for v in visuals] == [
        ("base_link", "cylinder", "#9ea3a8"), ("upper_arm", "box", "#ff6b00"),
        ("forearm", "cylinder", "#1a4ce6")]
    assert visuals[1]["size"] == [1.0, 0.05, 0.05]
    assert (visuals[2]["length"], visuals[2]["radius"]) == (0.8, 0.02)
    meshes = [v for v in kn.from_urdf(DATA / "industrial_arm.urdf").layout["ground"]["urdf"]
              ["visuals"] if v["kind"] == "mesh"]
    assert [(m["filename"], m["scale"]) for m in meshes] == [
        ("package://industrial_arm/meshes/base_link.stl", [0.001, 0.001, 0.001]),
        ("meshes/link_1.dae", [1.0, 1.0, 1.0])]
    box = model.components[visuals[1]["component"]]
    assert (box.mass, box.shape, box.shape_size, box.color, box.r_cm) == (
        0.0, "box", [1.0, 0.05, 0.05], "#ff6b00", [0.5, 0.0, 0.0])
    # the forearm's cylinder lies along the link's x: its z turned by the visual's pitch,
    # then onto the RigidBody's x (a rotation about y by 90 - 90 = 0 degrees: no part)
    forearm = model.components[visuals[2]["component"]]
    assert (forearm.shape, forearm.shape_size, forearm.r_cm) == (
        "cylinder", [0.8, 0.04, 0.04], [0.4, 0.0, 0.0])


def probe_values(system, x):
    """{signal name: value} of the system's probes at state x (t = 0)."""
    flat = np.asarray(system.outputs(0.0, x[None, :]), dtype=float).ravel()
    out, i = {}, 0
    for sig in system.signals:
        out[sig.name] = flat[i:i + sig.size].reshape(sig.shape)
        i += sig.size
    return out


@pytest.mark.parametrize("robot", ["planar_arm", "gantry", "puck"])
def test_visuals_sit_where_urdf_puts_them(robot):
    """Each shape's centre and axes (a cylinder's length along the RigidBody's x) against
    the link frames of Pinocchio's model composed with the visual's origin."""
    pair = Pair(robot)
    looks = [v for v in pair.model.layout["ground"]["urdf"]["visuals"] if v["component"]]
    for v in looks:
        probe = pair.model.add(kn.Probe(f"look_{v['component']}",
                                        quantities=["position", "orientation"]))
        pair.model.connect(probe.port, f"{v['component']}.frame_a")
    system = pair.model.compile()
    q, u = pair.random_state(np.random.default_rng(4))
    values = probe_values(system, pair.state(q, u))
    data = pair.pmodel.createData()
    pin.framesForwardKinematics(pair.pmodel, data, pair.to_pin(q, u)[0])
    for v in looks:
        link = data.oMf[pair.pmodel.getFrameId(v["link"])]
        turn = urdf.Z_TO_X if v["kind"] == "cylinder" else np.eye(3)
        want = link * pin.SE3(urdf.rpy_matrix(v["rpy"]) @ turn, np.array(v["xyz"]))
        body = pair.model.components[v["component"]]
        R, r = values[f"look_{body.name}.orientation"], values[f"look_{body.name}.position"]
        np.testing.assert_allclose(r + R @ body.r_cm, want.translation, atol=1e-12)
        np.testing.assert_allclose(R, want.rotation, atol=1e-9)   # LOOKS_ANGLE


def test_visual_bodies_change_no_dynamics():
    """A massless shape body adds nothing: M equals that of the model without visuals."""
    with_looks = Pair("planar_arm", limits=False)
    q, u = with_looks.random_state(np.random.default_rng(0))
    model = kn.from_urdf(DATA / "planar_arm.urdf", limits=False)
    for name in [v["component"] for v in model.layout["ground"]["urdf"]["visuals"]]:
        if name is not None:
            model.components[name].mass = 0.0
    np.testing.assert_allclose(with_looks.system.mass_matrix(q),
                               model.compile().mass_matrix(q), rtol=1e-14)


def test_probes_record_the_joints():
    model = kn.from_urdf(DATA / "planar_arm.urdf", probes=True)
    probe = model.components["shoulder_probe"]
    assert probe.quantities == ["angle", "speed", "torque"]
    model.components["shoulder"].q0 = 0.3
    res = kn.simulate(model, t_end=0.2, n_points=5)
    np.testing.assert_allclose(res["shoulder_probe.angle"], res.states[:, 0], rtol=1e-12)
    # the damper's torque is what the shoulder's flange carries
    np.testing.assert_allclose(res["shoulder_probe.torque"], -0.5 * res["shoulder_probe.speed"],
                               rtol=1e-9, atol=1e-12)
    gantry = kn.from_urdf(DATA / "gantry.urdf", probes=True)
    assert gantry.components["ram_joint_probe"].quantities == ["position", "velocity", "force"]
    free = kn.from_urdf(DATA / "floating_base.urdf", probes=True, floating=True)
    assert free.components["torso_floating_probe"].quantities == [
        "position", "orientation", "velocity", "angular_velocity"]


def test_floating_base_centre_of_mass_falls_at_g():
    """Free in gravity, whatever the joints do, the centre of mass accelerates at g: a law
    checked on kinetwork's accelerations (turned into Pinocchio's by d(T u)/dt)."""
    pair = Pair("floating_base", floating=True, gravity=(0.3, -0.4, -9.81))
    rng = np.random.default_rng(7)
    for _ in range(3):
        q, u = pair.random_state(rng)
        dx = np.asarray(pair.system.rhs(0.0, pair.state(q, u)), dtype=float).ravel()
        q_pin, v_pin, _ = pair.to_pin(q, u)
        a_pin = pair.pin_acceleration(q, u, dx[pair.nq:pair.nq + pair.nu])
        data = pair.pmodel.createData()
        pin.centerOfMass(pair.pmodel, data, q_pin, v_pin, a_pin)
        np.testing.assert_allclose(data.acom[0], [0.3, -0.4, -9.81], rtol=1e-10, atol=1e-10)


# ---------------------------------------------------------------------------------------------
# Rotations
# ---------------------------------------------------------------------------------------------

@pytest.mark.parametrize("rpy", [[0, 0, 0], [0.1, -0.2, 0.3], [np.pi, 0, 0], [0, np.pi, 0],
                                 [0, 0, np.pi], [np.pi / 2, np.pi / 2, 0], [3.0, 0.1, -0.2],
                                 [1e-9, 0, 0], [np.pi, 1e-9, -1e-9], [-2.5, 1.2, 2.9]])
def test_rpy_and_axis_angle(rpy):
    R = urdf.rpy_matrix(rpy)
    np.testing.assert_allclose(R, pin.rpy.rpyToMatrix(*rpy), atol=1e-15)
    axis, angle = urdf.axis_angle(R)
    assert 0 <= angle <= np.pi and np.linalg.norm(axis) == pytest.approx(1.0, abs=1e-15)
    np.testing.assert_allclose(pin.AngleAxis(angle, np.array(axis)).matrix(), R, atol=4e-16)


# ---------------------------------------------------------------------------------------------
# Files and the command line
# ---------------------------------------------------------------------------------------------

def test_saved_model_loads_and_simulates(tmp_path):
    model = kn.from_urdf(DATA / "industrial_arm.urdf", probes=True)
    model.save(tmp_path / "arm.json")
    again = kn.load(tmp_path / "arm.json")
    assert kn.dumps(again) == kn.dumps(model)
    assert again.layout["joint_5"]["urdf"]["limit"]["upper"] == 2.1
    res = kn.simulate(again, t_end=0.1, n_points=3)
    assert np.all(np.isfinite(res.states))


def test_cli_import(tmp_path, capsys):
    out = tmp_path / "gantry.json"
    assert main(["import", str(DATA / "gantry.urdf"), "-o", str(out), "--probes"]) == 0
    assert "3 degrees of freedom" in capsys.readouterr().out
    model = kn.load(out)
    assert "carriage_probe" in model.components
    res = kn.simulate(model, t_end=0.1, n_points=3)
    assert res["carriage_probe.position"].shape == (3,)

    out = tmp_path / "free.json"
    assert main(["import", str(DATA / "floating_base.urdf"), "-o", str(out), "--floating",
                 "--gravity", "0", "0", "-1.62"]) == 0
    model = kn.load(out)
    assert model.components["ground"].gravity == [0.0, 0.0, -1.62]
    assert type(model.components["torso_floating"]).__name__ == "FreeMotion"
    assert [c for c in model.components if c.endswith("_limits")]
    out = tmp_path / "unlimited.json"
    assert main(["import", str(DATA / "floating_base.urdf"), "-o", str(out), "--no-limits"]) == 0
    assert not [c for c in kn.load(out).components if c.endswith("_limits")]


def test_cli_import_refuses(tmp_path, capsys):
    out = tmp_path / "none.json"
    assert main(["import", str(tmp_path / "missing.urdf"), "-o", str(out)]) != 0
    assert "no such file" in capsys.readouterr().err
    assert not out.exists()


# ---------------------------------------------------------------------------------------------
# Refusals, each naming the element
# ---------------------------------------------------------------------------------------------

LINK = ('<link name="{}"><inertial><mass value="1"/><inertia ixx="0.1" iyy="0.1" izz="0.1" '
        'ixy="0" ixz="0" iyz="0"/></inertial></link>')


def joint(name, parent, child, kind="revolute", extra=""):
    return (f'<joint name="{name}" type="{kind}"><parent link="{parent}"/>'
            f'<child link="{child}"/><axis xyz="0 0 1"/>{extra}</joint>')


def robot(*parts):
    return '<robot name="r">' + "".join(parts) + "</robot>"


BAD = {
    "malformed": ("<robot name='r'><link name='a'></robot>", r"malformed XML at line 1"),
    "not_urdf": ("<sdf version='1.6'/>", r"root element is <sdf>, not <robot>"),
    "xacro": ('<robot xmlns:xacro="http://www.ros.org/wiki/xacro" name="r">'
              '<xacro:property name="L" value="1"/><link name="a"/></robot>', r"xacro"),
    "no_parent": (robot(LINK.format("a"), LINK.format("b"), joint("elbow", "nowhere", "b")),
                  r'joint "elbow": parent link "nowhere" does not exist'),
    "no_child": (robot(LINK.format("a"), joint("elbow", "a", "hand")),
                 r'joint "elbow": child link "hand" does not exist'),
    "two_parents": (robot(LINK.format("a"), LINK.format("b"), LINK.format("c"),
                          joint("j1", "a", "b"), joint("j2", "a", "c"), joint("j3", "b", "c")),
                    r'joint "j3": link "c" is already the child of joint "j2": a kinematic '
                    r'loop'),
    "cycle": (robot(LINK.format("a"), LINK.format("b"), LINK.format("c"),
                    joint("j1", "a", "b"), joint("j2", "b", "c"), joint("j3", "c", "b")),
              r'a kinematic loop'),
    "two_roots": (robot(LINK.format("a"), LINK.format("b")), r'2 root links \("a", "b"\)'),
    "negative_mass": (robot('<link name="arm"><inertial><mass value="-2"/><inertia ixx="1" '
                            'iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>'),
                      r'link "arm" inertial mass: must be >= 0, got -2'),
    "indefinite": (robot('<link name="arm"><inertial><mass value="2"/><inertia ixx="1" '
                         'iyy="1" izz="1" ixy="2" ixz="0" iyz="0"/></inertial></link>'),
                   r'link "arm" inertial inertia: must be positive definite'),
    "negative_moment": (robot('<link name="arm"><inertial><mass value="2"/><inertia ixx="-1" '
                              'iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>'),
                        r'link "arm" inertial inertia: must be positive definite'),
    "singular": (robot('<link name="arm"><inertial><mass value="2"/><inertia ixx="0" '
                       'iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>'),
                 r'link "arm" inertial inertia: must be positive definite, its principal '
                 r'moments are 0, 1, 1'),
    "massless_leaf": (robot(LINK.format("a"), LINK.format("b"), '<link name="finger"/>',
                            joint("j1", "a", "b"), joint("j2", "b", "finger")),
                      r'joint "j2": moves link "finger", which has no mass and carries none'),
    "type": (robot(LINK.format("a"), LINK.format("b"), joint("j", "a", "b", kind="ball")),
             r'joint "j": type "ball" is not one of revolute'),
    "axis": (robot(LINK.format("a"), LINK.format("b"),
                   joint("j", "a", "b").replace('xyz="0 0 1"', 'xyz="0 0 0"')),
             r'joint "j" axis: must not be zero'),
    "numbers": (robot(LINK.format("a"), LINK.format("b"),
                      joint("j", "a", "b", extra='<origin xyz="0 1"/>')),
                r'joint "j" origin xyz: expected 3 finite numbers, got "0 1"'),
    "duplicate": (robot(LINK.format("a"), LINK.format("a")), r'link "a": defined twice'),
    "damping": (robot(LINK.format("a"), LINK.format("b"),
                      joint("j", "a", "b", extra='<dynamics damping="-1"/>')),
                r'joint "j" dynamics damping: must be a number >= 0'),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_refusals(case, tmp_path):
    text, message = BAD[case]
    path = tmp_path / "robot.urdf"
    path.write_text(text)
    with pytest.raises(kn.ModelError, match=message) as info:
        kn.from_urdf(path)
    assert str(info.value).startswith("robot.urdf: ")


def test_idealised_inertia_is_warned_of(tmp_path):
    """Principal moments no rigid body has are kinetwork's idealisation: warned, imported."""
    path = tmp_path / "robot.urdf"
    path.write_text(robot('<link name="arm"><inertial><mass value="2"/><inertia ixx="1" '
                          'iyy="1" izz="3" ixy="0" ixz="0" iyz="0"/></inertial></link>'))
    with pytest.warns(kn.IdealisedInertiaWarning, match="triangle inequality"):
        model = kn.from_urdf(path)
    assert model.components["arm"].inertia == [[1, 0, 0], [0, 1, 0], [0, 0, 3]]


def test_point_masses_and_massless_links(tmp_path):
    """An all-zero inertia is a point mass; a link without inertial adds no body."""
    path = tmp_path / "robot.urdf"
    path.write_text(robot('<link name="base"/>', LINK.format("arm").replace(
        'ixx="0.1" iyy="0.1" izz="0.1"', 'ixx="0" iyy="0" izz="0"').replace(
        '<mass value="1"/>', '<origin xyz="1 0 0"/><mass value="1"/>'),
        joint("j", "base", "arm", extra='<axis xyz="0 1 0"/>').replace(
            '<axis xyz="0 0 1"/>', '')))
    model = kn.from_urdf(path)
    assert [c.name for c in model.components.values() if c.role == "body"] == ["arm"]
    assert model.compile().mass_matrix([0.3]).tolist() == [[1.0]]


def test_missing_file(tmp_path):
    with pytest.raises(kn.ModelError, match=r"missing\.urdf\": no such file"):
        kn.from_urdf(tmp_path / "missing.urdf")


def test_every_problem_reported_at_once(tmp_path):
    path = tmp_path / "robot.urdf"
    path.write_text(robot('<link name="a"><inertial><mass value="-1"/><inertia ixx="1" '
                          'iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>',
                          LINK.format("b"), joint("j", "a", "b", kind="hinge"),
                          joint("k", "b", "zz")))
    with pytest.raises(kn.ModelError) as info:
        kn.from_urdf(path)
    assert len(info.value.problems) == 2          # the tree is checked once the parts parse
    assert "mass" in info.value.problems[0] and "hinge" in info.value.problems[1]
    json.dumps(info.value.problems)


# ---------------------------------------------------------------------------------------------
# Real robots: the Panda and the UR5 of example-robot-data (its URDFs and meshes on PyPI)
# ---------------------------------------------------------------------------------------------
ROBOT_DATA = pathlib.Path(importlib.metadata.distribution("example-robot-data").locate_file(
    "cmeel.prefix/share/example-robot-data/robots"))
REAL = {"panda": ROBOT_DATA / "panda_description/urdf/panda.urdf",
        "ur5": ROBOT_DATA / "ur_description/urdf/ur5_robot.urdf"}


@pytest.fixture(scope="module", params=sorted(REAL))
def real(request):
    return Pair(REAL[request.param])


def test_real_robots_agree_with_pinocchio_while_no_stop_is_active(real):
    """Within their limits (every end stop free), M(q) and the accelerations to 1e-10 of
    Pinocchio's crba and aba, the URDF's damping added to its torques."""
    assert real.ranges, "the robot's joint limits are imposed"
    rng = np.random.default_rng(31)
    for k in range(6):
        q, u = real.random_state(rng)
        drive = rng.uniform(-5.0, 5.0, real.nu)
        e_M, e_a = real.compare(q, u, drive)
        assert e_M < 1e-10, f"mass matrix, state {k}: relative error {e_M:.2e}"
        assert e_a < 1e-10, f"accelerations, state {k}: relative error {e_a:.2e}"


def test_panda_joints_stay_within_their_limits():
    """Falling under gravity from its zero pose (joint 4, whose range excludes 0, starts at
    its upper limit), every joint stays within the URDF's limits and the fingers within
    0..0.04 m; without limits, joint 2 falls through its limit."""
    model = kn.from_urdf(REAL["panda"])
    res = kn.simulate(model, t_end=1.5, n_points=151)
    joints = ET.parse(REAL["panda"]).getroot().findall("joint")
    limited = {j.get("name"): (float(j.find("limit").get("lower")),
                               float(j.find("limit").get("upper")))
               for j in joints if j.get("type") in ("revolute", "prismatic")}
    assert {"panda_finger_joint1", "panda_finger_joint2"} <= set(limited)
    hit = set()
    for name, (low, high) in limited.items():
        q = res[f"{name}.q"]
        assert q.min() >= low - 1e-9 and q.max() <= high + 1e-9, name
        if np.isclose(q, low, atol=1e-9).any() or np.isclose(q, high, atol=1e-9).any():
            hit.add(name)
    assert {"panda_joint2", "panda_joint4"} <= hit     # they fall onto their stops
    free = kn.simulate(kn.from_urdf(REAL["panda"], limits=False), t_end=1.5, n_points=151)
    assert free["panda_joint2.q"].max() > limited["panda_joint2"][1] + 0.1
