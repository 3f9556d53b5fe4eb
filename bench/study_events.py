"""Events: what stopping at an input's breakpoints and at a contact costs, and what it buys.

Scenes (``tests/scenes/bumps.py``): the quarter car over a 0.1 s road bump written as
``if_else`` on t (3 s), and a ball dropped onto a penalty contact written as ``if_else`` on
its height (3 s, 8 contacts). Each run with the default settings (rtol 1e-6), every method
of ``kn.METHODS`` that takes the scene (RK4 at 1 ms), against the scene's reference at rtol
1e-13 (DOP853 piecewise across the bump's edges; from contact to contact for the ball): the
largest error of the body's (the ball's) height, and the wall time, as a ratio to the peer's
in the same run: scipy's ``solve_ivp`` DOP853 on the hand-written equations at rtol 1e-6,
told where the bump's edges are (integrated piecewise) and locating the contacts with its
own event function. The same scene with the relation in ``noEvent`` is run too: what the
default did before events (the bump stepped over; the contact's kinks left to the error
control).

Run: ``.venv/bin/python bench/study_events.py [--quick]``; writes results/study_events.md.
"""

import argparse
import sys

import numpy as np
from scipy.integrate import solve_ivp

from common import load, machine, table, timed, write_markdown
from scenes import bumps

import kinetwork as kn

T_END = 3.0


def peer_quarter_car(t):
    """scipy DOP853 at rtol 1e-6 on the hand-written quarter car, piecewise across the
    bump's edges: the body's height on t."""
    def rhs(time, y, mid):
        on = 0.5 <= mid < 0.6
        r = bumps.H / 2 * (1 - np.cos(2 * np.pi * (time - 0.5) / 0.1)) if on else 0.0
        zw, vw, zb, vb = y
        fs = bumps.KS * (zb - zw) + bumps.CS * (vb - vw)
        return [vw, (fs - bumps.KT * (zw - r)) / bumps.MW, vb, -fs / bumps.MB]
    y, out = np.zeros(4), []
    for a, b in [(0.0, 0.5), (0.5, 0.6), (0.6, T_END)]:
        inside = t[(t >= a) & (t < b)] if b < T_END else t[t >= a]
        sol = solve_ivp(rhs, (a, b), y, method="DOP853", rtol=1e-6, atol=1e-8,
                        t_eval=inside if b == T_END else np.append(inside, b),
                        args=((a + b) / 2,))
        out.append(sol.y[2] if b == T_END else sol.y[2][:-1])
        y = sol.y[:, -1]
    return np.concatenate(out)


def peer_ball(t):
    """scipy DOP853 at rtol 1e-6 on the hand-written ball, its contacts located by its own
    event function: the height on t."""
    def flight(_, y):
        return [y[1], -bumps.BALL_G]

    def contact(_, y):
        return [y[1], -bumps.BALL_G + (-bumps.BALL_K * y[0] - bumps.BALL_D * y[1]) / bumps.BALL_M]

    def height(_, y):
        return y[0]
    height.terminal = True
    y, now, inside, done, out = np.array([bumps.BALL_H, 0.0]), 0.0, False, 0, []
    while now < T_END:
        height.direction = 1 if inside else -1
        sol = solve_ivp(contact if inside else flight, (now, T_END), y, method="DOP853",
                        rtol=1e-6, atol=1e-8, events=height, dense_output=True)
        end = sol.t_events[0][0] if sol.status == 1 else T_END
        ahead = t[done:]
        reached = ahead[ahead < end] if sol.status == 1 else ahead
        out.extend(sol.sol(reached)[0])
        done += len(reached)
        if sol.status != 1:
            break
        now, y, inside = end, sol.y_events[0][0], not inside
        y[0] = 0.0
    return np.array(out)


def scene_rows(name, model, literal, reference, peer, column, methods):
    t = np.linspace(0.0, T_END, 1001)
    ref = reference(t)
    peer_time, peer_value = timed(lambda: peer(t))
    peer_error = float(np.max(np.abs(peer_value - ref)))
    rows = [(name, "scipy DOP853 (peer, told the events)", f"{peer_error:.1e}",
             f"{peer_time * 1e3:.1f}", "1")]
    for label, m in (("", model), (" in noEvent", literal)):
        system = m.compile()
        for method in methods:
            step = 1e-3 if method == "rk" else None
            try:
                seconds, res = timed(lambda: kn.simulate(system, t_end=T_END, method=method,
                                                         step=step))
            except (kn.ModelError, kn.SimulationError) as exc:
                rows.append((name, method + label, f"refused/failed: {exc}"[:60], "", ""))
                continue
            error = float(np.max(np.abs(res[column] - ref)))
            rows.append((name, method + label, f"{error:.1e}", f"{seconds * 1e3:.1f}",
                         f"{seconds / peer_time:.2g}"))
            if label:
                break                   # the literal run: once, to show what it misses
    return rows


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="auto and rk45 only")
    args = parser.parse_args()
    methods = ["auto", "rk45"] if args.quick else \
        [m for m in kn.METHODS if m != "midpoint"]
    rows = scene_rows(
        "quarter car", bumps.quarter_car(), _literal_car(),
        lambda t: bumps.quarter_car_reference(t)[:, 2], peer_quarter_car, "body.s", methods)
    rows += scene_rows(
        "ball", bumps.ball(), bumps.ball(f"noEvent({bumps.CONTACT})"),
        lambda t: bumps.ball_reference(t)[0][:, 0], peer_ball, "ball.s", methods)
    text = "\n\n".join([
        "# Events: their cost and what they buy",
        f"{machine()}; {load()}. Error: largest height error [m] over 3 s against the "
        "scene's reference at rtol 1e-13; time: median wall time of a run of the compiled "
        "model (JIT as by default), and its ratio to the peer's in the same run.",
        table(["scene", "run", "error [m]", "time [ms]", "/ peer"], rows)])
    print(text)
    write_markdown("study_events", text)
    return 0


def _literal_car():
    model = bumps.quarter_car()
    model.components["road"].set_param("s_ref", f"noEvent({bumps.BUMP})")
    return model


if __name__ == "__main__":
    sys.exit(main())
