"""MSL's RobotR3.FullRobot (issue 16): wall time of its 2 s run with stiction (events) against
the same scene with its bearing friction regularised by tanh (no events), and the states
before and after structural analysis.

The model is ``models/robot_r3/FullRobot.json`` (six axes: the op-amp current controller of
each motor, gears with elasticity on axes 1-3, stiction on every bearing, P-PI cascade
control, KinematicPTP path planning, the six-joint mechanics). The regularised scene
replaces each BearingFriction by -(Rv0 tanh(w / w_s) + Rv1 w) (an Expression of the
flange's speed driving a Torque; ``tests/scenes/robot_r3.py``). Before: the flat acausal
system of a component-by-component translation (``study_network.flat_size``, plus two
unknowns per electrical pin and one state per inductor and capacitor). After:
``system.size()``. Both runs at the file's tolerances (rtol 1e-6, atol 1e-8), JIT on, warm.

Run: ``.venv/bin/python bench/study_robot.py [--quick]``; writes results/study_robot.md and
results/study_robot.csv.
"""

import argparse
import time

import numpy as np
from common import machine, table, write_csv, write_markdown
from scenes import robot_r3
from study_network import flat_size

import kinetwork as kn

W_S = (0.1, 0.01)             # regularisation speeds [rad/s]


def flat_with_circuits(model, system):
    flat = model.flat()
    states, algebraic = flat_size(flat, system)
    pins = sum(1 for c in flat.components.values() for p in c.ports.values()
               if p.domain == "electrical")
    storage = sum(1 for c in flat.components.values()
                  if type(c).__name__ in ("Inductor", "Capacitor"))
    return states + storage, algebraic + 2 * pins


def run(name, model, t_end, quick):
    start = time.perf_counter()
    system = model.compile()
    built = time.perf_counter() - start
    kw = {"t_end": t_end, "n_points": 201}
    if quick:
        kw["jit"] = False
    else:
        try:
            kn.simulate(system, t_end=0.01, n_points=3)               # JIT, warm-up
        except kn.SimulationError:
            pass
    start = time.perf_counter()
    try:
        res, failure = kn.simulate(system, **kw), ""
    except kn.SimulationError as exc:
        res, failure = exc.results, str(exc).split(":")[0]
    wall = time.perf_counter() - start
    before = flat_with_circuits(model, system)
    size = system.size()
    row = {"scene": name, "flat_states": before[0], "flat_algebraic": before[1],
           "states": size["states"], "algebraic": size["algebraic"],
           "operations": size["operations"], "build_s": built, "wall_s": wall,
           "reached_s": float(res.t[-1]), "events": len(res.stats.get("events", [])),
           "steps": res.stats.get("steps"), "failure": failure}
    print(f"{name:28s} {before[0]} -> {size['states']} states, {size['algebraic']} algebraic; "
          f"build {built:.1f} s, run {wall:.1f} s to t = {res.t[-1]:.3f} s, "
          f"{row['events']} events {failure}", flush=True)
    return row, res


def main(quick=False):
    t_end = 0.3 if quick else 2.0
    rows, results = [], {}
    scenes = {"stiction (events)": kn.load(robot_r3.FOLDER / "FullRobot.json")}
    for w_s in W_S:
        scenes[f"tanh, w_s = {w_s} rad/s"] = robot_r3.full_robot_regularised(w_s)
    for name, model in scenes.items():
        row, res = run(name, model, t_end, quick)
        rows.append(row)
        results[name] = res
    write_csv("study_robot", rows)
    stick = results["stiction (events)"]
    diffs = []
    for name, res in list(results.items())[1:]:
        n = min(len(res.t), len(stick.t))
        diffs.append((name, max(np.max(np.abs(res[f"joint{k}.angle"][:n]
                                              - stick[f"joint{k}.angle"][:n]))
                                for k in range(1, 7)), stick.t[n - 1]))
    base = rows[0]
    body = [[r["scene"], r["flat_states"], r["flat_algebraic"], r["states"], r["algebraic"],
             r["operations"], f"{r['build_s']:.1f}", f"{r['wall_s']:.1f}",
             f"{r['reached_s']:.3f}", r["events"], r["steps"], r["failure"] or "-"]
            for r in rows]
    lines = ["## RobotR3.FullRobot: stiction with events against regularised friction", "",
             (f"{machine()}. The 2 s run of `models/robot_r3/FullRobot.json` (MSL's StopTime) "
             f"and the same scene with its six bearing frictions regularised by tanh; "
             f"tolerances of the file (rtol 1e-6, atol 1e-8), JIT on, warm"
             f"{' (quick: 0.3 s, no JIT)' if quick else ''}. Before: a "
             f"component-by-component translation (every 1-D port a potential and a flow, "
             f"every pin a potential and a current, every signal port a value, inertias, "
             f"inductors, capacitors, blocks and joints their states). After: "
             f"`system.size()`."), "",
             table(["scene", "flat states", "flat algebraic", "states", "algebraic",
                    "operations", "build [s]", "run [s]", "reached [s]", "events", "steps",
                    "failure"], body), "", "Findings:", "",
             (f"- Structural analysis leaves {base['states']} states and no algebraic variable "
              f"of the flat {base['flat_states']} states and {base['flat_algebraic']} "
              f"algebraic unknowns: the six joints' angles and speeds, the motor rotors of "
              f"the three elastic gears (angle and speed), each motor's inductor current and "
              f"capacitor voltage, each PI integral, and with stiction the six friction "
              f"modes (constant between events); the rotors geared rigidly to joints 4-6 "
              f"cost no state (their inertia J n^2 joins the joint's), the op-amp circuits "
              f"and every 1-D and signal alias are solved symbolically.")]
    for name, diff, until in diffs:
        lines.append(f"- {name}: the joint angles differ from the stiction run by at most "
                     f"{diff:.1e} rad up to t = {until:.3f} s.")
    if base["failure"]:
        lines.append(f"- With stiction the run stops at t = {base['reached_s']:.3f} s: all six "
                     f"axes reach the end of the synchronised path together and their "
                     f"frictions stick within one step; the driver's modes do not settle "
                     f"there (an open limit of the event driver, reported in issue 16). The "
                     f"regularised scenes need no events and reach 2 s.")
    write_markdown("study_robot", "\n".join(lines))


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    start = time.perf_counter()
    main(parser.parse_args().quick)
    print(f"study_robot: {time.perf_counter() - start:.1f} s")
