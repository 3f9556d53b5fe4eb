"""A slow mass carrying a fast one: the scene where stability, not accuracy, holds an explicit
step (``auto``'s RK4 choice, ``kinetwork/solver/explicit.py``).

Two prismatic joints along x in series: a 1 kg body on a 1 N/m spring (damped at 0.01 N s/m),
released 1 m out, and on it a 1 g body on a 90 N/m spring (0.006 N s/m): a mode of 300 rad/s
that decays at 3/s. The fast body starts where its spring already carries the slow body's
first acceleration (q = m2 / K), so that mode is barely excited. The reference is written
without kinetwork: the two masses' equations, x2 = q1 + q2.
"""

import numpy as np
from scipy.integrate import solve_ivp

import kinetwork as kn

K, M2, D2 = 90.0, 1e-3, 0.006


def follower():
    m = kn.Model("fast_follower")
    mb, tr = kn.multibody, kn.translational
    m.add(mb.Ground("ground", gravity=[0, -9.81, 0]))
    previous = "ground.frame"
    for name, mass, c, d, q0 in (("slow", 1.0, 1.0, 0.01, 1.0), ("fast", M2, K, D2, M2 / K)):
        joint = m.add(mb.Prismatic(f"{name}_joint", axis=[1, 0, 0], q0=q0))
        body = m.add(mb.RigidBody(name, mass=mass, inertia=np.eye(3).tolist()))
        spring = m.add(tr.SpringDamper(f"{name}_spring", c=c, d=d))
        m.connect(previous, joint.frame_a)
        m.connect(joint.frame_b, body.frame_a)
        m.connect(spring.flange_a, joint.support)
        m.connect(spring.flange_b, joint.axis)
        previous = joint.frame_b
    return m


def follower_reference(t, rtol=1e-13):
    """(q1, q2, v1, v2) at the times ``t`` (from 0) by DOP853 on the masses' own equations."""
    def rhs(_, y):
        q1, q2, v1, v2 = y
        forces = [-q1 - 0.01 * v1, -K * q2 - D2 * v2]
        a = np.linalg.solve([[1 + M2, M2], [M2, M2]], forces)
        return [v1, v2, a[0], a[1]]
    t = np.asarray(t, dtype=float)
    return solve_ivp(rhs, (0, t[-1]), [1.0, M2 / K, 0, 0], method="DOP853", rtol=rtol,
                     atol=rtol * 1e-2, t_eval=t).y.T
