"""Friction with stiction, elastic gaps and stops, against closed forms and an independently
written event-driven scipy reference (``components/friction.py``, ``equations/modes.py``)."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.special import ellipkinc

from close import assert_same_numbers

import kinetwork as kn

FAST = dict(jit=False)


def sliding_block(v0=3.0, m=2.0, f_c=4.0, d=0.0, peak=1.0, push=None):
    """A block of mass m sliding at v0 on a rough floor (Coulomb f_c, viscous d), pushed by
    the force ``push`` (an expression in t) if given."""
    model = kn.Model("block")
    block = model.add(kn.translational.Mass("block", m=m, v0=v0))
    floor = model.add(kn.translational.Friction("floor", f_c=f_c, d=d, peak=peak))
    probe = model.add(kn.Probe("p", quantities=["velocity", "force"]))
    model.connect(block.flange_a, floor.flange)
    model.connect(probe.port, floor.flange)
    if push is not None:
        force = model.add(kn.translational.Force("push", f=push))
        model.connect(force.flange, block.flange_b)
    return model


@pytest.mark.parametrize("method", ["cvodes", "rk45", "rk"])
def test_block_slides_to_a_stop_at_the_closed_form_time(method):
    # m v' = -f_c - d v: v = (v0 + f_c/d) exp(-d t/m) - f_c/d, zero at t = m/d ln(1 + d v0/f_c)
    m, v0, f_c, d = 2.0, 3.0, 4.0, 0.5
    res = kn.simulate(sliding_block(v0, m, f_c, d), t_end=3.0, n_points=31, method=method,
                      rtol=1e-11, atol=1e-13, step=1e-3, **FAST)
    t_stop = m / d * np.log(1 + d * v0 / f_c)
    events = res.stats["events"]
    assert [(e["component"], e["kind"]) for e in events] == [("floor", "stuck")]
    assert abs(events[0]["t"] - t_stop) < 1e-9
    v = res["block.v"]
    before = res.t < t_stop
    exact = (v0 + f_c / d) * np.exp(-d * res.t[before] / m) - f_c / d
    assert np.max(np.abs(v[before] - exact)) < 1e-8
    assert np.all(v[~before] == 0.0)                 # stuck exactly, not creeping
    s_stop = (m / d) * ((v0 + f_c / d) * (1 - np.exp(-d * t_stop / m))) - f_c / d * t_stop
    assert abs(res["block.s"][-1] - s_stop) < 1e-8


def test_a_push_below_the_static_limit_holds_and_breaks_away_where_it_reaches_it():
    # a ramp k t against static friction peak f_c: stuck until t_b = peak f_c / k, then
    # m v' = k t - f_c: v = k (t^2 - t_b^2) / (2 m) - f_c (t - t_b) / m
    m, f_c, peak, k = 2.0, 4.0, 1.5, 3.0
    res = kn.simulate(sliding_block(0.0, m, f_c, 0.0, peak, push=f"{k}*t"), t_end=3.0,
                      n_points=61, method="rk45", rtol=1e-11, atol=1e-13, **FAST)
    t_b = peak * f_c / k
    events = res.stats["events"]
    assert [(e["component"], e["kind"]) for e in events] == [("floor", "sliding forward")]
    assert abs(events[0]["t"] - t_b) < 1e-9
    stuck = res.t < t_b
    assert np.all(res["block.v"][stuck] == 0.0)
    # stuck, the floor holds against the push: it takes the push (the flow into its flange)
    assert np.allclose(res["p.force"][stuck], k * res.t[stuck], atol=1e-12)
    t = res.t[~stuck]
    exact = k * (t ** 2 - t_b ** 2) / (2 * m) - f_c * (t - t_b) / m
    assert np.max(np.abs(res["block.v"][~stuck] - exact)) < 1e-8


def belt_model(m, c, f_c, peak, v_belt):
    """A block on a belt moving at v_belt, tied to the wall by a spring c: stick-slip."""
    model = kn.Model("belt")
    wall = model.add(kn.translational.Fixed("wall"))
    spring = model.add(kn.translational.Spring("spring", c=c))
    block = model.add(kn.translational.Mass("block", m=m))
    belt = model.add(kn.translational.Speed("belt", v_ref=v_belt))
    rub = model.add(kn.translational.Friction("rub", f_c=f_c, peak=peak))
    model.connect(wall.flange, spring.flange_a)
    model.connect(spring.flange_b, block.flange_a)
    model.connect(block.flange_a, rub.flange)
    model.connect(rub.support, belt.flange)
    return model


def belt_reference(m, c, f_c, peak, v_belt, t_end):
    """Switching times of the same scene, written apart from kinetwork: scipy's solve_ivp
    with its own events, phase by phase. x is the block's position (the spring unstretched
    at 0), s the sign of its speed relative to the belt while it slips: m x'' = -c x - s f_c.
    Stuck, it rides the belt while the spring's pull stays within peak f_c."""
    t, x, v = 0.0, 0.0, 0.0
    s, stuck, times = np.sign(v - v_belt), False, []
    while True:
        if stuck:
            limit = peak * f_c / c            # the belt stretches the spring up to here
            t_next = t + (limit - x) / v_belt
            if t_next >= t_end:
                return np.array(times)
            t, x, v, s, stuck = t_next, limit, v_belt, -1.0, False
            times.append(t)
            continue

        def rhs(_, y, s=s):
            return [y[1], (-c * y[0] - s * f_c) / m]

        def same_speed(_, y):
            return y[1] - v_belt
        same_speed.terminal, same_speed.direction = True, -s
        sol = solve_ivp(rhs, (t, t_end), [x, v], events=same_speed, rtol=1e-13, atol=1e-15,
                        method="DOP853")
        if not sol.t_events[0].size:
            return np.array(times)
        t, (x, v) = sol.t_events[0][0], sol.y_events[0][0]
        times.append(t)
        if abs(c * x) <= peak * f_c:
            stuck = True
        else:
            s = np.sign(-c * x)


@pytest.mark.parametrize("method", ["cvodes", "dop853"])
def test_stick_slip_on_a_belt_switches_at_the_reference_times(method):
    m, c, f_c, peak, v_belt = 1.0, 10.0, 2.0, 1.5, 0.5
    t_end = 6.0
    ref = belt_reference(m, c, f_c, peak, v_belt, t_end)
    res = kn.simulate(belt_model(m, c, f_c, peak, v_belt), t_end=t_end, n_points=601,
                      method=method, rtol=1e-12, atol=1e-14, **FAST)
    got = np.array([e["t"] for e in res.stats["events"]])
    kinds = [e["kind"] for e in res.stats["events"]]
    assert len(ref) >= 6 and "stuck" in kinds and "sliding backward" in kinds
    assert len(got) == len(ref)
    assert np.max(np.abs(got - ref)) < 1e-8


def test_brake_stops_a_rotor_at_the_closed_form_time():
    # J w' = -mu cgeo fn_max: stops at J w0 / (mu cgeo fn_max), then stays
    J, w0, mu, cgeo, fn = 0.5, 10.0, 0.4, 0.1, 50.0
    model = kn.Model("brake")
    rotor = model.add(kn.rotational.Inertia("rotor", J=J, w0=w0))
    brake = model.add(kn.rotational.Brake("brake", mu=mu, cgeo=cgeo, fn_max=fn, peak=1.2))
    model.connect(rotor.flange_b, brake.flange)
    res = kn.simulate(model, t_end=4.0, n_points=41, method="cvodes", rtol=1e-11,
                      atol=1e-13, **FAST)
    t_stop = J * w0 / (mu * cgeo * fn)
    (event,) = res.stats["events"]
    assert event["kind"] == "stuck" and abs(event["t"] - t_stop) < 1e-9
    assert np.all(res["rotor.w"][res.t > t_stop] == 0.0)


def test_clutch_locks_two_rotors_at_the_closed_form_time_and_keeps_momentum():
    # tau = mu cgeo fn on each, opposite: w1 - w2 closes at rate tau (1/J1 + 1/J2)
    J1, J2, w1, mu, cgeo, fn = 1.0, 3.0, 8.0, 0.5, 0.2, 20.0
    model = kn.Model("clutch")
    a = model.add(kn.rotational.Inertia("a", J=J1, w0=w1))
    b = model.add(kn.rotational.Inertia("b", J=J2, w0=0.0))
    clutch = model.add(kn.rotational.Clutch("clutch", mu=mu, cgeo=cgeo, fn_max=fn))
    model.connect(a.flange_b, clutch.flange_a)
    model.connect(clutch.flange_b, b.flange_a)
    res = kn.simulate(model, t_end=3.0, n_points=31, method="rk45", rtol=1e-11, atol=1e-13,
                      **FAST)
    tau = mu * cgeo * fn
    t_lock = w1 / (tau * (1 / J1 + 1 / J2))
    (event,) = res.stats["events"]
    assert event["component"] == "clutch" and abs(event["t"] - t_lock) < 1e-9
    after = res.t > t_lock
    w_common = J1 * w1 / (J1 + J2)
    assert np.allclose(res["a.w"][after], w_common, atol=1e-9)
    assert np.allclose(res["b.w"][after], w_common, atol=1e-9)


def test_elasto_gap_contact_lasts_half_a_period_and_returns_the_speed():
    # a mass at v0 toward a spring gap: contact at gap / v0, leaves pi sqrt(m/c) later at -v0
    m, c, v0, gap = 2.0, 800.0, -1.5, 0.3
    model = kn.Model("gap")
    wall = model.add(kn.translational.Fixed("wall"))
    mass = model.add(kn.translational.Mass("mass", m=m, s0=gap, v0=v0))
    elasto = model.add(kn.translational.ElastoGap("gap", c=c, d=0.0))
    model.connect(wall.flange, elasto.flange_a)
    model.connect(elasto.flange_b, mass.flange_a)
    res = kn.simulate(model, t_end=1.0, n_points=101, method="rk45", rtol=1e-11, atol=1e-13,
                      **FAST)
    events = res.stats["events"]
    assert [e["kind"] for e in events] == ["contact", "open"]
    t_in = gap / -v0
    assert abs(events[0]["t"] - t_in) < 1e-9
    assert abs(events[1]["t"] - (t_in + np.pi * np.sqrt(m / c))) < 1e-9
    assert abs(res["mass.v"][-1] + v0) < 1e-8


def test_pendulum_hits_its_end_stop_at_the_elliptic_integral_time():
    # released at rest from q0, it reaches q_stop after sqrt(L/g) (K(k) - F(phi, k)) with
    # k = sin(q0/2), sin(q/2) = k sin(phi); it leaves with -e times the speed it came with
    g, L, q0, q_stop, e = 9.81, 0.8, -2.0, 0.6, 0.7
    model = kn.Model("pendulum")
    world = model.add(kn.multibody.Ground("world", gravity=[0, -g, 0]))
    joint = model.add(kn.multibody.Revolute("joint", axis=[0, 0, 1], q0=q0))
    bob = model.add(kn.multibody.RigidBody("bob", mass=1.0, r_cm=[0, -L, 0]))
    stop = model.add(kn.rotational.Stop("stop", phi_max=q_stop, e=e))
    model.connect(world.frame, joint.frame_a)
    model.connect(joint.frame_b, bob.frame_a)
    model.connect(stop.flange_a, joint.support)
    model.connect(stop.flange_b, joint.axis)
    res = kn.simulate(model, t_end=2.0, n_points=201, method="cvodes", rtol=1e-12,
                      atol=1e-14, **FAST)
    k = np.sin(abs(q0) / 2)
    amplitude = np.arcsin(np.sin(q_stop / 2) / k)
    t_hit = np.sqrt(L / g) * (ellipkinc(np.pi / 2, k ** 2) + ellipkinc(amplitude, k ** 2))
    first = res.stats["events"][0]
    assert first["kind"] == "impact" and abs(first["t"] - t_hit) < 1e-9
    # after it, the energy of the speed -e w_in at q_stop, w_in from the energy of the fall
    w_in = np.sqrt(2 * g / L * (np.cos(q_stop) - np.cos(q0)))
    energy = 0.5 * L ** 2 * res["joint.qd"] ** 2 - g * L * np.cos(res["joint.q"])
    between = (res.t > first["t"]) & (res.t < res.stats["events"][1]["t"])
    after = 0.5 * L ** 2 * (e * w_in) ** 2 - g * L * np.cos(q_stop)
    assert between.sum() > 10 and np.max(np.abs(energy[between] - after)) < 1e-9
    assert np.all(res["joint.q"] <= q_stop + 1e-12)


def ball_on_floor(f, v0=None, e=0.0):
    """A unit mass on a floor (a Stop with s_min = 0) starting on it, pushed by f."""
    model = kn.Model("ball")
    floor = model.add(kn.translational.Fixed("floor"))
    ball = model.add(kn.translational.Mass("ball", m=1.0, **({} if v0 is None else {"v0": v0})))
    push = model.add(kn.translational.Force("push", f=f))
    stop = model.add(kn.translational.Stop("stop", s_min=0.0, e=e))
    model.connect(floor.flange, stop.flange_a)
    model.connect(stop.flange_b, ball.flange_a)
    model.connect(push.flange, ball.flange_b)
    res = kn.simulate(model, t_end=1.0, n_points=101, method="cvodes", rtol=1e-10,
                      atol=1e-12, **FAST)
    return res, res["ball.s"]


@pytest.mark.parametrize("f", [-9.81, 9.81])
def test_a_stop_that_starts_on_its_limit_rests_on_it_or_lifts_off(f):
    # resting on the floor at t = 0 under its weight, it stays (a free start would fall
    # through: the gap starts at zero and never crosses it); pulled up, it rises as s = f t^2/2
    res, s = ball_on_floor(f)
    reference = np.maximum(f, 0.0) * res.t ** 2 / 2
    assert np.max(np.abs(s - reference)) < 1e-8


def test_a_stop_hit_at_the_start_bounces_at_once():
    # moving into the floor at 2 m/s at t = 0 with e = 0.5: it leaves at 1 m/s and lands
    # again at 2 * 1 / g, then at 2 * 0.5 / g later
    g = 9.81
    res, s = ball_on_floor(-g, v0=-2.0, e=0.5)
    times = [e["t"] for e in res.stats["events"] if e["kind"] == "impact"]
    assert abs(times[0] - 2 / g) < 1e-8 and abs(times[1] - 3 / g) < 1e-8
    mask = res.t < 2 / g
    assert np.max(np.abs(s[mask] - (res.t[mask] - g * res.t[mask] ** 2 / 2))) < 1e-8


def test_a_stop_without_limits_and_a_midpoint_run_are_refused_by_name():
    model = kn.Model("nolimit")
    wall = model.add(kn.translational.Fixed("wall"))
    mass = model.add(kn.translational.Mass("mass", m=1.0))
    stop = model.add(kn.translational.Stop("stop"))
    model.connect(wall.flange, stop.flange_a)
    model.connect(stop.flange_b, mass.flange_a)
    with pytest.raises(kn.ModelError, match="stop.*s_min"):
        model.compile()
    with pytest.raises(kn.ModelError, match="midpoint.*friction or stops"):
        kn.simulate(sliding_block(), t_end=1.0, method="midpoint", **FAST)


def test_bearing_friction_on_a_pendulum_joint_stops_it_at_the_energy_balance_angle():
    # Coulomb friction tau_c on the joint: between turning points q_n and q_n+1 the energy
    # lost is the friction's work, m g L (cos q_n+1 - cos q_n) = tau_c |q_n+1 - q_n|; it
    # sticks at the first turning point where m g L |sin q| <= peak tau_c
    from scipy.optimize import brentq
    g, L, q0, tau_c, peak = 9.81, 0.8, 1.0, 0.8, 1.3
    model = kn.Model("pendulum")
    world = model.add(kn.multibody.Ground("world", gravity=[0, -g, 0]))
    joint = model.add(kn.multibody.Revolute("joint", axis=[0, 0, 1], q0=q0))
    bob = model.add(kn.multibody.RigidBody("bob", mass=1.0, r_cm=[0, -L, 0]))
    bearing = model.add(kn.rotational.BearingFriction("bearing", tau_c=tau_c, peak=peak))
    probe = model.add(kn.Probe("p", quantities=["torque"]))
    model.connect(world.frame, joint.frame_a)
    model.connect(joint.frame_b, bob.frame_a)
    model.connect(bearing.support, joint.support)
    model.connect(bearing.flange, joint.axis)
    model.connect(probe.port, bearing.flange)
    res = kn.simulate(model, t_end=6.0, n_points=61, method="cvodes", rtol=1e-11,
                      atol=1e-13, **FAST)
    q, turns = q0, 0
    while g * L * abs(np.sin(q)) > peak * tau_c:
        ends = sorted([-np.sign(q) * 1e-9, -q * (1 - 1e-12)])      # on the other side
        q = brentq(lambda r, q=q: g * L * (np.cos(r) - np.cos(q)) - tau_c * abs(r - q), *ends,
                   xtol=1e-15)
        turns += 1
    kinds = [ev["kind"] for ev in res.stats["events"]]
    assert kinds[-1] == "stuck" and len(kinds) == turns
    assert abs(res["joint.q"][-1] - q) < 1e-9
    # stuck, the bearing holds the weight's torque
    assert abs(res["p.torque"][-1] + g * L * np.sin(res["joint.q"][-1])) < 1e-10


def test_friction_on_a_massless_flange_is_refused_and_files_keep_the_elements(tmp_path):
    model = kn.Model("massless")
    spring = model.add(kn.translational.Spring("spring", c=1.0))
    wall = model.add(kn.translational.Fixed("wall"))
    rub = model.add(kn.translational.Friction("rub", f_c=1.0))
    model.connect(wall.flange, spring.flange_a)
    model.connect(spring.flange_b, rub.flange)
    with pytest.raises(kn.ModelError, match="rub.*massless"):
        model.compile()
    belt = belt_model(1.0, 10.0, 2.0, 1.5, 0.5)
    belt.save(tmp_path / "belt.json")
    again = kn.load(tmp_path / "belt.json")
    assert again.components["rub"].peak == 1.5 and again.components["rub"].f_kinetic == 2.0
    a = kn.simulate(belt, t_end=1.0, n_points=11, method="rk45", **FAST)
    b = kn.simulate(again, t_end=1.0, n_points=11, method="rk45", **FAST)
    assert a.stats["events"] == b.stats["events"]
    assert_same_numbers(a.states, b.states)


@pytest.mark.parametrize("method", ["cvodes", "dop853"])
def test_gear_efficiency_loses_power_whichever_flange_drives(method):
    # a motor rotor J1 drives a load J2 through a gear (ratio r, efficiency eta) with the
    # torque T = T0 - k t. By the power balance, while the motor drives (eta of its power
    # reaches the load) a_load = c1 T, c1 = eta r / (J2 + eta r^2 J1); once T < 0 the load
    # drives the motor (eta of the load's power reaches it): a_load = c2 T,
    # c2 = r / (J1 r^2 + eta J2); stopped, the motor drives again
    J1, J2, r, eta, T0, k = 0.01, 0.5, 10.0, 0.8, 2.0, 2.0
    model = kn.Model("lossy")
    motor = model.add(kn.rotational.Inertia("motor", J=J1))
    gear = model.add(kn.rotational.IdealGear("gear", ratio=r, eta=eta))
    load = model.add(kn.rotational.Inertia("load", J=J2))
    torque = model.add(kn.rotational.Torque("torque", tau=f"{T0} - {k}*t"))
    probe = model.add(kn.Probe("p", quantities=["speed"]))
    model.connect(torque.flange, motor.flange_a)
    model.connect(motor.flange_b, gear.flange_a)
    model.connect(gear.flange_b, load.flange_a)
    model.connect(probe.port, load.flange_b)
    res = kn.simulate(model, t_end=3.0, n_points=31, method=method, rtol=1e-12, atol=1e-14,
                      **FAST)
    c1, c2 = eta * r / (J2 + eta * r ** 2 * J1), r / (J1 * r ** 2 + eta * J2)
    t1 = T0 / k
    w1 = c1 * T0 ** 2 / (2 * k)
    s_stop = np.sqrt(2 * w1 / (c2 * k))
    events = res.stats["events"]
    assert [e["kind"] for e in events] == ["flange_b driving", "flange_a driving"]
    assert abs(events[0]["t"] - t1) < 1e-9 and abs(events[1]["t"] - (t1 + s_stop)) < 1e-9
    t, s = res.t, res.t - t1
    exact = np.where(t <= t1, c1 * (T0 * t - k * t ** 2 / 2),
                     np.where(s <= s_stop, w1 - c2 * k * s ** 2 / 2,
                              -c1 * k * (s ** 2 - s_stop ** 2) / 2))
    assert np.max(np.abs(res["p.speed"] - exact)) < 1e-9


def test_a_gear_with_a_loss_on_a_joint_axis_is_refused_by_name():
    model = kn.Model("arm")
    world = model.add(kn.multibody.Ground("world", gravity=[0, -9.81, 0]))
    joint = model.add(kn.multibody.Revolute("joint", axis=[0, 0, 1], q0=0.5))
    bob = model.add(kn.multibody.RigidBody("bob", mass=1.0, r_cm=[0, -0.8, 0]))
    rotor = model.add(kn.rotational.Inertia("rotor", J=1e-3))
    gear = model.add(kn.rotational.IdealGear("gear", ratio=20.0, eta=0.7))
    model.connect(world.frame, joint.frame_a)
    model.connect(joint.frame_b, bob.frame_a)
    model.connect(rotor.flange_b, gear.flange_a)
    model.connect(gear.flange_b, joint.axis)
    with pytest.raises(kn.ModelError, match="gear.eta: a gear with a loss") as caught:
        model.compile()
    assert (caught.value.problems[0].component, caught.value.problems[0].parameter) == \
        ("gear", "eta")
    gear.eta = 1.0                                   # lossless: the rotor is armature
    assert model.compile().state_names == ["joint.q", "joint.qd"]


def msl_friction_reference(t_end):
    """Mode changes of MSL's Rotational.Examples.Friction, written apart from kinetwork: the
    three inertias' equations for each combination of modes, integrated by solve_ivp with
    its own terminal events, phase by phase. Clutch: torque +-80 on inertia3 (-+ on
    inertia2) while slipping, inertia3 and inertia2 together while stuck (the clutch holds
    J3 a - T); brake: -+800 fn(t) on inertia1 while slipping, inertia1 at rest while stuck
    (holding the spring). A holding torque beyond the limit slips the way it pushes."""
    J3, J2, J1, c, d, clutch_limit = 1.0, 0.05, 1.0, 160.0, 1.0, 80.0
    drive = lambda t: 200 * np.sin(100 * t) if t < 0.5 else 0.0      # noqa: E731
    brake_limit = lambda t: 800.0 if t >= 0.5 else 0.0               # noqa: E731
    spring = lambda y: c * (y[4] - y[2]) + d * (y[5] - y[3])         # noqa: E731

    def rates(t, y, mc, mb):
        if mc == 0:
            a3 = a2 = (drive(t) + spring(y)) / (J3 + J2)
        else:
            a3, a2 = (drive(t) + mc * clutch_limit) / J3, (spring(y) - mc * clutch_limit) / J2
        a1 = 0.0 if mb == 0 else (-spring(y) - mb * brake_limit(t)) / J1
        return [y[1], a3, y[3], a2, y[5], a1]

    def holds(t, y):
        """The torques clutch and brake hold with, were they stuck."""
        return J3 * (drive(t) + spring(y)) / (J3 + J2) - drive(t), -spring(y)

    def settle(t, y, mc, mb, fired):
        """The modes after the event of ``fired`` (or at a phase boundary: None)."""
        for who in ("clutch", "brake"):
            hold = holds(t, y)[who == "brake"]
            limit = clutch_limit if who == "clutch" else brake_limit(t)
            mode = mc if who == "clutch" else mb
            if who == fired and mode != 0:          # its slipping speed reached zero
                new = 0 if abs(hold) <= limit else np.sign(hold)
            elif (who == fired and mode == 0) or (mode == 0 and abs(hold) > limit):
                new = np.sign(hold)                 # its holding torque reached the limit
            else:
                continue
            if new != mode:
                found.append((t, who, new))
                mc, mb = (new, mb) if who == "clutch" else (mc, new)
        return mc, mb

    y = np.array([0.0, 100.0, 0.0, 90.0, 0.0, 90.0])
    t, mc, mb, found = 0.0, -1, 1, []          # slipping: w2 < w3, w1 > 0
    while t < t_end:
        stop = 0.5 if t < 0.5 else t_end
        events = []
        if mc:
            ev = lambda t, y, *_: y[3] - y[1]                              # noqa: E731
            ev.direction = -mc
        else:
            ev = lambda t, y, *_: clutch_limit - abs(holds(t, y)[0])       # noqa: E731
            ev.direction = -1
        events.append(ev)
        if mb:
            eb = lambda t, y, *_: y[5]                                     # noqa: E731
            eb.direction = -mb
        else:
            eb = lambda t, y, *_: brake_limit(t) - abs(holds(t, y)[1])     # noqa: E731
            eb.direction = -1
        events.append(eb)
        for e in events:
            e.terminal = True
        sol = solve_ivp(rates, (t, stop), y, args=(mc, mb), events=events, rtol=1e-12,
                        atol=1e-12, method="DOP853")
        t, y, fired = sol.t[-1], sol.y[:, -1].copy(), None
        if sol.status == 1:
            which = 0 if sol.t_events[0].size else 1
            t, y = sol.t_events[which][0], sol.y_events[which][0].copy()
            fired = ("clutch", "brake")[which]
        mc, mb = settle(t, y, mc, mb, fired)
        if fired == "clutch" and mc == 0:
            y[1] = y[3] = (J3 * y[1] + J2 * y[3]) / (J3 + J2)     # stuck together exactly
        if fired == "brake" and mb == 0:
            y[5] = 0.0
    return found


def test_msl_friction_example_switches_at_the_reference_times():
    import pathlib
    path = pathlib.Path(__file__).resolve().parents[2] / "models" / "msl_friction.json"
    res = kn.simulate(kn.load(path), t_end=2.0, n_points=201, method="cvodes", rtol=1e-11,
                      atol=1e-12, **FAST)
    ref = msl_friction_reference(2.0)
    assert len(ref) == 6
    # the brake is free until its normal force steps up at t = 0.5 (MSL's mode Free), and
    # then engages sliding forward: the same motion as sliding with no force, one more event
    ref.insert(3, (0.5, "brake", 1))
    kind = {0: "stuck", 1: "sliding forward", -1: "sliding backward"}
    assert [(e["component"], e["kind"]) for e in res.stats["events"]] == \
        [(who, kind[m]) for _, who, m in ref]
    assert np.max(np.abs([e["t"] for e in res.stats["events"]] - np.array(
        [t for t, _, _ in ref]))) < 1e-8
