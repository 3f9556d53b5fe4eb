"""Would another method or CVODES option reach a loose accuracy cheaper than ``auto``'s Adams on
the point-mass chains? (issue 30: pinocchio + DOP853 took only 1.83-1.97x auto's CPU time to
1e-4 on the 3-D 128-link chain, where 2x is asked.)

The scenes, reference and timing are ``work_precision_points``' (pinocchio's ABA + DOP853
at rtol 1e-13; CPU time, the least of ``--repeats`` interleaved runs, more for runs of a few
milliseconds, every curve's k-th setting in turn: ``work_precision_points.sweep``); here rtol
goes in half decades, 1e-1 .. 1e-7 (atol = rtol * 1e-2), so that a curve's Pareto front is not
decided by one lucky or unlucky setting: CVODES Adams's error on these chains is not monotone
in rtol (3-D N = 128: 2.0e-4 at rtol 1e-2, 4.2e-5 at 3.2e-2).

Curves: ``auto``; kinetwork's ``cvodes`` (BDF, Newton with a dense LU), ``dop853`` and
``rk45`` (scipy's, on kinetwork's compiled equations) and ``rk`` (CasADi's fixed-step RK4 at
steps 1e-2 .. 2.5e-3 s); CVODES Adams as ``auto`` runs it (functional iteration: no Jacobian,
no factorisation) with one option changed: ``max_order`` (CVODE's maximum order, 12 by
default), ``nonlin_conv_coeff`` (the convergence test of the corrector iteration: CVODES's
0.1, or ``tolerance.LOOSE_CORRECTOR`` as auto sets it on large equations), ``step0`` (the first step, CVODES's own estimate by default); and pinocchio +
DOP853. The Adams variants are entries added to ``methods.METHODS`` in this process only.

Per curve and accuracy: the CPU time to reach it on the Pareto front (log-log interpolation,
``study_work_precision.time_to``) and the evaluations of the equations it takes (a straight
line in log-log through the runs within 30x of that accuracy).

Run: ``python bench/work_precision_options.py [--sizes 16 128] [--repeats 9]``; writes
``results/work_precision_options.{md,csv}``.
"""

import argparse
import math
import time

import numpy as np

import kinetwork as kn
from kinetwork.solver import jit
from kinetwork.solver.methods import METHODS, Casadi

import common
from common import machine, max_error, table, write_csv, write_markdown
from scenes import chains
from study_work_precision import time_to      # and bench/peers on the path
from work_precision_points import HORIZON, REF_RTOL, SPACING, cpu, sweep

import pinocchio_peer

NAME = "work_precision_options"
ACCURACIES = (1e-4, 1e-5, 1e-6)
RTOLS = tuple(10.0 ** (-k / 2) for k in range(2, 15))
STEPS = (1e-2, 5e-3, 2.5e-3)
#: CVODES Adams as ``cvodes-adams`` is, with one option more
VARIANTS = {"adams max_order 3": {"max_order": 3.0}, "adams max_order 4": {"max_order": 4.0},
            "adams nonlin_conv_coeff 0.1": {"nonlin_conv_coeff": 0.1},
            "adams nonlin_conv_coeff 0.3": {"nonlin_conv_coeff": 0.3},
            "adams nonlin_conv_coeff 0.5": {"nonlin_conv_coeff": 0.5},
            "adams step0 1e-3": {"step0": 1e-3}}
#: a curve stops after a run over CAP s of CPU, or once its error is below FLOOR; BDF gets the
#: loosest BDF_SETTINGS rtols only (seconds a run at 128 links)
CAP, FLOOR, BDF_SETTINGS = 1.0, 1e-8, 3
PIN = "pinocchio + DOP853"


def register():
    """The Adams variants as methods of this process."""
    adams = METHODS["cvodes-adams"]
    for name, extra in VARIANTS.items():
        METHODS[name] = Casadi("cvodes", f"CVODES Adams, {name}", **adams.options, **extra)


def curves_of(system, pin, t):
    """label -> (settings, run(setting) -> joint angles); the stats of each kinetwork run."""
    stats = {}

    def kinetwork(method):
        def run(s):
            res = kn.simulate(system, t_end=HORIZON, n_points=len(t), method=method, **s)
            st = res.stats
            stats[method, tuple(s.items())] = (
                res.method, st.get("rhs_evaluations") or 4 * st.get("steps", 0),
                st.get("jacobian_evaluations", 0), st.get("factorisations", 0))
            return chains.joint_angles(res)
        return run

    tols = [{"rtol": r, "atol": r * 1e-2} for r in RTOLS]
    curves = {m: (tols, kinetwork(m)) for m in ("auto", "cvodes-adams", "dop853", "rk45")}
    curves["cvodes"] = (tols[:BDF_SETTINGS], kinetwork("cvodes"))
    curves["rk"] = ([{"step": h} for h in STEPS], kinetwork("rk"))
    curves.update({name: (tols, kinetwork(name)) for name in VARIANTS})
    curves[PIN] = ([{"method": "DOP853", "rtol": r} for r in RTOLS if r <= 1.01e-2],
                   lambda s: pinocchio_peer.run(pin, t, **s))
    return curves, stats


def evaluations_at(points, target):
    """Evaluations to ``target`` from (error, evaluations) of the runs within 30x of it: a line
    in log-log; None with fewer than 3 such runs."""
    near = [(e, n) for e, n in points if n and target / 30 <= e <= target * 30]
    if len(near) < 3:
        return None
    fit = np.polyfit(np.log([e for e, _ in near]), np.log([n for _, n in near]), 1)
    return math.exp(np.polyval(fit, math.log(target)))


def study(sizes, repeats):
    start = time.perf_counter()
    register()
    t = np.linspace(0.0, HORIZON, round(HORIZON / SPACING) + 1)
    summary, every = [], []
    for planar in (True, False):
        for n in sizes:
            scene = f"{'planar' if planar else '3-D'} N = {n}"
            spec = chains.point_mass_spec(n, planar)
            system = chains.point_masses(n, planar).compile()
            pin = pinocchio_peer.build(spec)
            ref = pinocchio_peer.run(pin, t, method="DOP853", rtol=REF_RTOL,
                                     atol=REF_RTOL * 1e-2)
            curves, stats = curves_of(system, pin, t)
            for settings, run in curves.values():           # JIT, integrators, first calls
                cpu(run, settings[0])
            jit.wait()                                      # the optimised library swapped in
            rows = sweep(curves, ref, repeats, CAP, FLOOR)
            for label, rs in rows.items():
                ran = [(r["setting"], r["cpu_s"], r["error"],
                        stats.get((label, tuple(r["setting"].items())))) for r in rs]
                cells = [scene, label]
                for target in ACCURACIES:
                    took = time_to([(c, e) for _, c, e, _ in ran if math.isfinite(e)], target)
                    evals = evaluations_at([(e, st[1]) for _, _, e, st in ran if st], target)
                    cells += [f"{took * 1e3:.2f}" if took else "—",
                              f"{evals:.0f}" if evals else "—"]
                summary.append(cells)
                for s, took, e, st in ran:
                    every.append([scene, label, " ".join(f"{k}={v:.3g}" if isinstance(v, float)
                                                         else f"{k}={v}" for k, v in s.items()),
                                  f"{took * 1e3:.2f}", f"{e:.1e}",
                                  *(st[1:] if st else ("", "", ""))])
            print(f"  {scene}: done at {time.perf_counter() - start:.0f} s", flush=True)
    header = ["scene", "curve"]
    for e in ACCURACIES:
        header += [f"CPU ms to {e:.0e}", "evaluations"]
    write_csv(NAME, [dict(zip(["scene", "curve", "setting", "cpu_ms", "error", "evaluations",
                               "jacobians", "factorisations"], r)) for r in every])
    lines = [
        "# Work-precision: methods and CVODES options on the point-mass chains, CPU time", "",
        f"{machine()}; {common.load()}. Study run time {time.perf_counter() - start:.0f} s.",
        "", f"rtol 1e-1..1e-7 in half decades (atol = rtol * 1e-2); least CPU time of {repeats} "
        "interleaved runs; error: max joint-angle difference from pinocchio ABA + DOP853 at "
        f"rtol {REF_RTOL:g}. CPU ms on the Pareto front; evaluations of the equations from a "
        "log-log line through the runs within 30x of the accuracy (— : fewer than 3 such "
        "runs, or none reach it). See the module's docstring.", "",
        table(header, summary), "", "## Every run", "",
        table(["scene", "curve", "setting", "CPU ms", "error", "evaluations", "Jacobians",
               "factorisations"], every)]
    write_markdown(NAME, "\n".join(lines))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="*", default=[16, 128])
    parser.add_argument("--repeats", type=int, default=9)
    args = parser.parse_args()
    study(args.sizes, args.repeats)


if __name__ == "__main__":
    main()
