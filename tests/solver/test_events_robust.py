"""Events that must not depend on the output grid, nor chatter (issue 16, hardening): a
friction that sticks for less than the sampled interval is seen on any grid, against the
closed form; a friction kept at the edge of its static limit decides its modes once."""

import pytest

import kinetwork as kn


def pushed_block(v0):
    """A 1 kg block at v0 on a rough floor (Coulomb 1 N, static = kinetic), pushed forward by
    2 t N. Sliding, v = v0 + t^2 - t = (t - 1/2)^2 - (1/4 - v0): it comes to rest at
    t_s = 1/2 - sqrt(1/4 - v0), where holding it takes 2 t_s < 1 N, so it sticks; the push
    reaches the limit at t = 1/2 and it slides on forward, v = (t - 1/2)^2."""
    model = kn.Model("pushed_block")
    block = model.add(kn.translational.Mass("block", m=1.0, v0=v0))
    push = model.add(kn.translational.Force("push", f="2*t"))
    floor = model.add(kn.translational.Friction("floor", f_c=1.0))
    model.connect(push.flange, block.flange_a)
    model.connect(block.flange_a, floor.flange)
    return model


@pytest.mark.parametrize("stick", [1e-2, 2e-4])
@pytest.mark.parametrize("n_points", [2, 201])
def test_a_short_stick_is_seen_on_any_output_grid(stick, n_points):
    # between the two samples of a sparse grid the sliding speed dips below zero and back:
    # without the stick its speed is positive at every sampled point (a 0.2 ms stick is
    # shorter than the sampling lattice too: found as a minimum of the indicator)
    half = stick / 2
    v0 = 0.25 - half ** 2
    res = kn.simulate(pushed_block(v0), t_end=1.9, n_points=n_points, method="cvodes",
                      rtol=1e-10, atol=1e-12, jit=False)
    events = [(e["kind"], e["t"]) for e in res.stats["events"]]
    assert [k for k, _ in events] == ["stuck", "sliding forward"]
    assert abs(events[0][1] - (0.5 - half)) < 1e-8 and abs(events[1][1] - 0.5) < 1e-8
    assert abs(res["block.v"][-1] - 1.4 ** 2) < 1e-7


def block_under(push, v0=0.0):
    """A 1 kg block at v0 on a rough floor (Coulomb 1 N, static = kinetic) under ``push``."""
    model = kn.Model("edge")
    block = model.add(kn.translational.Mass("block", m=1.0, v0=v0))
    force = model.add(kn.translational.Force("push", f=push))
    floor = model.add(kn.translational.Friction("floor", f_c=1.0))
    model.connect(force.flange, block.flange_a)
    model.connect(block.flange_a, floor.flange)
    return model


@pytest.mark.parametrize("n_points", [3, 101])
def test_a_push_that_levels_off_at_the_static_limit_holds_until_it_exceeds_it(n_points):
    # the push ramps to exactly the static limit at t = 1, stays there, and exceeds it from
    # t = 2 on: stuck to t = 2 (MSL: stuck while |f| <= f_static), then a = t - 2, so
    # v = (t - 2)^2 / 2 and s = (t - 2)^3 / 6; the old rule chattered at t = 1 (a slide
    # with zero acceleration stopping at once, 200 events without time passing)
    res = kn.simulate(block_under("min(t, 1) + max(t - 2, 0)"), t_end=3.0, n_points=n_points,
                      method="cvodes", rtol=1e-10, atol=1e-12, jit=False)
    (event,) = res.stats["events"]
    assert event["kind"] == "sliding forward" and abs(event["t"] - 2.0) < 1e-8
    assert abs(res["block.v"][-1] - 0.5) < 1e-7 and abs(res["block.s"][-1] - 1 / 6) < 1e-7


def test_a_slide_that_stops_where_holding_takes_exactly_the_limit_sticks():
    # sliding backward at 0.5 m/s under a constant 1 N forward push: a = 2 until it stops at
    # t = 0.25, s = -1/16, where holding it takes exactly the static limit: it sticks and stays
    res = kn.simulate(block_under("1", v0=-0.5), t_end=1.0, n_points=11, method="cvodes",
                      rtol=1e-10, atol=1e-12, jit=False)
    (event,) = res.stats["events"]
    assert event["kind"] == "stuck" and abs(event["t"] - 0.25) < 1e-8
    assert abs(res["block.s"][-1] + 1 / 16) < 1e-8 and res["block.v"][-1] == 0.0


@pytest.mark.parametrize("method", ["cvodes", "rk45"])
def test_a_slide_that_touches_zero_speed_at_the_limit_goes_on(method):
    # v0 = 1/4: v = (t - 1/2)^2 touches zero at t = 1/2, where holding would take exactly the
    # limit and the push then exceeds it: whether a method sees the touch (stuck, then
    # sliding forward, both at 1/2) or not, the motion is the closed form's, s = ((t - 1/2)^3
    # + 1/8) / 3, and no slide restarts at rest again and again
    res = kn.simulate(pushed_block(0.25), t_end=1.9, n_points=3, method=method, rtol=1e-10,
                      atol=1e-12, jit=False)
    events = res.stats["events"]
    assert [e["kind"] for e in events] in ([], ["stuck", "sliding forward"])
    assert all(abs(e["t"] - 0.5) < 1e-7 for e in events)
    assert abs(res["block.v"][-1] - 1.4 ** 2) < 1e-9
    assert abs(res["block.s"][-1] - (1.4 ** 3 + 0.125) / 3) < 1e-9
