"""Events in the driver (``solver/events.py``): located to the integrator's tolerance by
every method that takes them, against closed forms."""

import matplotlib
import numpy as np
import pytest

import kinetwork as kn
from kinetwork.solver.methods import METHODS

matplotlib.use("Agg")

G, H = 9.81, 1.0


def ball(e, v_rest=1e-4):
    """A ball dropped from H onto a floor (a translational Stop at s = 0) with restitution e."""
    model = kn.Model("ball")
    body = model.add(kn.translational.Mass("ball", m=0.5, s0=H))
    weight = model.add(kn.translational.Force("weight", f=-0.5 * G))
    floor = model.add(kn.translational.Fixed("floor"))
    stop = model.add(kn.translational.Stop("floor_stop", s_min=0.0, e=e, v_rest=v_rest))
    model.connect(weight.flange, body.flange_a)
    model.connect(stop.flange_b, body.flange_a)
    model.connect(stop.flange_a, floor.flange)
    return model


def bounce_times(e, n):
    """Closed form: the first impact at sqrt(2H/g), then flights of 2 e^k v1 / g."""
    v, times = np.sqrt(2 * G * H), [np.sqrt(2 * H / G)]
    for _ in range(n - 1):
        v *= e
        times.append(times[-1] + 2 * v / G)
    return np.array(times), v


@pytest.mark.parametrize("method", ["rk45", "cvodes", "rk"])
def test_a_ball_bounces_twenty_times_at_the_closed_form_times(method):
    e = 0.9
    times, _ = bounce_times(e, 21)
    res = kn.simulate(ball(e), t_end=float(times[19] + 0.05), n_points=151, method=method,
                      rtol=1e-12, atol=1e-14, step=1e-2, jit=False)
    events = res.stats["events"]
    assert [(ev["component"], ev["kind"]) for ev in events] == [("floor_stop", "impact")] * 20
    assert np.max(np.abs([ev["t"] for ev in events] - times[:20])) < 1e-9
    # between impacts the height is the closed-form parabola of each flight
    k = np.searchsorted(times, res.t)           # flights before each output time
    v_up = np.sqrt(2 * G * H) * e ** k
    start = np.where(k > 0, times[np.maximum(k - 1, 0)], 0.0)
    tau = res.t - start
    exact = np.where(k == 0, H - G * res.t ** 2 / 2, v_up * tau - G * tau ** 2 / 2)
    assert np.max(np.abs(res["ball.s"] - exact)) < 1e-8


@pytest.mark.parametrize("method", [m for m in METHODS if m != "midpoint"])
def test_every_method_locates_a_stop_of_friction(method):
    # a block at 3 m/s against Coulomb friction 4 N, 2 kg: stuck from t = 1.5 s, at 2.25 m
    model = kn.Model("block")
    block = model.add(kn.translational.Mass("block", m=2.0, v0=3.0))
    floor = model.add(kn.translational.Friction("floor", f_c=4.0))
    model.connect(block.flange_a, floor.flange)
    res = kn.simulate(model, t_end=2.0, n_points=21, method=method, rtol=1e-10, atol=1e-12,
                      step=1e-2, jit=False)
    (event,) = res.stats["events"]
    assert event["component"] == "floor" and event["kind"] == "stuck"
    assert abs(event["t"] - 1.5) < 1e-8
    assert abs(res["block.s"][-1] - 2.25) < 1e-8 and res["block.v"][-1] == 0.0


def test_a_ball_without_a_rest_speed_comes_to_rest_where_its_bounces_accumulate():
    # e = 0.2: the flights sum to t_inf = sqrt(2H/g) + 2 v1 e / (g (1 - e)); the bounces
    # beyond the tolerance end resting, not falling through the floor
    e = 0.2
    v1 = np.sqrt(2 * G * H)
    t_inf = np.sqrt(2 * H / G) + 2 * v1 * e / (G * (1 - e))
    res = kn.simulate(ball(e, v_rest=0.0), t_end=1.0, n_points=11, method="rk45",
                      rtol=1e-10, atol=1e-12, jit=False)
    last = res.stats["events"][-1]
    assert last["kind"] == "resting" and abs(last["t"] - t_inf) < 1e-9
    assert np.all(np.abs(res["ball.s"][res.t > t_inf]) < 1e-12)
    assert np.all(res["ball.v"][res.t > t_inf] == 0.0)
    assert np.all(res["floor_stop.mode"][res.t > t_inf] == 1.0)


def test_events_are_marked_in_plots():
    res = kn.simulate(ball(0.5), t_end=1.5, n_points=31, method="rk45", jit=False)
    fig = res.plot("ball.s", "ball.v")
    marks = [line for ax in fig.axes for line in ax.lines
             if (line.get_gid() or "").startswith("event:floor_stop")]
    assert len(marks) == 2 * len(res.stats["events"]) > 0
    assert sorted({line.get_xdata()[0] for line in marks}) == \
        sorted({ev["t"] for ev in res.stats["events"]})


def test_a_run_again_builds_no_integrator_for_its_event_chunks(monkeypatch):
    """After each event a chunk starts off the output grid, with an integrator of its own
    grid; the same run again has the same chunks, and finds every one of them kept (a run of
    over a hundred events: more than the 64 once kept, which were all built again)."""
    from unittest import mock
    from kinetwork.solver import compiled as compiled_module, methods
    system = ball(0.9).compile()
    kw = {"t_end": 9.0, "n_points": 91, "method": "cvodes", "rtol": 1e-8, "atol": 1e-10}
    first = kn.simulate(system, **kw)
    assert len(first.stats["events"]) > 64

    def again():
        with mock.patch.object(methods.ca, "integrator", wraps=methods.ca.integrator) as build:
            res = kn.simulate(system, **kw)
        return res, build.call_count
    res, built = again()
    assert built == 0
    np.testing.assert_array_equal([e["t"] for e in res.stats["events"]],
                                  [e["t"] for e in first.stats["events"]])
    times, _ = bounce_times(0.9, 20)
    assert np.max(np.abs([e["t"] for e in res.stats["events"][:20]] - times)) < 1e-6
    monkeypatch.setattr(compiled_module, "INTEGRATORS_MOST", 64)    # as before: rebuilt
    compiled_module.compiled(system)._integrators.clear()
    again()
    assert again()[1] > 64
