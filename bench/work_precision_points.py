"""Work-precision on the point-mass chains with a damper: kinetwork's ``auto`` against the same
route by hand, pinocchio + DOP853 and MuJoCo RK4, in CPU time, at 1e-4, 1e-6 and 1e-9.

Scenes (``scenes.chains.point_mass_spec``): N point masses of 1 kg on massless 1 m links, a
damper of 0.1 N m s/rad on each joint, about z (planar) or about z and x in turn (3-D); N = 2,
16, 128; 10 s, output every 0.01 s. Reference: pinocchio's ABA with DOP853 at rtol 1e-13 (atol
1e-15), independent of kinetwork; the hand-written route at rtol 1e-12 is compared with it.

Timing: CPU time (``time.process_time``) of one run, the least of REPEATS (up to MOST_REPEATS for
a run of a few milliseconds: see ``sweep``), the curves' runs of one setting taken in turn (interleaved: a shared machine's load falls on every tool alike);
every model is built and every integrator called once first, and kinetwork's optimised
library is in (``jit.wait``: a large model's first runs call a quick -O0 build while the
optimised one is made in the background, ``kinetwork/solver/jit.py``; what that first
answer costs is ``study_scaling``'s). A curve stops after a run over
CAP s of CPU or once its error is below FLOOR. Time to an accuracy: log-log interpolation on
each curve's Pareto front (``study_work_precision.time_to``).

Run: ``python bench/study_work_precision.py --point-masses [--quick]``; writes
``results/work_precision_points.{md,csv}``; with ``--sizes 32 64``, the sizes between the
table's, ``results/work_precision_points_sizes.{md,csv}``.
"""

import math
import time

import numpy as np

import kinetwork as kn
from kinetwork.solver import jit

import common
from common import machine, max_error, table, write_csv, write_markdown
from scenes import chains

import casadi_peer
import mujoco_peer
import pinocchio_peer

NAME = "work_precision_points"
SIZES = (2, 16, 128)
HORIZON, SPACING = 10.0, 0.01
ACCURACIES = (1e-4, 1e-6, 1e-9)
RTOLS = tuple(10.0 ** -k for k in range(1, 13))
REF_RTOL = 1e-13
CAP, FLOOR, REPEATS = 3.0, 1e-11, 3
#: a run of a few milliseconds varies by half on a shared machine: such runs are repeated up
#: to MOST_REPEATS times, while their setting has cost under SMALL s of CPU
MOST_REPEATS, SMALL = 15, 0.05
AUTO, HAND, PIN, MUJOCO = ("kinetwork auto", "by hand (CasADi ABA + CVODES Adams)",
                           "pinocchio + DOP853", "MuJoCo RK4")


def cpu(fn, setting):
    """(CPU seconds, value or the exception) of one call."""
    start = time.process_time()
    try:
        value = fn(setting)
    except Exception as exc:  # noqa: BLE001 -- a failed run is a result
        value = exc
    return time.process_time() - start, value


def curves_of(spec, system, t, quick):
    """label -> (settings, run(setting) -> joint angles), and auto's runs' details."""
    rtols = (1e-4, 1e-8) if quick else RTOLS
    steps = (1e-2, 1e-3) if quick else [h for h in mujoco_peer.TIMESTEPS if h >= 5e-5]
    hand, pin, mj = casadi_peer.build(spec), pinocchio_peer.build(spec), mujoco_peer.build(spec)
    details = {}

    def auto(s):
        res = kn.simulate(system, t_end=HORIZON, n_points=len(t), **s)
        details[s["rtol"]] = (res.method, res.stats.get("rhs_evaluations",
                                                        4 * res.stats.get("steps", 0)))
        return chains.joint_angles(res)

    curves = {
        AUTO: ([{"rtol": r, "atol": r * 1e-2} for r in rtols], auto),
        HAND: ([{"rtol": r} for r in rtols], lambda s: casadi_peer.run(hand, t, **s)),
        PIN: ([{"method": "DOP853", "rtol": r} for r in rtols if r <= 1e-2],
              lambda s: pinocchio_peer.run(pin, t, **s)),
        MUJOCO: ([{"integrator": "RK4", "timestep": h} for h in steps],
                 lambda s: mujoco_peer.run(mj, t, **s)),
    }
    return curves, details, hand


def sweep(curves, ref, repeats=REPEATS, cap=CAP, floor=FLOOR):
    """Interleaved: every curve's k-th setting in turn, ``repeats`` times, and up to
    MOST_REPEATS while a curve has spent under SMALL s on it; rows per curve. A curve stops
    after a run over ``cap`` s or an error below ``floor``."""
    rows = {label: [] for label in curves}
    active = set(curves)
    for k in range(max(len(s) for s, _ in curves.values())):
        best, value, spent = {}, {}, {}
        for r in range(max(MOST_REPEATS, repeats)):
            for label in curves:
                settings, run = curves[label]
                if label in active and k < len(settings) and \
                        (r < repeats or spent[label] < SMALL):
                    took, value[label] = cpu(run, settings[k])
                    best[label] = min(best.get(label, math.inf), took)
                    spent[label] = spent.get(label, 0.0) + took
        for label, took in best.items():
            v = value[label]
            error = math.inf if isinstance(v, Exception) else max_error(v, ref)
            rows[label].append({"setting": curves[label][0][k], "cpu_s": took, "error": error,
                                "status": f"failed: {str(v)[:120]}"
                                if isinstance(v, Exception) else "ok"})
            if took > cap or error < floor:
                active.discard(label)
    return rows


def time_to(rows, target):
    from study_work_precision import time_to as along_front
    return along_front([(r["cpu_s"], r["error"]) for r in rows if r["status"] == "ok"], target)


def study(quick=False, sizes=None):
    """The study at SIZES (the issue's table), or at ``sizes`` (written to
    ``NAME_sizes``: the table's and these are each a file of their own)."""
    start = time.perf_counter()
    name = NAME if not sizes else f"{NAME}_sizes"
    sizes = (2, 16) if quick else tuple(sizes or SIZES)
    t = np.linspace(0.0, HORIZON, round(HORIZON / SPACING) + 1)
    summary, every, csv_rows, notes = [], [], [], []
    for planar in (True, False):
        for n in sizes:
            scene = f"{'planar' if planar else '3-D'} N = {n}"
            spec = chains.point_mass_spec(n, planar)
            system = chains.point_masses(n, planar).compile()
            ref = pinocchio_peer.run(pinocchio_peer.build(spec), t, method="DOP853",
                                     rtol=REF_RTOL, atol=REF_RTOL * 1e-2)
            curves, details, hand = curves_of(spec, system, t, quick)
            for settings, run in curves.values():           # JIT, integrators, first calls
                cpu(run, settings[0])
            jit.wait()                                      # the optimised library swapped in
            agree = max_error(casadi_peer.run(hand, t, rtol=1e-12), ref)
            notes.append(f"{scene}: the hand-written route at rtol 1e-12 is {agree:.1e} rad "
                         f"from the reference")
            rows = sweep(curves, ref)
            cells = [scene]
            for e in ACCURACIES:
                mine = time_to(rows[AUTO], e)
                for peer in (HAND, PIN, MUJOCO):
                    theirs = time_to(rows[peer], e)
                    cells.append(f"{theirs / mine:.2f}" if mine and theirs else
                                 "auto never" if theirs else "—")
                cells.insert(len(cells) - 3, f"{mine * 1e3:.2f} ms" if mine else "—")
            summary.append(cells)
            for label, rs in rows.items():
                for r in rs:
                    s = r["setting"]
                    chosen = details.get(s.get("rtol")) if label == AUTO else None
                    every.append([scene, label, " ".join(f"{k}={v:g}" if isinstance(v, float)
                                                         else f"{k}={v}" for k, v in s.items()),
                                  f"{r['cpu_s'] * 1e3:.2f}", f"{r['error']:.1e}",
                                  f"{chosen[0]}, {chosen[1]} evaluations" if chosen else "",
                                  r["status"]])
                    csv_rows.append({"scene": scene, "curve": label, "setting": every[-1][2],
                                     "cpu_s": r["cpu_s"], "error": r["error"],
                                     "auto_ran": every[-1][5], "status": r["status"]})
            print(f"  {scene}: done at {time.perf_counter() - start:.0f} s", flush=True)
    write_csv(name, csv_rows)
    header = ["scene"]
    for e in ACCURACIES:
        header += [f"auto to {e:.0e}", "by hand / auto", "pinocchio / auto", "MuJoCo / auto"]
    lines = [
        "# Work-precision: point-mass chains with a damper, CPU time", "",
        f"{machine()}; {common.load()}. Study run time {time.perf_counter() - start:.0f} s"
        + (" (quick: N = 2, 16; rtol 1e-4, 1e-8)." if quick else "."), "",
        "CPU time to each accuracy (max joint-angle error against pinocchio ABA + DOP853 at "
        f"rtol {REF_RTOL:g}) along each curve's Pareto front; a ratio is the peer's time over "
        "auto's: above 1, kinetwork is faster. — : never reached in the settings swept; "
        "`auto never`: the peer reaches it and auto does not. Settings: rtol 1e-1..1e-12 "
        "(atol = rtol * 1e-2) for kinetwork and by hand, 1e-2..1e-12 for DOP853, steps "
        "1e-2..5e-5 s for MuJoCo RK4; least CPU time of "
        f"{REPEATS} interleaved runs, up to {MOST_REPEATS} while a setting has cost a curve "
        f"under {SMALL:g} s; a curve stops after a run over {CAP:g} s.", "",
        table(header, summary), "", *[f"- {n}" for n in notes], "",
        "## Every run", "",
        table(["scene", "curve", "setting", "CPU ms", "error", "auto ran", "status"], every)]
    write_markdown(name, "\n".join(lines))


CHOICE_RTOLS = (1e-2, 1e-3, 1e-4, 1e-6)


def choice(repeats=5):
    """``--choice``: where stability holds the step (``scenes/follower.py``: a mode of 300
    rad/s, barely excited), auto against Adams forced, CPU time and evaluations, per rtol;
    writes ``results/work_precision_choice.md``."""
    from scenes.follower import follower, follower_reference
    system = follower().compile()
    t = np.linspace(0.0, HORIZON, 101)
    ref = follower_reference(t)
    rows = []
    for rtol in CHOICE_RTOLS:
        settings = {"t_end": HORIZON, "n_points": len(t), "rtol": rtol, "atol": rtol * 1e-2}
        runs = {"auto": lambda s=settings: kn.simulate(system, **s),
                "cvodes-adams": lambda s=settings: kn.simulate(system, method="cvodes-adams",
                                                               **s)}
        best, res = {}, {}
        for fn in runs.values():
            fn()                                    # integrators, first calls
        for _ in range(repeats):
            for name, fn in runs.items():
                took, res[name] = cpu(lambda _s, fn=fn: fn(), None)
                best[name] = min(best.get(name, math.inf), took)
        cells = [f"{rtol:g}"]
        for name in runs:
            r = res[name]
            evaluations = r.stats.get("rhs_evaluations") or 4 * r.stats["steps"] + \
                r.stats.get("rk4", {}).get("trial_evaluations", 0)
            error = np.max(np.abs(r.states - ref) / (rtol * 1e-2 + rtol * np.abs(ref)))
            cells += [r.method, evaluations, f"{best[name] * 1e3:.2f}", f"{error:.2g}"]
        cells.append(f"{best['cvodes-adams'] / best['auto']:.2f}")
        rows.append(cells)
    lines = [
        "# auto's choice where stability holds the step", "",
        f"{machine()}; {common.load()}. The slow mass carrying a fast one "
        "(`tests/scenes/follower.py`: a mode of 300 rad/s decaying at 3/s, barely excited), "
        "10 s, 101 output points; CPU time, the least of "
        f"{repeats} interleaved runs; error: the largest over all states in units of the "
        "tolerance (atol + rtol |x|, atol = rtol * 1e-2) against DOP853 at rtol 1e-13 on the "
        "masses' own equations. auto's evaluations include its trial (RK4 at h and h/2 over "
        "the first 5 % of the run).", "",
        table(["rtol", "auto ran", "evaluations", "CPU ms", "error / tol",
               "Adams forced", "evaluations", "CPU ms", "error / tol", "Adams / auto"], rows)]
    write_markdown("work_precision_choice", "\n".join(lines))
