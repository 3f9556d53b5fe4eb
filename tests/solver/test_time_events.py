"""Time events (``solver/schedule.py``, ``solver/events.py``): every method stops at the
breakpoints of the inputs and starts afresh there, so a short input is never stepped over.
Against hand-written equations integrated by scipy's DOP853 piecewise across the breakpoints
(``scenes/bumps.py``), with the default settings."""

import json

import numpy as np
import pytest

import kinetwork as kn
from kinetwork.solver.methods import METHODS
from scenes.bumps import BUMP, T_END, quarter_car, quarter_car_reference

ROADS = ["expression", "table", "long_table", "steps", "pulse", "pulse_blocks"]
#: the methods that take a quarter car (midpoint: a multibody tree's joints only)
VARIABLE = [m for m in METHODS if not METHODS[m].fixed]
#: fixed steps: RK4 needs 1 ms for the 50 Hz filter of the tables (at the default, the
#: output spacing of 3 ms, its error is 5e-5 m on the steps: the step's, not the events')
FIXED = {"rk": 1e-3, "collocation": None}


@pytest.fixture(scope="module")
def references():
    t = np.linspace(0.0, T_END, 1001)
    return {road: quarter_car_reference(t, road) for road in ROADS}


@pytest.fixture(scope="module")
def systems():
    return {road: quarter_car(road).compile() for road in ROADS}


@pytest.mark.parametrize("method", [*VARIABLE, *FIXED])
@pytest.mark.parametrize("road", ROADS)
def test_the_quarter_car_over_a_bump_matches_the_piecewise_reference(systems, references,
                                                                     road, method):
    system = systems[road]
    res = kn.simulate(system, t_end=T_END, method=method, step=FIXED.get(method))
    ref = references[road]
    for name, column in (("wheel.s", -4), ("body.s", -2)):
        error = np.max(np.abs(res[name] - ref[:, column]))
        assert error < 1e-6, (name, error)
    assert res["body.s"].max() > 1e-3          # the bump was felt (it was not: 0 exactly)
    # a long table: each of its 299 inner rows is an instant, as MSL's CombiTimeTable's
    assert res.stats["time_events"] == {"table": 3, "long_table": 299}.get(road, 2)


def test_the_bump_is_not_stepped_over_whatever_the_output_grid():
    # 4 outputs over 3 s: the integrator's steps are its own, the events still stop it
    res = kn.simulate(quarter_car(), t_end=T_END, n_points=4)
    ref = quarter_car_reference(res.t)
    np.testing.assert_allclose(res["body.s"], ref[:, 2], atol=1e-6)
    assert res.stats["time_events"] == 2


def test_a_skipped_input_has_an_error_estimate_of_what_was_missed():
    # the bump in noEvent: no event, and the default run steps over it (6 steps); its
    # estimate, from repetitions that step at most the output spacing, is what it missed
    model = quarter_car()
    model.components["road"].set_param("s_ref", f"noEvent({BUMP})")
    assert model.compile().relations is None
    res = kn.simulate(model, t_end=T_END, error_estimate=True)
    ref = quarter_car_reference(res.t)
    missed = np.max(np.abs(res["body.s"] - ref[:, 2]))
    assert missed > 1e-2
    estimate = res.stats["error_estimate"]["signals"]["body.s"]["error"]
    assert 0.5 * missed < estimate < 2 * missed
    # with the events, the estimate is the run's own small error
    res = kn.simulate(quarter_car(), t_end=T_END, error_estimate=True)
    error = np.max(np.abs(res["body.s"] - quarter_car_reference(res.t)[:, 2]))
    estimate = res.stats["error_estimate"]["signals"]["body.s"]["error"]
    assert 0 < estimate and error / 10 < estimate < 10 * error


def free_mass(force, parameters=None):
    """A 2 kg mass at rest pushed by ``force`` (an expression in t)."""
    m = kn.Model("free", parameters=parameters or {})
    m.add(kn.translational.Mass("mass", m=2.0))
    m.add(kn.translational.Force("push", f=force))
    m.connect("push.flange", "mass.flange_a")
    return m


@pytest.mark.parametrize("method", sorted(set(METHODS) - {"midpoint"}))
def test_a_pulse_far_shorter_than_the_outputs_gives_its_whole_impulse(method):
    # 1 ms of 5 N at t0 + 0.3 (t0 a parameter, set per run): the speed after is 5e-3 / 2
    model = free_mass("if_else(t - t0 > 0.3, if_else(t - t0 < 0.301, 5, 0), 0)", {"t0": 0.1})
    for t0 in (0.1, 0.45):
        res = kn.simulate(model, t_end=2.0, n_points=3, method=method, params={"t0": t0})
        # the whole impulse, at the right time (scipy's BDF: within 2 atol of the position)
        assert res["mass.v"][-1] == pytest.approx(2.5e-3, abs=1e-9)
        assert res["mass.s"][-1] == pytest.approx(2.5e-3 * (2.0 - t0 - 0.3005), abs=1e-7)


def test_a_max_of_two_equal_values_switches_nothing_until_they_part():
    # max(if_else(t > 0.5, 4 (t - 0.5), 0), 0): zero and zero until 0.5, then 4 (t - 0.5)
    # and 0 (a Brake's normal force before it is applied); one switch, where they part (MSL's
    # Friction example made 3,414 events of its plateau, one at every scanned point)
    model = free_mass("max(if_else(t > 0.5, 4*(t - 0.5) + sin(t) - sin(0.5), 0), 0)")
    res = kn.simulate(model, t_end=1.0, n_points=11)
    assert res.stats.get("time_events", 0) <= 2
    # v = integral of f / 2 from 0.5: (2 (t - 0.5)^2 - cos t + cos 0.5 - (t - 0.5) sin 0.5) / 2
    t = 1.0
    v = (2 * (t - 0.5) ** 2 - np.cos(t) + np.cos(0.5) - (t - 0.5) * np.sin(0.5)) / 2
    assert res["mass.v"][-1] == pytest.approx(v, abs=1e-8)


def test_msl_friction_has_its_documented_switches_and_no_others():
    # Modelica.Mechanics.Rotational.Examples.Friction: the brake stops inertia1 at 0.64 s,
    # the clutch locks for good at 1.66 s (MSL's documentation); the brake's normal force,
    # zero until 0.5 s, is one time event, not one per scanned point
    res = kn.simulate(kn.load("msl_friction"))
    assert res.stats["time_events"] == 1
    events = [(e["component"], e["kind"]) for e in res.stats["events"]]
    assert events[-2:] == [("brake", "stuck"), ("clutch", "stuck")]
    assert [round(e["t"], 2) for e in res.stats["events"][-2:]] == [0.64, 1.66]


def msl_periodic(kind, t, start=0.3, period=0.2, nperiod=-1):
    """MSL's Pulse (amplitude 2, width 30 %), SawTooth (amplitude 2) and Trapezoid
    (amplitude 2, rising 0.02, width 0.05, falling 0.04 s) with offset 0.5, written from
    MSL's definitions in numpy."""
    tau = t - start
    phase = np.mod(tau, period)
    shape = {"pulse": np.where(phase < 0.3 * period, 1.0, 0.0),
             "sawtooth": phase / period,
             "trapezoid": np.interp(phase, [0, 0.02, 0.07, 0.11, period], [0, 1, 1, 0, 0])}[kind]
    on = (tau >= 0) & ((nperiod < 0) | (tau < nperiod * period))
    return 0.5 + 2.0 * np.where(on, shape, 0.0)


@pytest.mark.parametrize("nperiod", [-1, 3])
@pytest.mark.parametrize("kind", ["pulse", "sawtooth", "trapezoid"])
@pytest.mark.parametrize("method", ["auto", "rk45", "idas"])
def test_periodic_blocks_push_with_their_exact_impulse(kind, nperiod, method):
    # a 1 kg mass pushed by the block: its speed is the signal's integral, exact by the
    # midpoint rule on a grid through every breakpoint (the signals are piecewise linear)
    params = {"amplitude": 2.0, "offset": 0.5, "period": 0.2, "nperiod": nperiod,
              "start_time": 0.3}
    block = {"pulse": lambda: kn.signals.Pulse("y", width=30, **params),
             "sawtooth": lambda: kn.signals.SawTooth("y", **params),
             "trapezoid": lambda: kn.signals.Trapezoid("y", rising=0.02, width=0.05,
                                                       falling=0.04, **params)}[kind]()
    m = kn.Model("pushed")
    m.add(kn.translational.Mass("mass", m=1.0))
    m.add(kn.translational.Force("push"))
    m.add(block)
    m.connect("y.y", "push.u")
    m.connect("push.flange", "mass.flange_a")
    res = kn.simulate(m, t_end=1.5, n_points=7, method=method)
    edges = 0.3 + 0.2 * np.arange(7)[:, None] + np.array([0, 0.02, 0.06, 0.07, 0.11])
    fine = np.union1d(np.linspace(0, 1.5, 1501), edges.ravel())
    fine = fine[(fine >= 0) & (fine <= 1.5)]
    middles = (fine[1:] + fine[:-1]) / 2
    speed = np.concatenate([[0], np.cumsum(np.diff(fine) * msl_periodic(kind, middles,
                                                                           nperiod=nperiod))])
    np.testing.assert_allclose(res["mass.v"], np.interp(res.t, fine, speed), atol=1e-6)
    # events at its edges and kinks only while it runs
    per_period = {"pulse": 2, "sawtooth": 1, "trapezoid": 4}[kind]
    shown = 6 if nperiod < 0 else 3
    assert res.stats["time_events"] <= per_period * shown + 2


@pytest.mark.parametrize("method", ["auto", "rk45", "rk", "midpoint"])
def test_a_kinematic_ptp_drive_reaches_its_end_exactly(method):
    # a joint driven through the torque an inertia needs for the PTP's acceleration: its
    # angle is the PTP's own, phases switching at 0.25, 1 and 1.25 s
    m = kn.Model("ptp")
    m.add(kn.multibody.Ground("ground", gravity=[0, 0, 0]))
    m.add(kn.multibody.Revolute("joint", axis=[0, 0, 1]))
    m.add(kn.multibody.RigidBody("body", mass=1.0, r_cm=[0, 0, 0],
                                 inertia=[0.0, 0.0, 0.5]))
    m.add(kn.rotational.Torque("drive"))
    m.add(kn.signals.KinematicPTP("ptp", q_begin=[0], q_end=[1], qd_max=[1], qdd_max=[4],
                                  quantity="qdd"))
    m.add(kn.signals.Gain("J", k=0.5))
    m.add(kn.Probe("p", quantities=["angle"]))
    for a, b in [("ground.frame", "joint.frame_a"), ("joint.frame_b", "body.frame_a"),
                 ("ptp.y", "J.u"), ("J.y", "drive.u"), ("drive.flange", "joint.axis"),
                 ("p.port", "joint.axis")]:
        m.connect(a, b)
    step = {"rk": 0.01, "midpoint": 0.01}.get(method)
    res = kn.simulate(m, t_end=2.0, n_points=9, method=method, rtol=1e-10, atol=1e-12,
                      step=step)
    tau = res.t
    exact = np.where(tau < 0.25, 2 * tau**2, np.where(
        tau < 1.0, 0.125 + (tau - 0.25), np.where(tau < 1.25, 1 - 2 * (1.25 - tau)**2, 1.0)))
    np.testing.assert_allclose(res["p.angle"], exact, atol=1e-9)
    assert res.stats["time_events"] == 3


def test_a_table_with_steps_in_a_model_file_round_trips_and_runs(tmp_path):
    model = quarter_car("steps")
    model.simulation.update(t_end=T_END, max_step=0.5)
    path = tmp_path / "steps.json"
    model.save(path)
    data = json.loads(path.read_text())
    table = next(c for c in data["components"] if c["name"] == "profile")["params"]["table"]
    assert [row[0] for row in table].count(0.5) == 2
    assert data["simulation"]["max_step"] == 0.5
    again = kn.load(path)
    res = kn.simulate(again)
    assert res.settings["max_step"] == 0.5
    np.testing.assert_allclose(res["body.s"], quarter_car_reference(res.t, "steps")[:, -2],
                               atol=1e-6)


def test_a_table_refuses_three_equal_abscissae():
    with pytest.raises(kn.ModelError, match=r"table\[3\]: x = 1 a third time"):
        kn.signals.Table("t", table=[[0, 0], [1, 1], [1, 2], [1, 3]])


def test_the_command_takes_max_step_and_shows_what_each_method_takes(tmp_path, capsys):
    from kinetwork.cli import main
    path = tmp_path / "car.json"
    quarter_car().save(path)
    out = tmp_path / "car.csv"
    assert main(["run", str(path), "--t-end", "1", "--n-points", "11", "--method", "rk45",
                 "--max-step", "0.001", "--out", str(out), "-q"]) == 0
    data = np.loadtxt(out, delimiter=",", skiprows=1)
    assert len(data) == 11
    capsys.readouterr()
    assert main(["run", str(path), "--t-end", "1", "--n-points", "11"]) == 0
    assert ", 2 time events) in" in capsys.readouterr().out
    assert main(["run", str(path), "--max-step", "-1", "-q"]) == 1
    assert "simulation.max_step: must be a finite number > 0" in capsys.readouterr().err
    assert main(["methods"]) == 0
    listing = capsys.readouterr().out
    assert "events: time and state" in listing and "events: time\n" in listing


def test_sensitivities_refuse_a_run_with_events_rather_than_carry_a_law_past_them():
    with pytest.raises(kn.ModelError, match="time events at 0.5, 0.6 s.*central differences"):
        kn.sensitivity(quarter_car(), ["h"], t_end=T_END)
    # before the bump no event is met, and the road's height changes nothing yet
    sens = kn.sensitivity(quarter_car(), ["h"], t_end=0.4, n_points=5, outputs=["body.s"])
    assert np.all(sens.S == 0)


def test_sensitivities_before_a_relation_switches_see_the_branch_it_holds():
    # F while t < 1: over 0.5 s the mass is pushed (s = F t^2 / (2 m), m = 2 kg), and the
    # sensitivity ds/dF = t^2 / 4 is the pushed branch's, not the other one's (0)
    model = free_mass("if_else(t < 1, F, 0)", {"F": 3.0})
    sens = kn.sensitivity(model, ["F"], t_end=0.5, n_points=6, outputs=["mass.s"])
    np.testing.assert_allclose(sens["mass.s", "F"], sens.t ** 2 / 4, rtol=1e-6, atol=1e-12)


@pytest.mark.parametrize("road", ["expression", "table", "pulse", "pulse_blocks"])
def test_a_sweep_member_with_events_gets_simulates_answer(references, road):
    # each member through the plan's run, its events and all: the reference, and the very
    # numbers of kn.simulate, in threads (batch 1 and 4) and serially; the road is linear
    # in h, so the member of 2 h (the expression's bump twice as high) moves twice as far
    model = quarter_car(road)
    ref = references[road]
    one = kn.simulate(model, t_end=T_END)
    scale = 2.0 if road == "expression" else 1.0
    for batch, workers in ((1, 2), (4, 2), (None, 1)):
        ds = kn.sweep(model, {"h": [0.05, 0.1]}, t_end=T_END, batch=batch, workers=workers,
                      progress=False)
        assert list(ds.status.values) == ["ok", "ok"]
        for h, factor in ((0.05, 1.0), (0.1, scale)):
            for name, column in (("wheel.s", -4), ("body.s", -2)):
                member = ds[name].sel(h=h).values
                assert np.max(np.abs(member - factor * ref[:, column])) < 1e-6, (name, h)
        np.testing.assert_allclose(ds["body.s"].sel(h=0.05).values, one["body.s"],
                                   rtol=1e-6, atol=1e-12)
