"""An independent reference for a pendulum tied to a fixed point by a line force with two
point masses (MSL's LineForceWithTwoMasses): a sympy Lagrangian, written without kinetwork.

The pendulum turns about z at ``pivot``; its tip is ``tip`` along its rotated x axis, its
centre of mass ``cm`` along it (mass ``mass``, moment ``izz`` about the centre of mass). The
line runs from the fixed ``anchor`` to the tip: m_a at anchor + L_a e, m_b at tip - L_b e
(e the unit vector from anchor to tip), tension c (length - s0) + d d(length)/dt.
"""

from dataclasses import dataclass

import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp


@dataclass
class Scene:
    pivot: tuple
    anchor: tuple
    tip: float
    mass: float
    cm: float
    izz: float
    m_a: float
    m_b: float
    L_a: float
    L_b: float
    c: float
    d: float
    s0: float
    gravity: tuple = (0.0, -9.81, 0.0)


def lagrangian(s):
    """(acc(phi, w), kin(phi)): phi'' of the Lagrangian, and per phi the masses' positions
    with their first and second derivatives in phi, e, the spring's tension at w = 0 and
    d(length)/dphi."""
    phi, w = sp.symbols("phi w")
    rot = sp.Matrix([[sp.cos(phi), -sp.sin(phi), 0], [sp.sin(phi), sp.cos(phi), 0], [0, 0, 1]])
    pivot, anchor = sp.Matrix(s.pivot), sp.Matrix(s.anchor)
    tip = pivot + rot * sp.Matrix([s.tip, 0, 0])
    cm = pivot + rot * sp.Matrix([s.cm, 0, 0])
    length = sp.sqrt((tip - anchor).dot(tip - anchor))
    e = (tip - anchor) / length
    r_a, r_b = anchor + s.L_a * e, tip - s.L_b * e
    g = sp.Matrix(s.gravity)
    points = [(s.mass, cm), (s.m_a, r_a), (s.m_b, r_b)]
    inertia = s.izz + sum(m * r.diff(phi).dot(r.diff(phi)) for m, r in points)
    # d/dt (inertia w) - dT/dphi = inertia w' + inertia_phi w^2 / 2; V = -sum m g . r
    potential = -sum(m * g.dot(r) for m, r in points)
    dl = length.diff(phi)
    tension = s.c * (length - s.s0) + s.d * dl * w
    acc = (-tension * dl - potential.diff(phi) - inertia.diff(phi) * w**2 / 2) / inertia
    kin = sp.lambdify(phi, [r_a, r_a.diff(phi), r_a.diff(phi, 2), r_b, r_b.diff(phi),
                            r_b.diff(phi, 2), e, tension.subs(w, 0), dl], "numpy")
    return sp.lambdify((phi, w), acc, "numpy"), kin


def solve(s, t, phi0=0.0, w0=0.0):
    """(acc, kin, phi(t), w(t)) by DOP853 at rtol 1e-12."""
    acc, kin = lagrangian(s)
    ref = solve_ivp(lambda _, x: [x[1], acc(x[0], x[1])], (t[0], t[-1]), [phi0, w0],
                    method="DOP853", rtol=1e-12, atol=1e-13, t_eval=t)
    return acc, kin, ref.y[0], ref.y[1]


def msl_cut_forces(s, acc, kin, phi, w):
    """MSL's LineForceWithTwoMasses equations for (frame_a.f, frame_b.f), in the world:
    m_a ag1 - aux2 - e fa and m_b ag2 + aux2 - e fb, aux2 the part of
    aux1 = ag1 m_a L_a / L - ag2 m_b L_b / L normal to the line; fa = -fb = T, the tension
    (a damper between the flanges)."""
    a = acc(phi, w)
    r_a, J_a, H_a, r_b, J_b, H_b, e, T0, dl = [np.asarray(v, dtype=float).ravel()
                                                 for v in kin(phi)]
    G = np.asarray(s.gravity)
    length = np.linalg.norm((r_b + s.L_b * e) - (r_a - s.L_a * e))
    ag1 = J_a * a + H_a * w**2 - G
    ag2 = J_b * a + H_b * w**2 - G
    aux1 = ag1 * (s.m_a * s.L_a / length) - ag2 * (s.m_b * s.L_b / length)
    aux2 = aux1 - (aux1 @ e) * e
    tension = T0[0] + s.d * dl[0] * w
    return s.m_a * ag1 - aux2 - tension * e, s.m_b * ag2 + aux2 + tension * e
