"""kn.sensitivity (the integrators' forward sensitivities) against central differences of
tightly integrated runs."""

import numpy as np
import pytest

import kinetwork as kn
from scenes import double_pendulum, fourbar

OUTPUTS = ["probe1.angle", "probe2.speed", "probe1.torque", "elbow.qd"]


def runs(model, outputs, t_end, n, **params):
    res = kn.simulate(model, t_end=t_end, n_points=n, rtol=1e-12, atol=1e-12, params=params,
                      jit=False)
    return np.column_stack([res[k] for k in outputs])


def central(model, outputs, name, h, t_end, n):
    base = model.parameters[name]
    return (runs(model, outputs, t_end, n, **{name: base + h}) -
            runs(model, outputs, t_end, n, **{name: base - h})) / (2 * h)


def test_seed_sensitivities_match_central_differences():
    # th0, the shoulder's initial angle, checks the start's dependence on the parameters
    model = double_pendulum(q0=("th0", 0.05), th0=0.05)
    params = ["c", "d", "m2", "th0"]
    sens = kn.sensitivity(model, params, t_end=2.0, n_points=21, outputs=OUTPUTS,
                          rtol=1e-12, atol=1e-12)
    assert sens.S.shape == (21, 4, 4) and sens.param_names == params
    np.testing.assert_allclose(sens.values, runs(model, OUTPUTS, 2.0, 21), atol=1e-9)
    for name in params:
        fd = central(model, OUTPUTS, name, 1e-4, 2.0, 21)
        ours = sens.S[:, :, params.index(name)]
        scale = np.max(np.abs(fd), axis=0)
        assert np.all(np.max(np.abs(ours - fd), axis=0) <= 1e-6 * scale), name
    assert sens["probe1.angle", "th0"][0] == pytest.approx(1.0)
    assert sens["probe1.torque", "c"][0] == pytest.approx(-0.05)      # -(c q + d qd)


def test_fourbar_sensitivities_follow_the_closure():
    """In a loop the dependent coordinates move with the parameters through the closure;
    the crank length a changes where the mechanism starts."""
    model = fourbar()
    outputs = ["rocker_probe.angle", "crank_probe.angle"]
    sens = kn.sensitivity(model, ["g", "a"], t_end=0.5, n_points=6, outputs=outputs,
                          rtol=1e-11, atol=1e-12)
    for k, name in enumerate(["g", "a"]):
        # Richardson's extrapolation of two steps: an error of O(h^4), where steps small
        # enough for plain central differences drown in the loop solver's noise
        fd = (4 * central(model, outputs, name, 1e-3, 0.5, 6) -
              central(model, outputs, name, 2e-3, 0.5, 6)) / 3
        scale = np.max(np.abs(fd), axis=0)
        assert np.all(np.max(np.abs(sens.S[:, :, k] - fd), axis=0) <= 1e-6 * scale), name


def test_a_loop_starts_where_the_values_asked_put_it():
    """The four-bar's crank starting at a parameter th0: the trajectory differentiated is
    the one at the values given, its loop closed there."""
    model = fourbar()
    model.set_parameter("th0", 1.0)
    model.components["A"].q0 = "th0"
    outputs = ["rocker_probe.angle"]
    sens = kn.sensitivity(model, ["g"], t_end=0.3, n_points=4, outputs=outputs,
                          values={"th0": 1.2}, rtol=1e-11, atol=1e-12)
    np.testing.assert_allclose(sens.values, runs(model, outputs, 0.3, 4, th0=1.2), atol=1e-8)


def test_unknown_parameters_are_refused():
    with pytest.raises(kn.ModelError, match="'cc' is no model parameter.*'c'"):
        kn.sensitivity(double_pendulum(), ["cc"], t_end=1.0)


@pytest.mark.parametrize("rtol", [1e-6, 1e-8])
def test_sensitivities_are_as_accurate_as_rtol_says(rtol):
    """At large angles, the shoulder's and elbow's sensitivity to c at the tolerance asked
    (the plan's mapping of rtol, not the solver's tolerance as asked) against Richardson's
    extrapolation of central differences of the paper's closed form (scipy DOP853 at
    1e-13): within rtol times their size."""
    from scenes.reference import seed_reference
    t = np.linspace(0.0, 2.0, 21)

    def ref(c):
        return seed_reference(t, x0=(1.0, 0.5, 0.0, 0.0), c=c, rtol=1e-13, atol=1e-15)[:, :2]

    def cd(h):
        return (ref(1 + h) - ref(1 - h)) / (2 * h)
    exact = (4 * cd(1e-3) - cd(2e-3)) / 3
    sens = kn.sensitivity(double_pendulum(q0=(1.0, 0.5)), ["c"], t=t, rtol=rtol,
                          atol=rtol / 100, outputs=["shoulder.q", "elbow.q"])
    assert np.abs(sens.S[:, :, 0] - exact).max() <= rtol * np.abs(exact).max()
