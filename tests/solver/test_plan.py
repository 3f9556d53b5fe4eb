"""The integration plan (``solver/plan.py``) and component parameters by path: a run given
``"spring.c"`` or ``"cyl3.mass.m"`` is the run of the model with that value, against the
closed form; the twin is compiled once however many runs use it, and the model the user
wrote is left as it was."""

import numpy as np
import pytest
from close import assert_same_numbers
from scenes.oscillator import closed_form, oscillator, stage

import kinetwork as kn
from kinetwork.graph import model as graph_model
from kinetwork.solver.plan import Plan

TIGHT = {"t_end": 2.0, "n_points": 201, "rtol": 1e-9, "atol": 1e-11, "jit": False}


@pytest.fixture
def compilations(monkeypatch):
    """How many Systems the model compiler builds."""
    count = []
    real = graph_model.upcall

    def counting_upcall(name):
        build = real(name)
        if name != "compile":
            return build

        def counting(*args, **kwargs):
            count.append(args[0].name)
            return build(*args, **kwargs)
        return counting
    monkeypatch.setattr(graph_model, "upcall", counting_upcall)
    return count


def test_a_component_parameter_by_path_is_a_parameter_of_the_run(compilations):
    model = oscillator()
    written = kn.dumps(model)
    for c, m in ((9.0, 1.0), (16.0, "500 g"), (2.0, "2 kg")):
        res = kn.simulate(model, params={"spring.c": c, "mass.m": m}, **TIGHT)
        mass = {"500 g": 0.5, "2 kg": 2.0}.get(m, m)
        np.testing.assert_allclose(res["probe.position"], closed_form(res.t, c, mass),
                                   atol=1e-8)
        assert "spring.c -> spring_c" in res.stats["lifted"]
        assert res.settings["params"] == {"spring.c": c, "mass.m": m}
    assert compilations == ["oscillator"]          # the twin, once for the three runs
    assert kn.dumps(model) == written              # the model as written, untouched
    res = kn.simulate(model, **TIGHT)              # and its own run is its own
    np.testing.assert_allclose(res["probe.position"], closed_form(res.t, 4.0, 1.0), atol=1e-8)


def test_paths_inside_subsystems_and_a_subsystems_own_parameter():
    model = stage()
    res = kn.simulate(model, params={"cyl3.mass.m": 4.0}, **TIGHT)
    np.testing.assert_allclose(res["cyl3.probe.position"], closed_form(res.t, 9.0, 4.0),
                               atol=1e-8)
    res = kn.simulate(model, params={"cyl3.k": 25.0}, **TIGHT)
    np.testing.assert_allclose(res["cyl3.probe.position"], closed_form(res.t, 25.0, 1.0),
                               atol=1e-8)
    res = kn.simulate(model, params={"cyl3.k": 25.0, "cyl3.spring.c": 1.0}, **TIGHT)
    np.testing.assert_allclose(res["cyl3.probe.position"], closed_form(res.t, 1.0, 1.0),
                               atol=1e-8)


def test_an_entry_of_a_vector_parameter():
    from scenes import double_pendulum
    model = double_pendulum()
    other = double_pendulum()
    other.components["mass1"].r_cm = [0, -0.3, 0]
    res = kn.simulate(model, params={"mass1.r_cm[1]": -0.3}, **TIGHT)
    ref = kn.simulate(other, **TIGHT)
    np.testing.assert_allclose(res.states, ref.states, atol=1e-12)


def test_a_lifted_parameter_not_given_follows_the_model_parameter_it_was_given():
    from scenes import double_pendulum
    model = double_pendulum()            # spring.c = "c", spring.d = "d"
    res = kn.simulate(model, params={"spring.d": 0.3, "c": 3.0}, **TIGHT)
    ref = kn.simulate(model, params={"d": 0.3, "c": 3.0}, **TIGHT)
    np.testing.assert_allclose(res.states, ref.states, atol=1e-12)


def test_bad_paths_are_refused_by_name():
    model = oscillator()
    with pytest.raises(kn.ModelError, match=r"spring \(translational.Spring\) has no "
                                            r"parameter 'cc' \(did you mean 'c'\?\)"):
        kn.simulate(model, params={"spring.cc": 1.0})
    with pytest.raises(kn.ModelError, match=r"'sprung' is no component.*'spring.c'"):
        kn.simulate(model, params={"sprung.c": 1.0})
    with pytest.raises(kn.ModelError, match=r"params.mass.m = '2 m': m .*does not convert"):
        kn.simulate(model, params={"mass.m": "2 m"})
    with pytest.raises(kn.ModelError, match=r"mass.m = -1.0 kg: must be >= 0"):
        kn.simulate(model, params={"mass.m": -1.0})
    with pytest.raises(kn.ModelError, match="a names parameter, not a number"):
        kn.simulate(model, params={"probe.quantities": 1.0})
    with pytest.raises(kn.ModelError, match=r"has shape \(3,\); name one entry"):
        kn.simulate(kn.load("models/double_pendulum.json"), params={"mass1.r_cm": 1.0})
    pushed = oscillator()
    pushed.add(kn.translational.Force("push", f="sin(t)"))
    pushed.connect("push.flange", "mass.flange_a")
    with pytest.raises(kn.ModelError, match="varies in time"):
        kn.simulate(pushed, params={"push.f": 1.0})


def test_simulate_is_its_plan_run_and_settings_are_checked_once():
    model = oscillator()
    plan = Plan(model, names=["spring.c"], **TIGHT)
    a = plan.run({"spring.c": 9.0})
    b = kn.simulate(model, params={"spring.c": 9.0}, **TIGHT)
    assert_same_numbers(a.states, b.states)
    with pytest.raises(kn.ModelError, match="'rtool': no setting of a run.*'rtol'"):
        Plan(model, rtool=1e-3)
    with pytest.raises(kn.ModelError, match="is no model parameter"):
        plan.run({"mass.m": 2.0})          # not one of the plan's: its twin has no such name


@pytest.mark.parametrize("grid", [[0.0, 1.0, 1.5, 3.0], [0.0, 0.5, 2.5, 3.0],
                                  [0.0, 1.0, 2.0, 2.5, 4.0]])
def test_a_grid_of_unequal_intervals_is_never_taken_for_equal_ones(grid):
    """Output times whose span is a whole number of the first interval (0, 1, 1.5, 3: three
    intervals of 1 in all) are the times asked, not j times the first interval: the closed
    form at each."""
    res = Plan(oscillator(), grid=grid, rtol=1e-10, atol=1e-12).run()
    np.testing.assert_array_equal(res.t, grid)
    np.testing.assert_allclose(res.states[:, 0], closed_form(np.asarray(grid), 4.0, 1.0),
                               rtol=0, atol=1e-8)
