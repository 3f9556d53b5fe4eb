"""Per-run overhead: kinetwork's quiet run of a small model against the hand-written route.

Scenes: the seed (``models/double_pendulum.json``), and the anchors' point-mass chains of two
links with a damper on each joint, planar and 3-D (``scenes.chains.point_masses``), 10 s on
1001 output points. Per scene and rtol (1e-4, 1e-6, 1e-9; atol = rtol * 1e-2):

- kinetwork: ``kn.simulate(system, t_end, n_points, rtol, atol)`` (``auto``) on a compiled
  System, run twice beforehand (its C code, integrators, plan and the run's recipe are kept,
  as in any later run of a session: a repeated quiet run replays the recipe, its integrator
  call bound once, ``kinetwork/solver/replay.py``);
- its integrator call alone: the very CasADi integrator the run called, through a buffer
  bound once to the run's inputs (what the run would cost with no Python around it), with
  CasADi's per-evaluation clock made cheap as in a run (``kinetwork/solver/casadi_clock.py``)
  and with CasADi's own (``clock()``, a system call, twice per evaluation);
- the hand-written route (``peers/casadi_peer.py``: Featherstone's ABA in SX, gcc -O1,
  ``casadi.external``, CVODES Adams in one ``casadi.integrator`` call) at the solver
  tolerances kinetwork hands CVODES for that rtol (``tolerance.solver_tolerances``: the same
  method at the same tolerances, the same steps), and at the same accuracy: its time at
  kinetwork's error, interpolated (log-log) between the two runs of its rtol ladder
  (1e-3 .. 1e-13, atol = rtol * 1e-2) whose errors bracket it, both timed in the rounds.

Error: the largest joint-angle difference on the output grid from a reference by DOP853 at
rtol 3e-14 on equations that share nothing with kinetwork's (the seed: its closed-form
Lagrange equations, ``scenes.reference``; the chains: pinocchio's ABA).

Timing: CPU time (``time.process_time``), the tools interleaved in rounds in one process,
medians over the rounds, the machine's load average (1 min) at the end of each row's rounds
beside it (the machine may be shared). Ratios > 1: kinetwork is faster.

Where a run's time goes (one scene and rtol per row, ``breakdown``): CPU time of the thread
(``time.thread_time``) inside the replay's integrator call, inside the rest of the replay's
call (the states' array, the solvers' words caught, the rows checked), in setting up the probe
signals' deferred computation, in building the Results, and in the rest of the run (the
settings looked up, the recipe found, the run and its signal handlers), over many runs.

Writes ``results/study_overhead.md``. Run: ``python bench/study_overhead.py [--rounds R]``.
"""

import argparse
import os
import statistics
import sys
import time

import numpy as np

import common
from common import load, machine, table, write_markdown
from scenes import chains
from scenes.reference import seed_reference

sys.path.insert(0, str(common.HERE / "peers"))
import casadi_peer
import pinocchio_peer

import kinetwork as kn
from kinetwork.solver import replay
from kinetwork.solver.casadi_clock import cheap
from kinetwork.solver.compiled import compiled
from kinetwork.solver.results import Results
from kinetwork.solver.tolerance import solver_tolerances

NAME = "study_overhead"
SCENES = {
    "seed": (chains.seed, chains.seed_spec),
    "planar point masses, N = 2": (lambda: chains.point_masses(2),
                                   lambda: chains.point_mass_spec(2)),
    "3-D point masses, N = 2": (lambda: chains.point_masses(2, planar=False),
                                lambda: chains.point_mass_spec(2, planar=False)),
}
RTOLS = (1e-4, 1e-6, 1e-9)
HORIZON, POINTS = 10.0, 1001
REF_RTOL = 3e-14
#: the hand route's rtol ladder, for its time at a given accuracy
LADDER = tuple(10.0 ** -k for k in range(3, 14))


def reference(name, spec, t):
    """Joint angles on ``t`` by DOP853 at REF_RTOL on independent equations."""
    if name == "seed":
        return seed_reference(t, x0=(*spec.q0, *spec.qd0), rtol=REF_RTOL, atol=1e-16)[:, :2]
    built = pinocchio_peer.build(spec)
    return pinocchio_peer.trajectory(built, t, rtol=REF_RTOL, atol=1e-16)[0]


def error(q, ref):
    return float(np.max(np.abs(np.asarray(q) - ref)))


def integrator_call(system):
    """The integrator that the last run of ``system`` replays (its recipe's), as a function
    of no arguments that calls it with that run's inputs through a buffer bound once
    (nothing but the call, CasADi's own clock), and its evaluations per call."""
    integ = next(reversed(compiled(system)._recipes.values())).integ
    x0 = np.ascontiguousarray(system.x0[:system.n_states])
    p = np.append(system.param_vector(), 0.0)
    xf = np.empty((POINTS - 1, system.n_states))
    buf, trigger = integ.buffer()
    buf.set_arg(integ.index_in("x0"), memoryview(x0))
    buf.set_arg(integ.index_in("p"), memoryview(p))
    buf.set_res(integ.index_out("xf"), memoryview(xf))

    def call(_keep=(x0, p, xf, buf)):
        trigger()
    call()
    return call, int(buf.stats()["nfevals"])


def equations_alone(system, calls=2000, rounds=7):
    """CPU microseconds per evaluation, each through a buffer bound once, of the compiled
    right-hand side alone and of the integrators' DAE Function around it (CasADi's MX
    wrapper: the time shifted by the chunk's start, the parameters split), least of
    ``rounds``; a loop that calls nothing is taken off."""
    table = compiled(system)._cache
    rhs = table[("rhs", False)]
    dae = next(v for k, v in table.items() if isinstance(k, tuple) and k[0] == "dae")
    n, p = system.n_states, system.param_vector()
    x = np.ascontiguousarray(system.x0[:n], dtype=float)
    keep, triggers = [], {}
    for name, f, args in (("rhs", rhs, {0: np.zeros(1), 1: x, 2: np.array(p, dtype=float)}),
                          ("dae", dae, {0: np.zeros(1), 1: x, 3: np.append(p, 0.0)})):
        buf, trigger = f.buffer()
        for i, value in args.items():
            buf.set_arg(i, memoryview(value))
        out = np.empty(n)
        buf.set_res(0, memoryview(out))
        keep.append((buf, args, out))
        triggers[name] = trigger

    def loop(trigger):
        start = time.process_time()
        for _ in range(calls):
            trigger()
        return time.process_time() - start
    best = {k: min(loop(t) for _ in range(rounds)) for k, t in triggers.items()}
    empty = min(loop(lambda: None) for _ in range(rounds))
    return {k: (v - empty) / calls * 1e6 for k, v in best.items()}


def cheap_clock(call):
    """``call`` with CasADi's clock made cheap, as a run makes its integrator calls."""
    def cheap_call():
        with cheap():
            call()
    return cheap_call


def breakdown(system, kw, runs):
    """Microseconds of the thread's CPU per run of ``system`` (its recipe kept) over ``runs``
    runs: (whole run, integrator call, rest of the replay's call, the probe signals' deferred
    computation set up, the Results built, the rest of the run around the call: settings and
    recipe looked up, the run and its signal handlers)."""
    recipe = next(reversed(compiled(system)._recipes.values()))
    buffer, trigger, *rest = recipe.call
    spent = dict.fromkeys(("call", "_call", "outputs", "results"), 0.0)

    def timed(fn, key):
        def wrapper(*args):
            start = time.thread_time()
            try:
                return fn(*args)
            finally:
                spent[key] += time.thread_time() - start
        return wrapper
    inner, later, renewed = replay._call, replay.later_outputs, Results.__dict__["renewed"]
    recipe.call = (buffer, timed(trigger, "call"), *rest)
    replay._call, replay.later_outputs = timed(inner, "_call"), timed(later, "outputs")
    Results.renewed = classmethod(timed(renewed.__func__, "results"))
    try:
        start = time.thread_time()
        for _ in range(runs):
            kn.simulate(system, **kw)
        whole = time.thread_time() - start
    finally:
        recipe.call, replay._call, replay.later_outputs = (buffer, trigger, *rest), inner, later
        Results.renewed = renewed
    us = 1e6 / runs
    around = whole - spent["_call"] - spent["outputs"] - spent["results"]
    return (whole * us, spent["call"] * us, (spent["_call"] - spent["call"]) * us,
            spent["outputs"] * us, spent["results"] * us, around * us)


def bracket(ladder, target):
    """The rtols of the hand route's ladder [(rtol, error)] whose errors bracket ``target``
    ((r1, e1), (r2, e2)) with e1 <= target <= e2; one pair twice when the loosest run
    that is as accurate stands alone; None when no run is as accurate."""
    pts = sorted((e, r) for r, e in ladder if np.isfinite(e) and e > 0)
    if not pts or target < pts[0][0]:
        return None
    below = [(e, r) for e, r in pts if e <= target]
    above = [(e, r) for e, r in pts if e > target]
    lo = max(below, key=lambda er: er[1])          # the loosest rtol as accurate
    if not above:
        return (lo[1], lo[0]), (lo[1], lo[0])
    hi = min(above)                                  # the nearest less accurate
    return (lo[1], lo[0]), (hi[1], hi[0])


def at_accuracy(pair, times, target):
    """The time to ``target`` error between the bracketing runs ``pair`` (log-log)."""
    (r1, e1), (r2, e2) = pair
    s1, s2 = times[r1], times[r2]
    if r1 == r2 or e2 <= e1:
        return s1
    w = (np.log(target) - np.log(e1)) / (np.log(e2) - np.log(e1))
    return float(np.exp(np.log(s1) + w * (np.log(s2) - np.log(s1))))


def cpu(fn, rounds_out, key):
    start = time.process_time()
    value = fn()
    rounds_out.setdefault(key, []).append(time.process_time() - start)
    return value


def study(rounds):
    t = np.linspace(0.0, HORIZON, POINTS)
    adams = kn.METHODS["cvodes-adams"]
    rows, counts, where = [], [], []
    for name, (make, spec_of) in SCENES.items():
        spec, system = spec_of(), make().compile()
        n = spec.n
        ref = reference(name, spec, t)
        hand = casadi_peer.build(spec)
        # the hand route's ladder: its error per rtol (its times are taken in the rounds)
        ladder = []
        for r in LADDER:
            try:
                ladder.append((r, error(casadi_peer.run(hand, t, rtol=r), ref)))
            except RuntimeError:            # below what CVODES can do
                continue
        for rtol in RTOLS:
            kw = {"t_end": HORIZON, "n_points": POINTS, "rtol": rtol, "atol": rtol * 1e-2}
            res = kn.simulate(system, **kw)
            kn.simulate(system, **kw)               # the first replay binds its call
            srt, sat = solver_tolerances(adams, system, rtol, rtol * 1e-2)
            own_clock, evals = integrator_call(system)
            call = cheap_clock(own_clock)
            casadi_peer.run(hand, t, rtol=srt, atol=sat)
            hand_evals = int(casadi_peer.integrator(hand, t, srt, sat).stats()["nfevals"])
            err = error(chains.joint_angles(res), ref)
            pair = bracket(ladder, err)
            neighbours = sorted({r for r, _ in pair}) if pair else []
            spent = {}
            for _ in range(rounds):
                cpu(lambda: kn.simulate(system, **kw), spent, "kinetwork")
                cpu(call, spent, "call")
                cpu(own_clock, spent, "own clock")
                cpu(lambda: casadi_peer.run(hand, t, rtol=srt, atol=sat), spent, "hand")
                for r in neighbours:
                    cpu(lambda r=r: casadi_peer.run(hand, t, rtol=r), spent, r)
            med = {k: statistics.median(v) for k, v in spent.items()}
            hand_err = error(casadi_peer.run(hand, t, rtol=srt, atol=sat)[:, :n], ref)
            same_accuracy = at_accuracy(pair, med, err) if pair else float("nan")
            rows.append([name, f"{rtol:.0e} ({srt:.0e})", res.method, f"{err:.1e}",
                         f"{med['kinetwork'] * 1e3:.3f}", f"{med['hand'] * 1e3:.3f}",
                         f"{hand_err:.1e}", f"{med['hand'] / med['kinetwork']:.2f}",
                         f"{same_accuracy * 1e3:.3f}",
                         f"{same_accuracy / med['kinetwork']:.2f}",
                         f"{os.getloadavg()[0]:.1f}"])
            counts.append([name, f"{rtol:.0e}", evals, hand_evals,
                           f"{med['call'] / evals * 1e6:.2f}",
                           f"{med['own clock'] / evals * 1e6:.2f}",
                           f"{med['hand'] / hand_evals * 1e6:.2f}",
                           f"{(med['kinetwork'] - med['call']) * 1e6:.0f}",
                           f"{(med['kinetwork'] - med['call']) / med['kinetwork'] * 100:.0f} %"])
            parts = breakdown(system, kw, 10 * rounds)
            alone = equations_alone(system)
            counts[-1][6:6] = [f"{alone['dae']:.2f}", f"{alone['rhs']:.2f}"]
            where.append([name, f"{rtol:.0e}", *(f"{v:.0f}" for v in parts),
                          f"{os.getloadavg()[0]:.1f}"])
            print("  ", rows[-1], counts[-1][2:], where[-1][2:], flush=True)
    return rows, counts, where


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=41, help="interleaved rounds per row")
    args = parser.parse_args()
    start = time.perf_counter()
    rows, counts, where = study(args.rounds)
    text = "\n".join([
        "# Per-run overhead: the quiet run of a small model against the hand-written route",
        "",
        f"{machine()}; {load()}; {args.rounds} interleaved rounds per row, CPU time, "
        f"medians; study wall time {time.perf_counter() - start:.0f} s. See "
        "``bench/study_overhead.py`` for what each column is.", "",
        "## Time per run", "",
        "rtol as asked of kinetwork (the solver's in brackets, at which the hand route runs "
        "in the same-tolerance columns); errors: the largest joint-angle difference from "
        f"DOP853 at {REF_RTOL:g} on independent equations. Ratios: hand route / kinetwork "
        "(> 1: kinetwork is faster).", "",
        table(["scene", "rtol (solver)", "auto ran", "kinetwork error", "kinetwork [ms]",
               "hand, same tolerance [ms]", "hand error", "ratio", "hand, same accuracy [ms]",
               "ratio at same accuracy", "load (1 min)"], rows), "",
        "## Where the time goes", "",
        "Evaluations of the right-hand side per run, CPU time per evaluation (each route's "
        "integrator call divided by its evaluations: CVODES' work included; kinetwork's "
        "with CasADi's clock made cheap as its runs make it, ``casadi_clock.py``, and with "
        "CasADi's own, a system call twice per evaluation, as the hand route runs; then one "
        "evaluation outside the integrator of the DAE Function it calls, CasADi's MX wrapper "
        "around the compiled equations, and of the compiled equations alone, each through a "
        "buffer bound once), and what "
        "kinetwork's run costs beyond its integrator call (the replay: settings and "
        "parameters looked up, signal handlers, the solvers' words caught, Results; the "
        "probe signals are computed when first read).", "",
        table(["scene", "rtol", "kinetwork evaluations", "hand evaluations",
               "kinetwork us/evaluation", "the same call, CasADi's own clock",
               "the DAE Function alone [us]", "its compiled equations alone [us]",
               "hand us/evaluation (whole run)",
               "kinetwork per-run overhead [us]", "share of the run"], counts), "",
        "## Where a run's microseconds go", "",
        f"CPU time of the thread per run (``time.thread_time``, {10 * args.rounds} runs in a "
        "row after the rounds): the whole ``kn.simulate`` call; its integrator call (CVODES "
        "and the compiled equations); the rest of the replay's call (the states' array, the "
        "solvers' words caught, the rows checked, the counts); the probe signals' computation "
        "set up (copies of the states, computed when first read: not in a run); the Results "
        "built; the rest of the run around the call (settings and the recipe looked up, the "
        "run, its signal handlers, its statistics).", "",
        table(["scene", "rtol", "whole run [us]", "integrator call [us]",
               "rest of the call [us]", "probe signals set up [us]", "Results [us]",
               "rest of the run [us]", "load (1 min)"], where)])
    write_markdown(NAME, text)
    print(f"done in {time.perf_counter() - start:.0f} s", flush=True)


if __name__ == "__main__":
    main()
