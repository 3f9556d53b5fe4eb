"""The relations of a System's equations (``equations/relations.py``): which nodes are events,
of which kind, and the equations with them held, against the equations as they are."""

import casadi as ca
import numpy as np
import pytest

import kinetwork as kn
from kinetwork.solver.schedule import MAX_TIME_EVENTS, Schedule


def driven(f, **parameters):
    """A mass (and a spring to the ground) pushed by the force expression ``f``, which may
    read the mass's position as ``pos.y`` and its speed as ``vel.y``."""
    m = kn.Model("driven", parameters=parameters)
    m.add(kn.translational.Mass("mass", m=2.0, s0=0.3))
    m.add(kn.translational.Spring("spring", c=50.0))
    m.add(kn.translational.Fixed("ground"))
    m.add(kn.translational.PositionSensor("pos"))
    m.add(kn.translational.SpeedSensor("vel"))
    m.add(kn.translational.Force("push", f=f))
    for a, b in [("spring.flange_a", "ground.flange"), ("spring.flange_b", "mass.flange_a"),
                 ("pos.flange", "mass.flange_a"), ("vel.flange", "mass.flange_a"),
                 ("push.flange", "mass.flange_a")]:
        m.connect(a, b)
    return m


def kinds(f, **parameters):
    """(kind, operation) of each event node of ``driven(f)``."""
    rel = driven(f, **parameters).compile().relations
    if rel is None:
        return []
    out = [("time", rel.ops[i]) for i in rel.time] + [("state", rel.ops[i]) for i in rel.state]
    return sorted(out)


@pytest.mark.parametrize("f, expected", [
    ("if_else(t < 0.5, 1, 0)", [("time", ca.OP_LT)]),
    ("if_else(t >= t0, 1, 0)", [("time", ca.OP_LE)]),
    ("if_else(t - t0 > 0.2, 1, if_else(t < 0.1, 2, 0))", [("time", ca.OP_LT)] * 2),
    ("if_else(pos.y < 0, -1e3*pos.y, 0)", [("state", ca.OP_LT)]),
    ("if_else(vel.y > 0, -1, 1)*if_else(t < 1, 1, 0)", [("state", ca.OP_LT), ("time", ca.OP_LT)]),
    ("max(0, t - 1)", [("time", ca.OP_FMAX)]),
    ("abs(t - 1) + sign(t - 2) + min(t, 3)",
     sorted([("time", ca.OP_FABS), ("time", ca.OP_SIGN), ("time", ca.OP_FMIN)])),
    # taken as they are: kinks on the states, relations on parameters, equality, noEvent
    ("max(0, -pos.y)*100 + abs(vel.y)", []),
    ("if_else(t0 < 1, 2, 3)", []),
    ("if_else(t == 1, 2, 3)", []),
    ("noEvent(if_else(t < 0.5, 1, 0) + if_else(pos.y < 0, 1, 0) + max(0, t - 1))", []),
])
def test_which_nodes_are_events(f, expected):
    assert kinds(f, t0=0.3) == expected


def test_signal_blocks_read_in_time_are_time_events():
    m = kn.Model("blocks")
    m.add(kn.translational.Mass("mass", m=1.0))
    m.add(kn.translational.Force("push"))
    m.add(kn.signals.Table("table", table=[[0, 0], [1, 1], [1, 2], [2, 0]]))
    m.add(kn.signals.Step("step", start_time=0.5))
    m.add(kn.signals.Ramp("ramp", duration=0.2, start_time=0.7))
    m.add(kn.signals.KinematicPTP("ptp", q_begin=[0], q_end=[1], qd_max=[1], qdd_max=[4],
                                  quantity="qdd"))
    m.add(kn.signals.Sum("sum"))
    for i, name in enumerate(["table", "step", "ramp", "ptp"]):
        m.connect(f"{name}.y", f"sum.u{i + 1}")
    m.connect("sum.y", "push.u")
    m.connect("push.flange", "mass.flange_a")
    system = m.compile()
    rel = system.relations
    assert not len(rel.state) and len(rel.time) >= 7
    schedule = Schedule(rel, system.param_vector(), 0.0, 3.0)
    # the table's kink and step at 1 (one instant); the step at 0.5; the ramp's two ends
    # (the second a min of a max: found by the scan); the PTP's phases (accelerating to
    # 0.25 s, coasting to 1 s, braking to 1.25 s)
    np.testing.assert_allclose(schedule.times, [0.25, 0.5, 0.7, 0.9, 1.0, 1.25], atol=1e-14)


def long_table(read_at_state):
    """A mass pushed by a Table of 201 rows (an interpolant), read in time or at the
    mass's position."""
    m = kn.Model("long")
    m.add(kn.translational.Mass("mass", m=1.0))
    m.add(kn.translational.Force("push"))
    x = np.linspace(0.0, 2.0, 201)
    m.add(kn.signals.Table("table", table=np.column_stack([x, np.abs(x - 1)]).tolist()))
    m.connect("table.y", "push.u")
    m.connect("push.flange", "mass.flange_a")
    if read_at_state:
        m.add(kn.translational.PositionSensor("pos"))
        m.connect("pos.flange", "mass.flange_a")
        m.connect("pos.y", "table.u")
    return m, x


def test_every_row_of_a_long_table_read_in_time_is_a_time_event():
    # as MSL's CombiTimeTable: the interpolant's knots, with no node of their own
    m, x = long_table(read_at_state=False)
    system = m.compile()
    rel = system.relations
    assert rel.n == 0 and len(rel.tables) == 1
    times = Schedule(rel, system.param_vector(), 0.0, 3.0).times
    np.testing.assert_allclose(times, x[1:], rtol=1e-15)
    # read at a state, its kinks are taken as they are
    assert long_table(read_at_state=True)[0].compile().relations is None


@pytest.mark.parametrize("rows", [5, 201])
def test_a_table_whose_time_events_are_its_steps_has_no_others(rows):
    # MSL's AtDiscontinuities: the same values, events at the step at 1 only
    x = np.linspace(0.0, 2.0, rows)
    table = np.column_stack([x, np.abs(x - 1)]).tolist()
    table.insert(rows // 2 + 1, [1.0, 0.5])
    values = []
    for events in ("always", "steps"):
        m = kn.Model("steps")
        m.add(kn.translational.Mass("mass", m=1.0))
        m.add(kn.translational.Force("push"))
        m.add(kn.signals.Table("table", table=table, time_events=events))
        m.connect("table.y", "push.u")
        m.connect("push.flange", "mass.flange_a")
        system = m.compile()
        times = Schedule(system.relations, system.param_vector(), 0.0, 3.0).times
        if events == "steps":
            np.testing.assert_allclose(times, [1.0], rtol=1e-15)
        else:       # the kinks too: of the short table where its slope changes
            np.testing.assert_allclose(times, [1.0, 1.5] if rows == 5 else x[1:], rtol=1e-15)
        values.append([float(system.rhs(t, [0.0, 0.0])[1]) for t in (0.3, 0.999, 1.0, 2.5)])
    np.testing.assert_allclose(values[0], values[1], rtol=1e-14)
    np.testing.assert_allclose(values[0], [0.7, 0.001, 0.5, 1.5], rtol=1e-12)


@pytest.mark.parametrize("argument, instants", [
    ("2*t - t0", lambda x, t0: (x + t0) / 2),          # affine, a parameter in it
    ("t^2", np.sqrt),                                  # curved: found on the scan
])
def test_a_long_table_read_at_a_function_of_time_has_its_instants_where_it_is_read(
        argument, instants):
    m, x = long_table(read_at_state=False)
    m.set_parameter("t0", 0.4)
    m.add(kn.signals.Expression("clock", expression=argument))
    m.connect("clock.y", "table.u")
    system = m.compile()
    for t0 in (0.4, 0.7):
        p = system.param_vector({"t0": t0})
        times = Schedule(system.relations, p, 0.0, 1.5).times
        expected = instants(x, t0) if argument != "t^2" else np.sqrt(x)
        expected = expected[(expected > 0) & (expected < 1.5)]
        np.testing.assert_allclose(times, expected, rtol=1e-13, atol=1e-14)


def test_the_held_equations_are_the_equations_where_the_values_are_their_own():
    system = driven("if_else(pos.y < 0, -1e3*pos.y - 5*vel.y, 0) + if_else(t < 0.5, 2, "
                    "if_else(t < 0.6, 2 + sin(10*t), 0)) + max(0, t - 1)").compile()
    rel = system.relations
    p = system.param_vector()
    rng = np.random.default_rng(3)
    rhs_held = ca.Function("h", [system.asm.t, system.eq.x, rel.p], [rel.ode])
    for _ in range(50):
        t, x = rng.uniform(0, 2), rng.normal(size=2)
        r = np.zeros(rel.n)
        for _ in range(rel.n + 1):          # the values of the point, nested ones in turn
            r = np.asarray(rel.f_select(t, x, np.concatenate([p, r]))).ravel()
        held = np.asarray(rhs_held(t, x, np.concatenate([p, r]))).ravel()
        np.testing.assert_allclose(held, system.rhs(t, x), rtol=1e-13, atol=1e-13)


def test_a_schedule_finds_curved_nested_and_periodic_switches():
    # sin(2 pi t) > 0.5 switches at 1/12 + k, 5/12 + k; the fold of t at 1 crosses 0.5 at
    # 0.5 and 1.5; floor(4 t) steps every quarter second
    system = driven("if_else(sin(2*pi*t) > 0.5, 1, 0) + "
                    "if_else(if_else(t < 1, t, 2 - t) > 0.5, 1, 0)").compile()
    times = Schedule(system.relations, system.param_vector(), 0.0, 2.0).times
    expected = sorted([1 / 12, 5 / 12, 13 / 12, 17 / 12, 0.5, 1.0, 1.5])
    np.testing.assert_allclose(times, expected, atol=1e-13)


def test_a_pulse_shorter_than_the_scan_is_found_at_its_extremum():
    # exp(-((t - 1.2345)/5e-4)^2) > 0.5: a pulse 0.8 ms wide between two points of the
    # scan (2.4 ms apart over 10 s), where the indicator is below zero; its peak is found
    # where the derivative changes sign between them
    system = driven("if_else(exp(-((t - 1.2345)/5e-4)^2) > 0.5, 1, 0)").compile()
    times = Schedule(system.relations, system.param_vector(), 0.0, 10.0).times
    half = 5e-4 * np.sqrt(np.log(2))
    np.testing.assert_allclose(times, [1.2345 - half, 1.2345 + half], atol=1e-12)


def test_too_many_time_events_are_refused_before_the_run():
    m = kn.Model("fast")
    m.add(kn.translational.Mass("mass", m=1.0))
    m.add(kn.translational.Force("push"))
    m.add(kn.signals.Pulse("pulses", period=1e-8))
    m.connect("pulses.y", "push.u")
    m.connect("push.flange", "mass.flange_a")
    with pytest.raises(kn.ModelError, match=f"more than {MAX_TIME_EVENTS} time events"):
        kn.simulate(m, t_end=1.0)
