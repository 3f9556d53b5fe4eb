"""Several frictions changing mode at one instant: their modes decided together
(``solver/events.py``, ``Events._together``), against closed forms."""

import numpy as np
import pytest

import kinetwork as kn

FAST = dict(jit=False)


def stack(m1, m2, fa, fb, peak_a, peak_b, v1, v2, push):
    """Block 2 on block 1 on a rough floor (friction a between the floor and block 1, b
    between the blocks), block 1 pushed by the force ``push`` (an expression in t)."""
    model = kn.Model("stack")
    lower = model.add(kn.translational.Mass("lower", m=m1, v0=v1))
    upper = model.add(kn.translational.Mass("upper", m=m2, v0=v2))
    floor = model.add(kn.translational.Friction("floor", f_c=fa, peak=peak_a))
    between = model.add(kn.translational.Friction("between", f_c=fb, peak=peak_b))
    force = model.add(kn.translational.Force("push", f=push))
    model.connect(lower.flange_a, floor.flange)
    model.connect(upper.flange_a, between.flange)
    model.connect(between.support, lower.flange_b)
    model.connect(force.flange, lower.flange_b)
    return model


# Closed form of the stack (m1 = m2 = 1, floor 4 N, between 0.8 N, push 2 t N), written from
# Newton's law phase by phase. Until t = 1 block 1 slides forward (v1 = (t - 1)(t - 3.8)) and
# block 2 backward on it (v2 = 0.8 (t - 1)): both come to rest at t = 1 at once. Stuck
# together, the floor holds the push until it reaches its static limit 1.5 * 4 N at t = 3;
# there block 1 breaks away, and the stack's acceleration (6 - 4) / 2 would need 1 N on block 2,
# above its 0.8 N: block 2 slips backward at the same instant, v2 = 0.8 (t - 3) and
# v1 = t^2 - 9 - 4.8 (t - 3), and never catches up.
def v_exact(t):
    v1 = np.where(t < 1, (t - 1) * (t - 3.8), np.where(t < 3, 0.0, t ** 2 - 9 - 4.8 * (t - 3)))
    v2 = np.where(t < 1, 0.8 * (t - 1), np.where(t < 3, 0.0, 0.8 * (t - 3)))
    return v1, v2


@pytest.mark.parametrize("method", ["cvodes", "dop853"])
def test_two_frictions_stick_and_break_away_together_at_the_closed_form_times(method):
    model = stack(1.0, 1.0, 4.0, 0.8, 1.5, 1.0, v1=3.8, v2=-0.8, push="2*t")
    res = kn.simulate(model, t_end=4.0, n_points=81, method=method, rtol=1e-11, atol=1e-12,
                      **FAST)
    events = sorted((round(e["t"], 6), e["component"], e["kind"]) for e in res.stats["events"])
    assert events == [(1.0, "between", "stuck"), (1.0, "floor", "stuck"),
                      (3.0, "between", "sliding backward"), (3.0, "floor", "sliding forward")]
    times = np.array([e["t"] for e in res.stats["events"]])
    assert np.max(np.abs(times - np.round(times))) < 1e-8
    v1, v2 = v_exact(res.t)
    assert np.max(np.abs(res["lower.v"] - v1)) < 1e-8
    assert np.max(np.abs(res["upper.v"] - v2)) < 1e-8
    together = (res.t > 1.0) & (res.t < 3.0)
    # stuck, not creeping: the speeds at the rounding of the impulse that set them to zero
    assert np.max(np.abs(res["lower.v"][together])) < 1e-20
    assert np.max(np.abs(res["upper.v"][together])) < 1e-20


def test_frictions_at_rest_at_the_start_take_their_modes_together():
    # both at rest from the start under 2 t N: stuck together until the floor gives at t = 3
    # (as above); the start decides the two at once, no event at t = 0
    model = stack(1.0, 1.0, 4.0, 0.8, 1.5, 1.0, v1=0.0, v2=0.0, push="2*t")
    res = kn.simulate(model, t_end=3.5, n_points=36, method="rk45", rtol=1e-11, atol=1e-12,
                      **FAST)
    events = sorted((round(e["t"], 6), e["component"], e["kind"]) for e in res.stats["events"])
    assert events == [(3.0, "between", "sliding backward"), (3.0, "floor", "sliding forward")]
    v1, v2 = v_exact(np.maximum(res.t, 1.0))     # at rest from t = 0
    assert np.max(np.abs(res["lower.v"] - v1)) < 1e-8
    assert np.max(np.abs(res["upper.v"] - v2)) < 1e-8
