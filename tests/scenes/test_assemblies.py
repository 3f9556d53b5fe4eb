"""MSL's Joints.Assemblies, which close a loop in closed form, against references written
apart from kinetwork: Lagrangians in two coordinates with a multiplier for the loop's length
constraint (``scenes.multiplier``, sympy and DOP853)."""

import math
import pathlib

import numpy as np
import pytest
import sympy as sp

import kinetwork as kn
from scenes import assemblies
from scenes.multiplier import Mechanism, rot

mb = kn.multibody

MODELS = pathlib.Path(__file__).resolve().parents[2] / "models"


def _cylinder(r, diameter=0.05, density=7700.0):
    """MSL's BodyCylinder along ``r`` (no inner bore): mass, centre, inertia about the centre
    in the frame the vector is given in."""
    r = np.asarray(r, dtype=float)
    length, radius = np.linalg.norm(r), diameter / 2
    mass = density * math.pi * radius**2 * length
    e = r / length
    axial, across = mass * radius**2 / 2, mass * (3 * radius**2 + length**2) / 12
    inertia = across * (np.eye(3) - np.outer(e, e)) + axial * np.outer(e, e)
    return mass, r / 2, inertia


def test_fourbar_analytic_follows_the_multiplier_lagrangian():
    """MSL's Fourbar_analytic: j1's angle and speed and the prismatic's distance, over MSL's
    5 s, against the crank and slider with the rod's length as a constraint."""
    res = kn.simulate(kn.load(MODELS / "fourbar_analytic.json"), t_end=5.0, n_points=26,
                      rtol=1e-11, atol=1e-12, jit=False)
    assert res.state_names == ["j1.q", "j1.qd"]
    phi, s = sp.symbols("phi s")
    R1 = rot((1, 0, 0), phi)
    m1, c1, I1 = _cylinder([0, 0.5, 0.1])
    m2, c2, I2 = _cylinder([0, 0.2, 0])
    frame_ib = sp.Matrix([1.2 + s, 0, 0])
    A = R1 * sp.Matrix([0, 0.5, 0.1])
    S = frame_ib + sp.Matrix([0, 0.2, 0])
    length2 = 1 + 0.3**2 + 0.1**2
    mech = Mechanism([phi, s], [(m1, I1.tolist(), R1, R1 * sp.Matrix(c1)),
                                (m2, I2.tolist(), sp.eye(3), frame_ib + sp.Matrix(c2))],
                     [(S - A).dot(S - A) - length2])
    q0, qd0 = mech.start([0.0, -0.1], [1], [5.235987755983, 0.0], [1])
    assert abs(q0[1] + 0.2) < 1e-9                 # MSL's s_guess = 0 picks -0.2, not -2.2
    Q, Qd = mech.solve(q0, qd0, res.t)
    assert mech.drift(Q) < 1e-9
    np.testing.assert_allclose(res["j1_probe.angle"], Q[:, 0], atol=1e-7)
    np.testing.assert_allclose(res["j1_probe.speed"], Qd[:, 0], atol=1e-6)
    np.testing.assert_allclose(res["j2_probe.position"] - 0.2, Q[:, 1], atol=1e-8)
    np.testing.assert_allclose(res["j2_probe.velocity"], Qd[:, 1], atol=1e-7)
    np.testing.assert_allclose(res["b2_tip.position"][:, 0], 1.2 + Q[:, 1], atol=1e-8)
    assert np.ptp(Q[:, 0]) > 10 and np.ptp(Q[:, 1]) > 0.2        # it turns round and slides


def _slider_crank():
    """A crank (about z, 0.1 m) and MSL's JointRRP from its tip to a rail along x: the
    coupler (0.3 m) on frame_ia, the piston on frame_ib, a damper on the slider's axis."""
    m = kn.Model("rrp")
    m.add(mb.Ground("world"))
    m.add(mb.Revolute("crank", axis=[0, 0, 1], q0=0.3, qd0=2.0))
    m.add(mb.RigidBody("crank_body", mass=2.0, r_cm=[0.05, 0, 0], inertia=[1e-3, 2e-3, 3e-3]))
    m.add(mb.FixedTranslation("tip", r=[0.1, 0, 0]))
    m.add(mb.FixedTranslation("rail", r=[0, -0.02, 0]))
    m.add(mb.JointRRP("loop", n_a=[0, 0, 1], n_b=[1, 0, 0], rRod1_ia=[0.3, 0, 0],
                      rRod2_ib=[0, 0.02, 0], s_guess=0.4))
    m.add(mb.RigidBody("piston", mass=1.5))
    m.add(mb.RigidBody("coupler", mass=0.5, r_cm=[0.15, 0, 0], inertia=[1e-4, 4e-3, 4e-3]))
    m.add(kn.translational.Damper("damper", d=0.5))
    m.add(kn.Probe("crank_p", quantities=["angle", "speed"]))
    m.add(kn.Probe("slider", quantities=["position", "velocity"]))
    m.add(kn.Probe("pin", quantities=["position"]))
    for a, b in [("world.frame", "crank.frame_a"), ("crank.frame_b", "crank_body.frame_a"),
                 ("crank.frame_b", "tip.frame_a"), ("tip.frame_b", "loop.frame_a"),
                 ("world.frame", "rail.frame_a"), ("rail.frame_b", "loop.frame_b"),
                 ("loop.frame_ib", "piston.frame_a"), ("loop.frame_ia", "coupler.frame_a"),
                 ("damper.flange_a", "loop.bearing"), ("damper.flange_b", "loop.axis"),
                 ("crank_p.port", "crank.axis"), ("slider.port", "loop.axis"),
                 ("pin.port", "loop.frame_im")]:
        m.connect(a, b)
    return m


def test_joint_rrp_slider_crank_follows_the_multiplier_lagrangian():
    res = kn.simulate(_slider_crank(), t_end=2.0, n_points=21, rtol=1e-11, atol=1e-12,
                      jit=False)
    assert res.state_names == ["crank.q", "crank.qd"]
    th, s = sp.symbols("theta s")
    Rz = rot((0, 0, 1), th)
    A = Rz * sp.Matrix([0.1, 0, 0])
    pin = sp.Matrix([s, 0, 0])                           # frame_ib at (s, -0.02) + rRod2_ib
    e = (pin - A) / 0.3                                  # the coupler's x axis, |pin - A| = 0.3
    R_c = sp.Matrix.hstack(e, sp.Matrix([-e[1], e[0], 0]), sp.Matrix([0, 0, 1]))
    mech = Mechanism([th, s], [(2.0, np.diag([1e-3, 2e-3, 3e-3]).tolist(), Rz,
                                Rz * sp.Matrix([0.05, 0, 0])),
                               (1.5, np.zeros((3, 3)).tolist(), sp.eye(3),
                                sp.Matrix([s, -0.02, 0])),
                               (0.5, np.diag([1e-4, 4e-3, 4e-3]).tolist(), R_c, A + 0.15 * e)],
                     [(pin - A).dot(pin - A) - 0.09], forces=[0, -0.5 * sp.Symbol("qd1")])
    q0, qd0 = mech.start([0.3, 0.38], [1], [2.0, 0.0], [1])
    Q, Qd = mech.solve(q0, qd0, res.t)
    assert mech.drift(Q) < 1e-9
    np.testing.assert_allclose(res["crank_p.angle"], Q[:, 0], atol=1e-8)
    np.testing.assert_allclose(res["crank_p.speed"], Qd[:, 0], atol=1e-7)
    np.testing.assert_allclose(res["slider.position"], Q[:, 1], atol=1e-8)
    np.testing.assert_allclose(res["slider.velocity"], Qd[:, 1], atol=1e-7)
    np.testing.assert_allclose(res["pin.position"][:, 0], Q[:, 1], atol=1e-8)
    np.testing.assert_allclose(res["pin.position"][:, 1:], 0, atol=1e-10)
    assert np.ptp(Q[:, 0]) > 1.0


@pytest.mark.parametrize("assembly", ["JointSSR", "JointSSP", "JointUSR", "JointUSP"])
def test_spatial_assemblies_follow_the_multiplier_lagrangian(assembly):
    """A crank closed to a tilted base by each assembly (``scenes/assemblies.py``): bodies on
    its inner frames (or rod 1's point mass), a damper on its axis, a full turn of the crank;
    the crank, the end joint and the middle spherical joint against the reference's."""
    res = kn.simulate(assemblies.build(assembly), t_end=1.0, n_points=11, rtol=1e-11,
                      atol=1e-12, jit=False)
    assert res.state_names == ["crank.q", "crank.qd"]
    theta, end, middle, drift = assemblies.reference(assembly, res.t)
    assert drift < 1e-9
    np.testing.assert_allclose(res["crank_p.angle"], theta, atol=1e-8)
    key = "end_p.angle" if assembly.endswith("R") else "end_p.position"
    np.testing.assert_allclose(np.ravel(res[key]), end, atol=1e-8)
    np.testing.assert_allclose(res["middle.position"], middle, atol=1e-8)
    assert np.ptp(theta) > 1.0


def test_an_assembly_takes_the_root_nearer_its_guess():
    """JointSSR's two closing angles at the start, found apart (``closing_angles``): a guess
    near either one starts the end joint there (its axis reads the angle less phi_offset)."""
    roots = assemblies.closing_angles("revolute")
    assert len(roots) == 2
    offset = assemblies.OFFSET["revolute"]
    tip = assemblies.TIP * np.array([math.cos(assemblies.THETA0),
                                     math.sin(assemblies.THETA0), 0.0])
    length = np.linalg.norm(assemblies.rod1_ia("revolute"))
    for root in roots:
        res = kn.simulate(assemblies.build("JointSSR", guess=root - offset + 0.05),
                          t_end=0.01, n_points=2, jit=False)
        np.testing.assert_allclose(res["end_p.angle"][0], root - offset, atol=1e-10)
        np.testing.assert_allclose(np.linalg.norm(res["middle.position"][0] - tip), length,
                                   atol=1e-12)
    assert min(abs(r - assemblies.END0["revolute"]) for r in roots) < 1e-9
