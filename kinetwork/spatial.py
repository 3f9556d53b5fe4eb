"""3-D rotation helpers over CasADi SX (and numbers): shared by components and solver."""

import casadi as ca


def vec3(values):
    """A 3x1 SX column from three numbers or SX scalars."""
    return ca.vertcat(*[values[i] for i in range(3)])


def mat3(rows):
    """A 3x3 SX matrix from nested rows."""
    return ca.vertcat(*[ca.horzcat(*[rows[i][j] for j in range(3)]) for i in range(3)])


def skew(v):
    """Matrix of the cross product: skew(v) @ w == v x w."""
    return ca.vertcat(ca.horzcat(0, -v[2], v[1]),
                      ca.horzcat(v[2], 0, -v[0]),
                      ca.horzcat(-v[1], v[0], 0))


def vee(m):
    """Inverse of skew, from the antisymmetric part of ``m``."""
    return ca.vertcat(m[2, 1] - m[1, 2], m[0, 2] - m[2, 0], m[1, 0] - m[0, 1]) / 2


def unit(v):
    """``v`` scaled to length one (folds to plain numbers when ``v`` is constant)."""
    return v / ca.norm_2(v)


def rotation(axis, angle):
    """Rotation by ``angle`` about the unit vector ``axis`` (Rodrigues), as SX 3x3."""
    n = unit(axis)
    k = skew(n)
    return ca.SX.eye(3) + ca.sin(angle) * k + (1 - ca.cos(angle)) * (k @ k)
