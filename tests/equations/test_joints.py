"""Multi-DOF joints, line forces, world forces and frame probes, checked against independent
references: Pinocchio, conservation laws and closed-form solutions.

Joint conventions (kinetwork.components.multibody):

- Universal: frame_b = frame_a rotated by q[0] about ``n_a``, then by q[1] about ``n_b``
  (resolved in the once-rotated frame).
- Cylindrical: rotated by q[0] about ``axis`` and moved by q[1] along it.
- Planar: moved by q[0] along n_x (projected into the plane), q[1] along n x n_x, rotated by
  q[2] about n.
- Spherical: coordinates a quaternion [w, x, y, z] (the rotation of the normalised
  quaternion), speeds the angular velocity of frame_b relative to frame_a in frame_b axes.
- FreeMotion: coordinates r (in frame_a) then a quaternion; speeds v = dr/dt in frame_a axes,
  then w in frame_b axes.

Pinocchio builds the same mechanisms independently: composite joints (1-DOF unaligned joints
in series, no intermediate body) for Universal, Cylindrical and Planar, and its native
JointModelUniversal, JointModelPlanar, JointModelSpherical and JointModelFreeFlyer, whose
coordinates and velocities differ from kinetwork's and are converted here
(``test_oracle_follows_conventions`` checks the conversions against a numpy composition of
the conventions above, so that a mistake in the oracle cannot pass for one in kinetwork).
"""

from dataclasses import dataclass

import numpy as np
import pinocchio as pin
import pytest

import kinetwork as kn

mb = kn.multibody

TIGHT = {"rtol": 1e-12, "atol": 1e-12}


# ---------------------------------------------------------------------------------------------
# numpy geometry, independent of both libraries
# ---------------------------------------------------------------------------------------------

def unit(v):
    return np.asarray(v, dtype=float) / np.linalg.norm(v)


def skew(v):
    return np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])


def vee(m):
    return np.array([m[2, 1] - m[1, 2], m[0, 2] - m[2, 0], m[1, 0] - m[0, 1]]) / 2


def rodrigues(axis, angle):
    k = skew(unit(axis))
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k


def quat_R(quat):
    """Rotation of the normalised quaternion [w, x, y, z] (Hamilton, active)."""
    w, x, y, z = unit(quat)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def quat_dot(quat, w_b):
    """d(quat)/dt of a unit quaternion for the angular velocity w_b in the rotated frame:
    q * (0, w_b) / 2."""
    w, v = quat[0], np.asarray(quat[1:])
    return 0.5 * np.concatenate([[-v @ w_b], w * w_b + np.cross(v, w_b)])


def cardan_R(angles):
    """Body-fixed x-y-z: about x, then the new y, then the new z."""
    return (rodrigues([1, 0, 0], angles[0]) @ rodrigues([0, 1, 0], angles[1])
            @ rodrigues([0, 0, 1], angles[2]))


def random_rotation(rng):
    return rodrigues(rng.normal(size=3), rng.uniform(0, np.pi))


def random_inertia(rng, mass):
    """Random SPD inertia about the centre of mass (principal moments obey the triangle
    inequality), on random principal axes."""
    a, b, c = mass * rng.uniform(0.02, 0.2, 3)
    R = random_rotation(rng)
    return R @ np.diag([b + c, a + c, a + b]) @ R.T


def hom(R, p):
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, p
    return T


def se3(T):
    return pin.SE3(T[:3, :3].copy(), T[:3, 3].copy())


# ---------------------------------------------------------------------------------------------
# Joint kinds: kinetwork component, Pinocchio joint and the maps between their variables
# ---------------------------------------------------------------------------------------------

KINDS = ["revolute", "prismatic", "universal", "universal_native", "cylindrical", "planar",
         "planar_native", "spherical", "free"]
NQ = {"revolute": 1, "prismatic": 1, "universal": 2, "universal_native": 2, "cylindrical": 2,
      "planar": 3, "planar_native": 3, "spherical": 4, "free": 7}
NV = {"revolute": 1, "prismatic": 1, "universal": 2, "universal_native": 2, "cylindrical": 2,
      "planar": 3, "planar_native": 3, "spherical": 3, "free": 6}


@dataclass
class Joint:
    """One joint of a kind with its random axes (``planar_native`` and ``universal_native``
    are kinetwork's Planar and Universal, built in Pinocchio from its native joint)."""
    kind: str
    a: np.ndarray = None            # axis / n_a / plane normal n
    b: np.ndarray = None            # n_b / n_x

    @classmethod
    def random(cls, kind, rng):
        a, b = unit(rng.normal(size=3)), unit(rng.normal(size=3))
        if kind == "universal_native":            # Pinocchio's needs orthogonal unit axes
            b = unit(b - (b @ a) * a)
        return cls(kind, a, b)

    def plane(self):
        """(ex, ey, n) of a Planar joint: n_x projected into the plane."""
        n = unit(self.a)
        ex = unit(self.b - (self.b @ n) * n)
        return ex, np.cross(n, ex), n

    # -- kinetwork ---------------------------------------------------------------------------
    def component(self, name):
        k, a, b = self.kind, self.a.tolist(), self.b.tolist()
        if k == "revolute":
            return mb.Revolute(name, axis=a)
        if k == "prismatic":
            return mb.Prismatic(name, axis=a)
        if k.startswith("universal"):
            return mb.Universal(name, n_a=a, n_b=b)
        if k == "cylindrical":
            return mb.Cylindrical(name, axis=a)
        if k.startswith("planar"):
            return mb.Planar(name, n=a, n_x=b)
        if k == "spherical":
            return mb.Spherical(name)
        return mb.FreeMotion(name)

    def motion(self, q):
        """frame_b relative to frame_a (4x4) from the documented convention, in numpy."""
        k = self.kind
        if k == "revolute":
            return hom(rodrigues(self.a, q[0]), np.zeros(3))
        if k == "prismatic":
            return hom(np.eye(3), q[0] * unit(self.a))
        if k.startswith("universal"):
            return hom(rodrigues(self.a, q[0]) @ rodrigues(self.b, q[1]), np.zeros(3))
        if k == "cylindrical":
            return hom(rodrigues(self.a, q[0]), q[1] * unit(self.a))
        if k.startswith("planar"):
            ex, ey, n = self.plane()
            return hom(rodrigues(n, q[2]), q[0] * ex + q[1] * ey)
        if k == "spherical":
            return hom(quat_R(q), np.zeros(3))
        return hom(quat_R(q[3:]), q[:3])

    def qdot(self, q, u):
        """d(q)/dt for the speeds u (unit quaternions)."""
        if self.kind == "spherical":
            return quat_dot(unit(q), u)
        if self.kind == "free":
            return np.concatenate([u[:3], quat_dot(unit(q[3:]), u[3:])])
        return np.asarray(u, dtype=float)

    def random_q(self, rng, scale_quat=1.0):
        """Random coordinates; quaternions of norm ``scale_quat`` (kinetwork normalises)."""
        k = self.kind
        if k == "spherical":
            return scale_quat * unit(rng.normal(size=4))
        if k == "free":
            return np.concatenate([rng.uniform(-1, 1, 3), scale_quat * unit(rng.normal(size=4))])
        if k == "prismatic":
            return rng.uniform(-1, 1, 1)
        if k == "cylindrical":
            return np.array([rng.uniform(-np.pi, np.pi), rng.uniform(-1, 1)])
        if k.startswith("planar"):
            return np.array([rng.uniform(-1, 1), rng.uniform(-1, 1),
                             rng.uniform(-np.pi, np.pi)])
        return rng.uniform(-np.pi, np.pi, NQ[k])

    # -- Pinocchio ---------------------------------------------------------------------------
    def pin_joint(self):
        """(joint model, pre, post): Pinocchio's joint frame sits at pre (relative to where
        kinetwork's frame_a is) and kinetwork's frame_b at post relative to that."""
        k, a, b = self.kind, self.a, self.b
        ident = np.eye(4)
        rev, pri = pin.JointModelRevoluteUnaligned, pin.JointModelPrismaticUnaligned
        if k == "revolute":
            return rev(a), ident, ident
        if k == "prismatic":
            return pri(a), ident, ident
        if k == "universal":
            j = pin.JointModelComposite(rev(a))
            j.addJoint(rev(b))
            return j, ident, ident
        if k == "universal_native":
            return pin.JointModelUniversal(a, b), ident, ident
        if k == "cylindrical":
            j = pin.JointModelComposite(rev(a))
            j.addJoint(pri(a))
            return j, ident, ident
        if k == "planar":
            ex, ey, n = self.plane()
            j = pin.JointModelComposite(pri(ex))
            j.addJoint(pri(ey))
            j.addJoint(rev(n))
            return j, ident, ident
        if k == "planar_native":
            # Pinocchio's plane is the x-y plane of its joint frame: turn it onto (ex, ey, n)
            R0 = np.column_stack(self.plane())
            return pin.JointModelPlanar(), hom(R0, np.zeros(3)), hom(R0.T, np.zeros(3))
        if k == "spherical":
            return pin.JointModelSpherical(), ident, ident
        return pin.JointModelFreeFlyer(), ident, ident

    def q_pin(self, q):
        k = self.kind
        if k == "planar_native":
            return np.array([q[0], q[1], np.cos(q[2]), np.sin(q[2])])
        if k == "spherical":
            w, x, y, z = unit(q)
            return np.array([x, y, z, w])
        if k == "free":
            w, x, y, z = unit(q[3:])
            return np.concatenate([q[:3], [x, y, z, w]])
        return np.asarray(q, dtype=float)

    def v_map(self, q):
        """T with Pinocchio's velocity v = T u (kinetwork's speeds u)."""
        k = self.kind
        if k == "planar_native":       # [velocity in the joint frame, angular rate]
            T = np.eye(3)
            T[:2, :2] = rodrigues([0, 0, 1], q[2])[:2, :2].T
            return T
        if k == "free":                # [velocity in the body frame, w in the body frame]
            T = np.eye(6)
            T[:3, :3] = quat_R(q[3:]).T
            return T
        return np.eye(NV[k])

    def udot(self, q, u, a):
        """kinetwork's speed rates from Pinocchio's acceleration a = d(T u)/dt."""
        k = self.kind
        if k == "planar_native":       # d/dt(R2^T p') = R2^T p'' - w J R2^T p'
            R2 = rodrigues([0, 0, 1], q[2])[:2, :2]
            v_l = R2.T @ u[:2]
            return np.concatenate([R2 @ (a[:2] + u[2] * np.array([-v_l[1], v_l[0]])), a[2:]])
        if k == "free":                # d/dt(R^T r') = R^T r'' - w x R^T r'
            R = quat_R(q[3:])
            return np.concatenate([R @ (a[:3] + np.cross(u[3:], R.T @ u[:3])), a[3:]])
        return np.asarray(a, dtype=float)


def block_diag(blocks):
    n = sum(b.shape[0] for b in blocks)
    out, i = np.zeros((n, n)), 0
    for b in blocks:
        out[i:i + b.shape[0], i:i + b.shape[0]] = b
        i += b.shape[0]
    return out


# ---------------------------------------------------------------------------------------------
# Random mechanisms in both libraries
# ---------------------------------------------------------------------------------------------

@dataclass
class Link:
    """A fixed rotation and translation from the parent's outboard frame, a joint, a body."""
    parent: int
    placement: np.ndarray           # 4x4, parent outboard frame -> joint frame_a
    joint: Joint
    mass: float
    r_cm: np.ndarray
    inertia: np.ndarray
    rot: tuple = None                         # (axis, angle, r) of the FixedRotation
    tr: np.ndarray = None                     # r of the FixedTranslation


def random_mechanism(seed, kinds, parents):
    rng = np.random.default_rng(seed)
    links = []
    for kind, parent in zip(kinds, parents):
        axis, angle = unit(rng.normal(size=3)), float(rng.uniform(-np.pi, np.pi))
        rot_r, tr_r = rng.uniform(-0.5, 0.5, 3), rng.uniform(-1, 1, 3)
        mass = float(rng.uniform(0.5, 5.0))
        links.append(Link(parent=parent,
                          placement=hom(rodrigues(axis, angle), rot_r) @ hom(np.eye(3), tr_r),
                          joint=Joint.random(kind, rng), mass=mass,
                          r_cm=rng.uniform(-0.5, 0.5, 3), inertia=random_inertia(rng, mass),
                          rot=(axis, angle, rot_r), tr=tr_r))
    return links, rng.normal(size=3) * 5.0


def random_state(seed, links, scale_quat=1.0):
    rng = np.random.default_rng(10_000 + seed)
    q = np.concatenate([L.joint.random_q(rng, scale_quat) for L in links])
    u = rng.uniform(-2, 2, sum(NV[L.joint.kind] for L in links))
    return q, u


def split(links, q, u=None):
    """Per link (q_j, u_j) (u_j None without u)."""
    out, i, k = [], 0, 0
    for L in links:
        nq, nv = NQ[L.joint.kind], NV[L.joint.kind]
        out.append((q[i:i + nq], None if u is None else u[k:k + nv]))
        i, k = i + nq, k + nv
    return out


def build_kinetwork(links, gravity):
    """Joints added in link order (so are the states); probe ``p<i>`` on each joint's
    outboard frame records its pose."""
    model = kn.Model("joints")
    ground = model.add(mb.Ground("ground", gravity=gravity.tolist()))
    outboard = []
    for i, L in enumerate(links):
        axis, angle, r = L.rot
        rot = model.add(mb.FixedRotation(f"rot{i}", axis=axis.tolist(), angle=angle,
                                         r=r.tolist()))
        tr = model.add(mb.FixedTranslation(f"tr{i}", r=L.tr.tolist()))
        joint = model.add(L.joint.component(f"j{i}"))
        body = model.add(mb.RigidBody(f"body{i}", mass=L.mass, r_cm=L.r_cm.tolist(),
                                      inertia=L.inertia.tolist()))
        probe = model.add(kn.Probe(f"p{i}", quantities=["position", "orientation"]))
        model.connect(ground.frame if L.parent < 0 else outboard[L.parent], rot.frame_a)
        model.connect(rot.frame_b, tr.frame_a)
        model.connect(tr.frame_b, joint.frame_a)
        model.connect(joint.frame_b, body.frame_a)
        model.connect(joint.frame_b, probe.port)
        outboard.append(joint.frame_b)
    return model


def build_pinocchio(links, gravity):
    """Joint i + 1 is link i; things on kinetwork's frame_b sit at ``post`` on the joint."""
    model = pin.Model()
    model.gravity.linear = np.asarray(gravity, dtype=float)
    posts = []
    for i, L in enumerate(links):
        jmodel, pre, post = L.joint.pin_joint()
        before = np.eye(4) if L.parent < 0 else posts[L.parent]
        jid = model.addJoint(L.parent + 1, jmodel, se3(before @ L.placement @ pre), f"j{i}")
        model.appendBodyToJoint(jid, pin.Inertia(L.mass, L.r_cm, L.inertia), se3(post))
        posts.append(post)
    return model, posts


def to_pin(links, q, u):
    """Pinocchio's (q, v) and the velocity map T (v = T u) of kinetwork's state."""
    parts = split(links, q, u)
    q_pin = np.concatenate([L.joint.q_pin(qj) for L, (qj, _) in zip(links, parts)])
    T = block_diag([L.joint.v_map(qj) for L, (qj, _) in zip(links, parts)])
    return q_pin, T @ u, T


def udot_from_pin(links, q, u, a):
    out, k = [], 0
    for L, (qj, uj) in zip(links, split(links, q, u)):
        nv = NV[L.joint.kind]
        out.append(L.joint.udot(qj, uj, a[k:k + nv]))
        k += nv
    return np.concatenate(out)


def numpy_poses(links, q):
    """World pose (4x4) of every joint's frame_b, composing the conventions in numpy."""
    poses = []
    for L, (qj, _) in zip(links, split(links, q)):
        base = np.eye(4) if L.parent < 0 else poses[L.parent]
        poses.append(base @ L.placement @ L.joint.motion(qj))
    return poses


def kn_qdot(links, q, u):
    return np.concatenate([L.joint.qdot(qj, uj) for L, (qj, uj) in zip(links, split(links, q, u))])


def probe_values(system, x):
    """{signal name: value} of the system's probes at state x (t = 0)."""
    flat = np.asarray(system.outputs(0.0, x[None, :]), dtype=float).ravel()
    out, i = {}, 0
    for sig in system.signals:
        out[sig.name] = flat[i:i + sig.size].reshape(sig.shape)
        i += sig.size
    return out


# ---------------------------------------------------------------------------------------------
# The oracle follows the documented conventions
# ---------------------------------------------------------------------------------------------

@pytest.mark.parametrize("kind", KINDS[2:])
def test_oracle_follows_conventions(kind):
    """Pinocchio's frames, kinetic and potential energy equal a numpy composition of the
    conventions, with Pinocchio's (q, v) converted from kinetwork's by ``to_pin``."""
    links, gravity = random_mechanism(sum(map(ord, kind)) + 1, [kind, "revolute", kind],
                                      [-1, 0, 1])
    pmodel, posts = build_pinocchio(links, gravity)
    data = pmodel.createData()
    q, u = random_state(1, links)
    q_pin, v_pin, _ = to_pin(links, q, u)
    pin.forwardKinematics(pmodel, data, q_pin)
    poses = numpy_poses(links, q)
    for i, T in enumerate(poses):
        np.testing.assert_allclose(data.oMi[i + 1].homogeneous @ posts[i], T, atol=1e-12)

    potential = -sum(L.mass * gravity @ (T[:3, :3] @ L.r_cm + T[:3, 3])
                     for L, T in zip(links, poses))
    np.testing.assert_allclose(pin.computePotentialEnergy(pmodel, data, q_pin), potential,
                               rtol=1e-12)

    # kinetic energy by finite differences of the numpy poses along d(q)/dt
    h = 1e-6
    qdot = kn_qdot(links, q, u)
    after, before = numpy_poses(links, q + h * qdot), numpy_poses(links, q - h * qdot)
    kinetic = 0.0
    for L, T, Ta, Tb in zip(links, poses, after, before):
        R = T[:3, :3]
        v_cm = ((Ta[:3, :3] @ L.r_cm + Ta[:3, 3]) - (Tb[:3, :3] @ L.r_cm + Tb[:3, 3])) / (2 * h)
        omega = vee((Ta[:3, :3] - Tb[:3, :3]) / (2 * h) @ R.T)
        kinetic += 0.5 * L.mass * v_cm @ v_cm + 0.5 * omega @ R @ L.inertia @ R.T @ omega
    np.testing.assert_allclose(pin.computeKineticEnergy(pmodel, data, q_pin, v_pin), kinetic,
                               rtol=1e-7)


# ---------------------------------------------------------------------------------------------
# kinetwork against Pinocchio
# ---------------------------------------------------------------------------------------------

def assert_matches_pinocchio(system, links, pmodel, posts, q, u, context):
    """Frame poses, M(q) and the rhs of kinetwork against Pinocchio, to 1e-10."""
    n = len(u)
    q_pin, v_pin, T = to_pin(links, q, u)
    data = pmodel.createData()

    # poses of the joints' outboard frames (the probes)
    x = np.concatenate([q, u])
    values = probe_values(system, x)
    pin.forwardKinematics(pmodel, data, q_pin)
    for i in range(len(links)):
        ref = data.oMi[i + 1].homogeneous @ posts[i]
        np.testing.assert_allclose(values[f"p{i}.orientation"], ref[:3, :3], atol=1e-12,
                                   err_msg=f"orientation {i}, {context}")
        np.testing.assert_allclose(values[f"p{i}.position"], ref[:3, 3], atol=1e-12,
                                   err_msg=f"position {i}, {context}")

    # mass matrix: the kinetic energy 1/2 v^T M_pin v with v = T u
    M_pin = pin.crba(pmodel, data, q_pin).copy()
    M_pin = np.triu(M_pin) + np.triu(M_pin, 1).T
    M_ref = T.T @ M_pin @ T
    M = np.asarray(system.mass_matrix(q), dtype=float)
    assert M.shape == (n, n), context
    np.testing.assert_allclose(M, M_ref, rtol=1e-10, atol=1e-10 * np.abs(M_ref).max(),
                               err_msg=f"mass matrix, {context}")

    dx = np.asarray(system.rhs(0.0, x), dtype=float).ravel()
    nq = len(q)
    # coordinates' rates: u for angles and distances; quaternion rates turn the frame at w
    rates = dx[:nq]
    k = 0
    for L, (qj, uj) in zip(links, split(links, q, u)):
        nqj = NQ[L.joint.kind]
        r = rates[k:k + nqj]
        if L.joint.kind in ("spherical", "free"):
            quat, qrate = qj[-4:], r[-4:]
            h = 1e-6
            Rd = (quat_R(quat + h * qrate) - quat_R(quat - h * qrate)) / (2 * h)
            np.testing.assert_allclose(vee(quat_R(quat).T @ Rd), uj[-3:], atol=1e-8,
                                       err_msg=f"quaternion rate, {context}")
            np.testing.assert_array_equal(r[:nqj - 4], uj[:nqj - 4])
        else:
            np.testing.assert_array_equal(r, uj, err_msg=f"dq/dt, {context}")
        k += nqj

    a_pin = pin.aba(pmodel, data, q_pin, v_pin, np.zeros(pmodel.nv)).copy()
    qdd_ref = udot_from_pin(links, q, u, a_pin)
    np.testing.assert_allclose(dx[nq:], qdd_ref, rtol=1e-10,
                               atol=1e-10 * max(1.0, np.abs(qdd_ref).max()),
                               err_msg=f"speed rates, {context}")


@pytest.mark.parametrize("kind", KINDS[2:])
def test_joint_in_tree_matches_pinocchio(kind):
    """ground -> joint -> body -> revolute -> body -> joint -> body, with a prismatic branch
    on the first body: the joint at the ground and deeper in the chain."""
    links, gravity = random_mechanism(sum(map(ord, kind)),
                                      [kind, "revolute", kind, "prismatic"], [-1, 0, 1, 0])
    system = build_kinetwork(links, gravity).compile()
    names = [f"j{i}.{s}" for i, L in enumerate(links)
             for s in L.joint.component("x").coordinate_labels()]
    names += [f"j{i}.{s}" for i, L in enumerate(links)
              for s in L.joint.component("x").speed_labels()]
    assert system.state_names == names
    pmodel, posts = build_pinocchio(links, gravity)
    for k in range(3):
        # kinetwork normalises quaternions: a state off the unit sphere means the same
        q, u = random_state(100 * k + len(kind), links, scale_quat=[1.0, 0.6, 1.7][k])
        assert_matches_pinocchio(system, links, pmodel, posts, q, u,
                                 f"{kind}, point {k}: q={q}, u={u}")


def test_quaternion_joint_names():
    """Spherical and FreeMotion states are named as documented."""
    links, gravity = random_mechanism(5, ["free", "spherical"], [-1, 0])
    system = build_kinetwork(links, gravity).compile()
    assert system.state_names == (
        [f"j0.r[{i}]" for i in range(3)] + [f"j0.quat[{i}]" for i in range(4)]
        + [f"j1.quat[{i}]" for i in range(4)]
        + [f"j0.v[{i}]" for i in range(3)] + [f"j0.w[{i}]" for i in range(3)]
        + [f"j1.w[{i}]" for i in range(3)])


@pytest.mark.parametrize("kind", ["Spherical", "FreeMotion"])
def test_initial_state_from_cardan_angles(kind):
    """angles0 are body-fixed x-y-z angles of frame_b in frame_a; w0 (and r0, v0) are the
    initial speeds as given."""
    angles0, w0 = [0.7, -1.1, 2.4], [0.3, -2.0, 1.5]
    extra = {"r0": [1.0, -2.0, 0.5], "v0": [0.1, 0.2, -0.3]} if kind == "FreeMotion" else {}
    model = kn.Model("start")
    ground = model.add(mb.Ground("ground"))
    joint = model.add(getattr(mb, kind)("j", angles0=angles0, w0=w0, **extra))
    body = model.add(mb.RigidBody("body", mass=1.0, inertia=[0.1, 0.2, 0.3]))
    model.connect(ground.frame, joint.frame_a)
    model.connect(joint.frame_b, body.frame_a)
    system = model.compile()
    x0 = dict(zip(system.state_names, system.x0))
    quat = np.array([x0[f"j.quat[{i}]"] for i in range(4)])
    assert abs(np.linalg.norm(quat) - 1) < 1e-15
    np.testing.assert_allclose(quat_R(quat), cardan_R(angles0), atol=1e-15)
    np.testing.assert_array_equal([x0[f"j.w[{i}]"] for i in range(3)], w0)
    for key, values in extra.items():
        np.testing.assert_array_equal([x0[f"j.{key[0]}[{i}]"] for i in range(3)], values)


@pytest.mark.parametrize("seed", range(3))
def test_random_mixed_tree_matches_pinocchio(seed):
    """Six links of random kinds (all of them possible) in a random tree."""
    rng = np.random.default_rng(seed)
    kinds = [str(k) for k in rng.choice(KINDS, 6)]
    kinds[2] = "spherical"                         # a ball joint deep in the tree
    # each parent is on the path from the ground to the latest link, so that the links
    # come in depth-first order (pin.crba wants each subtree a contiguous block)
    parents, path = [], [-1]
    for i in range(6):
        parent = i - 1 if i == 0 or rng.uniform() < 0.6 else int(rng.choice(path[:-1]))
        path = path[:path.index(parent) + 1] + [i]
        parents.append(parent)
    links, gravity = random_mechanism(700 + seed, kinds, parents)
    assert all(p < i for i, p in enumerate(parents))
    system = build_kinetwork(links, gravity).compile()
    pmodel, posts = build_pinocchio(links, gravity)
    for k in range(2):
        q, u = random_state(900 + 10 * seed + k, links, scale_quat=1.0 + 0.3 * k)
        assert_matches_pinocchio(system, links, pmodel, posts, q, u,
                                 f"seed={seed}, kinds={kinds}, parents={parents}, "
                                 f"point {k}: q={q}, u={u}")


# ---------------------------------------------------------------------------------------------
# A free rigid body: conservation laws and the free fall of its centre of mass
# ---------------------------------------------------------------------------------------------

def free_body(gravity, mass, inertia, r_cm=(0, 0, 0), probes=False, force=None, torque=None,
              **initial):
    """A RigidBody on a FreeMotion from the ground; optional world force/torque on it."""
    model = kn.Model("free_body")
    ground = model.add(mb.Ground("ground", gravity=list(gravity)))
    joint = model.add(mb.FreeMotion("free", **initial))
    body = model.add(mb.RigidBody("body", mass=mass, r_cm=list(r_cm),
                                  inertia=np.asarray(inertia, dtype=float).tolist()))
    model.connect(ground.frame, joint.frame_a)
    model.connect(joint.frame_b, body.frame_a)
    if probes:
        probe = model.add(kn.Probe("probe", quantities=[
            "position", "velocity", "acceleration", "orientation", "angular_velocity",
            "angular_acceleration"]))
        model.connect(joint.frame_b, probe.port)
    if force is not None:
        model.add(mb.WorldForce("push", force=list(force)))
        model.connect("push.frame_b", "free.frame_b")
    if torque is not None:
        model.add(mb.WorldTorque("twist", torque=list(torque)))
        model.connect("twist.frame_b", "free.frame_b")
    return model


def free_states(res, name="free"):
    """r, quaternion, v, w of the FreeMotion ``name`` as (n, k) arrays."""
    def get(s, n):
        return np.column_stack([res[f"{name}.{s}[{i}]"] for i in range(n)])
    return get("r", 3), get("quat", 4), get("v", 3), get("w", 3)


def test_free_body_conserves_energy_and_momentum_through_dzhanibekov_flips():
    """Torque-free tumbling about the intermediate axis of diag(1, 2, 3) for 100 s: kinetic
    energy and the world angular momentum R I w + r x m v stay constant while w[1] flips."""
    mass, inertia = 2.0, np.diag([1.0, 2.0, 3.0])
    model = free_body([0, 0, 0], mass, inertia, r0=[0.3, -0.2, 0.5], v0=[0.4, 0.1, -0.3],
                      angles0=[0.4, -0.3, 1.2], w0=[0.01, 5.0, 0.01])
    res = kn.simulate(model, t_end=100, n_points=2001, **TIGHT)
    r, quat, v, w = free_states(res)
    R = np.array([quat_R(x) for x in quat])
    energy = 0.5 * np.einsum("ni,ij,nj->n", w, inertia, w) + 0.5 * mass * np.sum(v * v, 1)
    momentum = np.einsum("nij,jk,nk->ni", R, inertia, w) + mass * np.cross(r, v)
    e_err = np.abs(energy - energy[0]).max() / energy[0]
    l_err = np.abs(momentum - momentum[0]).max() / np.linalg.norm(momentum[0])
    assert e_err < 1e-7, e_err
    assert l_err < 1e-9, l_err
    flips = np.count_nonzero(np.diff(np.sign(w[:, 1])) != 0)
    assert flips >= 2, flips
    # the starting orientation is the body-fixed x-y-z angles0
    np.testing.assert_allclose(R[0], cardan_R([0.4, -0.3, 1.2]), atol=1e-15)


def test_free_body_centre_of_mass_falls_on_a_parabola():
    """A spinning body with its centre of mass off frame_b: the centre of mass follows
    r_c0 + v_c0 t + g t^2 / 2 whatever the tumbling."""
    g = np.array([0.5, -9.81, 1.2])
    rng = np.random.default_rng(3)
    mass, c = 1.7, np.array([0.3, -0.2, 0.25])
    inertia = random_inertia(rng, mass)
    r0, v0, angles0, w0 = [0.1, 2.0, -0.4], [1.0, 3.0, -0.5], [0.3, 0.2, -0.7], [2.0, -1.0, 3.5]
    res = kn.simulate(free_body(g, mass, inertia, r_cm=c, r0=r0, v0=v0, angles0=angles0,
                                w0=w0), t_end=5, n_points=201, **TIGHT)
    r, quat, v, w = free_states(res)
    R = np.array([quat_R(x) for x in quat])
    r_c = r + R @ c
    v_c = v + np.einsum("nij,nj->ni", R, np.cross(w, c))
    R0 = cardan_R(angles0)
    rc0 = np.array(r0) + R0 @ c
    vc0 = np.array(v0) + R0 @ np.cross(w0, c)
    t = res.t[:, None]
    ref = rc0 + vc0 * t + 0.5 * g * t ** 2
    err = np.abs(r_c - ref).max() / np.abs(ref).max()
    assert err < 1e-9, err
    v_err = np.abs(v_c - (vc0 + g * t)).max() / np.abs(vc0 + g * t).max()
    assert v_err < 1e-9, v_err
    assert np.abs(w - w[0]).max() > 0.1          # it does tumble (w is not constant)


# ---------------------------------------------------------------------------------------------
# Line forces
# ---------------------------------------------------------------------------------------------

def hanging_mass(carrier, element, mass, g, y0, anchor=(0.0, 0.0, 0.0), **law):
    """A body on a FreeMotion (or a vertical Prismatic) below ``anchor`` on the ground, hung
    from it by a multibody line force ``element``; the body's frame is its centre of mass."""
    model = kn.Model("hanging")
    ground = model.add(mb.Ground("ground", gravity=[0, -g, 0]))
    mount = model.add(mb.FixedTranslation("mount", r=list(anchor)))
    if carrier == "free":
        joint = model.add(mb.FreeMotion("joint", r0=[anchor[0], y0, anchor[2]]))
    else:
        joint = model.add(mb.Prismatic("joint", axis=[0, 1, 0], q0=y0))
        model.connect(ground.frame, "joint.frame_a")
    body = model.add(mb.RigidBody("body", mass=mass, inertia=[0.1, 0.2, 0.3]))
    force = model.add(getattr(mb, element)("line", **law))
    if carrier == "free":
        model.connect(ground.frame, joint.frame_a)
    model.connect(ground.frame, mount.frame_a)
    model.connect(joint.frame_b, body.frame_a)
    model.connect(mount.frame_b, force.frame_a)
    model.connect(joint.frame_b, force.frame_b)
    return model


@pytest.mark.parametrize("carrier", ["free", "prismatic"])
@pytest.mark.parametrize("element", ["Spring", "SpringDamper"])
def test_mass_on_line_spring_oscillates_as_closed_form(carrier, element):
    """m y'' = c (-y - s0) - d y' - m g below an anchor at the origin: about the equilibrium
    y_eq = -s0 - m g / c, x(t) = y_eq + e^(-zeta w t) (A cos(w_d t) + B sin(w_d t))."""
    mass, c, s0, g, y0 = 2.0, 40.0, 1.0, 9.81, -1.2
    d = 0.0 if element == "Spring" else 1.3
    law = {"c": c, "s_unstretched": s0, **({"d": d} if d else {})}
    res = kn.simulate(hanging_mass(carrier, element, mass, g, y0, **law), t_end=10,
                      n_points=501, **TIGHT)
    y = res["joint.r[1]"] if carrier == "free" else res["joint.q"]
    w0, zeta = np.sqrt(c / mass), d / (2 * np.sqrt(c * mass))
    wd = w0 * np.sqrt(1 - zeta ** 2)
    y_eq = -s0 - mass * g / c
    A = y0 - y_eq
    B = zeta * w0 * A / wd
    t = res.t
    ref = y_eq + np.exp(-zeta * w0 * t) * (A * np.cos(wd * t) + B * np.sin(wd * t))
    err = np.abs(y - ref).max()
    assert err < 1e-8, err
    if carrier == "free":      # nothing leaves the vertical line or turns the body
        r, quat, v, w = free_states(res, "joint")
        assert np.abs(r[:, [0, 2]]).max() < 1e-12 and np.abs(v[:, [0, 2]]).max() < 1e-12
        assert np.abs(w).max() < 1e-12
        assert np.abs(quat - [1, 0, 0, 0]).max() < 1e-12


def test_damper_alone_decays_exponentially():
    """A mass sliding away from an anchor on its line, against a Damper only: the speed
    decays as v0 e^(-d t / m)."""
    mass, d, x0, v0 = 1.5, 0.7, 1.0, 2.0
    model = kn.Model("damped_slide")
    ground = model.add(mb.Ground("ground", gravity=[0, -9.81, 0]))
    joint = model.add(mb.Prismatic("slide", axis=[1, 0, 0], q0=x0, qd0=v0))
    body = model.add(mb.RigidBody("body", mass=mass))
    damper = model.add(mb.Damper("damper", d=d))
    model.connect(ground.frame, joint.frame_a)
    model.connect(joint.frame_b, body.frame_a)
    model.connect(ground.frame, damper.frame_a)
    model.connect(joint.frame_b, damper.frame_b)
    res = kn.simulate(model, t_end=5, n_points=101, **TIGHT)
    t = res.t
    np.testing.assert_allclose(res["slide.qd"], v0 * np.exp(-d * t / mass), rtol=1e-9,
                               atol=1e-12)
    np.testing.assert_allclose(res["slide.q"], x0 + v0 * mass / d * (1 - np.exp(-d * t / mass)),
                               rtol=1e-9)


def spring_pendulum(variant, mass, inertia_z, c, s0, g):
    """A body swinging in the x-y plane below the ground origin, hung by a Spring: on a
    Planar joint, or on a Revolute (about z) carrying a Prismatic along its -y."""
    model = kn.Model("spring_pendulum")
    ground = model.add(mb.Ground("ground", gravity=[0, -g, 0]))
    body = model.add(mb.RigidBody("body", mass=mass, inertia=[inertia_z - 0.02, 0.02,
                                                              inertia_z]))
    spring = model.add(mb.Spring("spring", c=c, s_unstretched=s0))
    probe = model.add(kn.Probe("probe", quantities=["position", "velocity",
                                                    "angular_velocity"]))
    if variant == "planar":
        joint = model.add(mb.Planar("joint", q0=[0.5, -1.3, 0.2], qd0=[0.8, 0.3, 1.0]))
        model.connect(ground.frame, joint.frame_a)
        out = joint.frame_b
    else:
        swing = model.add(mb.Revolute("swing", axis=[0, 0, 1], q0=0.4, qd0=-0.6))
        slide = model.add(mb.Prismatic("slide", axis=[0, -1, 0], q0=1.4, qd0=0.5))
        model.connect(ground.frame, swing.frame_a)
        model.connect(swing.frame_b, slide.frame_a)
        out = slide.frame_b
    model.connect(out, body.frame_a)
    model.connect(out, probe.port)
    model.connect(ground.frame, spring.frame_a)
    model.connect(out, spring.frame_b)
    return model


@pytest.mark.parametrize("variant", ["planar", "revolute_prismatic"])
def test_spring_pendulum_conserves_energy(variant):
    """Kinetic + gravity + 0.5 c (s - s0)^2 constant over 20 s of a swinging, stretching
    spring pendulum; on the Planar joint the kinetic energy comes from the states."""
    mass, inertia_z, c, s0, g = 1.3, 0.05, 30.0, 1.0, 9.81
    res = kn.simulate(spring_pendulum(variant, mass, inertia_z, c, s0, g), t_end=20,
                      n_points=1001, **TIGHT)
    r, v, w = res["probe.position"], res["probe.velocity"], res["probe.angular_velocity"]
    if variant == "planar":
        qd = np.column_stack([res[f"joint.qd[{i}]"] for i in range(3)])
        x = np.column_stack([res[f"joint.q[{i}]"] for i in range(2)])
        np.testing.assert_allclose(r[:, :2], x, atol=1e-12)
        np.testing.assert_allclose(v[:, :2], qd[:, :2], atol=1e-12)
        np.testing.assert_allclose(w[:, 2], qd[:, 2], atol=1e-12)
    kinetic = 0.5 * mass * np.sum(v * v, 1) + 0.5 * inertia_z * w[:, 2] ** 2
    s = np.linalg.norm(r, axis=1)
    energy = kinetic + mass * g * r[:, 1] + 0.5 * c * (s - s0) ** 2
    err = np.abs(energy - energy[0]).max() / np.abs(energy).max()
    assert err < 1e-8, err
    assert np.ptp(s) > 0.1 and np.ptp(r[:, 0]) > 0.5        # it stretches and swings


def test_spring_between_free_bodies_conserves_momenta():
    """Two tumbling bodies joined by a Spring between points off their centres of mass,
    without gravity: linear and angular momentum and energy are constant."""
    rng = np.random.default_rng(11)
    model = kn.Model("two_bodies")
    ground = model.add(mb.Ground("ground", gravity=[0, 0, 0]))
    spring = model.add(mb.Spring("spring", c=25.0, s_unstretched=0.8))
    bodies = []
    for i, (r0, v0) in enumerate([([0, 0, 0], [0.3, -0.2, 0.1]), ([1.5, 0.4, -0.3],
                                                                   [-0.5, 0.4, 0.6])]):
        mass = [1.2, 2.5][i]
        inertia = random_inertia(rng, mass)
        w0 = rng.uniform(-2, 2, 3)
        joint = model.add(mb.FreeMotion(f"free{i}", r0=r0, v0=v0,
                                        angles0=rng.uniform(-1, 1, 3).tolist(), w0=w0.tolist()))
        body = model.add(mb.RigidBody(f"body{i}", mass=mass, inertia=inertia.tolist()))
        arm = model.add(mb.FixedTranslation(f"arm{i}", r=rng.uniform(-0.4, 0.4, 3).tolist()))
        model.connect(ground.frame, joint.frame_a)
        model.connect(joint.frame_b, body.frame_a)
        model.connect(joint.frame_b, arm.frame_a)
        model.connect(arm.frame_b, spring.frame_a if i == 0 else spring.frame_b)
        bodies.append((mass, inertia, np.array(arm.r, dtype=float)))
    res = kn.simulate(model, t_end=10, n_points=501, **TIGHT)
    P, L, E = 0, 0, 0
    ends = []
    for i, (mass, inertia, arm) in enumerate(bodies):
        r, quat, v, w = free_states(res, f"free{i}")
        R = np.array([quat_R(x) for x in quat])
        P = P + mass * v
        L = L + np.einsum("nij,jk,nk->ni", R, inertia, w) + mass * np.cross(r, v)
        E = E + 0.5 * mass * np.sum(v * v, 1) + 0.5 * np.einsum("ni,ij,nj->n", w, inertia, w)
        ends.append(r + R @ arm)
    s = np.linalg.norm(ends[1] - ends[0], axis=1)
    E = E + 0.5 * 25.0 * (s - 0.8) ** 2
    assert np.abs(P - P[0]).max() < 1e-10 * np.abs(P[0]).max()
    assert np.abs(L - L[0]).max() < 1e-9 * np.abs(L[0]).max()
    assert np.abs(E - E[0]).max() < 1e-8 * E[0]
    assert np.ptp(s) > 0.1


# ---------------------------------------------------------------------------------------------
# World forces and torques
# ---------------------------------------------------------------------------------------------

def test_world_force_accelerates_free_body_at_f_over_m():
    """A constant WorldForce on a non-rotating free body: r = r0 + v0 t + F t^2 / (2 m)."""
    mass, F = 2.5, np.array([1.5, -2.0, 0.7])
    r0, v0 = np.array([0.2, 0.1, -0.3]), np.array([0.5, 0.0, 1.0])
    model = free_body([0, 0, 0], mass, [0.1, 0.2, 0.3], force=F.tolist(), r0=r0.tolist(),
                      v0=v0.tolist(), angles0=[0.3, -0.5, 0.9])
    system = model.compile()
    dx = system.rhs(0.0, system.x0)
    np.testing.assert_allclose(dx[7:10], F / mass, rtol=1e-15)
    np.testing.assert_allclose(dx[10:], 0.0, atol=1e-14)
    res = kn.simulate(system, t_end=3, n_points=31, **TIGHT)
    r, quat, v, w = free_states(res)
    t = res.t[:, None]
    # Adams is exact on a quadratic but for its start-up steps, which the driver's chunks
    # repeat a few times (each restarts the method): errors of the asked 1e-12, not round-off
    np.testing.assert_allclose(r, r0 + v0 * t + F / (2 * mass) * t ** 2, rtol=1e-11, atol=5e-12)
    np.testing.assert_allclose(v, v0 + F / mass * t, rtol=1e-11, atol=5e-12)
    np.testing.assert_allclose(quat, np.tile(quat[0], (len(t), 1)), rtol=0, atol=1e-12)
    np.testing.assert_allclose(w, 0.0, atol=1e-12)


def random_tumbling_states(rng, n):
    """(t, x) of a FreeMotion at random: quaternions off the unit sphere too."""
    for _ in range(n):
        t = float(rng.uniform(0, 5))
        quat = unit(rng.normal(size=4)) * rng.uniform(0.5, 1.5)
        yield t, np.concatenate([rng.uniform(-1, 1, 3), quat, rng.uniform(-2, 2, 3),
                                 rng.uniform(-3, 3, 3)])


def test_world_force_on_tumbling_body():
    """At random states of a tumbling body with its centre of mass off frame_b, under a
    time-dependent WorldForce F at frame_b: the centre of mass accelerates at F/m + g, and
    about it I w' + w x I w = R^T ((r - r_c) x F)."""
    rng = np.random.default_rng(4)
    mass, c, g = 1.8, np.array([0.2, -0.3, 0.15]), np.array([0.0, -9.81, 0.0])
    inertia = random_inertia(rng, mass)
    system = free_body(g, mass, inertia, r_cm=c,
                       force=["sin(t)", "2", "-cos(2*t)"]).compile()
    for t, x in random_tumbling_states(rng, 4):
        dx = system.rhs(t, x)
        w, vd, wd = x[10:13], dx[7:10], dx[10:13]
        R = quat_R(x[3:7])
        F = np.array([np.sin(t), 2, -np.cos(2 * t)])
        a_c = vd + R @ (np.cross(wd, c) + np.cross(w, np.cross(w, c)))
        np.testing.assert_allclose(a_c, F / mass + g, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(inertia @ wd + np.cross(w, inertia @ w),
                                   R.T @ np.cross(-R @ c, F), rtol=1e-12, atol=1e-12)


def test_world_torque_on_tumbling_body():
    """At random states, a WorldTorque tau on a free body (centre of mass off frame_b):
    I w' + w x I w = R^T tau about the centre of mass, which moves at g only."""
    rng = np.random.default_rng(14)
    mass, c, g = 1.8, np.array([0.2, -0.3, 0.15]), np.array([0.0, -9.81, 0.0])
    inertia = random_inertia(rng, mass)
    system = free_body(g, mass, inertia, r_cm=c, torque=["0.5*t", "-1", "0.3"]).compile()
    for t, x in random_tumbling_states(rng, 4):
        dx = system.rhs(t, x)
        w, vd, wd = x[10:13], dx[7:10], dx[10:13]
        R = quat_R(x[3:7])
        a_c = vd + R @ (np.cross(wd, c) + np.cross(w, np.cross(w, c)))
        np.testing.assert_allclose(a_c, g, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(inertia @ wd + np.cross(w, inertia @ w),
                                   R.T @ np.array([0.5 * t, -1, 0.3]), rtol=1e-12, atol=1e-12)


def test_world_torque_on_revolute():
    """A WorldTorque on a body turning about z: q'' = tau_z / (I_zz + m (c_x^2 + c_y^2));
    its x and y components load the bearing only (gravity along the axis does nothing)."""
    rng = np.random.default_rng(5)
    mass, c = 1.4, np.array([0.3, -0.4, 0.2])
    inertia = random_inertia(rng, mass)
    model = kn.Model("turntable")
    ground = model.add(mb.Ground("ground", gravity=[0, 0, -9.81]))
    joint = model.add(mb.Revolute("turn", axis=[0, 0, 1]))
    body = model.add(mb.RigidBody("body", mass=mass, r_cm=c.tolist(), inertia=inertia.tolist()))
    twist = model.add(mb.WorldTorque("twist", torque=["0.7", "-1.1", "2*cos(t)"]))
    model.connect(ground.frame, joint.frame_a)
    model.connect(joint.frame_b, body.frame_a)
    model.connect(joint.frame_b, twist.frame_b)
    system = model.compile()
    J = inertia[2, 2] + mass * (c[0] ** 2 + c[1] ** 2)
    for t, q, qd in [(0.0, 0.0, 0.0), (0.7, 1.2, -3.0), (2.9, -2.5, 4.0)]:
        dx = system.rhs(t, [q, qd])
        assert dx[0] == qd
        np.testing.assert_allclose(dx[1], 2 * np.cos(t) / J, rtol=1e-13, atol=1e-15)


# ---------------------------------------------------------------------------------------------
# Frame probes
# ---------------------------------------------------------------------------------------------

def pendulum_with_cut_probes(q0):
    """Two bodies below a Revolute about z; probes on the revolute's frame_a and frame_b."""
    model = kn.Model("pendulum")
    ground = model.add(mb.Ground("ground", gravity=[0, -9.81, 0]))
    joint = model.add(mb.Revolute("pivot", axis=[0, 0, 1], q0=q0))
    bob = model.add(mb.RigidBody("bob", mass=1.5, r_cm=[0, -1.2, 0], inertia=[0.1, 0.1, 0.1]))
    rod = model.add(mb.FixedTranslation("rod", r=[0, -2.0, 0]))
    tip = model.add(mb.RigidBody("tip", mass=0.5, inertia=[0.01, 0.02, 0.03]))
    quantities = ["force", "torque"]
    pa = model.add(kn.Probe("pa", quantities=quantities))
    pb = model.add(kn.Probe("pb", quantities=quantities))
    for a, b in [(ground.frame, joint.frame_a), (joint.frame_b, bob.frame_a),
                 (joint.frame_b, rod.frame_a), (rod.frame_b, tip.frame_a),
                 (pa.port, joint.frame_a), (pb.port, joint.frame_b)]:
        model.connect(a, b)
    return model


def test_cut_force_of_pendulum_hanging_at_rest():
    """At rest the ground holds the pendulum up with (m1 + m2) g, and no torque."""
    res = kn.simulate(pendulum_with_cut_probes(0.0), t_end=1, n_points=11, **TIGHT)
    weight = np.array([0, 2.0 * 9.81, 0])
    np.testing.assert_allclose(res["pa.force"], np.tile(weight, (11, 1)), atol=1e-12)
    np.testing.assert_allclose(res["pb.force"], -np.tile(weight, (11, 1)), atol=1e-12)
    np.testing.assert_allclose(res["pa.torque"], 0.0, atol=1e-12)
    np.testing.assert_allclose(res["pb.torque"], 0.0, atol=1e-12)


def test_cut_force_of_swinging_pendulum():
    """Swinging, the bearing force is sum m (a_c - g), with a_c from the states and rhs."""
    model = pendulum_with_cut_probes(1.1)
    system = model.compile()
    res = kn.simulate(system, t_end=3, n_points=31, **TIGHT)
    th, thd = res["pivot.q"], res["pivot.qd"]
    thdd = np.array([system.rhs(t, x)[1] for t, x in zip(res.t, res.states)])
    force = 0
    for mass, L in [(1.5, 1.2), (0.5, 2.0)]:
        a_c = L * (thdd[:, None] * np.column_stack([np.cos(th), np.sin(th), 0 * th])
                   + thd[:, None] ** 2 * np.column_stack([-np.sin(th), np.cos(th), 0 * th]))
        force = force + mass * (a_c - [0, -9.81, 0])
    np.testing.assert_allclose(res["pa.force"], force, rtol=1e-12, atol=1e-12)
    # a revolute passes no torque about its axis
    np.testing.assert_allclose(res["pa.torque"][:, 2], 0.0, atol=1e-12)


def test_frame_probes_of_spinning_free_body():
    """Probes on a tumbling, falling body's frame equal the states: r, v, R(quat), R w, and
    from the rhs the acceleration v' and the angular acceleration R w'."""
    rng = np.random.default_rng(6)
    mass = 1.1
    model = free_body([0.3, -9.81, 0.2], mass, random_inertia(rng, mass), r_cm=[0.1, 0.2, -0.1],
                      probes=True, r0=[0.5, 1.0, -0.2], v0=[0.3, 2.0, -0.4],
                      angles0=[0.2, 0.9, -0.4], w0=[1.0, -4.0, 2.5])
    system = model.compile()
    res = kn.simulate(system, t_end=4, n_points=41, **TIGHT)
    r, quat, v, w = free_states(res)
    R = np.array([quat_R(x) for x in quat])
    dx = np.array([system.rhs(t, x) for t, x in zip(res.t, res.states)])
    np.testing.assert_allclose(res["probe.position"], r, rtol=0, atol=1e-14)
    np.testing.assert_allclose(res["probe.velocity"], v, rtol=0, atol=1e-14)
    np.testing.assert_allclose(res["probe.orientation"], R, rtol=0, atol=1e-14)
    np.testing.assert_allclose(res["probe.angular_velocity"], np.einsum("nij,nj->ni", R, w),
                               rtol=0, atol=1e-13)
    np.testing.assert_allclose(res["probe.acceleration"], dx[:, 7:10], rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(res["probe.angular_acceleration"],
                               np.einsum("nij,nj->ni", R, dx[:, 10:]), rtol=1e-12, atol=1e-12)
