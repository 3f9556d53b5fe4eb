"""How state events are located (``solver/events.py``): on the run's own points over a
sampled interval and the Hermite curve through them, then checked on the integration; and a
relation the equations compute twice is one event (``equations/relations.py``). Against the
event-to-event DOP853 reference of ``scenes/bumps.py`` and closed forms."""

import numpy as np
import pytest

import kinetwork as kn
from kinetwork.solver import curves
from kinetwork.solver import events as events_module
from kinetwork.solver import methods
from scenes.bumps import ball, ball_reference


@pytest.fixture(scope="module")
def reference():
    return ball_reference(np.linspace(0.0, 3.0, 301))


def test_each_contact_is_located_on_the_runs_points_and_a_check(reference, monkeypatch):
    """No event of the ball's if_else contact costs an integration per trial time. Each
    fall onto the contact is a parabola, which the cubic through the sampled points and
    their rates is: located on it with no integration at all. Each rise off it (the
    contact's spring, stiff) is located on the run's own points in its sampled interval (no
    integration over it) and costs two or three integrations from the point before the time
    found (Newton's steps from the curve's root to the integration's). The contact times
    agree with the reference's root finder to 1e-9 s."""
    calls = {"grid": 0, "state_at": 0}
    for name in calls:
        original = getattr(methods._CasadiRun, name)

        def counted(self, *args, _original=original, _name=name):
            calls[_name] += 1
            return _original(self, *args)
        monkeypatch.setattr(methods._CasadiRun, name, counted)
    exact = []
    monkeypatch.setattr(events_module.Events, "_locate_exact",
                        lambda self, *args: exact.append(args) or None)
    _, contacts = reference
    res = kn.simulate(ball(), t_end=3.0, n_points=301, method="cvodes-adams", rtol=1e-10,
                      atol=1e-12)
    times = [e["t"] for e in res.stats["events"]]
    assert len(times) == len(contacts) == 8 and not exact
    np.testing.assert_allclose(times, contacts, atol=1e-9)
    assert calls["grid"] == 0 and calls["state_at"] <= 3 * 4


def test_a_chunk_with_too_many_points_locates_on_an_integration_of_its_interval(
        reference, monkeypatch):
    """Over 3 output points the ball's chunks sample 500 points an interval (the events'
    lattice): 32 points in each from the chunk's own integration would be 16000, more than
    DENSE_MOST (its integrator, kept, would hold 170 kB). Each rise is then located on one
    integration of its sampled interval, at the reference's contact times as well."""
    grids = []
    original = methods._CasadiRun.grid

    def counted(self, *args):
        grids.append(args)
        return original(self, *args)
    monkeypatch.setattr(methods._CasadiRun, "grid", counted)
    _, contacts = reference
    res = kn.simulate(ball(), t_end=3.0, n_points=3, method="cvodes-adams", rtol=1e-10,
                      atol=1e-12)
    times = [e["t"] for e in res.stats["events"]]
    assert len(times) == len(contacts) == 8
    np.testing.assert_allclose(times, contacts, atol=1e-9)
    assert 1 <= len(grids) <= 8


def test_the_statistics_count_the_integrations_that_locate_events(monkeypatch):
    """``rhs_evaluations`` holds the evaluations of the integrations over the chunks and of
    those from the point before a contact time found (the ball's rises)."""
    spent = {"call": 0, "state_at": 0}
    for name in spent:
        original = getattr(methods._CasadiRun, name)

        def tallied(self, *args, _original=original, _name=name):
            before = self.stats["rhs_evaluations"]
            try:
                return _original(self, *args)
            finally:
                spent[_name] += self.stats["rhs_evaluations"] - before
        monkeypatch.setattr(methods._CasadiRun, name, tallied)
    res = kn.simulate(ball(), t_end=3.0, n_points=301, method="cvodes-adams", rtol=1e-10,
                      atol=1e-12)
    assert spent["state_at"] > 0
    assert res.stats["rhs_evaluations"] == spent["call"] + spent["state_at"]


def test_the_curve_through_two_rows_is_not_tried_again_where_it_did_not_fit(monkeypatch):
    """The ball's falls are parabolas: the curve through the two sampled rows fits each.
    Its rises off the contact's spring do not: that curve is tried on the first rise only
    (each try costs five evaluations of the equations), the later ones go straight to the
    run's own points over the interval (before: tried on each of the four rises), whose
    curve is checked on the one step the contact time is read off."""
    tried, dense = [], []
    fits, dense_fits = curves.Hermite.fits, curves.Steps.fits

    def counted(self, rates, tol, step=None):
        ok = fits(self, rates, tol, step)
        if not dense or dense[-1] is not None:
            tried.append(ok)                # a curve through two sampled rows
        return ok

    def counted_dense(self, rates, tol, step):
        dense.append(None)                  # its step's own check is not a two-row curve's
        ok = dense_fits(self, rates, tol, step)
        dense[-1] = len(self.T)
        return ok
    monkeypatch.setattr(curves.Hermite, "fits", counted)
    monkeypatch.setattr(curves.Steps, "fits", counted_dense)
    res = kn.simulate(ball(), t_end=3.0, n_points=301, method="cvodes-adams", rtol=1e-10,
                      atol=1e-12)
    assert len(res.stats["events"]) == 8
    assert tried.count(True) == 4 and tried.count(False) == 1
    assert dense == [33] * 4


def test_dense_and_exact_location_agree_on_a_stop_of_friction(monkeypatch):
    """A block at 3 m/s against Coulomb friction 4 N, 2 kg: stuck from t = 1.5 s at 2.25 m,
    located on the curve as on every trial integrated (the closed form to 1e-10)."""
    model = kn.Model("block")
    block = model.add(kn.translational.Mass("block", m=2.0, v0=3.0))
    floor = model.add(kn.translational.Friction("floor", f_c=4.0))
    model.connect(block.flange_a, floor.flange)
    dense = kn.simulate(model, t_end=2.0, n_points=21, method="cvodes", rtol=1e-10,
                        atol=1e-12)
    monkeypatch.setattr(events_module.Events, "_locate",
                        lambda self, *args: self._locate_exact(*args[:6]))
    exact = kn.simulate(model, t_end=2.0, n_points=21, method="cvodes", rtol=1e-10,
                        atol=1e-12)
    for res in (dense, exact):
        (event,) = res.stats["events"]
        assert event["kind"] == "stuck" and abs(event["t"] - 1.5) < 1e-10
        assert abs(res["block.s"][-1] - 2.25) < 1e-10


def test_a_relation_computed_twice_is_one_event(reference):
    """The contact law read by two forces of half the stiffness each (one expression each,
    the same relation in both): one relation on the states, the same contacts."""
    half = "if_else(s < 0, (-k*s - d*v)/2, 0)"
    m = ball(half)
    m.add(kn.translational.Force("contact2"))
    m.add(kn.signals.Expression("law2", expression=half, names=["s", "v"]))
    for a, b in [("contact2.flange", "ball.flange_a"), ("height.y", "law2.u1"),
                 ("speed.y", "law2.u2"), ("law2.y", "contact2.u")]:
        m.connect(a, b)
    system = m.compile()
    assert len(system.relations.state) == 1
    _, contacts = reference
    res = kn.simulate(system, t_end=3.0, n_points=301, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose([e["t"] for e in res.stats["events"]], contacts, atol=1e-9)
