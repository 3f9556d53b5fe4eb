"""Random spatial chains and trees against Pinocchio, an independent rigid-body library.

Each link is a random FixedRotation, a random FixedTranslation, a Revolute or Prismatic
joint on a random skew axis, and a RigidBody with a random mass, centre of mass and full
inertia tensor on the joint's outboard frame; gravity is a random vector. The same mechanism
is built in Pinocchio (``JointModelRevoluteUnaligned`` / ``JointModelPrismaticUnaligned``,
joint placements as SE3 products of the fixed transforms), and kinetwork's joint-space mass
matrix and forward dynamics are compared with ``pin.crba`` and ``pin.aba``.

Conventions (DESIGN.md): Revolute: frame_b is frame_a rotated by q about ``axis`` (resolved
in frame_a); Prismatic: frame_b is frame_a moved by q along ``axis``; FixedTranslation:
frame_b = frame_a moved by ``r``; FixedRotation: frame_b origin = frame_a origin + ``r`` (in
frame_a), orientation R(axis, angle); RigidBody: ``r_cm`` from frame_a to the centre of mass
and ``inertia`` about it, both in frame_a. A joint connected reversed (frame_b towards the
ground) moves its frame_a relative to frame_b by the inverse transform, which Pinocchio
models as the same joint type on the negated axis. ``test_oracle_follows_conventions`` checks
the Pinocchio construction against a plain numpy composition of these conventions, so that a
mistake in the oracle cannot pass for one in kinetwork.
"""

import numpy as np
import pinocchio as pin
import pytest

import kinetwork as kn
from scenes.random_trees import build_kinetwork, random_mechanism, random_state, rodrigues, unit

mb = kn.multibody


# ---------------------------------------------------------------------------------------------
# The same mechanism in kinetwork and in Pinocchio
# ---------------------------------------------------------------------------------------------

def pin_joint(kind, axis):
    """Pinocchio's 1-DOF joint of ``kind`` on ``axis``."""
    if kind == "revolute":
        return pin.JointModelRevoluteUnaligned(np.asarray(axis, dtype=float))
    return pin.JointModelPrismaticUnaligned(np.asarray(axis, dtype=float))


def build_pinocchio(links, gravity):
    """The mechanism as a ``pin.Model``; joint i + 1 is link i, q index i."""
    model = pin.Model()
    model.gravity.linear = np.asarray(gravity, dtype=float)
    for i, L in enumerate(links):
        placement = (pin.SE3(rodrigues(L.rot_axis, L.rot_angle), L.rot_r)
                     * pin.SE3(np.eye(3), L.tr_r))
        # reversed, the outboard frame (frame_a) moves relative to frame_b by the inverse
        # motion: a rotation by -q about axis, or a shift by -q along it
        axis = -L.axis if L.reversed else L.axis
        jid = model.addJoint(L.parent + 1, pin_joint(L.kind, axis), placement, f"j{i}")
        model.appendBodyToJoint(jid, pin.Inertia(L.mass, L.r_cm, L.inertia), pin.SE3.Identity())
    return model


def pin_mass_matrix(model, q):
    """pin.crba, symmetrised (it fills the upper triangle)."""
    M = pin.crba(model, model.createData(), np.asarray(q, dtype=float)).copy()
    return np.triu(M) + np.triu(M, 1).T


def pin_qdd(model, q, qd):
    """Forward dynamics without joint forces (pin.aba)."""
    return pin.aba(model, model.createData(), np.asarray(q, dtype=float),
                   np.asarray(qd, dtype=float), np.zeros(model.nv)).copy()


def assert_matches_pinocchio(system, pmodel, q, qd, context):
    """kinetwork's M(q) and rhs against crba and aba, to 1e-9 relative."""
    n = len(q)
    M_ref = pin_mass_matrix(pmodel, q)
    M = np.asarray(system.mass_matrix(q), dtype=float)
    assert M.shape == (n, n), context
    np.testing.assert_allclose(M, M_ref, rtol=1e-9, atol=1e-9 * np.abs(M_ref).max(),
                               err_msg=f"mass matrix, {context}")

    x = np.concatenate([q, qd])
    dx = np.asarray(system.rhs(0.0, x), dtype=float).ravel()
    assert dx.shape == (2 * n,), context
    np.testing.assert_array_equal(dx[:n], qd, err_msg=f"dq/dt, {context}")
    qdd_ref = pin_qdd(pmodel, q, qd)
    np.testing.assert_allclose(dx[n:], qdd_ref, rtol=1e-9,
                               atol=1e-9 * max(1.0, np.abs(qdd_ref).max()),
                               err_msg=f"qdd, {context}")


# ---------------------------------------------------------------------------------------------
# The oracle itself follows DESIGN's conventions
# ---------------------------------------------------------------------------------------------

def numpy_body_poses(links, q):
    """World pose (R, p) of every body frame, composing DESIGN's conventions in numpy."""
    def hom(R, p):
        T = np.eye(4)
        T[:3, :3], T[:3, 3] = R, p
        return T

    poses = []
    for i, L in enumerate(links):
        base = np.eye(4) if L.parent < 0 else poses[L.parent]
        fixed = hom(rodrigues(L.rot_axis, L.rot_angle), L.rot_r) @ hom(np.eye(3), L.tr_r)
        if L.kind == "revolute":
            motion = hom(rodrigues(L.axis, q[i]), np.zeros(3))
        else:
            motion = hom(np.eye(3), q[i] * L.axis)
        poses.append(base @ fixed @ (np.linalg.inv(motion) if L.reversed else motion))
    return poses


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_oracle_follows_conventions(seed):
    """Pinocchio's body placements, potential and kinetic energy equal a numpy composition.

    Kinetic energy, from finite-difference body velocities, checks that ``pin.Inertia``
    takes the centre of mass and the inertia about it in the body frame, as RigidBody does,
    and that the symmetrised ``pin.crba`` is the mass matrix of this tree.
    """
    links, gravity = random_mechanism(seed, 5, reversed_fraction=0.4, tree=True)
    pmodel = build_pinocchio(links, gravity)
    data = pmodel.createData()
    q, qd = random_state(seed, links)
    pin.forwardKinematics(pmodel, data, q)
    poses = numpy_body_poses(links, q)
    for i, T in enumerate(poses):
        np.testing.assert_allclose(data.oMi[i + 1].homogeneous, T, atol=1e-12)

    potential = -sum(L.mass * gravity @ (T[:3, :3] @ L.r_cm + T[:3, 3])
                     for L, T in zip(links, poses))
    np.testing.assert_allclose(pin.computePotentialEnergy(pmodel, data, q), potential,
                               rtol=1e-12, atol=1e-12)

    h = 1e-6
    after, before = numpy_body_poses(links, q + h * qd), numpy_body_poses(links, q - h * qd)
    kinetic = 0.0
    for L, T, Ta, Tb in zip(links, poses, after, before):
        R = T[:3, :3]
        v_cm = ((Ta[:3, :3] @ L.r_cm + Ta[:3, 3]) - (Tb[:3, :3] @ L.r_cm + Tb[:3, 3])) / (2 * h)
        W = (Ta[:3, :3] - Tb[:3, :3]) / (2 * h) @ R.T     # skew(omega), world frame
        omega = np.array([W[2, 1], W[0, 2], W[1, 0]])
        kinetic += 0.5 * L.mass * v_cm @ v_cm + 0.5 * omega @ R @ L.inertia @ R.T @ omega
    np.testing.assert_allclose(pin.computeKineticEnergy(pmodel, data, q, qd), kinetic,
                               rtol=1e-7)
    np.testing.assert_allclose(0.5 * qd @ pin_mass_matrix(pmodel, q) @ qd, kinetic, rtol=1e-7)


# ---------------------------------------------------------------------------------------------
# kinetwork against Pinocchio
# ---------------------------------------------------------------------------------------------

N_POINTS = 3      # random states per compiled mechanism


@pytest.mark.parametrize("n", range(1, 8))
@pytest.mark.parametrize("seed", range(6))
def test_random_chain(seed, n):
    """Chains of 1..7 links: M(q) and forward dynamics equal Pinocchio's."""
    links, gravity = random_mechanism(100 * seed + n, n)
    system = build_kinetwork(links, gravity).compile()
    assert system.state_names == ([f"j{i}.q" for i in range(n)]
                                  + [f"j{i}.qd" for i in range(n)])
    pmodel = build_pinocchio(links, gravity)
    for k in range(N_POINTS):
        q, qd = random_state(1000 * seed + 10 * n + k, links)
        assert_matches_pinocchio(system, pmodel, q, qd,
                                 f"seed={seed}, n={n}, point {k}: q={q}, qd={qd}")


@pytest.mark.parametrize("n", [1, 3, 6])
@pytest.mark.parametrize("seed", range(3))
def test_random_chain_reversed_joints(seed, n):
    """Joints wired frame_b towards the ground act by their inverse transform."""
    links, gravity = random_mechanism(200 + 100 * seed + n, n, reversed_fraction=0.5)
    links[0].reversed = True          # at least one, and one right at the ground
    system = build_kinetwork(links, gravity).compile()
    pmodel = build_pinocchio(links, gravity)
    for k in range(N_POINTS):
        q, qd = random_state(5000 + 1000 * seed + 10 * n + k, links)
        flags = [L.reversed for L in links]
        assert_matches_pinocchio(system, pmodel, q, qd,
                                 f"seed={seed}, n={n}, reversed={flags}, point {k}: "
                                 f"q={q}, qd={qd}")


@pytest.mark.parametrize("seed", range(4))
def test_random_tree(seed):
    """Branched trees (several links on one outboard frame) match Pinocchio too."""
    links, gravity = random_mechanism(300 + seed, 6, reversed_fraction=0.2, tree=True)
    system = build_kinetwork(links, gravity).compile()
    pmodel = build_pinocchio(links, gravity)
    for k in range(N_POINTS):
        q, qd = random_state(7000 + 10 * seed + k, links)
        assert_matches_pinocchio(system, pmodel, q, qd,
                                 f"seed={seed}, parents={[L.parent for L in links]}, "
                                 f"point {k}: q={q}, qd={qd}")


# ---------------------------------------------------------------------------------------------
# Rigid connections cost no state
# ---------------------------------------------------------------------------------------------

def test_body_welded_to_ground_gives_zero_states():
    """Bodies fixed to the ground, directly or through fixed parts, have no states."""
    model = kn.Model("welded")
    ground = model.add(mb.Ground("ground", gravity=[0, -9.81, 0]))
    fixed = model.add(mb.FixedTranslation("fixed", r=[1.0, 2.0, 3.0]))
    turn = model.add(mb.FixedRotation("turn", axis=[1, 1, 0], angle=0.7))
    on_ground = model.add(mb.RigidBody("on_ground", mass=2.0, r_cm=[0.1, 0, 0],
                                       inertia=[0.1, 0.2, 0.3]))
    on_parts = model.add(mb.RigidBody("on_parts", mass=1.0, inertia=[0.1, 0.1, 0.1]))
    model.connect(ground.frame, on_ground.frame_a)
    model.connect(ground.frame, fixed.frame_a)
    model.connect(fixed.frame_b, turn.frame_a)
    model.connect(turn.frame_b, on_parts.frame_a)
    system = model.compile()
    assert list(system.state_names) == []
    assert np.asarray(system.x0).shape == (0,)


def _one_joint_model(kind, axis, welded):
    """A joint at an offset from the ground carrying body ``a`` directly and body ``b``
    through a FixedTranslation and a FixedRotation; with ``welded``, extra bodies fixed to
    the ground as well."""
    model = kn.Model("folded")
    ground = model.add(mb.Ground("ground", gravity=[1.0, -9.0, 2.0]))
    mount = model.add(mb.FixedTranslation("mount", r=[0.3, -0.2, 0.5]))
    joint_class = mb.Revolute if kind == "revolute" else mb.Prismatic
    joint = model.add(joint_class("j", axis=list(axis)))
    arm = model.add(mb.FixedTranslation("arm", r=[0.4, -0.9, 0.2]))
    bend = model.add(mb.FixedRotation("bend", axis=[0.2, 1.0, -0.5], angle=1.1,
                                      r=[0.1, 0.0, -0.3]))
    a = model.add(mb.RigidBody("a", mass=1.5, r_cm=[0.1, -0.2, 0.05],
                               inertia=[[0.3, 0.01, -0.02], [0.01, 0.2, 0.03],
                                        [-0.02, 0.03, 0.25]]))
    b = model.add(mb.RigidBody("b", mass=0.7, r_cm=[-0.1, 0.3, 0.2],
                               inertia=[[0.05, -0.01, 0.0], [-0.01, 0.08, 0.01],
                                        [0.0, 0.01, 0.06]]))
    model.connect(ground.frame, mount.frame_a)
    model.connect(mount.frame_b, joint.frame_a)
    model.connect(joint.frame_b, a.frame_a)
    model.connect(joint.frame_b, arm.frame_a)
    model.connect(arm.frame_b, bend.frame_a)
    model.connect(bend.frame_b, b.frame_a)
    if welded:
        w1 = model.add(mb.RigidBody("w1", mass=3.0, r_cm=[1, 1, 1], inertia=[1, 2, 2.5]))
        w2 = model.add(mb.RigidBody("w2", mass=4.0, inertia=[1, 1, 1]))
        model.connect(ground.frame, w1.frame_a)
        model.connect(mount.frame_b, w2.frame_a)
    return model


def _one_joint_pinocchio(kind, axis):
    """The same as one Pinocchio joint with bodies a and b appended to it."""
    model = pin.Model()
    model.gravity.linear = np.array([1.0, -9.0, 2.0])
    jid = model.addJoint(0, pin_joint(kind, unit(axis)),
                         pin.SE3(np.eye(3), np.array([0.3, -0.2, 0.5])), "j")
    model.appendBodyToJoint(jid, pin.Inertia(1.5, np.array([0.1, -0.2, 0.05]),
                                             np.array([[0.3, 0.01, -0.02], [0.01, 0.2, 0.03],
                                                       [-0.02, 0.03, 0.25]])),
                            pin.SE3.Identity())
    placement = (pin.SE3(np.eye(3), np.array([0.4, -0.9, 0.2]))
                 * pin.SE3(rodrigues([0.2, 1.0, -0.5], 1.1), np.array([0.1, 0.0, -0.3])))
    model.appendBodyToJoint(jid, pin.Inertia(0.7, np.array([-0.1, 0.3, 0.2]),
                                             np.array([[0.05, -0.01, 0.0], [-0.01, 0.08, 0.01],
                                                       [0.0, 0.01, 0.06]])),
                            placement)
    return model


@pytest.mark.parametrize("welded", [False, True], ids=["plain", "with-welded-bodies"])
@pytest.mark.parametrize("kind", ["revolute", "prismatic"])
def test_fixed_parts_fold_into_joint_body(kind, welded):
    """Bodies on fixed parts after a joint fold into one body: 2 states, Pinocchio's M.

    Bodies welded to the ground (directly or on the fixed mount) add neither states nor
    anything to the dynamics.
    """
    axis = tuple(unit([0.3, -0.4, 0.86]))
    system = _one_joint_model(kind, axis, welded).compile()
    assert list(system.state_names) == ["j.q", "j.qd"]
    pmodel = _one_joint_pinocchio(kind, axis)
    for q, qd in [(0.0, 0.0), (0.8, -1.3), (-2.9, 0.4)]:
        assert_matches_pinocchio(system, pmodel, np.array([q]), np.array([qd]),
                                 f"{kind}, welded={welded}, q={q}, qd={qd}")
