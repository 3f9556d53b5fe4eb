"""kn.linearize and kn.equilibrium close a model's loops wherever its independent coordinates
put it, on the branch the model starts on (issue 25 item 6): the four-bar of
``models/fourbar.json`` against the sympy Lagrangian of ``scenes/reference_loops.py`` (its
right-hand side differentiated by central differences), its equilibrium against a root of
that right-hand side; a crank angle where a non-Grashof linkage does not assemble is refused
naming the loop and the residual left."""

import pathlib

import numpy as np
import pytest
from scipy.optimize import brentq

import kinetwork as kn
import scenes.loops
from scenes import reference_loops as ref

MODELS = pathlib.Path(__file__).resolve().parents[2] / "models"


def reference_A(theta, h=1e-6, **params):
    """A of the reduced reference at rest: d(theta'')/d(theta), d(theta'')/d(theta')."""
    def acc(q, qd):
        return ref.fourbar_rhs(0.0, [q, qd], **params)[1]
    return np.array([[0.0, 1.0],
                     [(acc(theta + h, 0.0) - acc(theta - h, 0.0)) / (2 * h),
                      (acc(theta, h) - acc(theta, -h)) / (2 * h)]])


@pytest.mark.parametrize("theta", [1.2, 2.0, 4.5, -2.0, 7.5])
def test_the_fourbar_linearises_at_any_crank_angle(theta):
    model = kn.load(MODELS / "fourbar.json")
    lin = kn.linearize(model, at={"A.q": theta, "A.qd": 0.0},
                       outputs=["rocker_probe.angle"])
    np.testing.assert_allclose(lin.A, reference_A(theta), rtol=1e-7, atol=1e-7)
    # on the start's branch (the open assembly): the rocker where the closed form puts it
    _, psi = ref.fourbar_closure(theta)
    assert np.cos(lin.y[0] - psi) == pytest.approx(1.0, abs=1e-12)


def test_the_fourbar_equilibrium_from_far_off_its_start():
    model = kn.load(MODELS / "fourbar.json")
    eq = kn.equilibrium(model, at={"A.q": 1.5, "A.qd": 0.0})
    theta = brentq(lambda q: ref.fourbar_rhs(0.0, [q, 0.0])[1], 1.3, 1.6, xtol=1e-14)
    phi, psi = ref.fourbar_closure(theta)
    assert eq.state["A.q"] == pytest.approx(theta, abs=1e-9)
    assert eq.state["B.q"] == pytest.approx(phi - theta, abs=1e-9)
    assert eq.state["D.q"] == pytest.approx(psi, abs=1e-9)


def test_a_full_state_given_keeps_its_own_branch():
    """With the dependent coordinates given too (the mirror assembly), the caller's branch
    is kept: the rocker where the mirror closed form puts it."""
    model = kn.load(MODELS / "fourbar.json")
    system = model.compile(loops="partition")
    theta = 1.2
    phi, psi = ref.fourbar_closure(theta, branch=-1)
    z = dict(zip(system.algebraic_names, system.z0))
    z.update({"B.q": phi - theta, "D.q": psi})
    z["C.q"] = (psi - phi) + 1e-7                   # a little off: Newton closes it
    X = np.concatenate([[theta, 0.0], [z[n] for n in system.algebraic_names]])
    lin = kn.linearize(model, at=X, outputs=["rocker_probe.angle"])
    assert np.cos(lin.y[0] - psi) == pytest.approx(1.0, abs=1e-12)
    np.testing.assert_allclose(lin.A, reference_A(theta, branch=-1), rtol=1e-7, atol=1e-7)


def test_where_the_linkage_does_not_assemble_is_refused_with_the_residual():
    """A non-Grashof four-bar (crank 0.6, coupler and rocker 0.5, ground 1.0) assembles only
    while |BD| <= 1, up to cos(theta) = 0.3 (1.2661 rad)."""
    model = scenes.loops.fourbar(theta0=0.3, a=0.6, b=0.5, c=0.5, d=1.0,
                                 guesses=scenes.loops.fourbar_guesses(0.3, 0.6, 0.5, 0.5, 1.0))
    kn.linearize(model, at={"A.q": 1.2, "A.qd": 0.0})            # still assembles
    for call in (kn.linearize, kn.equilibrium):
        with pytest.raises(kn.ModelError, match=r"kinematic loop through .*crank.* cannot "
                                                r"close at A.q = 3.14159: .* closes only up "
                                                r"to A.q = 1.266\d*; at the asked point a "
                                                r"residual of 0.9\d* .* is left"):
            call(model, at={"A.q": np.pi, "A.qd": 0.0})
