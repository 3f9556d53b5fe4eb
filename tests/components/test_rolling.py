"""Rolling contact (kinetwork/components/rolling.py, MSL's Joints/Parts.RollingWheel).

References, all independent of the joint's own kinematics:
- a disk rolling straight and upright: x = x0 + a s t, the contact force its weight;
- steady circular rolling of a leaning disk, from the moment balance about the centre
  (derived by hand below): lean, heading rate and the circle of the centre stay as the
  closed form says, and the contact force is m a_G + m g;
- general motion (MSL's Elementary.RollingWheel start): energy is conserved and the contact
  point, computed here from the wheel's pose, has no velocity.
"""

import numpy as np
import pytest

import kinetwork as kn

mb = kn.multibody
G = 9.81
RADIUS, MASS, I_AXIS, I_LONG = 0.3, 2.0, 0.06, 0.12


def wheel(der_angles0, angles0=(0, 0, 0), x0=0.0, y0=0.0):
    model = kn.Model("wheel")
    model.add(mb.Ground("ground", gravity=[0, 0, -G]))
    model.add(mb.RollingWheel("wheel", radius=RADIUS, m=MASS, I_axis=I_AXIS, I_long=I_LONG,
                              x0=x0, y0=y0, angles0=list(angles0),
                              der_angles0=list(der_angles0)))
    model.add(kn.Probe("centre", quantities=["position", "velocity", "orientation",
                                             "angular_velocity", "force", "torque"]))
    model.connect("ground.frame", "wheel.frame_a")
    model.connect("centre.port", "wheel.frame_b")
    return model


def rot(axis, a):
    c, s = np.cos(a), np.sin(a)
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    R = np.eye(3)
    R[i, i], R[i, j], R[j, i], R[j, j] = c, -s, s, c
    return R


def run(model, t_end, n=41):
    return kn.simulate(model, t_end=t_end, n_points=n, rtol=1e-11, atol=1e-12, jit=False)


def test_upright_disk_rolls_straight():
    s = 4.0
    res = run(wheel([0, s, 0], x0=0.2, y0=-0.1), 1.0, 11)
    pos = res["centre.position"]
    np.testing.assert_allclose(pos[:, 0], 0.2 + RADIUS * s * res.t, atol=1e-9)
    np.testing.assert_allclose(pos[:, 1:], [[-0.1, RADIUS]] * len(res.t), atol=1e-9)
    np.testing.assert_allclose(res["wheel.joint.der_angles[1]"], s, atol=1e-9)
    # the probe reads what the wheel exerts on the joint: minus the contact force
    np.testing.assert_allclose(res["centre.force"], [[0, 0, -MASS * G]] * len(res.t),
                               atol=1e-8)


def steady(theta, s):
    """Heading rate Omega of steady rolling at lean theta (the axis theta above the plane)
    and spin s (the wheel's angular velocity along its axis): with A, C the transverse and
    axial inertia, the moment of the contact force about the centre balances dH/dt,
        A Omega^2 sin(theta) cos(theta) - (C + m a^2) s Omega cos(theta) = m g a sin(theta);
    the root of smaller size (the gyroscopic branch)."""
    a2 = I_LONG * np.sin(theta) * np.cos(theta)
    a1 = -(I_AXIS + MASS * RADIUS**2) * s * np.cos(theta)
    a0 = -MASS * G * RADIUS * np.sin(theta)
    roots = np.roots([a2, a1, a0])
    return roots[np.argmin(abs(roots))].real


def test_steady_circular_rolling_matches_the_closed_form():
    theta, s = 0.3, 12.0
    omega = steady(theta, s)
    spin = s - omega * np.sin(theta)          # rate of the wheel relative to its lean frame
    # at t = 0 the wheel frame is the lean frame Rx(theta): MSL angles (0, 0, theta), rates
    # from w = Omega z + spin e2, e2 = Rx(theta) y
    rates = [omega + spin * np.sin(theta), spin * np.cos(theta), 0.0]
    period = 2 * np.pi / abs(omega)
    res = run(wheel(rates, angles0=(0, 0, theta)), period, 41)
    t = res.t
    R = res["centre.orientation"].reshape(-1, 3, 3)
    axis = R[:, :, 1]
    np.testing.assert_allclose(axis[:, 2], np.sin(theta), atol=1e-8)        # lean held
    heading = np.unwrap(np.arctan2(axis[:, 1], axis[:, 0]))                 # axis turns at Omega
    np.testing.assert_allclose(heading - heading[0], omega * t, atol=1e-8)
    v = RADIUS * s                                                          # centre's speed
    pos = res["centre.position"]
    # over a period, on a circle 5.7 m across (steady leaning rolling is not asymptotically
    # stable: the integration error grows slowly)
    np.testing.assert_allclose(pos[:, 0], v * np.sin(omega * t) / omega, atol=2e-7)
    np.testing.assert_allclose(pos[:, 1], v * (1 - np.cos(omega * t)) / omega, atol=2e-7)
    np.testing.assert_allclose(pos[:, 2], RADIUS * np.cos(theta), atol=1e-10)
    np.testing.assert_allclose(pos[-1], pos[0], atol=2e-7)                 # the circle closes
    # contact force F = m a_G + m g z, a_G = a s Omega (cos(theta) e2 - sin(theta) e3)
    L = np.array([rot(2, omega * ti) @ rot(0, theta) for ti in t])
    a_G = v * omega * (np.cos(theta) * L[:, :, 1] - np.sin(theta) * L[:, :, 2])
    F = MASS * a_G + MASS * G * np.array([0, 0, 1])
    np.testing.assert_allclose(res["centre.force"], -F, atol=1e-7)
    # its moment about the centre: the contact point is a below along -e3
    np.testing.assert_allclose(res["centre.torque"],
                               -np.cross(-RADIUS * L[:, :, 2], F), atol=1e-7)


def test_msl_rolling_wheel_keeps_energy_and_rolls_without_slip():
    res = run(wheel([0, 5, 1], x0=0.2, y0=0.2), 2.0, 81)
    pos, v = res["centre.position"], res["centre.velocity"]
    w = res["centre.angular_velocity"]
    R = res["centre.orientation"].reshape(-1, 3, 3)
    inertia = np.diag([I_LONG, I_AXIS, I_LONG])
    energy = (0.5 * MASS * np.sum(v**2, axis=1) + MASS * G * pos[:, 2]
              + 0.5 * np.einsum("ni,nij,jk,nlk,nl->n", w, R, inertia, R, w))
    np.testing.assert_allclose(energy, energy[0], rtol=1e-8)
    # the contact point: down the steepest line of the wheel's plane, a from the centre
    axis = R[:, :, 1]
    along = np.cross([0, 0, 1], axis)
    along /= np.linalg.norm(along, axis=1)[:, None]
    delta = RADIUS * np.cross(along, axis)
    np.testing.assert_allclose(pos[:, 2] + delta[:, 2], 0, atol=1e-10)
    np.testing.assert_allclose(v + np.cross(w, delta), 0, atol=1e-8)
    assert np.ptp(pos[:, 2]) > 0.05                  # it does lean: the motion is general


def test_rolling_wheel_cannot_close_a_loop():
    model = kn.Model("held")
    model.add(mb.Ground("ground", gravity=[0, 0, -G]))
    model.add(mb.Revolute("hinge", axis=[1, 0, 0]))
    model.add(mb.FixedTranslation("arm", r=[0, 0, RADIUS]))
    model.add(mb.RollingWheelJoint("roll", radius=RADIUS, cut=True))
    for a, b in [("ground.frame", "hinge.frame_a"), ("hinge.frame_b", "arm.frame_a"),
                 ("ground.frame", "roll.frame_a"), ("roll.frame_b", "arm.frame_b")]:
        model.connect(a, b)
    with pytest.raises(kn.ModelError, match="roll: a rolling wheel cannot close a kinematic"):
        model.compile()
