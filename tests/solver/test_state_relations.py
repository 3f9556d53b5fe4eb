"""State events of the relations (``solver/switches.py``): an ``if_else`` on the states is
held between its events, which are located like friction's; ``noEvent`` takes it as it is.
Against a ball on a penalty contact integrated by scipy's DOP853 from event to event
(``scenes/bumps.py``)."""

import numpy as np
import pytest

import kinetwork as kn
from kinetwork.solver.methods import METHODS
from scenes.bumps import CONTACT, ball, ball_reference

TAKES_STATE_EVENTS = sorted(m for m in METHODS if "state" in METHODS[m].events)
#: scipy's BDF and LSODA get rtol as asked (only SUNDIALS' is tightened: tolerance.py); at
#: 1e-9 their global error here is 3e-7 m and 4e-5 m/s, the contacts' times within 1e-7 s
LOOSE = {"bdf": (1e-6, 1e-4), "lsoda": (1e-6, 1e-4)}


@pytest.fixture(scope="module")
def system():
    return ball().compile()


@pytest.fixture(scope="module")
def reference():
    return ball_reference(np.linspace(0.0, 3.0, 301))


@pytest.mark.parametrize("method", TAKES_STATE_EVENTS)
def test_a_ball_bouncing_on_an_if_else_contact_matches_the_event_located_reference(
        system, reference, method):
    states, contacts = reference
    step = 1e-3 if METHODS[method].fixed else None
    res = kn.simulate(system, t_end=3.0, n_points=301, method=method, rtol=1e-9,
                      atol=1e-11, step=step)
    times = [e["t"] for e in res.stats["events"]]
    kinds = [e["kind"] for e in res.stats["events"]]
    assert kinds == ["relation true", "relation false"] * 4
    np.testing.assert_allclose(times, contacts, atol=1e-7)
    height, speed = LOOSE.get(method, (1e-7, 1e-5))
    np.testing.assert_allclose(res["ball.s"], states[:, 0], atol=height)
    np.testing.assert_allclose(res["ball.v"], states[:, 1], atol=speed)


@pytest.mark.parametrize("method", ["auto", "cvodes", "idas", "rk45", "dop853", "radau"])
def test_with_the_defaults_the_contacts_are_where_the_reference_has_them(system, reference,
                                                                        method):
    states, contacts = reference
    res = kn.simulate(system, t_end=3.0, n_points=301, method=method)
    times = [e["t"] for e in res.stats["events"]]
    np.testing.assert_allclose(times, contacts, atol=1e-5)
    np.testing.assert_allclose(res["ball.s"], states[:, 0], atol=2e-5)


def test_noevent_keeps_the_contact_as_it_is(reference):
    states, _ = reference
    model = ball(f"noEvent({CONTACT})")
    assert model.compile().relations is None
    res = kn.simulate(model, t_end=3.0, n_points=301, rtol=1e-9, atol=1e-11)
    assert "events" not in res.stats
    # the integrator's error control alone, across the kinks: near, not at, the reference
    assert np.max(np.abs(res["ball.s"] - states[:, 0])) < 1e-3
    # the midpoint rule takes no state events: refused with the relation named, and not
    # for the same law in noEvent (refused only as a model of other states than a tree's)
    with pytest.raises(kn.ModelError, match=r"locates no state events.*< of ball_s and 0 "
                                            r"\(reads ball.s\).*noEvent"):
        kn.simulate(ball(), method="midpoint")


def test_a_coulomb_law_on_a_speed_chatters_where_it_would_stick():
    # -c sign(w) written as if_else on the speed: at the turning point where the spring can
    # no longer overcome c (0.04 rad < c/k = 0.08), every value of the relation drives the
    # speed back across zero; the run stops there, saying so, with what it reached
    m = kn.Model("coulomb", parameters={"c": 0.4})
    m.add(kn.rotational.Fixed("fix"))
    m.add(kn.rotational.Spring("spring", c=5.0))
    m.add(kn.rotational.Inertia("rotor", J=0.2, phi0=1.0))
    m.add(kn.rotational.Torque("friction", tau="if_else(w.y > 0, -c, c)"))
    m.add(kn.rotational.SpeedSensor("w"))
    for a, b in [("spring.flange_a", "fix.flange"), ("spring.flange_b", "rotor.flange_a"),
                 ("friction.flange", "rotor.flange_a"), ("w.flange", "rotor.flange_a")]:
        m.connect(a, b)
    with pytest.raises(kn.SimulationError, match="chatters.*friction element.*noEvent") as err:
        kn.simulate(m, t_end=5.0, method="cvodes")
    stick = 6 * np.pi / np.sqrt(5.0 / 0.2)          # the sixth turning point
    assert stick - 0.01 < err.value.t_reached <= stick
    assert abs(err.value.results["rotor.phi"][-1] - 0.04) < 1e-3


@pytest.mark.parametrize("method", [m for m in METHODS if not METHODS[m].fixed and m != "auto"])
def test_max_step_bounds_every_variable_step_method(method):
    m = kn.Model("free")
    m.add(kn.translational.Mass("mass", m=1.0, v0=1.0))
    res = kn.simulate(m, t_end=1.0, n_points=3, method=method, max_step=0.01)
    assert res.settings["max_step"] == 0.01
    assert res.stats["steps"] >= 100          # a uniform motion: 1 or 2 steps without
    loose = kn.simulate(m, t_end=1.0, n_points=3, method=method)
    assert loose.stats["steps"] < 50


def test_max_step_is_a_setting_of_files_and_is_checked():
    m = kn.Model("free")
    m.add(kn.translational.Mass("mass", m=1.0, v0=1.0))
    for bad in (0.0, -1.0, "x", float("nan")):
        with pytest.raises(kn.ModelError, match="simulation.max_step: must be a finite number"):
            kn.simulate(m, t_end=1.0, max_step=bad)
    with pytest.raises(kn.ModelError, match="simulation.max_step = 1e-12: .* steps"):
        kn.simulate(m, t_end=1e4, max_step=1e-12)
    m.simulation["max_step"] = 0.25
    res = kn.simulate(m, t_end=1.0, n_points=3, method="rk45")
    assert res.settings["max_step"] == 0.25 and res.stats["steps"] >= 4
    # a fixed step is at most max_step too
    res = kn.simulate(m, t_end=1.0, n_points=3, method="rk", max_step=0.01)
    assert res.stats["step"] <= 0.01
    schema = kn.schema()["properties"]["simulation"]["properties"]
    assert schema["max_step"] == {"type": "number", "exclusiveMinimum": 0}


def test_a_loop_as_a_dae_locates_the_events_of_its_ode():
    # a one-sided spring on the four-bar's crank angle, written as if_else on its sensor:
    # the partition's DAE under IDAS (algebraic variables, events located on IDAS's own
    # integration from the interval's start) meets the projected ODE's events under Adams
    m = kn.load("models/fourbar.json")
    m.add(kn.rotational.AngleSensor("angle"))
    m.add(kn.rotational.Torque("stop", tau="if_else(angle.y < 0.9, 200*(0.9 - angle.y), 0)"))
    m.connect("angle.flange", "A.axis")
    m.connect("stop.flange", "A.axis")
    runs = [kn.simulate(m.compile(loops=loops), t_end=1.0, n_points=101, rtol=1e-10,
                        atol=1e-12) for loops in ("projected", "partition")]
    assert runs[1].method == "idas" and runs[1].system.n_algebraic == 3
    times = [[e["t"] for e in r.stats["events"]] for r in runs]
    assert len(times[0]) == len(times[1]) >= 4
    np.testing.assert_allclose(times[0], times[1], atol=1e-8)
    np.testing.assert_allclose(runs[0]["A.q"], runs[1]["A.q"], atol=1e-8)
