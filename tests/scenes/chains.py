"""The scenes of the speed-against-accuracy studies, as kinetwork models and as plain data.

Every peer (pinocchio, MuJoCo, sympy.physics.mechanics) builds its own model from the plain
data of ``chain_spec`` / ``spatial_spec``, so that nothing of kinetwork's is shared with them.

Scenes
------
seed       the seed paper's double pendulum (``models/double_pendulum.json``), 10 s
chaotic    the same at large angles (q0 = 2.5, 2.0 rad), the damper removed so that the motion
           stays chaotic
stiff      the seed with its shoulder spring-damper ``k`` times stiffer (c = d = k, k = 1e4..1e6)
chain      N identical uniform rods (1 m, 1 kg, radius 1 cm) on revolute z joints in relative
           coordinates, hanging under gravity, released from the first joint at 0.5 rad,
           undamped
point masses  N point masses of 1 kg on massless 1 m links, a damper of 0.1 N m s/rad on each
           joint, about z (planar) or about z and x in turn (3-D)
spatial    N links on skew revolute axes with full inertia tensors (seeded), undamped
"""

import json
import pathlib
from dataclasses import dataclass, field

import numpy as np

import kinetwork as kn

ROOT = pathlib.Path(__file__).resolve().parents[2]
SEED_FILE = ROOT / "models" / "double_pendulum.json"
G = 9.81


def seed(q0=None, **params):
    """The seed double pendulum, with model-parameter overrides and optional initial angles."""
    data = json.loads(SEED_FILE.read_text())
    data["parameters"].update({k: float(v) for k, v in params.items()})
    for comp in data["components"]:
        if q0 is not None and comp["name"] in ("shoulder", "elbow"):
            comp["params"]["q0"] = float(q0[comp["name"] == "elbow"])
    return kn.loads(json.dumps(data))


def chaotic():
    return seed(q0=(2.5, 2.0), d=0.0)


def stiff(k):
    return seed(c=k, d=k)


@dataclass
class ChainSpec:
    """Plain data of a serial chain: link ``i`` hangs from joint ``i`` at the end of link i-1.

    For each link: ``offset`` (3,) from the joint to the next joint, in the link's frame;
    ``axis`` (3,) of its joint in the parent's frame (unit); ``mass``; ``r_cm`` (3,) from the
    joint to the centre of mass; ``inertia`` (3, 3) about the centre of mass, link axes.
    ``gravity`` (3,) in the ground frame; ``q0``, ``qd0`` (N,) joint angles and rates;
    ``stiffness``, ``damping`` (N,): a linear spring-damper on each joint, torque
    ``-(stiffness*q + damping*qd)`` (zero by default).
    """
    offset: np.ndarray
    axis: np.ndarray
    mass: np.ndarray
    r_cm: np.ndarray
    inertia: np.ndarray
    gravity: np.ndarray
    q0: np.ndarray
    qd0: np.ndarray = field(default=None)
    stiffness: np.ndarray = field(default=None)
    damping: np.ndarray = field(default=None)

    def __post_init__(self):
        zeros = np.zeros(len(self.mass))
        self.qd0 = zeros if self.qd0 is None else np.asarray(self.qd0, dtype=float)
        self.stiffness = zeros if self.stiffness is None else np.asarray(self.stiffness, float)
        self.damping = zeros if self.damping is None else np.asarray(self.damping, float)

    @property
    def n(self):
        return len(self.mass)


def seed_spec(q0=(0.05, 0.05), c=1.0, d=1.0):
    """The seed double pendulum as plain data: point masses of 1 kg at mid-link of 1 m links,
    g = 9.8, the spring-damper on the shoulder only (same as ``models/double_pendulum.json``)."""
    return ChainSpec(offset=np.array([[0.0, -1.0, 0.0]] * 2), axis=np.array([[0.0, 0, 1]] * 2),
                     mass=np.ones(2), r_cm=np.array([[0.0, -0.5, 0.0]] * 2),
                     inertia=np.zeros((2, 3, 3)), gravity=np.array([0.0, -9.8, 0.0]),
                     q0=np.array(q0, dtype=float), stiffness=np.array([c, 0.0]),
                     damping=np.array([d, 0.0]))


def rod_inertia(mass, length, radius=0.01):
    """A uniform rod along -y: moments about x and z m L^2/12 (+ m r^2/4), about y m r^2/2."""
    side = mass * (length**2 / 12 + radius**2 / 4)
    return np.diag([side, mass * radius**2 / 2, side])


def chain_spec(n, length=1.0, mass=1.0, q0=0.5):
    """N uniform rods hanging along -y, joints about z, the first released at ``q0`` rad."""
    q = np.zeros(n)
    q[0] = q0
    return ChainSpec(offset=np.tile([0.0, -length, 0.0], (n, 1)),
                     axis=np.tile([0.0, 0.0, 1.0], (n, 1)),
                     mass=np.full(n, mass),
                     r_cm=np.tile([0.0, -length / 2, 0.0], (n, 1)),
                     inertia=np.array([rod_inertia(mass, length)] * n),
                     gravity=np.array([0.0, -G, 0.0]), q0=q)


def point_mass_spec(n, planar=True, length=1.0, mass=1.0, damping=0.1, q0=0.5):
    """N point masses, each at the end of a massless link, on revolute joints with a linear
    damper each, hanging along -y: about z only (``planar``), or about z and x in turn (3-D);
    the first joint released at ``q0`` rad. Relative coordinates make the mass matrix's
    condition number grow as N^4 (2e12 at N = 1024) while it stays positive definite."""
    axes = [[0.0, 0.0, 1.0]] if planar else [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]
    q = np.zeros(n)
    q[0] = q0
    return ChainSpec(offset=np.tile([0.0, -length, 0.0], (n, 1)),
                     axis=np.array([axes[i % len(axes)] for i in range(n)]),
                     mass=np.full(n, mass), r_cm=np.tile([0.0, -length, 0.0], (n, 1)),
                     inertia=np.zeros((n, 3, 3)), gravity=np.array([0.0, -G, 0.0]), q0=q,
                     damping=np.full(n, damping))


def spatial_spec(n, seed=7):
    """N links on random skew axes with random full inertia tensors, seeded."""
    rng = np.random.default_rng(seed)
    axes, inertias = [], []
    for _ in range(n):
        a = rng.normal(size=3)
        axes.append(a / np.linalg.norm(a))
        m = 1.0
        a2, b2, c2 = m * rng.uniform(0.01, 0.1, 3)
        R = _rotation(rng.normal(size=3), rng.uniform(0, np.pi))
        inertias.append(R @ np.diag([b2 + c2, a2 + c2, a2 + b2]) @ R.T)
    offset = rng.uniform(-0.3, 0.3, (n, 3)) + [0.0, -0.7, 0.0]
    return ChainSpec(offset=offset, axis=np.array(axes), mass=rng.uniform(0.5, 2.0, n),
                     r_cm=offset * rng.uniform(0.3, 0.7, (n, 1)), inertia=np.array(inertias),
                     gravity=np.array([0.0, -G, 0.0]), q0=rng.uniform(-0.5, 0.5, n))


def _rotation(axis, angle):
    n = np.asarray(axis) / np.linalg.norm(axis)
    k = np.array([[0, -n[2], n[1]], [n[2], 0, -n[0]], [-n[1], n[0], 0]])
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k


def chain_model(spec, name="chain"):
    """A kinetwork model of ``spec``: Ground, then per link Revolute, RigidBody and
    FixedTranslation (and a rotational SpringDamper where the spec has one)."""
    m = kn.Model(name)
    mb = kn.multibody
    m.add(mb.Ground("ground", gravity=list(spec.gravity)))
    previous = "ground.frame"
    for i in range(spec.n):
        joint = m.add(mb.Revolute(f"j{i}", axis=list(spec.axis[i]), q0=float(spec.q0[i]),
                                  qd0=float(spec.qd0[i])))
        body = m.add(mb.RigidBody(f"b{i}", mass=float(spec.mass[i]), r_cm=list(spec.r_cm[i]),
                                  inertia=spec.inertia[i].tolist()))
        link = m.add(mb.FixedTranslation(f"l{i}", r=list(spec.offset[i])))
        m.connect(previous, joint.frame_a)
        m.connect(joint.frame_b, body.frame_a)
        m.connect(joint.frame_b, link.frame_a)
        previous = f"l{i}.frame_b"
        if spec.stiffness[i] or spec.damping[i]:
            sd = m.add(kn.rotational.SpringDamper(f"sd{i}", c=float(spec.stiffness[i]),
                                                  d=float(spec.damping[i])))
            m.connect(sd.flange_a, joint.support)
            m.connect(sd.flange_b, joint.axis)
    return m


def chain(n):
    return chain_model(chain_spec(n), f"chain{n}")


def spatial(n):
    return chain_model(spatial_spec(n), f"spatial{n}")


def point_masses(n, planar=True):
    return chain_model(point_mass_spec(n, planar), f"{'planar' if planar else 'spatial'}"
                                                   f"_point_masses{n}")


def joint_angles(results):
    """The joint angles (n_points, N) of a kinetwork result, coordinates in model order."""
    n = results.states.shape[1] // 2
    return results.states[:, :n]


#: scene name -> (kinetwork model, plain data for the peers, horizon [s])
SCENES = {
    "seed": (seed, seed_spec, 10.0),
    "chaotic": (chaotic, lambda: seed_spec(q0=(2.5, 2.0), d=0.0), 10.0),
    **{f"stiff{k:.0e}".replace("+0", ""): ((lambda k=k: stiff(k)),
                                           (lambda k=k: seed_spec(c=k, d=k)), 10.0)
       for k in (1e4, 1e5, 1e6)},
    **{f"chain{n}": ((lambda n=n: chain(n)), (lambda n=n: chain_spec(n)), 10.0)
       for n in (2, 4, 8, 16, 32, 64, 128)},
    "spatial6": ((lambda: spatial(6)), (lambda: spatial_spec(6)), 10.0),
    **{f"{kind}{n}": ((lambda n=n, p=planar: point_masses(n, p)),
                      (lambda n=n, p=planar: point_mass_spec(n, p)), 10.0)
       for kind, planar in (("points", True), ("points3d_", False)) for n in (2, 16, 128)},
}
