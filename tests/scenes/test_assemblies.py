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
