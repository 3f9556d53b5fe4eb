"""The seed's double pendulum, built through the API, against independent oracles.

The seed paper (``/work/shared/seed/000_3928cab48146f736.txt``) derives, by recursive
Newton-Euler in Maple, the equations of a double pendulum with a rotational spring-damper at
the shoulder, in the form ``M(q) qdd + V(q, qd) + G(q) = 0``. Its printed M and G are right;
its V has two typos (DESIGN.md), corrected here: the first row ends in ``d*T1d``, the second
row has ``T1d^2``.

Geometry and sign convention: both angles are measured counter-clockwise about +z, the
shoulder from the hanging-down position and the elbow relative to the first link; each link
is a massless rod of length ``L`` with a point mass ``m`` at ``L/2``; gravity is ``-g`` along
y. With q = 0 the pendulum hangs straight down, and the potential energy
``-g (m1 L1/2 cos q1 + m2 (L1 cos q1 + L2/2 cos(q1 + q2)))`` has gradient equal to the seed's
G (e.g. ``G1 = (1/2 sin(T1+T2) L2 m2 + 1/2 L1 m1 sin T1 + L1 m2 sin T1) g``), so the seed's
equations hold as printed in this convention.

Oracles, none of which runs kinetwork code:

- the seed's closed-form M, V, G, evaluated in plain numpy;
- trajectories of those closed forms integrated by scipy's DOP853 at rtol = atol = 1e-12
  (checked here to conserve energy when undamped);
- a Lagrangian derivation in sympy, independent of the paper, with rotary inertia of the
  links added so that it also exercises ``RigidBody.inertia``.
"""

import functools

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

import kinetwork as kn
from scenes import double_pendulum
from scenes.reference import seed_mvg    # the paper's formulas, in numpy

#: the paper's numerical values (section 3.15)
PAPER = {"L1": 1.0, "L2": 1.0, "m1": 1.0, "m2": 1.0, "c": 1.0, "d": 1.0, "g": 9.8}

STATE_NAMES = ["shoulder.q", "elbow.q", "shoulder.qd", "elbow.qd"]
QUANTITIES = ["angle", "speed", "acceleration", "torque"]


# ---------------------------------------------------------------------------------------------
# The closed forms of the seed (the oracle)
# ---------------------------------------------------------------------------------------------

def seed_terms(q, qd, p):
    """The seed's M, V (corrected) and G at one state.

    Parameters
    ----------
    q, qd : array_like, shape (2,)
        Joint angles (shoulder absolute, elbow relative) and their rates.
    p : dict
        Values of L1, L2, m1, m2, c, d, g.

    Returns
    -------
    M : ndarray, shape (2, 2)
    V : ndarray, shape (2,)
        Coriolis and centripetal terms plus the shoulder spring-damper ``c*T1 + d*T1d``.
    G : ndarray, shape (2,)
    """
    return seed_mvg(q, qd, **{k: p[k] for k in PAPER})


def seed_qdd(q, qd, p):
    """Joint accelerations ``M^-1 (-(V + G))`` from the closed forms."""
    M, V, G = seed_terms(q, qd, p)
    return np.linalg.solve(M, -(V + G))


def seed_energy(x, p):
    """Kinetic + gravity + spring energy at state ``x`` (used to check the oracle itself)."""
    q, qd = x[:2], x[2:]
    M, _, _ = seed_terms(q, qd, p)
    L1, L2, m1, m2, c, g = (p[k] for k in ("L1", "L2", "m1", "m2", "c", "g"))
    height = -(m1 * L1 / 2 * np.cos(q[0])
               + m2 * (L1 * np.cos(q[0]) + L2 / 2 * np.cos(q[0] + q[1])))
    return 0.5 * qd @ M @ qd + g * height + 0.5 * c * q[0] ** 2


def reference_trajectory(p, x0, t):
    """The closed forms integrated by DOP853 at rtol = atol = 1e-12, sampled at ``t``.

    Returns
    -------
    dict
        ``"probe1.angle"`` ... ``"probe2.torque"`` as arrays shaped like ``t``, and
        ``"states"`` of shape (len(t), 4).
    """
    return _reference_cached(tuple(sorted(p.items())), tuple(x0), tuple(t))


@functools.lru_cache(maxsize=None)
def _reference_cached(p_items, x0, t):
    p, t = dict(p_items), np.asarray(t)

    def f(_, x):
        return np.concatenate([x[2:], seed_qdd(x[:2], x[2:], p)])

    sol = solve_ivp(f, (t[0], t[-1]), x0, method="DOP853", rtol=1e-12, atol=1e-12,
                    dense_output=True)
    assert sol.success, sol.message
    x = sol.sol(t).T
    qdd = np.array([seed_qdd(xi[:2], xi[2:], p) for xi in x])
    return {
        "states": x,
        "probe1.angle": x[:, 0], "probe2.angle": x[:, 1],
        "probe1.speed": x[:, 2], "probe2.speed": x[:, 3],
        "probe1.acceleration": qdd[:, 0], "probe2.acceleration": qdd[:, 1],
        "probe1.torque": -(p["c"] * x[:, 0] + p["d"] * x[:, 2]),
        "probe2.torque": np.zeros_like(t),
    }


# ---------------------------------------------------------------------------------------------
# The model, built through the API as in DESIGN's contract
# ---------------------------------------------------------------------------------------------

def build_pendulum(parameters=PAPER, q0=(0.05, 0.05), qd0=(0.0, 0.0), inertia=False):
    """The seed's double pendulum with two probes, as a ``kn.Model``.

    Parameters
    ----------
    parameters : dict
        Model parameters L1, L2, m1, m2, c, d, g (and, with ``inertia``, J1, J2).
    q0, qd0 : pair of (float or str)
        Initial angles and rates of shoulder and elbow: numbers or expressions in model
        parameters.
    inertia : bool
        Give each link a rotary inertia ``J1``, ``J2`` about its centre of mass (z axis);
        the seed's links have none.
    """
    return double_pendulum(q0=q0, qd0=qd0, inertia=("J1", "J2") if inertia else None,
                           **parameters)


@pytest.fixture(scope="module")
def system():
    """The seed's pendulum compiled once; parameters stay symbols, so it serves every value."""
    return build_pendulum().compile()


@pytest.fixture(scope="module")
def system_inertia():
    """The pendulum with rotary link inertias J1, J2 as model parameters."""
    return build_pendulum({**PAPER, "J1": 0.0, "J2": 0.0}, inertia=True).compile()


def random_parameters(rng):
    """Physical parameters spread over four decades (log-uniform), damping possibly zero."""
    def lu(lo, hi):
        return float(np.exp(rng.uniform(np.log(lo), np.log(hi))))
    return {"L1": lu(1e-2, 1e2), "L2": lu(1e-2, 1e2), "m1": lu(1e-2, 1e2),
            "m2": lu(1e-2, 1e2), "c": lu(1e-2, 1e2) * rng.integers(0, 2),
            "d": lu(1e-2, 1e2) * rng.integers(0, 2), "g": lu(0.1, 100.0)}


def random_state(rng):
    """Angles of any size (many turns), rates of either sign."""
    return rng.uniform(-30.0, 30.0, 2), rng.uniform(-10.0, 10.0, 2)


SEEDS = list(range(25))


# ---------------------------------------------------------------------------------------------
# Structure of the compiled system
# ---------------------------------------------------------------------------------------------

def test_state_names(system):
    """Minimal coordinates: tree joints in the order they were added, positions then rates."""
    assert system.state_names == STATE_NAMES


def test_x0_from_joint_initial_values():
    """``x0`` holds each Revolute's q0 and qd0 in state order."""
    sys_ = build_pendulum(q0=(1.5, -2.0), qd0=(0.25, -0.75)).compile()
    np.testing.assert_array_equal(np.asarray(sys_.x0, dtype=float), [1.5, -2.0, 0.25, -0.75])


# ---------------------------------------------------------------------------------------------
# Oracle self-checks: a wrong oracle must not pass for a wrong implementation
# ---------------------------------------------------------------------------------------------

def test_oracle_energy_conserved_without_damping():
    """The reference integration of the closed forms conserves energy when d = 0."""
    p = {**PAPER, "d": 0.0, "c": 2.0}
    t = np.linspace(0.0, 5.0, 501)
    ref = reference_trajectory(p, (1.5, -2.0, 0.0, 0.0), t)
    energy = np.array([seed_energy(x, p) for x in ref["states"]])
    assert np.ptp(energy) < 1e-8 * max(1.0, abs(energy[0]))


def test_oracle_gravity_is_potential_gradient():
    """The seed's G is the gradient of the potential energy in the stated convention."""
    rng = np.random.default_rng(7)
    p = {**random_parameters(rng), "c": 0.0}
    q, _ = random_state(rng)
    h = 1e-6
    grad = [(seed_energy(np.r_[q + h * e, 0, 0], p) - seed_energy(np.r_[q - h * e, 0, 0], p))
            / (2 * h) for e in np.eye(2)]
    _, _, G = seed_terms(q, np.zeros(2), p)
    np.testing.assert_allclose(grad, G, rtol=1e-6, atol=1e-8 * np.abs(G).max())


# ---------------------------------------------------------------------------------------------
# M, rhs and (M, V, G) against the closed forms at random parameters and states
# ---------------------------------------------------------------------------------------------

@pytest.mark.parametrize("seed", SEEDS)
def test_mass_matrix_matches_seed(system, seed):
    """``mass_matrix(q, params)`` equals the seed's M to 1e-12 relative.

    Each entry is compared in units of ``sqrt(M_ii M_jj)``, the scale its terms have, so a
    near-cancelling off-diagonal entry or a small M22 beside a large M11 is still checked.
    """
    rng = np.random.default_rng(seed)
    p = random_parameters(rng)
    q, qd = random_state(rng)
    M_ref, _, _ = seed_terms(q, qd, p)
    M = np.asarray(system.mass_matrix(q, params=p), dtype=float)
    assert M.shape == (2, 2)
    scale = np.sqrt(np.outer(np.diag(M_ref), np.diag(M_ref)))
    np.testing.assert_array_less(np.abs(M - M_ref), 1e-12 * scale,
                                 err_msg=f"params={p}, q={q}\nM=\n{M}\nexpected\n{M_ref}")


def force_scale(q, qd, p):
    """Per row, the size of the terms that make up V and G (before they cancel).

    Returns
    -------
    v_scale, g_scale : ndarray, shape (2,)
    """
    L1, L2, m1, m2 = p["L1"], p["L2"], p["m1"], p["m2"]
    inertial = L1 * L2 * m2
    v_scale = np.array([inertial * abs(qd[1]) * (abs(qd[0]) + abs(qd[1]))
                        + abs(p["c"] * q[0]) + abs(p["d"] * qd[0]),
                        inertial * qd[0] ** 2])
    g_scale = p["g"] * np.array([L1 * (m1 + m2) + L2 * m2, L2 * m2])
    return v_scale, g_scale


@pytest.mark.parametrize("seed", SEEDS)
def test_rhs_matches_seed(system, seed):
    """``rhs(t, x, params)`` is ``[qd; M^-1 (-(V + G))]`` of the closed forms.

    Over four decades of parameters M can be ill-conditioned, so qdd is judged by its
    residual in the closed-form equation, relative to the size of its terms (backward
    error), and also forward, through |M^-1|.
    """
    rng = np.random.default_rng(seed)
    p = random_parameters(rng)
    q, qd = random_state(rng)
    x = np.concatenate([q, qd])
    dx = np.asarray(system.rhs(0.0, x, params=p), dtype=float).ravel()
    assert dx.shape == (4,)
    np.testing.assert_array_equal(dx[:2], qd)
    M, V, G = seed_terms(q, qd, p)
    qdd = dx[2:]
    residual = M @ qdd + V + G
    scale = np.abs(M) @ np.abs(qdd) + sum(force_scale(q, qd, p))
    np.testing.assert_array_less(np.abs(residual), 1e-11 * scale,
                                 err_msg=f"params={p}, x={x}, qdd={qdd}")
    # the forward consequence of that backward error: |dqdd| <= |M^-1| |residual|
    qdd_ref = seed_qdd(q, qd, p)
    tol = 1e-11 * np.linalg.norm(np.linalg.inv(M), np.inf) * scale.max()
    np.testing.assert_allclose(qdd, qdd_ref, rtol=1e-11, atol=tol,
                               err_msg=f"params={p}, x={x}")


@pytest.mark.parametrize("seed", SEEDS[:10])
def test_rhs_matches_seed_moderate(system, seed):
    """At everyday parameter values qdd matches the closed form to 1e-12 relative."""
    rng = np.random.default_rng(1000 + seed)
    p = {"L1": rng.uniform(0.3, 3), "L2": rng.uniform(0.3, 3), "m1": rng.uniform(0.3, 3),
         "m2": rng.uniform(0.3, 3), "c": rng.uniform(0, 5), "d": rng.uniform(0, 5),
         "g": rng.uniform(1, 20)}
    q, qd = random_state(rng)
    x = np.concatenate([q, qd])
    dx = np.asarray(system.rhs(1.7, x, params=p), dtype=float).ravel()
    expected = np.concatenate([qd, seed_qdd(q, qd, p)])
    np.testing.assert_allclose(dx, expected, rtol=1e-12, atol=1e-12 * np.abs(expected).max(),
                               err_msg=f"params={p}, x={x}")


@pytest.mark.parametrize("seed", SEEDS[:10])
def test_dynamics_terms_match_seed(system, seed):
    """``dynamics_terms(q, qd, params)`` returns the seed's (M, V, G) separately.

    V carries the Coriolis/centripetal terms and the shoulder spring-damper ``c*q1 + d*qd1``,
    G the gravity terms, as the seed splits them.
    """
    rng = np.random.default_rng(2000 + seed)
    p = random_parameters(rng)
    q, qd = random_state(rng)
    M_ref, V_ref, G_ref = seed_terms(q, qd, p)
    M, V, G = (np.asarray(a, dtype=float) for a in system.dynamics_terms(q, qd, params=p))
    V, G = V.ravel(), G.ravel()
    assert M.shape == (2, 2) and V.shape == (2,) and G.shape == (2,)
    scale = np.sqrt(np.outer(np.diag(M_ref), np.diag(M_ref)))
    np.testing.assert_array_less(np.abs(M - M_ref), 1e-12 * scale, err_msg="M")
    v_scale, g_scale = force_scale(q, qd, p)
    np.testing.assert_array_less(np.abs(V - V_ref), 1e-11 * v_scale + 1e-300,
                                 err_msg=f"V={V}, expected {V_ref}, params={p}, q={q}, qd={qd}")
    np.testing.assert_array_less(np.abs(G - G_ref), 1e-11 * g_scale,
                                 err_msg=f"G={G}, expected {G_ref}, params={p}, q={q}")


def test_dynamics_terms_default_params(system):
    """With ``params=None`` the model's own parameter values (the paper's) are used."""
    q, qd = np.array([0.3, -1.1]), np.array([0.7, 0.2])
    for got, want, name in zip(system.dynamics_terms(q, qd), seed_terms(q, qd, PAPER),
                               "MVG"):
        np.testing.assert_allclose(np.asarray(got, dtype=float).reshape(np.shape(want)), want,
                                   rtol=1e-12, atol=1e-12, err_msg=name)


# ---------------------------------------------------------------------------------------------
# Trajectories and probes against the integrated closed forms
# ---------------------------------------------------------------------------------------------

#: (id, parameters, q0, qd0, how q0 is given: numbers on the joints or model parameters)
CASES = {
    "paper": (PAPER, (0.05, 0.05), (0.0, 0.0), "number"),
    "paper-large": (PAPER, (1.5, -2.0), (0.0, 0.0), "number"),
    "asymmetric": ({"L1": 0.7, "L2": 1.3, "m1": 2.0, "m2": 0.5, "c": 3.0, "d": 0.4,
                    "g": 9.81}, (1.5, -2.0), (0.3, -1.0), "parameter"),
    "long-tip": ({"L1": 0.5, "L2": 2.0, "m1": 4.0, "m2": 0.3, "c": 10.0, "d": 2.0,
                  "g": 9.81}, (-2.5, 3.0), (0.0, 0.0), "parameter"),
}
# Every case is damped and only mildly sensitive: the reference itself moves by < 1e-8 from
# rtol 1e-10 to 1e-13. (An undamped large swing is chaotic: 1e-12 perturbations grow to 1e-6
# within 10 s, so it could not judge a solver at 1e-6.)
METHODS = ["auto", "cvodes", "idas", "DOP853"]
TRAJECTORY_CASES = [pytest.param(case, method, id=f"{case}-{method}")
                    for case in CASES for method in METHODS]


@functools.lru_cache(maxsize=None)
def _trajectory_model(case):
    p, q0, qd0, how = CASES[case]
    if how == "number":
        return build_pendulum(p, q0=q0, qd0=qd0), dict(p)
    init = {"th1_0": q0[0], "th2_0": q0[1], "om1_0": qd0[0], "om2_0": qd0[1]}
    # the model's own initial values are wrong on purpose: simulate(params=...) must apply
    model = build_pendulum({**p, **{k: 0.0 for k in init}},
                           q0=("th1_0", "th2_0"), qd0=("om1_0", "om2_0"))
    return model, {**p, **init}


@pytest.mark.parametrize("case, method", TRAJECTORY_CASES)
def test_trajectory_matches_closed_form(case, method):
    """All four probe quantities of both joints follow the closed-form reference to 1e-6.

    The tolerance is absolute for signals of size up to 1 and relative beyond.
    """
    p, q0, qd0, _ = CASES[case]
    model, params = _trajectory_model(case)
    res = kn.simulate(model, t_end=10.0, n_points=1001, method=method, rtol=1e-10,
                      atol=1e-12, params=params)
    t = np.asarray(res.t, dtype=float)
    np.testing.assert_allclose(t, np.linspace(0.0, 10.0, 1001), rtol=0, atol=1e-12)
    ref = reference_trajectory({k: p[k] for k in PAPER}, (*q0, *qd0), t)

    states = np.asarray(res.states, dtype=float)
    assert states.shape == (1001, 4)
    assert list(res.state_names) == STATE_NAMES
    tol = 1e-6 * np.maximum(1.0, np.abs(ref["states"]).max(axis=0))
    np.testing.assert_array_less(np.abs(states - ref["states"]),
                                 np.broadcast_to(tol, states.shape), err_msg="states")

    failures = []
    for probe in ("probe1", "probe2"):
        for quantity in QUANTITIES:
            key = f"{probe}.{quantity}"
            got = np.asarray(res[key], dtype=float)
            want = ref[key]
            if got.shape != want.shape:
                failures.append(f"{key}: shape {got.shape}, expected {want.shape}")
                continue
            err = np.abs(got - want).max()
            tol = 1e-6 * max(1.0, np.abs(want).max())
            if not err <= tol:
                i = int(np.argmax(np.abs(got - want)))
                failures.append(f"{key}: max error {err:.3g} > {tol:.3g} at t={t[i]}: "
                                f"got {got[i]!r}, expected {want[i]!r}")
    assert not failures, "\n".join(failures)


# ---------------------------------------------------------------------------------------------
# A Lagrangian derivation in sympy, independent of the paper
# ---------------------------------------------------------------------------------------------

@functools.lru_cache(maxsize=None)
def lagrange_functions():
    """M(q, p) and the forcing f(q, qd, p), with ``M qdd = f``, from a hand Lagrangian.

    Links are rods with the centre of mass at L/2 and rotary inertia J about it; the
    shoulder carries a spring (potential c q1^2 / 2) and a damper (Rayleigh d qd1^2 / 2).
    """
    q1, q2, u1, u2 = sp.symbols("q1 q2 u1 u2")
    L1, L2, m1, m2, J1, J2, c, d, g = sp.symbols("L1 L2 m1 m2 J1 J2 c d g")
    q, u = sp.Matrix([q1, q2]), sp.Matrix([u1, u2])
    p1 = sp.Matrix([L1 / 2 * sp.sin(q1), -L1 / 2 * sp.cos(q1)])
    elbow = sp.Matrix([L1 * sp.sin(q1), -L1 * sp.cos(q1)])
    p2 = elbow + sp.Matrix([L2 / 2 * sp.sin(q1 + q2), -L2 / 2 * sp.cos(q1 + q2)])
    v1, v2 = p1.jacobian(q) * u, p2.jacobian(q) * u
    T = (m1 * v1.dot(v1) + m2 * v2.dot(v2) + J1 * u1**2 + J2 * (u1 + u2) ** 2) / 2
    U = g * (m1 * p1[1] + m2 * p2[1]) + c * q1**2 / 2
    D = d * u1**2 / 2
    L = T - U
    dL_du = sp.Matrix([L]).jacobian(u).T
    M = dL_du.jacobian(u)
    # d/dt dL/du = M qdd + (d dL/du / dq) u ;  EOM: d/dt dL/du - dL/dq + dD/du = 0
    f = -dL_du.jacobian(q) * u + sp.Matrix([L]).jacobian(q).T - sp.Matrix([D]).jacobian(u).T
    args = (q1, q2, u1, u2, L1, L2, m1, m2, J1, J2, c, d, g)
    return sp.lambdify(args, M, "numpy"), sp.lambdify(args, f, "numpy")


@pytest.mark.parametrize("seed", list(range(8)))
@pytest.mark.parametrize("with_inertia", [False, True], ids=["point-masses", "rods"])
def test_against_sympy_lagrangian(system_inertia, seed, with_inertia):
    """M and qdd agree with a symbolic Lagrangian derivation at random points."""
    rng = np.random.default_rng(3000 + seed)
    p = {"L1": rng.uniform(0.2, 3), "L2": rng.uniform(0.2, 3), "m1": rng.uniform(0.2, 3),
         "m2": rng.uniform(0.2, 3), "c": rng.uniform(0, 5), "d": rng.uniform(0, 5),
         "g": rng.uniform(1, 20),
         "J1": rng.uniform(0.01, 1) if with_inertia else 0.0,
         "J2": rng.uniform(0.01, 1) if with_inertia else 0.0}
    q, qd = random_state(rng)
    M_fun, f_fun = lagrange_functions()
    args = (*q, *qd, *(p[k] for k in ("L1", "L2", "m1", "m2", "J1", "J2", "c", "d", "g")))
    M_ref = np.array(M_fun(*args), dtype=float)
    qdd_ref = np.linalg.solve(M_ref, np.array(f_fun(*args), dtype=float).ravel())

    M = np.asarray(system_inertia.mass_matrix(q, params=p), dtype=float)
    np.testing.assert_allclose(M, M_ref, rtol=1e-12, atol=1e-12 * np.abs(M_ref).max())
    dx = np.asarray(system_inertia.rhs(0.0, np.concatenate([q, qd]), params=p),
                    dtype=float).ravel()
    np.testing.assert_allclose(dx[:2], qd, rtol=0, atol=0)
    np.testing.assert_allclose(dx[2:], qdd_ref, rtol=1e-10,
                               atol=1e-10 * np.abs(qdd_ref).max())
