"""Joint reaction forces of the seed's double pendulum through frame probes, against the
closed form: the seed paper's M, V, G give the accelerations, plain kinematics the
accelerations of the two point masses, and Newton's law the forces every joint carries."""

import numpy as np
import pytest

import kinetwork as kn
from scenes import SEED_PARAMS, double_pendulum, fourbar
from scenes.reference import seed_mvg, seed_reference

T = np.linspace(0.0, 3.0, 301)
PORTS = {"shoulder_a": "shoulder.frame_a", "shoulder_b": "shoulder.frame_b",
         "elbow_a": "elbow.frame_a", "link_end": "link1.frame_b", "ground": "ground.frame",
         "mass2": "mass2.frame_a"}


@pytest.fixture(scope="module")
def run():
    model = double_pendulum(q0=(0.8, -0.4), qd0=(0.3, 1.0))
    for name, port in PORTS.items():
        model.add(kn.Probe(f"at_{name}", quantities=["position", "force", "torque"]))
        model.connect(f"at_{name}.port", port)
    res = kn.simulate(model, t_end=T[-1], n_points=len(T), rtol=1e-12, atol=1e-12)
    p = {k: SEED_PARAMS[k] for k in ("L1", "L2", "m1", "m2", "c", "d", "g")}
    X = seed_reference(T, x0=(0.8, -0.4, 0.3, 1.0), **p)
    qdd = np.array([np.linalg.solve(*_mvg(x, p)) for x in X])
    return res, X, qdd, p


def _mvg(x, p):
    M, V, G = seed_mvg(x[:2], x[2:], **p)
    return np.asarray(M, dtype=float), -(np.asarray(V, dtype=float).ravel()
                                         + np.asarray(G, dtype=float).ravel())


def _point(angle, w, a, L):
    """Position and acceleration of the point L along a link hanging at ``angle``."""
    pos = np.stack([L * np.sin(angle), -L * np.cos(angle)], -1)
    acc = np.stack([L * (a * np.cos(angle) - w * w * np.sin(angle)),
                    L * (a * np.sin(angle) + w * w * np.cos(angle))], -1)
    return pos, acc


def test_reaction_forces_follow_newtons_law(run):
    res, X, qdd, p = run
    t1, t2, w1, w2 = X.T
    a1, a2 = qdd.T
    _, acc1 = _point(t1, w1, a1, p["L1"] / 2)
    _, elbow_acc = _point(t1, w1, a1, p["L1"])
    _, rel = _point(t1 + t2, w1 + w2, a1 + a2, p["L2"] / 2)
    acc2 = elbow_acc + rel
    g = np.array([0.0, -p["g"]])
    F2 = p["m2"] * (acc2 - g)                      # what the elbow carries
    F = p["m1"] * (acc1 - g) + F2                  # what the shoulder carries
    scale = np.max(np.abs(F))
    for name, expected in [("shoulder_a", F), ("shoulder_b", -F), ("ground", -F),
                           ("elbow_a", F2), ("link_end", -F2), ("mass2", F2)]:
        got = res[f"at_{name}.force"]
        assert np.max(np.abs(got[:, :2] - expected)) < 1e-8 * scale, name
        assert np.max(np.abs(got[:, 2])) < 1e-12 * scale, name


def test_a_revolute_carries_no_torque_about_its_axis(run):
    """The shoulder spring-damper acts through the flanges (support at rest in the world, as
    in Modelica), so the frames carry only the bending moment, which is zero in the plane:
    the torque about the frame origin vanishes, while the flange carries -(c q + d qd)."""
    res, X, _, p = run
    for name in ("shoulder_a", "elbow_a", "ground"):
        assert np.max(np.abs(res[f"at_{name}.torque"])) < 1e-9, name
    spring = -(p["c"] * X[:, 0] + p["d"] * X[:, 2])
    assert np.max(np.abs(res["probe1.torque"] - spring)) < 1e-8


def test_bending_moment_of_a_spinning_arm():
    """A point mass m at the end of a massless arm L, spinning at w about the vertical axis y
    (gravity -y): the hub carries the weight, the centripetal force, and the bending moment
    r x m(a - g) = m g L (sin wt, 0, cos wt); nothing about the axis itself."""
    m, L, g, w = 2.0, 0.7, 9.81, 3.0
    model = kn.Model("spinning_arm")
    mb = kn.multibody
    model.add(mb.Ground("ground", gravity=[0, -g, 0]))
    model.add(mb.Revolute("hub", axis=[0, 1, 0], qd0=w))
    model.add(mb.FixedTranslation("arm", r=[L, 0, 0]))
    model.add(mb.RigidBody("bob", mass=m))
    model.add(kn.Probe("cut", quantities=["force", "torque"]))
    for a, b in [("ground.frame", "hub.frame_a"), ("hub.frame_b", "arm.frame_a"),
                 ("arm.frame_b", "bob.frame_a"), ("cut.port", "hub.frame_a")]:
        model.connect(a, b)
    res = kn.simulate(model, t_end=2.0, n_points=101, rtol=1e-12, atol=1e-12)
    th = w * res.t
    r = L * np.stack([np.cos(th), 0 * th, -np.sin(th)], -1)
    force = m * (-w * w * r + np.array([0.0, g, 0.0]))
    torque = m * g * L * np.stack([np.sin(th), 0 * th, np.cos(th)], -1)
    assert np.max(np.abs(res["cut.force"] - force)) < 1e-9
    assert np.max(np.abs(res["cut.torque"] - torque)) < 1e-9


def test_flows_balance_at_every_frame_connection():
    """Kirchhoff's law for frames: at every connection set the flows into the components
    there sum to zero, forces and torques, in a four-bar driven at its cut joint, pulled by
    a line spring and pushed by a world force (every kind of flow the wrench balance has)."""
    model = fourbar(probes=False)
    mb = kn.multibody
    model.add(kn.rotational.Torque("motor", tau="2*sin(3*t)"))
    model.connect("motor.flange", "C.axis")
    model.connect("motor.support", "C.support")
    model.add(mb.Spring("spring", c=30.0, s_unstretched=0.5))
    model.connect("spring.frame_a", "base.frame_b")
    model.connect("spring.frame_b", "coupler.frame_b")
    model.add(mb.WorldForce("push", force=[1.0, "cos(t)", 0.0]))
    model.connect("push.frame_b", "crank.frame_b")
    # a driven pendulum hung by its frame_b: a joint the tree walks in reverse
    model.add(mb.Revolute("rev", q0=0.3))
    model.add(mb.RigidBody("weight", mass=0.5, r_cm=[0.0, -0.2, 0.0], inertia=[0, 0, 0.01]))
    model.add(kn.rotational.Torque("drive", tau="0.5 + t"))
    for a, b in [("rev.frame_b", "crank.frame_b"), ("rev.frame_a", "weight.frame_a"),
                 ("drive.flange", "rev.axis"), ("drive.support", "rev.support")]:
        model.connect(a, b)
    ports = [ref for comp in list(model.components.values()) for ref in
             (comp.port_ref(p) for p in comp.ports) if ref.domain == "frame"]
    for i, ref in enumerate(ports):
        model.add(kn.Probe(f"f{i}", quantities=["force", "torque"]))
        model.connect(f"f{i}.port", ref.path)
    system = model.compile()
    assert [c.component.name for c in system.topology.cuts] == ["C"]
    assert [e.reversed for e in system.topology.tree if e.component.name == "rev"] == [True]
    res = kn.simulate(system, t_end=2.0, n_points=41)
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
