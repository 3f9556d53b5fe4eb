"""LineForceWithTwoMasses (MSL's Forces.LineForceWithTwoMasses): two point masses on a
line force, at fixed distances from its ends.

The reference is written independently: a sympy Lagrangian of a pendulum whose tip a
spring-damper with the two masses ties to a fixed point (the masses at A + L_a e and
p - L_b e, e the unit vector from A to the tip p), integrated by scipy's DOP853 at 1e-12.
The cut force at the line's frame_b is checked against MSL's own equations for it
(frame_b.f = m_b ag_CM2 + aux2 - e fb, aux2 the part of aux1 normal to the line).
"""

import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp

import kinetwork as kn

mb = kn.multibody
G = np.array([0.0, -9.81, 0.0])
PIVOT, ANCHOR, TIP = [0.0, 0.3, 0.3], [0.0, -0.9, 0.3], 0.7
MASS, CM, IZZ = 2.0, 0.35, 0.08
M_A, M_B, L_A, L_B = 1.0, 0.7, 0.2, 0.25
C, D, S0 = 5.0, 3.0, 0.8


def model(q0=0.4):
    m = kn.Model("line_two_masses")
    m.add(mb.Ground("ground", gravity=G.tolist()))
    m.add(mb.FixedTranslation("to_pivot", r=PIVOT))
    m.add(mb.FixedTranslation("to_anchor", r=ANCHOR))
    m.add(mb.Revolute("hinge", axis=[0, 0, 1], q0=q0))
    m.add(mb.BodyShape("arm", r=[TIP, 0, 0], mass=MASS, r_cm=[CM, 0, 0],
                       inertia=[0.001, IZZ, IZZ]))
    m.add(mb.LineForceWithTwoMasses("line", m_a=M_A, m_b=M_B, L_a=L_A, L_b=L_B, c=C, d=D,
                                    s_unstretched=S0))
    m.add(kn.Probe("end", quantities=["force"]))
    for a, b in [("ground.frame", "to_pivot.frame_a"), ("ground.frame", "to_anchor.frame_a"),
                 ("to_pivot.frame_b", "hinge.frame_a"), ("hinge.frame_b", "arm.frame_a"),
                 ("to_anchor.frame_b", "line.frame_a"), ("arm.frame_b", "line.frame_b"),
                 ("end.port", "line.frame_b")]:
        m.connect(a, b)
    return m


def reference():
    """phi'' from the Lagrangian, and the masses' positions with their derivatives in phi."""
    phi, w = sp.symbols("phi w")
    rot = sp.Matrix([[sp.cos(phi), -sp.sin(phi), 0], [sp.sin(phi), sp.cos(phi), 0], [0, 0, 1]])
    pivot, anchor = sp.Matrix(PIVOT), sp.Matrix(ANCHOR)
    tip = pivot + rot * sp.Matrix([TIP, 0, 0])
    cm = pivot + rot * sp.Matrix([CM, 0, 0])
    length = sp.sqrt((tip - anchor).dot(tip - anchor))
    e = (tip - anchor) / length
    r_a, r_b = anchor + L_A * e, tip - L_B * e
    g = sp.Matrix(G)
    points = [(MASS, cm), (M_A, r_a), (M_B, r_b)]
    inertia = IZZ + sum(m * r.diff(phi).dot(r.diff(phi)) for m, r in points)
    # d/dt (inertia w) - dT/dphi = inertia w' + inertia_phi w^2 / 2; V = -sum m g . r
    potential = -sum(m * g.dot(r) for m, r in points)
    dl = length.diff(phi)
    tension = C * (length - S0) + D * dl * w
    acc = (-tension * dl - potential.diff(phi) - inertia.diff(phi) * w**2 / 2) / inertia
    f_acc = sp.lambdify((phi, w), acc, "numpy")
    kin = sp.lambdify(phi, [r_a, r_a.diff(phi), r_a.diff(phi, 2), r_b, r_b.diff(phi),
                            r_b.diff(phi, 2), e, tension.subs(w, 0), dl], "numpy")
    return f_acc, kin


def test_pendulum_on_a_line_force_with_two_masses_matches_the_lagrangian():
    f_acc, kin = reference()
    t = np.linspace(0, 1.5, 16)
    ref = solve_ivp(lambda _, x: [x[1], f_acc(x[0], x[1])], (0, t[-1]), [0.4, 0.0],
                    method="DOP853", rtol=1e-12, atol=1e-13, t_eval=t)
    res = kn.simulate(model(), t_end=t[-1], n_points=len(t), rtol=1e-11, atol=1e-12)
    np.testing.assert_allclose(res["hinge.q"], ref.y[0], atol=1e-9)
    np.testing.assert_allclose(res["hinge.qd"], ref.y[1], atol=1e-9)
    assert np.ptp(ref.y[0]) > 0.3                       # it swings
    # MSL's cut force at frame_b: m_b ag2 + aux2 + T e (T the tension, -fb)
    for k in range(0, len(t), 3):
        phi, w = ref.y[:, k]
        a = f_acc(phi, w)
        r_a, J_a, H_a, r_b, J_b, H_b, e, T0, dl = [np.asarray(v, dtype=float).ravel()
                                                     for v in kin(phi)]
        length = np.linalg.norm(r_b + L_B * e - (r_a - L_A * e))
        ag1 = J_a * a + H_a * w**2 - G
        ag2 = J_b * a + H_b * w**2 - G
        aux1 = ag1 * (M_A * L_A / length) - ag2 * (M_B * L_B / length)
        aux2 = aux1 - (aux1 @ e) * e
        tension = T0[0] + D * dl[0] * w
        expected = M_B * ag2 + aux2 + tension * e
        np.testing.assert_allclose(res["end.force"][k], expected, atol=1e-8)
