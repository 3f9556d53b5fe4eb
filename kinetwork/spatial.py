"""3-D rotation helpers over CasADi SX (and numbers): shared by components and solver.

CasADi is imported in each function, not by this module: the components that use these
helpers stay free of it at import (``components/quantities.py``)."""

import functools


def eye3():
    """The 3x3 identity as SX: no rotation."""
    import casadi as ca
    return ca.SX.eye(3)


def zero3():
    """A 3x1 zero as SX: no translation, no force."""
    import casadi as ca
    return ca.SX.zeros(3)


def vec3(values):
    """A 3x1 SX column from three numbers or SX scalars."""
    import casadi as ca
    return ca.vertcat(*[values[i] for i in range(3)])


def mat3(rows):
    """A 3x3 SX matrix from nested rows."""
    import casadi as ca
    return ca.vertcat(*[ca.horzcat(*[rows[i][j] for j in range(3)]) for i in range(3)])


def skew(v):
    """Matrix of the cross product: skew(v) @ w == v x w."""
    import casadi as ca
    return ca.vertcat(ca.horzcat(0, -v[2], v[1]),
                      ca.horzcat(v[2], 0, -v[0]),
                      ca.horzcat(-v[1], v[0], 0))


def vee(m):
    """Inverse of skew, from the antisymmetric part of ``m``."""
    import casadi as ca
    if isinstance(m, ca.SX) and m.shape == (3, 3):
        return _vee()(m)                   # one call, not ten (see ``rotation``)
    return _antisymmetric(m)


def _antisymmetric(m):
    import casadi as ca
    return ca.vertcat(m[2, 1] - m[1, 2], m[0, 2] - m[2, 0], m[1, 0] - m[0, 1]) / 2


@functools.lru_cache(maxsize=1)
def _vee():
    import casadi as ca
    m = ca.SX.sym("m", 3, 3)
    return ca.Function("vee", [m], [_antisymmetric(m)])


def unit(v):
    """``v`` scaled to length one (folds to plain numbers when ``v`` is constant)."""
    import casadi as ca
    return v / ca.norm_2(v)


def rotation(axis, angle):
    """Rotation by ``angle`` about the unit vector ``axis`` (Rodrigues), as SX 3x3."""
    import casadi as ca
    if isinstance(axis, ca.SX) and isinstance(angle, ca.SX) and axis.shape == (3, 1) \
            and angle.shape == (1, 1):
        # one call of the same expression: a dozen calls from Python cost ~1 ms (a 1024-link
        # chain's build paid a second for them)
        return _rotation()(axis, angle)
    return _rodrigues(axis, angle)


def _rodrigues(axis, angle):
    import casadi as ca
    n = unit(axis)
    k = skew(n)
    return ca.SX.eye(3) + ca.sin(angle) * k + (1 - ca.cos(angle)) * (k @ k)


@functools.lru_cache(maxsize=1)
def _rotation():
    import casadi as ca
    axis, angle = ca.SX.sym("axis", 3), ca.SX.sym("angle")
    return ca.Function("rotation", [axis, angle], [_rodrigues(axis, angle)])


# -- quaternions [w, x, y, z] (scalar first) ----------------------------------------------
def quat_rotation(quat):
    """Rotation matrix of ``quat`` divided by its norm: orthonormal for any non-zero quat,
    so a drift of the norm during integration never distorts the motion."""
    import casadi as ca
    w, v = quat[0], quat[1:4]
    k = skew(v)
    return ca.SX.eye(3) + 2 / ca.sumsqr(quat) * (w * k + k @ k)


#: rate [1/s] at which the quaternion kinematics pull the norm back to one
QUATERNION_NORM_RATE = 1.0


def quat_rate(quat, w_b):
    """d(quat)/dt for the angular velocity ``w_b`` resolved in the rotated frame, plus a term
    that pulls the norm back to one without touching the rotation it represents."""
    import casadi as ca
    w, v = quat[0], quat[1:4]
    rate = ca.vertcat(-ca.dot(v, w_b), w * w_b + ca.cross(v, w_b)) / 2
    return rate + QUATERNION_NORM_RATE * (1 - ca.sumsqr(quat)) * quat


def cardan_quat(angles):
    """Quaternion of the body-fixed x-y-z (Cardan) sequence: rotate about x by angles[0],
    then about the new y by angles[1], then about the new z by angles[2]."""
    import casadi as ca
    def half(i, axis):
        e = [0, 0, 0]
        e[axis] = ca.sin(angles[i] / 2)
        return ca.vertcat(ca.cos(angles[i] / 2), *e)
    return quat_product(quat_product(half(0, 0), half(1, 1)), half(2, 2))


def quat_product(a, b):
    """Hamilton product a * b."""
    import casadi as ca
    aw, av, bw, bv = a[0], a[1:4], b[0], b[1:4]
    return ca.vertcat(aw * bw - ca.dot(av, bv), aw * bv + bw * av + ca.cross(av, bv))


#: length [m] below which a line force has no direction (Modelica's s_small)
S_SMALL = 1e-10


def line_length(d):
    """The length of a line force along ``d``, regularised as sqrt(d.d + S_SMALL^2).

    At zero length the direction d/s of the force is undefined; so regularised, s and its
    rate stay smooth, d/s is zero there and the force vanishes (Modelica's line forces divide
    by max(s, s_small) to the same end). Beyond a micrometre it differs from |d| by less than
    1e-14 m.
    """
    import casadi as ca
    return ca.sqrt(ca.dot(d, d) + S_SMALL**2)
