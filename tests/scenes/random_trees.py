"""Random spatial chains and trees of revolute and prismatic joints on skew axes, as plain
data (``Link``) and as kinetwork models (``build_kinetwork``): the pinocchio comparison
(``tests/equations/test_pinocchio.py``) builds the same data in Pinocchio."""

from dataclasses import dataclass

import numpy as np

import kinetwork as kn

mb = kn.multibody


def unit(v):
    """``v`` scaled to length one."""
    return np.asarray(v, dtype=float) / np.linalg.norm(v)


def rodrigues(axis, angle):
    """Rotation matrix of ``angle`` about ``axis`` (numpy, independent of both libraries)."""
    n = unit(axis)
    k = np.array([[0, -n[2], n[1]], [n[2], 0, -n[0]], [-n[1], n[0], 0]])
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k


def random_rotation(rng):
    """A uniformly random rotation matrix."""
    return rodrigues(rng.normal(size=3), rng.uniform(0, np.pi))


def random_inertia(rng, mass):
    """A random full, symmetric positive-definite inertia about the centre of mass.

    Principal moments are built from second moments (a, b, c) > 0 as (b+c, a+c, a+b), so they
    satisfy the triangle inequality, then turned to random principal axes.
    """
    a, b, c = mass * rng.uniform(0.005, 0.2, 3)
    R = random_rotation(rng)
    return R @ np.diag([b + c, a + c, a + b]) @ R.T


@dataclass
class Link:
    """One link: fixed rotation, fixed translation, joint, body; ``parent`` -1 is the ground."""
    parent: int
    rot_axis: np.ndarray
    rot_angle: float
    rot_r: np.ndarray
    tr_r: np.ndarray
    kind: str
    axis: np.ndarray
    reversed: bool
    mass: float
    r_cm: np.ndarray
    inertia: np.ndarray


def random_mechanism(seed, n, reversed_fraction=0.0, tree=False):
    """``n`` random links; a chain, or a tree (each parent drawn from the earlier links).

    Returns
    -------
    links : list of Link
    gravity : ndarray, shape (3,)
    """
    rng = np.random.default_rng(seed)
    links = []
    path = [-1]       # the ground and the ancestors of the latest link, itself included
    for i in range(n):
        mass = float(rng.uniform(0.2, 5.0))
        # a tree's parent is on that path, so that links come in depth-first order (pin.crba
        # assumes each subtree is a contiguous block of joint indices): mostly the latest
        # link, so that the tree grows deep, else an earlier one, so that it branches
        if tree and i > 0 and rng.uniform() < 0.4:
            parent = int(rng.choice(path[:-1]))
        else:
            parent = i - 1
        path = path[:path.index(parent) + 1] + [i]
        links.append(Link(
            parent=parent,
            rot_axis=unit(rng.normal(size=3)), rot_angle=float(rng.uniform(-np.pi, np.pi)),
            rot_r=rng.uniform(-0.5, 0.5, 3), tr_r=rng.uniform(-1.0, 1.0, 3),
            kind=str(rng.choice(["revolute", "prismatic"])), axis=unit(rng.normal(size=3)),
            reversed=bool(rng.uniform() < reversed_fraction),
            mass=mass, r_cm=rng.uniform(-0.5, 0.5, 3), inertia=random_inertia(rng, mass)))
    gravity = rng.normal(size=3) * 5.0
    return links, gravity


def random_state(seed, links):
    """Random q (revolute: any angle; prismatic: +-1 m) and qd."""
    rng = np.random.default_rng(10_000 + seed)
    q = np.array([rng.uniform(-np.pi, np.pi) if L.kind == "revolute" else rng.uniform(-1, 1)
                  for L in links])
    return q, rng.uniform(-2.0, 2.0, len(links))


def build_kinetwork(links, gravity):
    """The mechanism as a ``kn.Model`` (joints added in link order, so states follow it)."""
    model = kn.Model("random_chain")
    ground = model.add(mb.Ground("ground", gravity=gravity.tolist()))
    outboard = []
    for i, L in enumerate(links):
        rot = model.add(mb.FixedRotation(f"rot{i}", axis=L.rot_axis.tolist(),
                                         angle=L.rot_angle, r=L.rot_r.tolist()))
        tr = model.add(mb.FixedTranslation(f"tr{i}", r=L.tr_r.tolist()))
        joint_class = mb.Revolute if L.kind == "revolute" else mb.Prismatic
        joint = model.add(joint_class(f"j{i}", axis=L.axis.tolist()))
        body = model.add(mb.RigidBody(f"body{i}", mass=L.mass, r_cm=L.r_cm.tolist(),
                                      inertia=L.inertia.tolist()))
        model.connect(ground.frame if L.parent < 0 else outboard[L.parent], rot.frame_a)
        model.connect(rot.frame_b, tr.frame_a)
        if L.reversed:
            model.connect(tr.frame_b, joint.frame_b)
            out = joint.frame_a
        else:
            model.connect(tr.frame_b, joint.frame_a)
            out = joint.frame_b
        model.connect(out, body.frame_a)
        outboard.append(out)
    return model
