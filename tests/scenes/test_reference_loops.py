"""Checks of ``reference_loops`` (the independent four-bar / slider-crank references of
issue 4) by independent means: distances, finite differences, energy, a linearised period."""

import numpy as np
import pytest
from scipy.integrate import cumulative_trapezoid
from scipy.optimize import brentq

from scenes import reference_loops as ref

THETAS = np.linspace(0.0, 2 * np.pi, 721, endpoint=False)
FD_STEP = 1e-6


def central(f, x, h=FD_STEP):
    return (f(x + h) - f(x - h)) / (2 * h)


def wrap(angle):
    return np.angle(np.exp(1j * angle))


def fourbar_cm(theta, **params):
    """Centres of mass of crank, coupler, rocker from the closure's joint positions."""
    p = ref.fourbar_params(**params)
    B, C = ref.fourbar_points(theta, **p)
    D = np.array([p["d"], 0.0])
    return B / 2, (B + C) / 2, (C + D) / 2


def slider_cm(theta, **params):
    A, B = ref.slider_crank_points(theta, **params)
    return A / 2, (A + B) / 2, B


# ---------------------------------------------------------------------------- (a) closure


@pytest.mark.parametrize("branch", [1, -1])
def test_fourbar_closure_lengths_and_branch(branch):
    p = ref.fourbar_params(branch=branch)
    phi, psi = ref.fourbar_closure(THETAS, **p)
    B, C = ref.fourbar_points(THETAS, **p)
    D = np.array([p["d"], 0.0])
    np.testing.assert_allclose(np.hypot(*(C - B).T), p["b"], rtol=0, atol=1e-12)
    np.testing.assert_allclose(np.hypot(*(C - D).T), p["c"], rtol=0, atol=1e-12)
    np.testing.assert_allclose(np.hypot(*B.T), p["a"], rtol=0, atol=1e-12)
    # the returned angles are the directions of B -> C and D -> C
    np.testing.assert_allclose(wrap(np.arctan2(*(C - B).T[::-1]) - phi), 0, atol=1e-12)
    np.testing.assert_allclose(wrap(np.arctan2(*(C - D).T[::-1]) - psi), 0, atol=1e-12)
    # branch +1: C on the left of B -> D (positive cross product), -1 on the right
    BD, BC = D - B, C - B
    cross = BD[:, 0] * BC[:, 1] - BD[:, 1] * BC[:, 0]
    assert np.all(np.sign(cross) == branch)


def test_fourbar_default_branch_is_elbow_up():
    _, C = ref.fourbar_points(1.0)
    assert C[1] > 0.5
    _, C = ref.fourbar_points(np.pi / 2)
    assert C[1] > 0
    _, C = ref.fourbar_points(1.0, branch=-1)
    assert C[1] < 0


def test_fourbar_cannot_assemble():
    with pytest.raises(ValueError):
        ref.fourbar_closure(0.0, a=0.3, b=0.2, c=0.2, d=1.0)


@pytest.mark.parametrize("e", [0.0, 0.07])
def test_slider_crank_closure(e):
    p = ref.slider_crank_params(e=e)
    x, beta = ref.slider_crank_closure(THETAS, **p)
    A, B = ref.slider_crank_points(THETAS, **p)
    np.testing.assert_allclose(np.hypot(*(B - A).T), p["l"], rtol=0, atol=1e-12)
    np.testing.assert_allclose(np.hypot(*A.T), p["r"], rtol=0, atol=1e-12)
    np.testing.assert_array_equal(B[:, 1], e)
    assert np.all(B[:, 0] > A[:, 0])                        # slider to the right of the pin
    np.testing.assert_allclose(A + p["l"] * np.stack([np.cos(beta), np.sin(beta)], -1), B,
                               rtol=0, atol=1e-12)
    # the closed forms in the sympy-derived functions agree with the numpy closure
    kin = ref.slider_crank_kinematics(THETAS, **p)
    np.testing.assert_allclose(kin["x"], x, rtol=0, atol=1e-12)
    np.testing.assert_allclose(kin["beta"], beta, rtol=0, atol=1e-12)


# ------------------------------------------------------------- (b) velocities and masses


@pytest.mark.parametrize("branch", [1, -1])
def test_fourbar_derivatives_against_finite_differences(branch):
    p = ref.fourbar_params(branch=branch, g=9.81)
    kin = ref.fourbar_kinematics(THETAS, **p)

    def phi(th):
        return ref.fourbar_closure(th, **p)[0]

    def psi(th):
        return ref.fourbar_closure(th, **p)[1]

    # unwrap-safe differences of the closure angles
    dphi = wrap(phi(THETAS + FD_STEP) - phi(THETAS - FD_STEP)) / (2 * FD_STEP)
    dpsi = wrap(psi(THETAS + FD_STEP) - psi(THETAS - FD_STEP)) / (2 * FD_STEP)
    np.testing.assert_allclose(kin["phi_p"], dphi, rtol=0, atol=1e-6)
    np.testing.assert_allclose(kin["psi_p"], dpsi, rtol=0, atol=1e-6)
    h = 1e-4
    np.testing.assert_allclose(
        kin["phi_pp"], central(lambda th: ref.fourbar_kinematics(th, **p)["phi_p"], THETAS, h),
        rtol=0, atol=1e-6)
    np.testing.assert_allclose(
        kin["psi_pp"], central(lambda th: ref.fourbar_kinematics(th, **p)["psi_p"], THETAS, h),
        rtol=0, atol=1e-6)

    # generalised mass from finite-difference velocities of the centres of mass
    cm_p = [central(lambda th, i=i: fourbar_cm(th, **p)[i], THETAS) for i in range(3)]
    masses, inertias = (p["m1"], p["m2"], p["m3"]), (p["J1"], p["J2"], p["J3"])
    mass = (sum(m * np.sum(v ** 2, axis=-1) for m, v in zip(masses, cm_p))
            + inertias[0] + inertias[1] * dphi ** 2 + inertias[2] * dpsi ** 2)
    np.testing.assert_allclose(kin["mass"], mass, rtol=1e-7)
    np.testing.assert_allclose(
        kin["mass_p"], central(lambda th: ref.fourbar_kinematics(th, **p)["mass"], THETAS, h),
        rtol=0, atol=1e-6)

    # gravity potential from the centres of mass, and its derivatives
    cms = fourbar_cm(THETAS, **p)
    Vg = p["g"] * sum(m * r[:, 1] for m, r in zip(masses, cms))
    np.testing.assert_allclose(kin["Vg"], Vg, rtol=1e-13, atol=1e-13)
    np.testing.assert_allclose(
        kin["Vg_p"], central(lambda th: ref.fourbar_kinematics(th, **p)["Vg"], THETAS),
        rtol=0, atol=1e-7)
    np.testing.assert_allclose(
        kin["Vg_pp"], central(lambda th: ref.fourbar_kinematics(th, **p)["Vg_p"], THETAS),
        rtol=0, atol=1e-7)


@pytest.mark.parametrize("e", [0.0, 0.07])
def test_slider_crank_derivatives_against_finite_differences(e):
    p = ref.slider_crank_params(e=e)
    kin = ref.slider_crank_kinematics(THETAS, **p)

    def closure(i):
        return lambda th: ref.slider_crank_closure(th, **p)[i]

    np.testing.assert_allclose(kin["x_p"], central(closure(0), THETAS), rtol=0, atol=1e-7)
    np.testing.assert_allclose(kin["beta_p"], central(closure(1), THETAS), rtol=0, atol=1e-7)
    h = 1e-4
    for name in ("x", "beta", "mass", "Vg"):
        derivative = central(lambda th, n=name: ref.slider_crank_kinematics(th, **p)[n], THETAS, h)
        np.testing.assert_allclose(kin[name + "_p"], derivative, rtol=0, atol=1e-6)

    cm_p = [central(lambda th, i=i: slider_cm(th, **p)[i], THETAS) for i in range(3)]
    mass = (sum(m * np.sum(v ** 2, axis=-1) for m, v in zip((p["m1"], p["m2"], p["m3"]), cm_p))
            + p["J1"] + p["J2"] * kin["beta_p"] ** 2)
    np.testing.assert_allclose(kin["mass"], mass, rtol=1e-7)


def test_rhs_matches_simulation_output():
    t = np.linspace(0, 0.5, 6)
    params = {"k": 2.0, "cdamp": 0.1, "tau": 0.3, "theta_rest": 0.4}
    sim = ref.fourbar_simulate(1.0, 0.5, t, **params)
    for i in range(t.size):
        y = [sim["theta"][i], sim["thetad"][i]]
        np.testing.assert_allclose(ref.fourbar_rhs(0.0, y, **params)[1], sim["thetadd"][i],
                                   rtol=1e-13)
    # phid consistent with the sampled phi (finite difference in time, fine grid)
    t = np.linspace(0, 0.2, 2001)
    sim = ref.fourbar_simulate(1.0, 2.0, t)
    np.testing.assert_allclose(np.gradient(sim["phi"], t)[1:-1], sim["phid"][1:-1], atol=1e-5)
    np.testing.assert_allclose(np.gradient(sim["psi"], t)[1:-1], sim["psid"][1:-1], atol=1e-5)
    sc_params = {"ks": 5.0, "x_rest": 0.65, "cdamp": 0.02}
    sim = ref.slider_crank_simulate(0.5, 3.0, t, **sc_params)
    np.testing.assert_allclose(np.gradient(sim["x"], t)[1:-1], sim["xd"][1:-1], atol=1e-5)
    for i in (0, 1000, 2000):
        y = [sim["theta"][i], sim["thetad"][i]]
        np.testing.assert_allclose(ref.slider_crank_rhs(0.0, y, **sc_params)[1],
                                   sim["thetadd"][i], rtol=1e-13)


# ------------------------------------------------------------------ (c) energy conservation


def cumulative_integral(y, t):
    """Cumulative integral on the even samples (Simpson's rule, via Richardson on trapezoids)."""
    fine = cumulative_trapezoid(y, t, initial=0)[::2]
    coarse = cumulative_trapezoid(y[::2], t[::2], initial=0)
    return (4 * fine - coarse) / 3


def relative_drift(energy):
    return np.max(np.abs(energy - energy[0])) / abs(energy[0])


T10 = np.linspace(0.0, 10.0, 1001)


def test_fourbar_energy_conserved():
    sim = ref.fourbar_simulate(1.0, 0.0, T10)
    assert relative_drift(sim["energy"]) < 1e-10
    assert np.ptp(sim["theta"]) > 1.0                       # it really swings


def test_fourbar_energy_conserved_with_spring_other_branch():
    sim = ref.fourbar_simulate(1.0, 2.0, T10[:301], branch=-1, k=3.0, theta_rest=2.0)
    assert relative_drift(sim["energy"]) < 1e-10


def test_slider_crank_energy_conserved():
    sim = ref.slider_crank_simulate(0.5, 3.0, T10)
    assert relative_drift(sim["energy"]) < 1e-10
    assert np.ptp(sim["x"]) > 0.1


def test_slider_crank_energy_conserved_with_springs_and_offset():
    sim = ref.slider_crank_simulate(0.5, 3.0, T10[:301], e=0.05, k=1.0, ks=20.0, x_rest=0.7)
    assert relative_drift(sim["energy"]) < 1e-10


# ------------------------------------------------------------------ (d) small oscillations


def test_fourbar_small_oscillation_period():
    p = ref.fourbar_params(g=9.81)
    grid = np.linspace(0, 2 * np.pi, 721)
    kin = ref.fourbar_kinematics(grid, **p)
    i = int(np.argmin(kin["Vg"]))

    def slope(th):
        return ref.fourbar_kinematics(th, **p)["Vg_p"]

    theta_star = brentq(slope, grid[i - 1], grid[i + 1], xtol=1e-15)
    at_star = ref.fourbar_kinematics(theta_star, **p)
    assert at_star["Vg_pp"] > 0
    period = 2 * np.pi * np.sqrt(at_star["mass"] / at_star["Vg_pp"])

    t = np.linspace(0, 6 * period, 6001)
    sim = ref.fourbar_simulate(theta_star + 1e-3, 0.0, t, **p)
    x = sim["theta"] - theta_star
    down = np.nonzero((x[:-1] > 0) & (x[1:] <= 0))[0]     # downward zero crossings
    crossings = t[down] + x[down] / (x[down] - x[down + 1]) * (t[down + 1] - t[down])
    measured = np.mean(np.diff(crossings))
    assert len(crossings) >= 5
    assert abs(measured / period - 1) < 1e-3


# ------------------------------------------------------------------ (e) damping


def test_damped_energy_decays_and_balances():
    t = np.linspace(0, 5, 5001)
    for simulate, theta0, thetad0 in ((ref.fourbar_simulate, 1.0, 0.0),
                                      (ref.slider_crank_simulate, 0.5, 3.0)):
        cdamp = 0.05
        sim = simulate(theta0, thetad0, t, cdamp=cdamp)
        E = sim["energy"]
        assert np.all(np.diff(E) <= 1e-12 * abs(E[0]))
        assert E[-1] < E[0] - 1e-3 * abs(E[0])
        # energy balance: E(t) - E(0) = -int cdamp thetad^2 dt
        dissipated = cumulative_integral(cdamp * sim["thetad"] ** 2, t)
        np.testing.assert_allclose((E - E[0])[::2], -dissipated, rtol=0, atol=1e-8 * abs(E[0]))


def test_drive_torque_work_balance():
    t = np.linspace(0, 2, 4001)
    tau, cdamp = 0.5, 0.02
    sim = ref.fourbar_simulate(1.0, 0.0, t, tau=tau, cdamp=cdamp, k=1.0)
    power = (tau - cdamp * sim["thetad"]) * sim["thetad"]
    E = sim["energy"]
    np.testing.assert_allclose((E - E[0])[::2], cumulative_integral(power, t), rtol=0,
                               atol=1e-8 * abs(E[0]))
