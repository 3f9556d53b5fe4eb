"""MSL's PointMass: point masses in a point gravity field and on a pendulum, against their
equations of motion written by hand (scipy's DOP853) and closed forms."""

import pathlib

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import kinetwork as kn

MODELS = pathlib.Path(__file__).resolve().parents[2] / "models"
mb = kn.multibody


def _particles(t):
    """PointGravityWithPointMasses by hand: r'' = -mu r / |r|^3 for each mass (mu = 1, m = 1),
    and the spring c = 10 (unstretched length 0) pulling body3 and body4 together."""
    r0 = [[0, 0.6, 0], [0.6, 0.6, 0], [0, 0.8, 0], [0.3, 0.8, 0]]
    v0 = [[1, 0, 0], [0.6, 0, 0], [0.6, 0, 0], [0.6, 0, 0]]

    def rhs(_, y):
        r, v = y[:12].reshape(4, 3), y[12:].reshape(4, 3)
        a = -r / np.linalg.norm(r, axis=1)[:, None] ** 3
        a[2] += 10 * (r[3] - r[2])
        a[3] -= 10 * (r[3] - r[2])
        return np.concatenate([v.ravel(), a.ravel()])
    sol = solve_ivp(rhs, (t[0], t[-1]), np.concatenate([np.ravel(r0), np.ravel(v0)]),
                    method="DOP853", rtol=1e-12, atol=1e-13, t_eval=t)
    return sol.y[:12].T.reshape(-1, 4, 3), sol.y[12:].T.reshape(-1, 4, 3)


def test_point_gravity_with_point_masses_follows_the_particles_equations():
    model = kn.load(MODELS / "point_gravity_with_point_masses.json")
    res = kn.simulate(model, t_end=2.0, n_points=41, rtol=1e-11, atol=1e-12, jit=False)
    # MSL: the orientation of a point mass is no state; its position and velocity are
    assert len(res.state_names) == 24
    assert all(".r[" in n or ".v[" in n for n in res.state_names)
    r, v = _particles(res.t)
    for k in range(4):
        np.testing.assert_allclose(res[f"probe{k + 1}.position"], r[:, k], atol=1e-8)
        np.testing.assert_allclose(res[f"probe{k + 1}.velocity"], v[:, k], atol=1e-8)
    assert np.ptp(r[:, 0, 0]) > 0.5                      # they orbit, not sit


def _pendulum(point):
    m = kn.Model("pendulum")
    m.add(mb.Ground("world"))
    m.add(mb.Revolute("rev", axis=[0, 0, 1], q0=0.5))
    m.add(mb.FixedTranslation("rod", r=[0.8, 0, 0]))
    m.add(mb.PointMass("tip", m=1.5) if point else mb.RigidBody("tip", mass=1.5))
    m.add(kn.Probe("cut", quantities=["force", "torque"]))
    for a, b in [("world.frame", "rev.frame_a"), ("rev.frame_b", "rod.frame_a"),
                 ("rod.frame_b", "tip.frame_a"), ("cut.port", "rod.frame_b")]:
        m.connect(a, b)
    return m


def test_point_mass_on_a_pendulum_takes_no_torque_and_swings_as_the_closed_form():
    """A PointMass at the end of a rod: the simple pendulum (energy kept), the rod's end
    passes it a force and no torque, and it is a body without inertia."""
    res = kn.simulate(_pendulum(True), t_end=2.0, n_points=21, rtol=1e-11, atol=1e-12,
                      jit=False)
    assert res.state_names == ["rev.q", "rev.qd"]
    phi, w = res["rev.q"], res["rev.qd"]
    energy = 0.5 * 1.5 * 0.8**2 * w**2 + 1.5 * 9.81 * 0.8 * np.sin(phi)
    np.testing.assert_allclose(energy, energy[0], atol=1e-9)
    np.testing.assert_allclose(res["cut.torque"], 0, atol=1e-10)
    body = kn.simulate(_pendulum(False), t_end=2.0, n_points=21, rtol=1e-11, atol=1e-12,
                       jit=False)
    np.testing.assert_allclose(res["rev.q"], body["rev.q"], atol=1e-10)


def test_point_mass_alone_on_a_free_motion_keeps_its_orientation_and_refuses_a_spin():
    m = kn.Model("thrown")
    m.add(mb.Ground("world"))
    m.add(mb.FreeMotion("free", r0=[0, 1, 0], v0=[1, 2, 0], angles0=[0, 0, 0.3]))
    m.add(mb.PointMass("ball", m=0.2))
    m.add(kn.Probe("p", quantities=["position", "orientation"]))
    for a, b in [("world.frame", "free.frame_a"), ("free.frame_b", "ball.frame_a"),
                 ("p.port", "ball.frame_a")]:
        m.connect(a, b)
    res = kn.simulate(m, t_end=1.0, n_points=11, rtol=1e-11, atol=1e-12, jit=False)
    t = res.t
    np.testing.assert_allclose(res["p.position"], np.stack(
        [t, 1 + 2 * t - 9.81 / 2 * t**2, 0 * t], axis=1), atol=1e-10)
    assert res.state_names == [f"free.{x}[{i}]" for x in "rv" for i in range(3)]
    m.components["free"].w0 = [0, 0, 1.0]
    with pytest.raises(kn.ModelError, match="w0"):
        kn.simulate(m, t_end=1.0)
    # a body with inertia on it turns: the orientation is a state again
    m.components["free"].w0 = None
    m.add(mb.RigidBody("shell", mass=0.1, inertia=[1e-3, 1e-3, 1e-3]))
    m.connect("free.frame_b", "shell.frame_a")
    assert len(kn.simulate(m, t_end=0.1, n_points=2).state_names) == 13


def _wgs84(y, latitude):
    """MSL's Utilities.theoreticalNormalGravityWGS84: the normal gravity at height y."""
    a, b, g_e, g_p = 6378137.0, 6356752.3142, 9.7803253359, 9.8321849378
    k, e2, f = b / a * g_p / g_e - 1, 8.1819190842622e-2**2, 1 / 298.257223563
    m = 7292115e-11**2 * a**2 * b / 3986004.418e8
    s2 = np.sin(np.radians(latitude))**2
    ha = y / a
    return g_e * (1 + k * s2) / np.sqrt(1 - e2 * s2) * (1 - ha * (2 * (1 + f + m - 2 * f * s2)
                                                                  + 3 * ha))


@pytest.mark.parametrize("latitude, msl", [(0.0, -2.39), (90.0, -2.42)])
def test_user_defined_gravity_field_matches_the_pendulum_by_hand_and_msl(latitude, msl):
    """MSL's UserDefinedGravityField: the pendulum under the WGS84 field written as the
    Ground's expression, against its equation by hand, J phi'' = -10 m g(y) cos(phi) - d phi',
    and MSL's documented rev.phi(10 s) at the equator and at the poles."""
    model = kn.load(MODELS / "user_defined_gravity_field.json")
    model.parameters["geodeticLatitude"] = latitude
    res = kn.simulate(model, t_end=10.0, n_points=21, rtol=1e-11, atol=1e-12, jit=False)
    mass, J = 1000.0, 1000.0 * 10**2 + 0.001

    def rhs(_, y):
        phi, w = y
        return [w, (-10 * mass * _wgs84(20 + 10 * np.sin(phi), latitude) * np.cos(phi)
                    - 0.1 * w) / J]
    sol = solve_ivp(rhs, (0, 10), [0.0, 0.0], method="DOP853", rtol=1e-12, atol=1e-12,
                    t_eval=res.t)
    np.testing.assert_allclose(res["angle.angle"], sol.y[0], atol=1e-7)
    np.testing.assert_allclose(res["angle.speed"], sol.y[1], atol=1e-7)
    assert abs(res["angle.angle"][-1] - msl) < 0.005


def test_a_gravity_field_names_its_place_when_wrong():
    model = kn.load(MODELS / "user_defined_gravity_field.json")
    model.components["world"].field = ["0", "-9.81*(1 - w/6e6)", "0"]
    with pytest.raises(kn.ModelError, match=r"world.field\[1\].*'w'"):
        kn.simulate(model, t_end=1.0)
    with pytest.raises(kn.ModelError, match="field"):
        model.components["world"].field = ["0", "-9.81*(", "0"]
    model.components["world"].gravity_type = "uniform"
    with pytest.raises(kn.ModelError, match="field"):
        kn.simulate(model, t_end=1.0)


def test_point_masses_joined_by_rigid_parts_turn_with_their_arrangements_inertia():
    """Two PointMasses 0.5 m either side of a revolute's axis (no gravity), 1 N m on the
    axis: J = 2 m 0.5^2 = 0.5 kg m^2, so phi = t^2."""
    m = kn.Model("dumbbell")
    m.add(mb.Ground("world", gravity=[0, 0, 0]))
    m.add(mb.Revolute("rev", axis=[0, 0, 1]))
    m.add(kn.rotational.Torque("drive", tau=1.0))
    for side, x in (("left", -0.5), ("right", 0.5)):
        m.add(mb.FixedTranslation(f"arm_{side}", r=[x, 0, 0]))
        m.add(mb.PointMass(side, m=1.0))
        m.connect("rev.frame_b", f"arm_{side}.frame_a")
        m.connect(f"arm_{side}.frame_b", f"{side}.frame_a")
    m.connect("world.frame", "rev.frame_a")
    m.connect("drive.flange", "rev.axis")
    res = kn.simulate(m, t_end=1.0, n_points=5, rtol=1e-11, atol=1e-12, jit=False)
    np.testing.assert_allclose(res["rev.q"], res.t**2, atol=1e-10)
