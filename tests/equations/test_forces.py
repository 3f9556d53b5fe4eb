"""Force elements resolved in any frame, point gravity and line forces with mass.

- ``Force``, ``Torque``, ``ForceAndTorque`` (MSL's Forces): on random spatial chains against
  Pinocchio's forward dynamics with the external forces written in the joint frames by hand
  from MSL's definition (the force on frame_b at its origin, the reaction -f on frame_a
  along the same line of action, i.e. -f at frame_a's origin and the moment -t - r_ab x f),
  one test per ``resolve_in``; and against closed forms on two pendulums, where the reaction's
  lever arm decides the answer.
- Point gravity (the Ground's ``gravity_type`` "point", MSL's PointGravity): a circular orbit
  closes after 2 pi sqrt(r^3/mue); MSL's Elementary.PointGravity example keeps its energy and
  angular momentum and each body returns to its start after its Kepler period; the gravity
  torque of an offset centre of mass against numpy.
- Line forces with a point mass (MSL's Spring with m > 0): MSL's SpringWithMass example
  against its closed form (a harmonic oscillation), and two pendulums joined by a spring with
  mass against a sympy Lagrangian of the same scene (mass matrix and accelerations, where the
  point mass's velocity terms do not vanish), a four-bar with one (a loop) conserving energy.
"""

import json
import pathlib

import numpy as np
import pinocchio as pin
import pytest
import sympy as sp

import kinetwork as kn
from scenes import fourbar
from scenes.random_trees import build_kinetwork, random_mechanism, random_state
from scenes.reference_loops import fourbar_energy

mb = kn.multibody
MODELS = pathlib.Path(__file__).resolve().parents[2] / "models"


def rz(angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def rates(system, x, t=0.0):
    return np.asarray(system.rhs(t, np.asarray(x, dtype=float)), dtype=float).ravel()


def probe_values(system, x, t=0.0):
    """{signal name: value} of the system's probes at state x."""
    flat = np.asarray(system.outputs(t, np.asarray(x, dtype=float)[None, :]),
                      dtype=float).ravel()
    out, i = {}, 0
    for sig in system.signals:
        out[sig.name] = flat[i:i + sig.size].reshape(sig.shape)
        i += sig.size
    return out


# ---------------------------------------------------------------------------------------------
# Forces and torques between two frames, against Pinocchio
# ---------------------------------------------------------------------------------------------

def build_pinocchio(links, gravity):
    """The chain of ``scenes.random_trees`` in Pinocchio (as tests/equations/test_pinocchio):
    joint i + 1 is link i, its frame that of j{i}.frame_b."""
    model = pin.Model()
    model.gravity.linear = np.asarray(gravity, dtype=float)
    for i, L in enumerate(links):
        placement = (pin.SE3(_rodrigues(L.rot_axis, L.rot_angle), L.rot_r)
                     * pin.SE3(np.eye(3), L.tr_r))
        joint = (pin.JointModelRevoluteUnaligned(L.axis) if L.kind == "revolute"
                 else pin.JointModelPrismaticUnaligned(L.axis))
        jid = model.addJoint(L.parent + 1, joint, placement, f"j{i}")
        model.appendBodyToJoint(jid, pin.Inertia(L.mass, L.r_cm, L.inertia), pin.SE3.Identity())
    return model


def _rodrigues(axis, angle):
    n = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    k = np.array([[0, -n[2], n[1]], [n[2], 0, -n[0]], [-n[1], n[0], 0]])
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k


F_EXPR = ["1.5*cos(t)", -2.0, 0.7]
T_EXPR = [0.3, "sin(2*t)", -1.1]
T_NOW = 0.4
F_NOW = np.array([1.5 * np.cos(T_NOW), -2.0, 0.7])
T_VAL = np.array([0.3, np.sin(2 * T_NOW), -1.1])
#: joints (pinocchio indices) the element's frames sit on: frame_a, frame_b, frame_resolve
A, B, RES = 1, 3, 2


def pin_rates(pmodel, q, v, wrenches):
    """pin.aba with ``wrenches``: {joint: (force, moment about the world origin)}, both in
    the world, written as Pinocchio's external forces (joint frame, about its origin)."""
    data = pmodel.createData()
    pin.forwardKinematics(pmodel, data, q)
    fext = [pin.Force.Zero() for _ in range(pmodel.njoints)]
    for j, (f, m) in wrenches.items():
        R, p = data.oMi[j].rotation, data.oMi[j].translation
        f_old = fext[j]
        fext[j] = f_old + pin.Force(R.T @ f, R.T @ (m - np.cross(p, f)))
    return pin.aba(pmodel, data, q, v, np.zeros(pmodel.nv), fext).copy(), data


def msl_wrenches(data, resolve_in, f, t):
    """MSL's Force/Torque: f at frame_b's origin and t on frame_b; -f at frame_a's origin and
    -t - r_ab x f on frame_a (moments about the world origin)."""
    R = {"world": np.eye(3), "frame_a": data.oMi[A].rotation, "frame_b": data.oMi[B].rotation,
         "frame_resolve": data.oMi[RES].rotation}[resolve_in]
    F, T = R @ f, R @ t
    pa, pb = data.oMi[A].translation, data.oMi[B].translation
    return {B: (F, np.cross(pb, F) + T), A: (-F, np.cross(pa, -F) - T - np.cross(pb - pa, F))}


def chain_with(element, seed=11):
    links, gravity = random_mechanism(seed, 4)
    model = build_kinetwork(links, gravity)
    model.add(element)
    model.connect(f"{element.name}.frame_a", f"j{A - 1}.frame_b")
    model.connect(f"{element.name}.frame_b", f"j{B - 1}.frame_b")
    if "frame_resolve" in element.ports:
        model.connect(f"{element.name}.frame_resolve", f"j{RES - 1}.frame_b")
    return links, gravity, model


@pytest.mark.parametrize("resolve_in", ["world", "frame_a", "frame_b", "frame_resolve"])
def test_force_and_torque_matches_pinocchio(resolve_in):
    element = mb.ForceAndTorque("push", f=F_EXPR, t=T_EXPR, resolve_in=resolve_in)
    links, gravity, model = chain_with(element)
    system = model.compile()
    pmodel = build_pinocchio(links, gravity)
    for k in range(3):
        q, v = random_state(40 + k, links)
        data = pmodel.createData()
        pin.forwardKinematics(pmodel, data, q)
        ref, _ = pin_rates(pmodel, q, v, msl_wrenches(data, resolve_in, F_NOW, T_VAL))
        free, _ = pin_rates(pmodel, q, v, {})
        assert np.abs(ref - free).max() > 0.1          # the element matters
        got = rates(system, np.concatenate([q, v]), T_NOW)[len(q):]
        np.testing.assert_allclose(got, ref, rtol=1e-10, atol=1e-10 * np.abs(ref).max(),
                                   err_msg=f"{resolve_in}, point {k}")


@pytest.mark.parametrize("kind", ["Force", "Torque"])
def test_force_and_torque_alone_match_pinocchio(kind):
    """Force is ForceAndTorque with t = 0, Torque with f = 0 (here resolved in frame_resolve)."""
    element = (mb.Force("push", f=F_EXPR, resolve_in="frame_resolve") if kind == "Force"
               else mb.Torque("push", t=T_EXPR, resolve_in="frame_resolve"))
    links, gravity, model = chain_with(element)
    system = model.compile()
    pmodel = build_pinocchio(links, gravity)
    q, v = random_state(7, links)
    data = pmodel.createData()
    pin.forwardKinematics(pmodel, data, q)
    f, t = (F_NOW, np.zeros(3)) if kind == "Force" else (np.zeros(3), T_VAL)
    ref, _ = pin_rates(pmodel, q, v, msl_wrenches(data, "frame_resolve", f, t))
    got = rates(system, np.concatenate([q, v]), T_NOW)[len(q):]
    np.testing.assert_allclose(got, ref, rtol=1e-10, atol=1e-10 * np.abs(ref).max())


@pytest.mark.parametrize("resolve_in", ["world", "frame_b"])
def test_world_force_and_torque_resolved_in_frame_b_match_pinocchio(resolve_in):
    links, gravity = random_mechanism(12, 3)
    model = build_kinetwork(links, gravity)
    model.add(mb.WorldForce("push", force=F_EXPR, resolve_in=resolve_in))
    model.add(mb.WorldTorque("twist", torque=T_EXPR, resolve_in=resolve_in))
    model.connect("push.frame_b", "j2.frame_b")
    model.connect("twist.frame_b", "j1.frame_b")
    system = model.compile()
    pmodel = build_pinocchio(links, gravity)
    q, v = random_state(3, links)
    data = pmodel.createData()
    pin.forwardKinematics(pmodel, data, q)
    Rf = data.oMi[3].rotation if resolve_in == "frame_b" else np.eye(3)
    Rt = data.oMi[2].rotation if resolve_in == "frame_b" else np.eye(3)
    F = Rf @ F_NOW
    ref, _ = pin_rates(pmodel, q, v, {3: (F, np.cross(data.oMi[3].translation, F)),
                                      2: (np.zeros(3), Rt @ T_VAL)})
    got = rates(system, np.concatenate([q, v]), T_NOW)[len(q):]
    np.testing.assert_allclose(got, ref, rtol=1e-10, atol=1e-10 * np.abs(ref).max())


# ---------------------------------------------------------------------------------------------
# ... and against hand derivations
# ---------------------------------------------------------------------------------------------

L1, L2, M1, M2 = 0.7, 1.2, 2.0, 0.5


def two_arms(element, q0=(0.4, 2.1)):
    """Two arms turning about z at the world origin (no gravity), point masses at their
    tips: arm1's tip is frame_a of ``element``, arm2's tip its frame_b."""
    model = kn.Model("arms")
    model.add(mb.Ground("ground", gravity=[0, 0, 0]))
    for i, (L, m, q) in enumerate([(L1, M1, q0[0]), (L2, M2, q0[1])], start=1):
        model.add(mb.Revolute(f"j{i}", q0=q))
        model.add(mb.FixedTranslation(f"arm{i}", r=[L, 0, 0]))
        model.add(mb.RigidBody(f"tip{i}", mass=m))
        model.connect("ground.frame", f"j{i}.frame_a")
        model.connect(f"j{i}.frame_b", f"arm{i}.frame_a")
        model.connect(f"arm{i}.frame_b", f"tip{i}.frame_a")
    model.add(element)
    model.connect(f"{element.name}.frame_a", "arm1.frame_b")
    model.connect(f"{element.name}.frame_b", "arm2.frame_b")
    return model


@pytest.mark.parametrize("resolve_in", ["world", "frame_a", "frame_b"])
def test_reaction_acts_along_the_line_of_action(resolve_in):
    """F on arm2's tip r2 turns arm2 by (r2 x F)_z; the reaction on arm1 is -F along the same
    line, through r2, so it turns arm1 by -(r2 x F)_z, not -(r1 x F)_z."""
    f = np.array([0.8, -1.3, 0.4])
    system = two_arms(mb.Force("push", f=f.tolist(), resolve_in=resolve_in)).compile()
    for q in ([0.4, 2.1], [-1.0, 0.3]):
        R = {"world": np.eye(3), "frame_a": rz(q[0]), "frame_b": rz(q[1])}[resolve_in]
        F = R @ f
        r2 = L2 * np.array([np.cos(q[1]), np.sin(q[1]), 0.0])
        moment = np.cross(r2, F)[2]
        got = rates(system, [*q, 0.3, -0.5])[2:]
        np.testing.assert_allclose(got, [-moment / (M1 * L1**2), moment / (M2 * L2**2)],
                                   rtol=1e-12)


def test_torque_turns_frame_b_and_reacts_on_frame_a():
    system = two_arms(mb.Torque("twist", t=[0.2, -0.4, 1.5], resolve_in="world")).compile()
    got = rates(system, [0.4, 2.1, 0.0, 0.0])[2:]
    np.testing.assert_allclose(got, [-1.5 / (M1 * L1**2), 1.5 / (M2 * L2**2)], rtol=1e-12)


def test_world_force_in_frame_b_turns_with_the_body():
    """A force along the arm's own y axis at its tip: the torque L F whatever the angle."""
    model = kn.Model("arm")
    model.add(mb.Ground("ground", gravity=[0, 0, 0]))
    model.add(mb.Revolute("j"))
    model.add(mb.FixedTranslation("arm", r=[L1, 0, 0]))
    model.add(mb.RigidBody("tip", mass=M1))
    model.add(mb.WorldForce("push", force=[0.0, 3.0, 0.0], resolve_in="frame_b"))
    for a, b in [("ground.frame", "j.frame_a"), ("j.frame_b", "arm.frame_a"),
                 ("arm.frame_b", "tip.frame_a"), ("arm.frame_b", "push.frame_b")]:
        model.connect(a, b)
    system = model.compile()
    for q in (0.0, 1.0, 2.5):
        assert rates(system, [q, 0.7])[1] == pytest.approx(3.0 / (M1 * L1), rel=1e-12)


def test_world_torque_in_frame_b_drives_eulers_equations():
    """A torque fixed in the body on a free body: I dw/dt + w x I w = t (body axes)."""
    inertia = np.diag([0.4, 0.9, 1.3])
    tau = np.array([0.5, -0.2, 0.8])
    model = kn.Model("free")
    model.add(mb.Ground("ground", gravity=[0, 0, 0]))
    model.add(mb.FreeMotion("free", angles0=[0.3, -0.7, 1.1], w0=[1.0, -2.0, 0.5]))
    model.add(mb.RigidBody("body", mass=2.0, inertia=np.diag(inertia).tolist()))
    model.add(mb.WorldTorque("twist", torque=tau.tolist(), resolve_in="frame_b"))
    for a, b in [("ground.frame", "free.frame_a"), ("free.frame_b", "body.frame_a"),
                 ("free.frame_b", "twist.frame_b")]:
        model.connect(a, b)
    system = model.compile()
    w = np.array([1.0, -2.0, 0.5])
    got = rates(system, system.x0)[-3:]
    np.testing.assert_allclose(got, np.linalg.solve(inertia, tau - np.cross(w, inertia @ w)),
                               rtol=1e-12)


def test_signal_inputs_replace_the_entries_they_are_wired_to():
    """f1 from a Constant and t3 from a Sine: as the same values given as expressions."""
    by_signal = mb.ForceAndTorque("push", f=[9.0, -2.0, 0.7], t=[0.3, 0.1, 9.0],
                                  resolve_in="frame_resolve")
    by_value = mb.ForceAndTorque("push", f=[1.5, -2.0, 0.7], t=[0.3, 0.1, "0.8*sin(3*t)"],
                                 resolve_in="frame_resolve")
    _, _, wired = chain_with(by_signal)
    wired.add(kn.signals.Constant("k", k=1.5))
    wired.add(kn.signals.Sine("wave", amplitude=0.8, f=3 / (2 * np.pi)))
    wired.connect("k.y", "push.f1")
    wired.connect("wave.y", "push.t3")
    links, _, given = chain_with(by_value)
    a, b = wired.compile(), given.compile()
    for k in range(3):
        q, v = random_state(60 + k, links)
        x = np.concatenate([q, v])
        np.testing.assert_allclose(rates(a, x, 0.9), rates(b, x, 0.9), rtol=1e-12, atol=1e-12)


def test_an_acceleration_fed_back_to_a_force_is_an_algebraic_loop():
    model = two_arms(mb.Force("push", f=[0.0, 1.0, 0.0]))
    model.add(kn.rotational.AccSensor("acc"))
    model.connect("acc.flange", "j2.axis")
    model.connect("acc.y", "push.f1")
    with pytest.raises(kn.ModelError, match="algebraic loop through push"):
        model.compile()


def test_frame_resolve_must_be_wired_only_when_it_is_used():
    model = two_arms(mb.Force("push", f=[0.0, 1.0, 0.0], resolve_in="frame_resolve"))
    with pytest.raises(kn.ModelError, match=r"port push\.frame_resolve \(frame\) is not "
                                            r"connected"):
        model.validate()
    model.components["push"].resolve_in = "frame_a"
    assert model.compile().state_names == ["j1.q", "j2.q", "j1.qd", "j2.qd"]
    model.add(kn.Probe("where", quantities=["position"]))
    model.connect("where.port", "push.frame_resolve")
    with pytest.raises(kn.ModelError, match=r"push\.frame_resolve is not wired, so it has no "
                                            r"pose for a probe to measure"):
        model.validate()
    with pytest.raises(kn.ModelError, match=r"push\.resolve_in: must be one of world, frame_a, "
                                            r"frame_b, frame_resolve, got 'frame_c'"):
        mb.Force("push", resolve_in="frame_c")
    with pytest.raises(kn.ModelError, match=r"must be one of world, frame_b, got 'frame_a'"):
        mb.WorldForce("push", force=[1, 0, 0], resolve_in="frame_a")


def test_cut_forces_of_a_force_element():
    """Probes on the element's frames read the flow into it: -F at frame_b, and at frame_a
    +F with the torque T + r_ab x F about frame_a's origin (MSL's frame_a.f, frame_a.t)."""
    f, t = np.array([0.8, -1.3, 0.4]), np.array([0.2, 0.5, -0.3])
    model = two_arms(mb.ForceAndTorque("push", f=f.tolist(), t=t.tolist(), resolve_in="world"))
    for port in ("frame_a", "frame_b"):
        model.add(kn.Probe(f"at_{port}", quantities=["position", "force", "torque"]))
        model.connect(f"at_{port}.port", f"push.{port}")
    system = model.compile()
    out = probe_values(system, [0.4, 2.1, 0.3, -0.5])
    r_ab = out["at_frame_b.position"] - out["at_frame_a.position"]
    np.testing.assert_allclose(out["at_frame_b.force"], -f, atol=1e-14)
    np.testing.assert_allclose(out["at_frame_b.torque"], -t, atol=1e-14)
    np.testing.assert_allclose(out["at_frame_a.force"], f, atol=1e-14)
    np.testing.assert_allclose(out["at_frame_a.torque"], t + np.cross(r_ab, f), atol=1e-14)


# ---------------------------------------------------------------------------------------------
# Point gravity
# ---------------------------------------------------------------------------------------------

MUE = 3.986004418e14


def satellite(r0, v0, mue=MUE, w0=(0.0, 0.0, 0.0)):
    model = kn.Model("orbit")
    model.add(mb.Ground("ground", gravity_type="point", mue=mue))
    model.add(mb.FreeMotion("free", r0=list(r0), v0=list(v0), w0=list(w0)))
    model.add(mb.RigidBody("sat", mass=500.0, inertia=[80.0, 120.0, 150.0]))
    model.connect("ground.frame", "free.frame_a")
    model.connect("free.frame_b", "sat.frame_a")
    return model


def test_circular_orbit_closes_after_its_period():
    """At r = 7000 km with v = sqrt(mue/r): the radius stays r and the satellite is back
    after 2 pi sqrt(r^3/mue) (5828.5 s), turning at the constant rate sqrt(mue/r^3)."""
    r = 7.0e6
    v = np.sqrt(MUE / r)
    period = 2 * np.pi * np.sqrt(r**3 / MUE)
    res = kn.simulate(satellite([r, 0, 0], [0, v, 0]), t_end=period, n_points=101,
                      rtol=1e-12, atol=1e-6)
    pos = np.column_stack([res[f"free.r[{i}]"] for i in range(3)])
    assert np.max(np.abs(np.linalg.norm(pos, axis=1) / r - 1)) < 1e-9
    angle = np.unwrap(np.arctan2(pos[:, 1], pos[:, 0]))
    np.testing.assert_allclose(angle, np.sqrt(MUE / r**3) * res.t, atol=1e-8)
    np.testing.assert_allclose(pos[-1], [r, 0, 0], atol=1e-8 * r)


def test_msl_point_gravity_example_keeps_its_orbits():
    """models/point_gravity.json (MSL's Elementary.PointGravity, mue = 1): the energy
    v^2/2 - mue/|r| and the angular momentum r x v of each body are constant, and each is back
    at its start after its Kepler period 2 pi sqrt(a^3/mue), a = -mue / (2 energy)."""
    model = kn.load(MODELS / "point_gravity.json")
    system = model.compile()
    x0 = dict(zip(system.state_names, system.x0))
    for body in ("free1", "free2"):
        r0 = np.array([x0[f"{body}.r[{i}]"] for i in range(3)])
        v0 = np.array([x0[f"{body}.v[{i}]"] for i in range(3)])
        energy = v0 @ v0 / 2 - 1 / np.linalg.norm(r0)
        period = 2 * np.pi * (-1 / (2 * energy)) ** 1.5
        # errors shrink with the tolerance (1e-10: 6e-8, 1e-12: 1e-9, 1e-13: 1e-10): they
        # are the integrator's, not the field's
        res = kn.simulate(system, t_end=period, n_points=201, rtol=1e-13, atol=1e-13)
        r = np.column_stack([res[f"{body}.r[{i}]"] for i in range(3)])
        v = np.column_stack([res[f"{body}.v[{i}]"] for i in range(3)])
        e = np.sum(v * v, axis=1) / 2 - 1 / np.linalg.norm(r, axis=1)
        assert np.max(np.abs(e - energy)) < 1e-9
        np.testing.assert_allclose(np.cross(r, v), np.cross(r0, v0)[None, :].repeat(len(r), 0),
                                   atol=1e-9)
        np.testing.assert_allclose(r[-1], r0, atol=1e-8)
        np.testing.assert_allclose(v[-1], v0, atol=1e-8)


def test_point_gravity_torque_comes_from_the_centre_of_mass_offset():
    """A body on a revolute (about z) at p0, its centre of mass c off the axis: it turns by
    ((c - p0) x m g(c))_z / (I_zz + m d^2), g(c) = -mue c / |c|^3; the joint's frame_a
    carries m (a_c - g(c))."""
    p0, r_cm, m, izz, mue = np.array([2.0, 1.0, 0.0]), np.array([0.3, 0.1, 0.2]), 1.7, 0.05, 10.0
    model = kn.Model("offset")
    model.add(mb.Ground("ground", gravity_type="point", mue=mue))
    model.add(mb.FixedTranslation("post", r=p0.tolist()))
    model.add(mb.Revolute("j"))
    model.add(mb.RigidBody("body", mass=m, r_cm=r_cm.tolist(), inertia=[0.02, 0.03, izz]))
    model.add(kn.Probe("cut", quantities=["force"]))
    for a, b in [("ground.frame", "post.frame_a"), ("post.frame_b", "j.frame_a"),
                 ("j.frame_b", "body.frame_a"), ("cut.port", "j.frame_a")]:
        model.connect(a, b)
    system = model.compile()
    for q, qd in [(0.0, 0.0), (1.2, 0.8), (-2.5, -1.5)]:
        arm = rz(q) @ r_cm
        c = p0 + arm
        g = -mue * c / np.linalg.norm(c) ** 3
        qdd = np.cross(arm, m * g)[2] / (izz + m * (arm[0]**2 + arm[1]**2))
        assert rates(system, [q, qd])[1] == pytest.approx(qdd, rel=1e-12)
        ez = np.array([0.0, 0.0, 1.0])
        a_c = np.cross(qdd * ez, arm) + np.cross(qd * ez, np.cross(qd * ez, arm))
        np.testing.assert_allclose(probe_values(system, [q, qd])["cut.force"], m * (a_c - g),
                                   rtol=1e-12, atol=1e-12)


def test_gravity_type_round_trips_and_is_checked(tmp_path):
    model = satellite([7e6, 0, 0], [0, 7.5e3, 0], mue=4e14)
    model.save(tmp_path / "m.json")
    params = json.loads((tmp_path / "m.json").read_text())["components"][0]["params"]
    assert params == {"gravity_type": "point", "mue": 4e14}
    assert kn.load(tmp_path / "m.json").components["ground"].gravity_type == "point"
    with pytest.raises(kn.ModelError, match=r"ground\.gravity_type: must be one of uniform, "
                                            r"point, expression, got 'pont' \(did you mean "
                                            r"'point'\?\)"):
        mb.Ground("ground", gravity_type="pont")
    with pytest.raises(kn.ModelError, match=r"ground\.mue = -1 m\^3/s\^2: must be >= 0"):
        mb.Ground("ground", mue=-1)


def test_equations_keep_point_gravity_in_g():
    """M, V, G of a satellite: G is the point field's pull (V holds no gravity)."""
    r0 = np.array([7.0e6, 1.0e6, -2.0e6])
    system = satellite(r0, [0, 0, 0]).compile()
    q = system.x0[:7]
    M, V, G = system.dynamics_terms(q, np.zeros(6))
    g = -MUE * r0 / np.linalg.norm(r0) ** 3
    np.testing.assert_allclose(G[:3], -500.0 * g, rtol=1e-12)
    np.testing.assert_allclose(V, 0.0, atol=1e-12)


# ---------------------------------------------------------------------------------------------
# Line forces with a point mass
# ---------------------------------------------------------------------------------------------

def test_msl_spring_with_mass_is_its_closed_form():
    """models/spring_with_mass.json (MSL's Elementary.SpringWithMass): a body (1 kg) hung
    from the world origin by a spring (c = 40, s_unstretched = 0.2) whose 0.5 kg point mass
    sits halfway, at y/2. Along y: (m + ms/4) y'' = -c (y + s0) - (m + ms/2) g: a harmonic
    oscillation about y_eq = -s0 - (m + ms/2) g / c at w = sqrt(c / (m + ms/4))."""
    model = kn.load(MODELS / "spring_with_mass.json")
    c, s0, m, ms, g = 40.0, 0.2, 1.0, 0.5, 9.81
    y0 = -0.3
    w = np.sqrt(c / (m + ms / 4))
    y_eq = -s0 - (m + ms / 2) * g / c
    res = kn.simulate(model, rtol=1e-12, atol=1e-12)
    y = y_eq + (y0 - y_eq) * np.cos(w * res.t)
    np.testing.assert_allclose(res["free.r[1]"], y, atol=1e-9)
    np.testing.assert_allclose(res["free.r[0]"], 0.0, atol=1e-12)
    # the flow into the spring at frame_b: minus the tension's pull and the mass's share
    a = -(y0 - y_eq) * w**2 * np.cos(w * res.t)
    tension = c * (-y - s0)
    share = 0.5 * ms * (0.5 * a + g)
    np.testing.assert_allclose(res["spring_end.force"][:, 1], -(tension - share), atol=1e-8)


def test_a_mass_given_as_a_parameter_may_be_zero():
    """A point mass that is a model parameter is kept in the equations, and 0 is then as no
    point mass at all (I + J Y W stays regular)."""
    model = kn.load(MODELS / "spring_with_mass.json")
    model.parameters["ms"] = 0.5
    model.components["spring"].mass = "ms"
    system = model.compile()
    x = system.x0.copy()
    x[7:10] = [0.3, 0.4, -0.2]             # speeds, for the velocity terms
    reference = kn.load(MODELS / "spring_with_mass.json").compile()
    np.testing.assert_allclose(rates(system, x), rates(reference, x), rtol=1e-14, atol=1e-14)
    massless = kn.load(MODELS / "spring_with_mass.json")
    massless.components["spring"].mass = 0.0
    np.testing.assert_allclose(np.asarray(system.rhs(0.0, x, params={"ms": 0.0})).ravel(),
                               rates(massless.compile(), x), rtol=1e-14, atol=1e-14)


ELEMENTS = [("Spring", 0.5, {"c": 30.0, "s_unstretched": 0.4}),
            ("SpringDamper", 0.3, {"c": 30.0, "d": 2.5, "s_unstretched": 0.4}),
            ("Damper", 0.8, {"d": 2.5})]


def pendulums_with_line(kind, h, params, ms=0.7):
    """Two arms about z, at the origin and at (D, 0, 0), under gravity -y, joined at their
    tips by a line force carrying the point mass ``ms`` at ``h`` of the way."""
    model = kn.Model("pendulums")
    model.add(mb.Ground("ground", gravity=[0, -9.81, 0]))
    model.add(mb.FixedTranslation("post", r=[D, 0, 0]))
    model.connect("ground.frame", "post.frame_a")
    for i, (L, m, base) in enumerate([(L1, M1, "ground.frame"), (L2, M2, "post.frame_b")], 1):
        model.add(mb.Revolute(f"j{i}"))
        model.add(mb.FixedTranslation(f"arm{i}", r=[L, 0, 0]))
        model.add(mb.RigidBody(f"tip{i}", mass=m, inertia=[0, 0, 0.01 * i]))
        model.connect(base, f"j{i}.frame_a")
        model.connect(f"j{i}.frame_b", f"arm{i}.frame_a")
        model.connect(f"arm{i}.frame_b", f"tip{i}.frame_a")
    model.add(getattr(mb, kind)("line", mass=ms, length_fraction=h, **params))
    model.connect("line.frame_a", "arm1.frame_b")
    model.connect("line.frame_b", "arm2.frame_b")
    return model


D = 1.5


def lagrangian(kind, h, params, ms=0.7, g=9.81):
    """M(q) and the accelerations of the two pendulums, by sympy from the Lagrangian
    T = sum m_i |v_i|^2/2 + J_i qd_i^2/2 + ms |v_m|^2/2, V = the masses' weight + c (s -
    s0)^2/2, Rayleigh d sd^2/2, the point mass at (1 - h) r1 + h r2."""
    q1, q2, u1, u2 = sp.symbols("q1 q2 u1 u2", real=True)
    q, u = sp.Matrix([q1, q2]), sp.Matrix([u1, u2])
    r1 = sp.Matrix([L1 * sp.cos(q1), L1 * sp.sin(q1)])
    r2 = sp.Matrix([D + L2 * sp.cos(q2), L2 * sp.sin(q2)])
    rm = (1 - h) * r1 + h * r2
    points = [(M1, r1), (M2, r2), (ms, rm)]
    vel = [(m, r.jacobian(q) * u) for m, r in points]
    T = sum(m * (v.T * v)[0] for m, v in vel) / 2 + (0.01 * u1**2 + 0.02 * u2**2) / 2
    s = sp.sqrt(((r2 - r1).T * (r2 - r1))[0])
    sd = (sp.Matrix([s]).jacobian(q) * u)[0]
    V = g * sum(m * r[1] for m, r in points)
    V += params.get("c", 0.0) * (s - params.get("s_unstretched", 0.0)) ** 2 / 2
    rayleigh = params.get("d", 0.0) * sd**2 / 2
    M = sp.Matrix([T]).jacobian(u).T.jacobian(u)
    # M udot + (d/dt dT/du)_q - dT/dq + dV/dq + dR/du = 0
    dTdu = sp.Matrix([T]).jacobian(u).T
    bias = dTdu.jacobian(q) * u - sp.Matrix([T]).jacobian(q).T + sp.Matrix([V]).jacobian(q).T
    bias += sp.Matrix([rayleigh]).jacobian(u).T
    f_M = sp.lambdify([q1, q2], M, "numpy")
    f_b = sp.lambdify([q1, q2, u1, u2], bias, "numpy")
    return (lambda x: np.asarray(f_M(*x[:2]), dtype=float),
            lambda x: np.linalg.solve(f_M(*x[:2]), -np.asarray(f_b(*x), dtype=float).ravel()))


@pytest.mark.parametrize("kind, h, params", ELEMENTS, ids=[e[0] for e in ELEMENTS])
def test_line_mass_matches_a_lagrangian(kind, h, params):
    system = pendulums_with_line(kind, h, params).compile()
    mass_matrix, accelerations = lagrangian(kind, h, params)
    rng = np.random.default_rng(5)
    for _ in range(4):
        x = np.concatenate([rng.uniform(-np.pi, np.pi, 2), rng.uniform(-3, 3, 2)])
        np.testing.assert_allclose(np.asarray(system.mass_matrix(x[:2]), dtype=float),
                                   mass_matrix(x), rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(rates(system, x)[2:], accelerations(x), rtol=1e-10,
                                   atol=1e-10)


def test_line_mass_in_a_loop_conserves_energy():
    """A four-bar (a kinematic loop: the partition formulation) with a spring carrying a
    point mass from a fixed point to the coupler's tip: crank, coupler and rocker energy
    (``reference_loops.fourbar_energy``) plus the point mass's and the spring's stays put."""
    model = fourbar()
    model.add(mb.FixedTranslation("anchor", r=[0.4, 1.2, 0.0]))
    model.connect("ground.frame", "anchor.frame_a")
    model.add(mb.Spring("spring", c=25.0, s_unstretched=0.3, mass=0.8, length_fraction=0.35))
    model.connect("spring.frame_a", "anchor.frame_b")
    model.connect("spring.frame_b", "coupler.frame_b")
    model.add(kn.Probe("tip", quantities=["position", "velocity"]))
    model.connect("tip.port", "coupler.frame_b")
    # (the drift is the integrator's: 2.5e-8 at 1e-11, 3e-9 at 1e-12; massless alike)
    res = kn.simulate(model, t_end=3.0, n_points=301, rtol=1e-12, atol=1e-12)
    anchor, h, ms = np.array([0.4, 1.2, 0.0]), 0.35, 0.8
    tip, v = res["tip.position"], res["tip.velocity"]
    point, v_point = (1 - h) * anchor + h * tip, h * v
    energy = (fourbar_energy(res["crank_probe.angle"], res["crank_probe.speed"])
              + ms * np.sum(v_point**2, axis=1) / 2 + ms * 9.81 * point[:, 1]
              + 25.0 * (np.linalg.norm(tip - anchor, axis=1) - 0.3) ** 2 / 2)
    swing = np.ptp(ms * np.sum(v_point**2, axis=1) / 2)
    assert swing > 0.01                                     # the point mass moves
    assert np.max(np.abs(energy - energy[0])) < 1e-8


def test_flows_balance_with_the_new_elements():
    """Kirchhoff's law at every frame connection of a four-bar (cut joint C) carrying a
    spring with mass, a Force resolved in another frame and a Torque."""
    model = fourbar(probes=False)
    model.add(mb.Spring("spring", c=30.0, s_unstretched=0.5, mass=0.6, length_fraction=0.3))
    model.connect("spring.frame_a", "base.frame_b")
    model.connect("spring.frame_b", "coupler.frame_b")
    model.add(mb.Force("push", f=[1.0, "cos(t)", 0.2], resolve_in="frame_resolve"))
    model.connect("push.frame_a", "crank.frame_b")
    model.connect("push.frame_b", "rocker.frame_b")
    model.connect("push.frame_resolve", "B.frame_b")
    model.add(mb.Torque("twist", t=[0.0, 0.0, "0.5*sin(t)"], resolve_in="frame_a"))
    model.connect("twist.frame_a", "ground.frame")
    model.connect("twist.frame_b", "crank.frame_b")
    wired = {ref for pair in model.connections for ref in pair}
    ports = [ref for comp in list(model.components.values()) for ref in
             (comp.port_ref(p) for p in comp.ports) if ref.domain == "frame" and ref in wired]
    for i, ref in enumerate(ports):
        model.add(kn.Probe(f"f{i}", quantities=["force", "torque"]))
        model.connect(f"f{i}.port", ref.path)
    system = model.compile()
    res = kn.simulate(system, t_end=1.0, n_points=21)
    sets = {}
    for i, ref in enumerate(ports):
        sets.setdefault(system.topology.set_of[ref], []).append(i)
    scale = max(np.max(np.abs(res[f"f{i}.force"])) for i in range(len(ports)))
    for members in sets.values():
        if len(members) < 2:
            continue
        force = sum(res[f"f{i}.force"] for i in members)
        torque = sum(res[f"f{i}.torque"] for i in members)
        assert np.max(np.abs(force)) < 1e-9 * scale, [ports[i].path for i in members]
        assert np.max(np.abs(torque)) < 1e-9 * scale, [ports[i].path for i in members]


def test_midpoint_rule_with_a_line_mass():
    """The symplectic midpoint rule reads M^-1 p with the point mass (Woodbury): on the two
    pendulums joined by a spring with mass it follows a tight CVODES run to its second-order
    accuracy, and halving the step quarters the error."""
    model = pendulums_with_line("Spring", 0.5, {"c": 30.0, "s_unstretched": 0.4})
    model.components["j1"].q0 = 0.3
    reference = kn.simulate(model, t_end=1.0, n_points=11, rtol=1e-12, atol=1e-12)
    errors = []
    for step in (4e-3, 2e-3):
        res = kn.simulate(model, t_end=1.0, n_points=11, method="midpoint", step=step)
        errors.append(np.max(np.abs(res.states - reference.states)))
    assert errors[0] < 3e-3
    assert errors[0] / errors[1] == pytest.approx(4.0, rel=0.1)


def test_msl_force_and_torque_example_resolves_in_its_rotated_frame():
    """models/force_and_torque.json (MSL's Elementary.ForceAndTorque): f and t resolved in a
    frame turned 30 degrees about z act as Rz(30 deg) f and Rz(30 deg) t given in the world."""
    model = kn.load(MODELS / "force_and_torque.json")
    system = model.compile()
    world = kn.load(MODELS / "force_and_torque.json")
    element = world.components["force_and_torque"]
    element.f = (rz(np.pi / 6) @ [0, 1000, 0]).tolist()
    element.t = (rz(np.pi / 6) @ [-100, 100, 0]).tolist()
    element.resolve_in = "world"
    other = world.compile()
    rng = np.random.default_rng(2)
    for _ in range(3):
        x = rng.uniform(-2, 2, 4)
        np.testing.assert_allclose(rates(system, x), rates(other, x), rtol=1e-12, atol=1e-9)
