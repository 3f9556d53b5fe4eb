"""MSL's RobotR3 (``models/robot_r3``; builders in ``tests/scenes/robot_r3.py``) against
references written apart from kinetwork.

OneAxis: an event-driven scipy model of the same drive written from MSL's equations: the
motor's current controller reduced by nodal analysis (the power stage's gain 1 + Rp1/Rp2 = 5,
the op-amp integrator's Ri C, as in tests/components/test_electrical.py), the cascade
controller, the motor rotor with bearing friction that sticks (exactly: the rotor held,
the holding torque k i - tau_spring checked against peak Rv0) and slides (Rv0 sign(w) +
Rv1 w), the gear's spring-damper and the load through the ratio, and MSL's KinematicPTP
written out in its phases; integrated by LSODA (stiff: the current loop) from event to event (sticking where the motor
speed crosses zero with the holding torque within the static limit, breaking away where it
reaches it) and across the path's phase changes."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import kinetwork as kn
from scenes import robot_r3

OPT = {"rtol": 1e-10, "atol": 1e-10, "jit": False}
METHOD, RTOL = "LSODA", 1e-11




def path(t, q0, q1, v, a):
    """Trapezoidal speed profile (acceleration a up to speed v, then braking): q, qd."""
    dq = q1 - q0
    ta = min(v / a, math.sqrt(abs(dq) / a))
    v = a * ta
    tv = abs(dq) / v
    te = tv + ta
    sgn = math.copysign(1.0, dq)
    if t < ta:
        s, sd = a * t * t / 2, a * t
    elif t < tv:
        s, sd = a * ta * ta / 2 + v * (t - ta), v
    elif t < te:
        s, sd = abs(dq) - a * (te - t)**2 / 2, a * (te - t)
    else:
        s, sd = abs(dq), 0.0
    return q0 + sgn * s, sgn * sd, (ta, tv, te)


class OneAxis:
    """The drive of RobotR3.OneAxis as an ODE in (i, v_C, phi_m, w_m, phi_L, w_L, x_PI) with
    the friction's mode (+1, -1 sliding, 0 stuck)."""

    def __init__(self):
        p, a, m = robot_r3.ONE_AXIS, robot_r3.AXIS1, robot_r3.MOTOR
        self.kp, self.ks, self.Ts = p["kp"], p["ks"], p["Ts"]
        self.n, self.c, self.d = a["ratio"], a["c"], a["cd"]
        self.Rv0, self.Rv1, self.peak = a["Rv0"], a["Rv1"], 1.0
        D, w = m["D"], a["w"]
        self.k, self.J = m["k"], m["J"]
        self.La, self.Ra, self.C, self.Ri = 250 / (2 * D * w), 250.0, 0.004 * D / w, 10.0
        self.JL = 1.3 * p["mLoad"]
        self.q = (math.radians(p["startAngle"]), math.radians(p["endAngle"]),
                  p["refSpeedMax"], p["refAccMax"])

    def parts(self, t, x):
        pm, wm, pL, wL, xi = x[2:]
        q, qd, _ = path(t, *self.q)
        e = self.n * qd + self.kp * (self.n * q - pm) - wm
        i_ref = self.ks * (e + xi)
        tau_s = self.c * (pm - self.n * pL) + self.d * (wm - self.n * wL)
        return e, i_ref, tau_s

    def rhs(self, t, x, mode):
        i, vC, wm, wL = x[0], x[1], x[3], x[5]
        e, i_ref, tau_s = self.parts(t, x)
        if mode == 0:
            dwm = 0.0
        else:
            dwm = (self.k * i - tau_s - mode * self.Rv0 - self.Rv1 * wm) / self.J
        return [(-5 * vC - self.Ra * i - self.k * wm) / self.La,
                (i - i_ref) / (self.Ri * self.C), wm if mode else 0.0, dwm, wL,
                self.n * tau_s / self.JL, e / self.Ts]

    def holding(self, t, x):
        return self.k * x[0] - self.parts(t, x)[2]

    def solve(self, t_out):
        """The states at ``t_out`` and the events (t, new mode)."""
        breaks = list(path(0.0, *self.q)[2])
        x, t0, mode, events, out = np.zeros(7), 0.0, 0, [], []
        t_end = t_out[-1]
        while t0 < t_end:
            t1 = min([b for b in breaks if b > t0 + 1e-12] + [t_end])
            if mode == 0:
                def ev(t, x, mode):
                    return abs(self.holding(t, x)) - self.peak * self.Rv0
                ev.direction = 1
            else:
                def ev(t, x, mode):
                    return x[3]
                ev.direction = -mode
            ev.terminal = True
            sol = solve_ivp(self.rhs, (t0, t1), x, method=METHOD, rtol=RTOL, atol=1e-12,
                            args=(mode,), events=ev, dense_output=True)
            te = sol.t[-1]
            out += [(tk, *sol.sol(tk)) for tk in t_out if t0 <= tk <= te
                    and (not out or tk > out[-1][0])]
            x, t0 = sol.y[:, -1].copy(), te
            if sol.status == 1:
                if mode == 0:
                    mode = 1 if self.holding(t0, x) > 0 else -1
                else:
                    x[3] = 0.0
                    hold = self.holding(t0, x)
                    mode = 0 if abs(hold) <= self.peak * self.Rv0 else (1 if hold > 0 else -1)
                events.append((t0, mode))
        return np.array(out), events


@pytest.fixture(scope="module")
def one_axis():
    system = kn.load(robot_r3.FOLDER / "OneAxis.json").compile()
    t = np.linspace(0.0, 1.6, 33)
    res = kn.simulate(system, t_end=1.6, n_points=33, **OPT)
    return res, OneAxis().solve(t)


def test_one_axis_load_angle_and_motor_current_match_the_event_driven_reference(one_axis):
    res, (ref, events) = one_axis
    angle, current = res["load_angle.angle"], res["axis.motor.current.value"]
    assert angle[-1] == pytest.approx(math.radians(120), abs=2e-3)   # where the path ends
    scale = np.max(np.abs(ref[:, 1]))
    np.testing.assert_allclose(angle, ref[:, 5], atol=1e-6 * np.max(np.abs(ref[:, 5])))
    np.testing.assert_allclose(current, ref[:, 1], atol=1e-6 * scale)
    got = [(e["t"], e["kind"]) for e in res.stats["events"]]
    names = {1: "sliding forward", -1: "sliding backward", 0: "stuck"}
    assert [k for _, k in got] == [names[m] for _, m in events]
    np.testing.assert_allclose([t for t, _ in got], [t for t, _ in events], atol=1e-8)


def test_the_robot_files_are_what_the_builders_write(tmp_path):
    robot_r3.write_models(tmp_path)
    for path in robot_r3.FOLDER.glob("*.json"):
        assert (tmp_path / path.name).read_bytes() == path.read_bytes(), path.name


def _ptp_run(**params):
    m = kn.Model("ptp")
    for q in ("q", "qd", "qdd"):
        m.add(kn.signals.KinematicPTP(f"p_{q}", quantity=q, **params))
        m.add(kn.Probe(f"pr_{q}", quantities=["value"]))
        m.connect(f"p_{q}.y", f"pr_{q}.port")
    return kn.simulate(m, t_end=1.5, n_points=151, method="rk45", jit=False)


def test_kinematic_ptp_is_the_trapezoidal_profile_and_synchronises_axes():
    """One axis: the profile written out by hand (``path``); with a second, slower axis the
    first follows the second's timing scaled to its own distance, as MSL's KinematicPTP."""
    res = _ptp_run(q_begin=[0.0], q_end=[2.0944], qd_max=[3.0], qdd_max=[10.0])
    ref = np.array([path(t, 0.0, 2.0944, 3.0, 10.0)[:2] for t in res.t])
    np.testing.assert_allclose(res["pr_q.value"], ref[:, 0], atol=1e-12)
    np.testing.assert_allclose(res["pr_qd.value"], ref[:, 1], atol=1e-12)
    acc = np.gradient(ref[:, 1], res.t)
    inside = np.abs(res["pr_qdd.value"] - acc) < 1e-9
    assert inside.sum() > 100                        # the acceleration, away from its jumps
    # axis 2 of a pair: 1 -> 0.5 limited by 3 rad/s and 10 rad/s^2 alone, but axis 1 (2 rad
    # at 1 rad/s, 2 rad/s^2) is slower: both move on axis 1's normalised path
    res = _ptp_run(q_begin=[0.0, 1.0], q_end=[2.0, 0.5], qd_max=[1.0, 3.0],
                   qdd_max=[2.0, 10.0], axis=2)
    slow = np.array([path(t, 0.0, 2.0, 1.0, 2.0)[:2] for t in res.t])
    np.testing.assert_allclose(res["pr_q.value"], 1.0 - 0.25 * slow[:, 0], atol=1e-12)
    np.testing.assert_allclose(res["pr_qd.value"], -0.25 * slow[:, 1], atol=1e-12)


def test_kinematic_ptp_refuses_axes_that_do_not_match():
    with pytest.raises(kn.ModelError, match=r"ptp.qd_max\[0\]: must be > 0"):
        kn.signals.KinematicPTP("ptp", q_begin=0, q_end=1, qd_max=0, qdd_max=1)
    m = kn.Model("m")
    m.add(kn.signals.KinematicPTP("ptp", q_begin=[0, 0], q_end=[1], qd_max=1, qdd_max=1))
    with pytest.raises(kn.ModelError, match=r"q_end: 1 axes, but q_begin has 2"):
        m.validate()


def pinocchio_r3(m_load, r_load):
    """MSL's MechanicalStructure built in Pinocchio from MSL's numbers (``BODIES``): joint k
    at the end of body k - 1 (frames are never rotated in it), body k and, on the last
    joint, the load."""
    import pinocchio as pin
    model = pin.Model()
    model.gravity.linear = np.array([0.0, -9.81, 0.0])
    parent, offset = 0, np.array(robot_r3.BODIES[0][1], float)
    kinds = {(0, 1, 0): pin.JointModelRY, (1, 0, 0): pin.JointModelRX}
    for k, (axis, r, r_cm, mass, (i11, i22, i33, i21)) in enumerate(robot_r3.BODIES[1:], 1):
        joint = model.addJoint(parent, kinds[tuple(axis)](), pin.SE3(np.eye(3), offset),
                               f"r{k}")
        inertia = np.array([[i11, i21, 0], [i21, i22, 0], [0, 0, i33]])
        model.appendBodyToJoint(joint, pin.Inertia(mass, np.array(r_cm, float), inertia),
                                pin.SE3.Identity())
        parent, offset = joint, np.array(r, float)
    model.appendBodyToJoint(parent, pin.Inertia(m_load, np.array(r_load, float),
                                                np.eye(3) * 0.001), pin.SE3.Identity())
    return model


def test_r3_mechanics_match_pinocchio():
    """Mass matrix, Coriolis and gravity terms of MechanicalStructure.json (FullRobot's load)
    against Pinocchio's CRBA and RNEA at random states."""
    import pinocchio as pin
    load = robot_r3.FULL["rLoad"]
    params = {"mLoad": 15.0, "rLoad_x": load[0], "rLoad_y": load[1], "rLoad_z": load[2]}
    system = kn.load(robot_r3.FOLDER / "MechanicalStructure.json").compile()
    model = pinocchio_r3(15.0, load)
    data = model.createData()
    rng = np.random.default_rng(3)
    for _ in range(5):
        q, qd = rng.uniform(-2, 2, 6), rng.uniform(-2, 2, 6)
        M, V, G = system.dynamics_terms(q, qd, params)
        M_pin = pin.crba(model, data, q)
        M_pin = np.triu(M_pin) + np.triu(M_pin, 1).T
        G_pin = pin.computeGeneralizedGravity(model, data, q)
        C_pin = pin.rnea(model, data, q, qd, np.zeros(6)) - G_pin
        np.testing.assert_allclose(M, M_pin, atol=1e-10)
        np.testing.assert_allclose(G, G_pin, atol=1e-9)
        np.testing.assert_allclose(V, C_pin, atol=1e-9)


class FullRobotSmooth:
    """RobotR3.FullRobot with tanh-regularised friction, written apart from kinetwork: the
    mechanics by Pinocchio (CRBA and RNEA of ``pinocchio_r3``), each axis's motor current
    loop, cascade controller and gear as in ``OneAxis`` (axes 1-3 elastic with friction on
    the motor, axes 4-6 rigid: the rotor's J n^2 on the joint's diagonal, friction on the
    joint), and the six axes' synchronised KinematicPTP (one normalised trapezoid)."""

    def __init__(self, w_s):
        import pinocchio as pin
        self.pin, self.w_s = pin, w_s
        f = robot_r3.FULL
        self.model = pinocchio_r3(f["mLoad"], f["rLoad"])
        self.data = self.model.createData()
        self.q0 = np.radians(f["start"])
        self.dq = np.radians(f["end"]) - self.q0
        self.sd = min(v / abs(d) for v, d in zip(f["speed"], self.dq))
        self.sdd = min(a / abs(d) for a, d in zip(f["acc"], self.dq))
        self.axes = [{**robot_r3.MOTOR, "peak": 1.0, **a} for a in robot_r3.AXES]
        self.rotor = np.array([0, 0, 0] + [a["J"] * a["ratio"]**2 for a in self.axes[3:]])

    def friction(self, a, w):
        return a["Rv0"] * np.tanh(w / self.w_s) + a["Rv1"] * w

    def rhs(self, t, x):
        q, qd = x[:6], x[6:12]
        motor, elec, pi = x[12:18].reshape(3, 2), x[18:30].reshape(6, 2), x[30:36]
        r, rd, _ = path(t, 0.0, 1.0, self.sd, self.sdd)
        q_ref, qd_ref = self.q0 + self.dq * r, self.dq * rd
        dx, tau = np.zeros(36), np.zeros(6)
        for k, a in enumerate(self.axes):
            n = a["ratio"]
            pm, wm = motor[k] if k < 3 else (n * q[k], n * qd[k])
            e = n * qd_ref[k] + 5.0 * (n * q_ref[k] - pm) - wm
            i, vC = elec[k]
            La, C = 250 / (2 * a["D"] * a["w"]), 0.004 * a["D"] / a["w"]
            dx[18 + 2 * k] = (-5 * vC - 250 * i - a["k"] * wm) / La
            dx[19 + 2 * k] = (i - 0.5 * (e + pi[k])) / (10 * C)
            dx[30 + k] = e / 0.05
            if k < 3:
                tau_s = a["c"] * (pm - n * q[k]) + a["cd"] * (wm - n * qd[k])
                dx[12 + 2 * k] = wm
                dx[13 + 2 * k] = (a["k"] * i - tau_s - self.friction(a, wm)) / a["J"]
                tau[k] = n * tau_s
            else:
                tau[k] = n * a["k"] * i - self.friction(a, qd[k])
        pin = self.pin
        M = pin.crba(self.model, self.data, q)
        M = np.triu(M) + np.triu(M, 1).T + np.diag(self.rotor)
        h = pin.rnea(self.model, self.data, q, qd, np.zeros(6))
        dx[:6], dx[6:12] = qd, np.linalg.solve(M, tau - h)
        return dx

    def solve(self, t_out):
        x0 = np.zeros(36)
        x0[:6] = self.q0
        x0[12:18] = np.ravel([[a["ratio"] * q, 0.0] for a, q in zip(self.axes, self.q0)][:3])
        sol = solve_ivp(self.rhs, (0, t_out[-1]), x0, method="LSODA", rtol=1e-11, atol=1e-12,
                        t_eval=t_out)
        return sol.y[:6].T


def test_full_robot_with_regularised_friction_follows_the_independent_model():
    """The whole scene's coupling (six drives on Pinocchio's mechanics) over its first 0.06 s,
    where every axis accelerates from rest; the friction regularised (w_s = 0.1 rad/s) so
    the reference is smooth."""
    t = np.linspace(0.0, 0.06, 7)
    res = kn.simulate(robot_r3.full_robot_regularised(0.1).compile(), t_end=0.06, n_points=7,
                      **OPT)
    ref = FullRobotSmooth(0.1).solve(t)
    angles = np.array([res[f"joint{k}.angle"] for k in range(1, 7)]).T
    assert np.max(np.abs(angles[-1] - angles[0])) > 0.01           # the robot moves
    np.testing.assert_allclose(angles, ref, atol=1e-6 * np.max(np.abs(ref)))


class FullRobotStiction(FullRobotSmooth):
    """FullRobot as written, with stiction, event-driven as ``OneAxis``: each bearing's mode
    +1 / -1 (sliding) or 0 (stuck: the motor held on axes 1-3; the joint held on axes 4-6,
    its acceleration zero and the others from the reduced mass matrix); the holding torque
    against peak Rv0 decides break-away and sticking, and the start's modes settle as the
    friction helper's do (every element stuck unless it cannot hold)."""

    def __init__(self):
        super().__init__(1.0)

    def terms(self, t, x, modes):
        q, qd = x[:6], x[6:12]
        motor, elec, pi = x[12:18].reshape(3, 2), x[18:30].reshape(6, 2), x[30:36]
        r, rd, _ = path(t, 0.0, 1.0, self.sd, self.sdd)
        q_ref, qd_ref = self.q0 + self.dq * r, self.dq * rd
        dx, tau, hold = np.zeros(36), np.zeros(6), np.zeros(6)
        for k, a in enumerate(self.axes):
            n = a["ratio"]
            pm, wm = motor[k] if k < 3 else (n * q[k], n * qd[k])
            e = n * qd_ref[k] + 5.0 * (n * q_ref[k] - pm) - wm
            i, vC = elec[k]
            La, C = 250 / (2 * a["D"] * a["w"]), 0.004 * a["D"] / a["w"]
            dx[18 + 2 * k] = (-5 * vC - 250 * i - a["k"] * wm) / La
            dx[19 + 2 * k] = (i - 0.5 * (e + pi[k])) / (10 * C)
            dx[30 + k] = e / 0.05
            if k < 3:
                tau_s = a["c"] * (pm - n * q[k]) + a["cd"] * (wm - n * qd[k])
                hold[k] = a["k"] * i - tau_s
                if modes[k]:
                    dx[12 + 2 * k] = wm
                    dx[13 + 2 * k] = (hold[k] - modes[k] * a["Rv0"] - a["Rv1"] * wm) / a["J"]
                tau[k] = n * tau_s
            else:
                tau[k] = n * a["k"] * i
                if modes[k]:
                    tau[k] -= modes[k] * a["Rv0"] + a["Rv1"] * qd[k]
        pin = self.pin
        M = pin.crba(self.model, self.data, q)
        M = np.triu(M) + np.triu(M, 1).T + np.diag(self.rotor)
        rhs = tau - pin.rnea(self.model, self.data, q, qd, np.zeros(6))
        free = [k for k in range(6) if k < 3 or modes[k]]
        qdd = np.zeros(6)
        qdd[free] = np.linalg.solve(M[np.ix_(free, free)], rhs[free])
        for k in range(3, 6):
            if not modes[k]:
                hold[k] = rhs[k] - M[k] @ qdd
        dx[:6], dx[6:12] = qd, qdd
        for k in range(3, 6):
            if not modes[k]:
                dx[k] = 0.0
        return dx, hold

    def speed(self, x, k):
        return x[13 + 2 * k] if k < 3 else x[6 + k]

    def solve(self, t_out):
        x = np.zeros(36)
        x[:6] = self.q0
        x[12:18] = np.ravel([[a["ratio"] * q, 0.0] for a, q in zip(self.axes, self.q0)][:3])
        modes, t0, out, events = [0] * 6, 0.0, [], []
        limit = [a["peak"] * a["Rv0"] for a in self.axes]

        def settle(t, x):
            for _ in range(12):
                _, hold = self.terms(t, x, modes)
                change = [k for k in range(6) if modes[k] == 0 and abs(hold[k]) > limit[k]]
                if not change:
                    return
                k = change[0]
                modes[k] = 1 if hold[k] > 0 else -1
                events.append((t, k, modes[k]))
        settle(0.0, x)
        while t0 < t_out[-1]:
            evs = []
            for k in range(6):
                if modes[k]:
                    f = lambda t, x, k=k, t0=t0: (self.speed(x, k) if t > t0 + 1e-9
                                                  else float(modes[k]))
                    f.direction = -modes[k]
                else:
                    f = lambda t, x, k=k: abs(self.terms(t, x, modes)[1][k]) - limit[k]
                    f.direction = 1
                f.terminal = True
                evs.append(f)
            breaks = [b for b in path(0.0, 0.0, 1.0, self.sd, self.sdd)[2] if b > t0 + 1e-12]
            t1 = min(breaks + [t_out[-1]])
            sol = solve_ivp(lambda t, x: self.terms(t, x, modes)[0], (t0, t1), x,
                            method="LSODA", rtol=1e-11, atol=1e-12, events=evs,
                            dense_output=True)
            te = sol.t[-1]
            out += [(tk, *sol.sol(tk)[:6]) for tk in t_out if t0 <= tk <= te
                    and (not out or tk > out[-1][0])]
            x, t0 = sol.y[:, -1].copy(), te
            if sol.status == 1:
                k = next(j for j in range(6) if len(sol.t_events[j]))
                if modes[k] == 0:
                    _, hold = self.terms(t0, x, modes)
                    modes[k] = 1 if hold[k] > 0 else -1
                    events.append((t0, k, modes[k]))
                    settle(t0, x)
                    continue
                if modes[k]:
                    if k < 3:
                        x[13 + 2 * k] = 0.0
                    else:
                        x[6 + k] = 0.0
                    modes[k] = 0
                    _, hold = self.terms(t0, x, modes)
                    if abs(hold[k]) > limit[k]:
                        modes[k] = 1 if hold[k] > 0 else -1
                    events.append((t0, k, modes[k]))
                settle(t0, x)
        return np.array(out)[:, 1:], events


def test_full_robot_breaks_away_as_the_event_driven_model():
    """FullRobot as written (stiction): its first 10 ms, in which the six bearings break away
    or stick again (seven mode changes), against ``FullRobotStiction``: event times to 1e-9 s,
    joint angles to 1e-9 rad."""
    system = kn.load(robot_r3.FOLDER / "FullRobot.json").compile()
    t = np.linspace(0.0, 0.01, 11)
    res = kn.simulate(system, t_end=0.01, n_points=11, **OPT)
    ref, events = FullRobotStiction().solve(t)
    angles = np.array([res[f"joint{k}.angle"] for k in range(1, 7)]).T
    np.testing.assert_allclose(angles, ref, atol=1e-9)
    names = {1: "sliding forward", -1: "sliding backward", 0: "stuck"}
    expected = [(t_e, f"axis{k + 1}.gear.bearingFriction", names[m])
                for t_e, k, m in events if t_e > 0]      # the start's modes are no events
    got = [(e["t"], e["component"], e["kind"]) for e in res.stats["events"]]
    assert [g[1:] for g in got] == [e[1:] for e in expected]
    np.testing.assert_allclose([g[0] for g in got], [e[0] for e in expected], atol=1e-9)
    assert len(got) >= 6
