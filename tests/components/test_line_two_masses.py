"""LineForceWithTwoMasses (MSL's Forces.LineForceWithTwoMasses): two point masses on a
line force, at fixed distances from its ends.

The reference is written independently (``scenes/line_masses.py``): a sympy Lagrangian of a
pendulum whose tip a spring-damper with the two masses ties to a fixed point, integrated by
scipy's DOP853 at 1e-12. The cut forces at the line's frames are checked against MSL's own
equations for them (frame_b.f = m_b ag_CM2 + aux2 - e fb, aux2 the part of aux1 normal to
the line).
"""

import numpy as np

import kinetwork as kn
from scenes.line_masses import Scene, msl_cut_forces, solve

mb = kn.multibody
SCENE = Scene(pivot=(0.0, 0.3, 0.3), anchor=(0.0, -0.9, 0.3), tip=0.7, mass=2.0, cm=0.35,
              izz=0.08, m_a=1.0, m_b=0.7, L_a=0.2, L_b=0.25, c=5.0, d=3.0, s0=0.8)


def model(s, q0):
    m = kn.Model("line_two_masses")
    m.add(mb.Ground("ground", gravity=list(s.gravity)))
    m.add(mb.FixedTranslation("to_pivot", r=list(s.pivot)))
    m.add(mb.FixedTranslation("to_anchor", r=list(s.anchor)))
    m.add(mb.Revolute("hinge", axis=[0, 0, 1], q0=q0))
    m.add(mb.BodyShape("arm", r=[s.tip, 0, 0], mass=s.mass, r_cm=[s.cm, 0, 0],
                       inertia=[0.001, s.izz, s.izz]))
    m.add(mb.LineForceWithTwoMasses("line", m_a=s.m_a, m_b=s.m_b, L_a=s.L_a, L_b=s.L_b, c=s.c,
                                    d=s.d, s_unstretched=s.s0))
    m.add(kn.Probe("end_a", quantities=["force"]))
    m.add(kn.Probe("end_b", quantities=["force"]))
    for a, b in [("ground.frame", "to_pivot.frame_a"), ("ground.frame", "to_anchor.frame_a"),
                 ("to_pivot.frame_b", "hinge.frame_a"), ("hinge.frame_b", "arm.frame_a"),
                 ("to_anchor.frame_b", "line.frame_a"), ("arm.frame_b", "line.frame_b"),
                 ("end_a.port", "line.frame_a"), ("end_b.port", "line.frame_b")]:
        m.connect(a, b)
    return m


def test_pendulum_on_a_line_force_with_two_masses_matches_the_lagrangian():
    t = np.linspace(0, 1.5, 16)
    acc, kin, phi, w = solve(SCENE, t, 0.4)
    res = kn.simulate(model(SCENE, 0.4), t_end=t[-1], n_points=len(t), rtol=1e-11, atol=1e-12,
                      jit=False)
    np.testing.assert_allclose(res["hinge.q"], phi, atol=1e-9)
    np.testing.assert_allclose(res["hinge.qd"], w, atol=1e-9)
    assert np.ptp(phi) > 0.3                            # it swings
    for k in range(0, len(t), 3):
        f_a, f_b = msl_cut_forces(SCENE, acc, kin, phi[k], w[k])
        np.testing.assert_allclose(res["end_a.force"][k], f_a, atol=1e-8)
        np.testing.assert_allclose(res["end_b.force"][k], f_b, atol=1e-8)
