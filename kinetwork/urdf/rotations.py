"""URDF's rotations: roll-pitch-yaw to a matrix, a matrix to an axis and angle."""

import math

import numpy as np


def rpy_matrix(rpy):
    """URDF's roll-pitch-yaw: about the fixed x, then y, then z: Rz(yaw) Ry(pitch) Rx(roll)."""
    (cr, sr), (cp, sp), (cy, sy) = ((math.cos(a), math.sin(a)) for a in rpy)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def axis_angle(R):
    """(unit axis, angle in [0, pi]) of the rotation matrix ``R``, accurate near 0 and pi
    (through the quaternion, Shepperd's choice of its largest component)."""
    t = np.trace(R)
    diag = np.diag(R)
    k = int(np.argmax(diag))
    if t >= diag[k]:
        w = math.sqrt(max(1.0 + t, 0.0)) / 2
        v = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]]) / (4 * w)
    else:
        i, j, m = k, (k + 1) % 3, (k + 2) % 3
        v = np.zeros(3)
        v[i] = math.sqrt(max(1.0 + R[i, i] - R[j, j] - R[m, m], 0.0)) / 2
        v[j] = (R[j, i] + R[i, j]) / (4 * v[i])
        v[m] = (R[m, i] + R[i, m]) / (4 * v[i])
        w = (R[m, j] - R[j, m]) / (4 * v[i])
    if w < 0:
        w, v = -w, -v
    s = float(np.linalg.norm(v))
    if s < 1e-300:
        return [0.0, 0.0, 1.0], 0.0
    return (v / s).tolist(), 2 * math.atan2(s, w)
