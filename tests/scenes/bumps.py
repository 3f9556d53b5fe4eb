"""Short inputs and contacts, as kinetwork models and as hand-written equations integrated
by scipy's DOP853 piecewise between their discontinuities (or from event to event): the
references of the time-event and state-event tests.

Scenes
------
quarter car   a body (300 kg) on a suspension spring-damper over a wheel (40 kg) on a tire
              spring, driven over a 0.1 s road bump at t = 0.5 s: the bump as an expression
              in t (``BUMP``, an exact Position), as a Table of breakpoints (or of 301 rows)
              or with steps into a filtered Position, or the road flat and a force pulse
              on the body
ball          a ball dropped onto a penalty contact written as ``if_else`` on its height
"""

import numpy as np
from scipy.integrate import solve_ivp

import kinetwork as kn
from kinetwork.components.oned import BESSEL

MW, MB, KT, KS, CS, H = 40.0, 300.0, 2e5, 2e4, 1.5e3, 0.05
T_END = 3.0
BUMP = "if_else(t < 0.5, 0, if_else(t < 0.6, h/2*(1 - cos(2*pi*(t - 0.5)/0.1)), 0))"
#: a triangle 0.1 s wide, and a plateau with steps at both ends
TRIANGLE = [[0.0, 0.0], [0.5, 0.0], [0.55, H], [0.6, 0.0], [T_END, 0.0]]
PLATEAU = [[0.0, 0.0], [0.5, 0.0], [0.5, H], [0.6, H], [0.6, 0.0], [T_END, 0.0]]
#: the triangle sampled every 10 ms: a long table (an interpolant), the same function
LONG = np.linspace(0.0, T_END, 301)
LONG_TRIANGLE = np.column_stack([LONG, np.interp(LONG, *np.array(TRIANGLE).T)]).tolist()
#: the force pulse on the body: F for 20 ms from T0
PULSE_F, PULSE_T0, PULSE_W = 3000.0, 0.5, 0.02
F_CRIT = 50.0
TIGHT = {"method": "DOP853", "rtol": 1e-13, "atol": 1e-15}


def quarter_car(road="expression"):
    """The quarter car over the bump: ``road`` "expression" (``BUMP`` in an exact Position),
    "table" (TRIANGLE), "long_table" (LONG_TRIANGLE, an interpolant) or "steps" (PLATEAU)
    in a Table into a filtered Position, "pulse"
    (the road flat, a force pulse on the body written in t), "pulse_blocks" (the same pulse
    as two Step blocks into a Force)."""
    m = kn.Model("quarter_car", parameters={"h": H})
    m.add(kn.translational.Spring("tire", c=KT))
    m.add(kn.translational.Mass("wheel", m=MW))
    m.add(kn.translational.SpringDamper("susp", c=KS, d=CS))
    m.add(kn.translational.Mass("body", m=MB))
    m.connect("tire.flange_b", "wheel.flange_a")
    m.connect("wheel.flange_b", "susp.flange_a")
    m.connect("susp.flange_b", "body.flange_a")
    if road == "expression":
        m.add(kn.translational.Position("road", s_ref=BUMP))
    elif road in ("table", "long_table", "steps"):
        m.add(kn.translational.Position("road", exact=False, f_crit=F_CRIT))
        m.add(kn.signals.Table("profile", table={"table": TRIANGLE, "steps": PLATEAU,
                                                 "long_table": LONG_TRIANGLE}[road]))
        m.connect("profile.y", "road.u")
    else:
        m.add(kn.translational.Fixed("road"))
        if road == "pulse":
            m.add(kn.translational.Force("push", f=f"if_else(t < {PULSE_T0}, 0, if_else("
                                                   f"t < {PULSE_T0 + PULSE_W}, {PULSE_F}, 0))"))
        else:
            m.add(kn.translational.Force("push"))
            m.add(kn.signals.Step("on", height=PULSE_F, start_time=PULSE_T0))
            m.add(kn.signals.Step("off", height=-PULSE_F, start_time=PULSE_T0 + PULSE_W))
            m.add(kn.signals.Add("sum"))
            m.connect("on.y", "sum.u1")
            m.connect("off.y", "sum.u2")
            m.connect("sum.y", "push.u")
        m.connect("push.flange", "body.flange_a")
    m.connect("road.flange", "tire.flange_a")
    return m


def quarter_car_reference(t_out, road="expression"):
    """The states of ``quarter_car(road)`` on ``t_out`` (the filter's position and speed
    first for the tables, then wheel s, v, body s, v), integrated stretch by stretch between
    the road's breakpoints, each stretch with the branch it lies in."""
    breaks = {"expression": [0.5, 0.6], "table": [0.5, 0.55, 0.6],
              "long_table": [0.5, 0.55, 0.6], "steps": [0.5, 0.6],
              "pulse": [PULSE_T0, PULSE_T0 + PULSE_W],
              "pulse_blocks": [PULSE_T0, PULSE_T0 + PULSE_W]}[road]
    filtered = road in ("table", "long_table", "steps")
    w = 2 * np.pi * F_CRIT
    af, bf = BESSEL

    def rhs(t, y, mid):
        on = 0.5 <= mid < 0.6
        if road in ("table", "long_table"):
            u = np.interp(t, *np.array(TRIANGLE).T)
        elif road == "steps":
            u = H if on else 0.0
        elif road == "expression":
            u = H / 2 * (1 - np.cos(2 * np.pi * (t - 0.5) / 0.1)) if on else 0.0
        else:
            u = 0.0
        if filtered:
            pos, vel, zw, vw, zb, vb = y
            filter_rates = [vel, ((u - pos) * w - af * vel) * w / bf]
            r = pos
        else:
            zw, vw, zb, vb = y
            filter_rates, r = [], u
        pushed = road.startswith("pulse") and PULSE_T0 <= mid < PULSE_T0 + PULSE_W
        force = PULSE_F if pushed else 0.0
        fs = KS * (zb - zw) + CS * (vb - vw)
        return [*filter_rates, vw, (fs - KT * (zw - r)) / MW, vb, (force - fs) / MB]
    return _piecewise(rhs, np.zeros(6 if filtered else 4), t_out, breaks)


def _piecewise(rhs, y0, t_out, breaks):
    """``rhs(t, y, mid)`` integrated from t_out[0] across ``breaks``, each stretch with its
    middle ``mid`` (which branch), by DOP853 at tight tolerance: the states on t_out."""
    edges = [t_out[0], *[b for b in breaks if t_out[0] < b < t_out[-1]], t_out[-1]]
    y, rows = np.asarray(y0, dtype=float), []
    for a, b in zip(edges, edges[1:]):
        inside = t_out[(t_out >= a) & (t_out < b)]
        sol = solve_ivp(rhs, (a, b), y, t_eval=np.append(inside, b), args=((a + b) / 2,),
                        **TIGHT)
        rows.append(sol.y.T[:-1])
        y = sol.y[:, -1]
    rows.append(y[None, :])
    return np.vstack(rows)


# -- a ball on a penalty contact written as if_else on its height -----------------------------
BALL_M, BALL_K, BALL_D, BALL_G, BALL_H = 0.5, 1e4, 5.0, 9.81, 1.0
CONTACT = "if_else(s < 0, -k*s - d*v, 0)"


def ball(contact=CONTACT):
    """A ball dropped from BALL_H onto a spring-damper contact that acts while s < 0, written
    as an expression of its height and speed (sensors into an Expression into a Force)."""
    m = kn.Model("ball", parameters={"k": BALL_K, "d": BALL_D})
    m.add(kn.translational.Mass("ball", m=BALL_M, s0=BALL_H))
    m.add(kn.translational.Force("weight", f=-BALL_M * BALL_G))
    m.add(kn.translational.Force("contact"))
    m.add(kn.translational.PositionSensor("height"))
    m.add(kn.translational.SpeedSensor("speed"))
    m.add(kn.signals.Expression("law", expression=contact, names=["s", "v"]))
    for a, b in [("weight.flange", "ball.flange_a"), ("contact.flange", "ball.flange_a"),
                 ("height.flange", "ball.flange_a"), ("speed.flange", "ball.flange_a"),
                 ("height.y", "law.u1"), ("speed.y", "law.u2"), ("law.y", "contact.u")]:
        m.connect(a, b)
    return m


def ball_reference(t_out):
    """(states on t_out, contact times): the ball integrated from event to event, each
    flight and each contact with its own law, the events located by DOP853's root finder
    at tight tolerance."""
    def flight(t, y):
        return [y[1], -BALL_G]

    def contact(t, y):
        return [y[1], -BALL_G + (-BALL_K * y[0] - BALL_D * y[1]) / BALL_M]

    def height(t, y):
        return y[0]
    height.terminal = True
    y, t, in_contact, rows, events = np.array([BALL_H, 0.0]), t_out[0], False, [], []
    done = 0
    while t < t_out[-1]:
        height.direction = 1 if in_contact else -1
        ahead = t_out[done:]
        sol = solve_ivp(contact if in_contact else flight, (t, t_out[-1]), y,
                        events=height, dense_output=True, **TIGHT)
        end = sol.t_events[0][0] if sol.status == 1 else t_out[-1]
        reached = ahead[ahead < end] if sol.status == 1 else ahead
        if len(reached):                # a contact may be shorter than the output spacing
            rows.extend(sol.sol(reached).T)
        done += len(reached)
        if sol.status != 1:
            break
        t, y = end, sol.y_events[0][0]
        y[0] = 0.0
        events.append(end)
        in_contact = not in_contact
    return np.array(rows), np.array(events)
