"""Loops: kinetwork's three formulations of kinematic loops (issue 4), measured.

Four parts, all on the scenes of ``loop_scenes.py`` and against the independent closed-form
references of ``reference_loops.py``:

1. Loop models: fourbar, slider_crank, spatial_fourbar (and the issue's non-loop models
   dzhanibekov, spring_pendulum) at their own simulation settings (``kn.simulate(system)``):
   states, algebraic variables, operations per evaluation (``system.size()``), build time
   (model construction + ``compile``, median of 3), the first simulation (a cold JIT cache:
   C compilation included) and the median of 3 more (warm), the max closure residual and, for
   fourbar and slider_crank, the max crank-angle error against the reference and the relative
   energy drift, both over the 10 s of the run.
2. Formulations compared on the undamped four-bar (theta0 = 1 rad, from rest), 10 s, output
   every 0.05 s, against ``fourbar_simulate`` at rtol = atol = 1e-12: max crank-angle error
   against wall time for partition + idas, cvodes-adams / dop853 on the projected ODE and
   on the Baumgarte ODE (a = 10/s and a = 0) over rtol 1e-4 .. 1e-12 (atol = rtol / 100),
   and partition +
   collocation over steps 0.05 .. 0.003125 s. No probes (integration only); each time is the
   median of repeats (``common.timed``) after a warm-up run.
3. Drift over a long run: the same four-bar over 1000 s (2001 points) at rtol 1e-8
   (atol 1e-10): closure residual and relative energy error against time for partition + idas,
   projected, Baumgarte a = 10 and a = 0 (cvodes-adams). ``simulate`` Newton-polishes the partition's
   algebraic variables at the output points; what IDAS itself held there is measured too,
   by running the same integrator (``system.integrator``) without the polish.
4. Growth with N four-bars (``fourbar_chain(n)``, n = 1 .. 16): sizes, build time, 2 s of
   simulation at rtol 1e-6 (atol 1e-8, partition + idas), first call (cold JIT cache) and warm
   median; log-log slopes against n.

Energy: the references' ``fourbar_energy`` / ``slider_crank_energy`` applied to kinetwork's
crank angle and speed; relative energy error = (E(t) - E(0)) / (E(0) - E_rest), E_rest the
minimum of the potential (the mechanism at rest hanging in its stable position), as in
``study_long_run``. The whole study uses an empty JIT cache folder of its own, so "first
call" always includes the C compiler.

5. The Pareto front at 1e-6 (issue 18, item 3; ``--pareto``, its own report): for the four-bar,
   the slider-crank and the spatial four-bar, every formulation + method's cheapest run whose
   crank-angle error over 10 s is within 1e-6, with the tolerances as a user asks them.

Run: ``.venv/bin/python bench/study_loops.py [--quick] [--pareto]``; writes results/study_loops.csv
(one row per run, column ``part`` = models, formulations, drift, chain), study_loops.md,
study_loops_precision.png, study_loops_drift.png and study_loops_chain.png.
"""

import argparse
import os
import statistics
import tempfile
import time

import casadi as ca
import numpy as np

from common import RESULTS, load, machine, table, timed, write_csv, write_markdown

import kinetwork as kn
from scenes import loops as ls
from scenes import reference_loops as rl
from kinetwork.solver.compiled import JACOBIAN_JIT_LIMIT, compiled

THETA0 = 1.0
SPACING = 0.05
T_PRECISION = 10.0
RTOLS = tuple(10.0 ** -k for k in range(4, 13))
RTOLS_QUICK = (1e-4, 1e-8)
STEPS = (0.05, 0.025, 0.0125, 0.00625, 0.003125)
STEPS_QUICK = (0.05, 0.025)
TARGETS = (1e-3, 1e-6)
DRIFT_RTOL = 1e-8
CHAIN = (1, 2, 4, 8, 16)
CHAIN_QUICK = (1, 2)
CHAIN_T = 2.0
CHAIN_RTOL = 1e-6
#: the polished partition residual is ~1e-16 or exactly 0: drawn at this floor on log axes
FLOOR = 1e-17


def seconds(fn):
    start = time.perf_counter()
    value = fn()
    return time.perf_counter() - start, value


# -- energies -------------------------------------------------------------------------------
def rest_energy(energy):
    """Minimum of the potential energy(theta, 0) over the crank angle."""
    from scipy.optimize import minimize_scalar
    grid = np.linspace(-np.pi, np.pi, 3601)
    e = energy(grid, np.zeros_like(grid))
    k = int(np.argmin(e))
    best = minimize_scalar(lambda th: float(energy(np.array(th), np.array(0.0))),
                           bounds=(grid[max(k - 1, 0)], grid[min(k + 1, len(grid) - 1)]),
                           method="bounded", options={"xatol": 1e-12})
    return min(float(best.fun), float(e[k]))


def relative_energy(energy, e_rest, theta, thetad):
    E = energy(np.asarray(theta), np.asarray(thetad))
    return (E - E[0]) / (E[0] - e_rest)


def _tol(r):
    """1e-08 -> "1e-8"."""
    k = int(round(np.log10(r)))
    return f"1e{k}" if abs(r - 10.0 ** k) < 1e-3 * r else f"{r:g}"


def finite_max(a):
    a = np.asarray(a, float)
    return float(np.max(np.abs(a))) if len(a) and np.all(np.isfinite(a)) else float("inf")


# -- part 1: the loop models ------------------------------------------------------------------
#: model -> (crank state, reference simulate, energy function, (theta0, thetad0))
REFERENCES = {"fourbar": ("A", rl.fourbar_simulate, rl.fourbar_energy, (1.0, 0.0)),
              "slider_crank": ("O", rl.slider_crank_simulate, rl.slider_crank_energy,
                               (0.5, 3.0))}


def part_models(quick):
    rows = []
    for name, build in ls.FILES.items():
        builds = [seconds(lambda: build().compile()) for _ in range(3)]
        build_s = statistics.median(b[0] for b in builds)
        system = builds[-1][1]
        size = system.size()
        first, res = seconds(lambda: kn.simulate(system))
        cached = res.stats.get("jit_cached")
        warm = statistics.median(seconds(lambda: kn.simulate(system))[0] for _ in range(3))
        residual = system.constraint_residual(res.states)
        row = {"part": "models", "model": name, "formulation": size["formulation"],
               "method": res.settings["method"], "setting": f"rtol {_tol(res.settings['rtol'])}",
               "states": size["states"], "algebraic": size["algebraic"],
               "operations": size["operations"], "loop_equations": size["loop_equations"],
               "redundant_equations": size["redundant_equations"], "build_s": build_s,
               "first_s": first, "first_jit_cached": cached,
               "first_jit_s": res.stats.get("jit_seconds", ""), "wall_s": warm,
               "steps": res.stats.get("steps", ""),
               "max_residual": float(residual.max()) if size["loop_equations"] else "",
               "t_end": res.settings["t_end"]}
        if name in REFERENCES:
            joint, simulate, energy, (th0, thd0) = REFERENCES[name]
            ref = simulate(th0, thd0, res.t)
            row["max_error"] = finite_max(res[f"{joint}.q"] - ref["theta"])
            rel = relative_energy(energy, rest_energy(energy), res[f"{joint}.q"],
                                  res[f"{joint}.qd"])
            row["energy_drift"] = finite_max(rel)
        rows.append(row)
        print(f"{name:16s} {size['formulation']:9s} states {size['states']:3d} alg "
              f"{size['algebraic']:2d} ops {size['operations']:5d} build "
              f"{build_s * 1e3:6.1f} ms first {first:6.3f} s warm {warm:6.3f} s  residual "
              f"{_g(row['max_residual'])} error {_g(row.get('max_error', ''))} energy "
              f"{_g(row.get('energy_drift', ''))}", flush=True)
    return rows


# -- part 2: formulations compared, work-precision ----------------------------------------------
def fourbar_systems():
    return {"partition": ls.fourbar(THETA0, probes=False).compile(),
            "projected": ls.fourbar(THETA0, probes=False).compile(loops="projected"),
            "baumgarte a=10": ls.fourbar(THETA0, probes=False).compile(
                loops="baumgarte", baumgarte_rate=10.0),
            "baumgarte a=0": ls.fourbar(THETA0, probes=False).compile(
                loops="baumgarte", baumgarte_rate=0.0)}


def run_once(system, t_end, n_points, method, **settings):
    """(Results, failure message or None): what ran, up to a failure."""
    try:
        return kn.simulate(system, t_end=t_end, n_points=n_points, method=method, jit=True,
                           **settings), None
    except kn.SimulationError as exc:
        return exc.results, str(exc)


def part_formulations(quick, systems):
    t_end, n = T_PRECISION, int(round(T_PRECISION / SPACING)) + 1
    t = np.linspace(0.0, t_end, n)
    ref = rl.fourbar_simulate(THETA0, 0.0, t)
    floor = "" if quick else finite_max(
        ref["theta"] - rl.fourbar_simulate(THETA0, 0.0, t, rtol=1e-13, atol=1e-13)["theta"])
    e_rest = rest_energy(rl.fourbar_energy)
    rtols = RTOLS_QUICK if quick else RTOLS
    steps = STEPS_QUICK if quick else STEPS
    runs = [("partition", "idas", dict(rtol=r, atol=r / 100), f"rtol {_tol(r)}")
            for r in rtols]
    runs += [("partition", "collocation", dict(step=h), f"h = {h:g} s") for h in steps]
    runs += [(f, m, dict(rtol=r, atol=r / 100), f"rtol {_tol(r)}")
             for f, m in (("projected", "cvodes-adams"), ("projected", "dop853"),
                          ("baumgarte a=10", "idas"), ("baumgarte a=10", "cvodes-adams"),
                          ("baumgarte a=10", "dop853"),
                          ("baumgarte a=0", "cvodes-adams")) for r in rtols]
    for form, method in dict.fromkeys((f, m) for f, m, _, _ in runs):
        run_once(systems[form], 1.0, 21, method, rtol=1e-6, atol=1e-8, step=0.05)
    rows = []
    for form, method, settings, label in runs:
        system = systems[form]
        wall, (res, failure) = timed(
            lambda: run_once(system, t_end, n, method, **settings), budget=0.3,
            max_repeats=5)
        q = res["A.q"] if len(res.t) else np.zeros(0)
        err = finite_max(q - ref["theta"]) if len(q) == n and failure is None else float("inf")
        size = system.size()
        rows.append({"part": "formulations", "model": "fourbar", "formulation": form,
                     "method": method, "setting": label, "rtol": settings.get("rtol", ""),
                     "step": settings.get("step", ""), "states": size["states"],
                     "algebraic": size["algebraic"], "operations": size["operations"],
                     "wall_s": wall, "steps": res.stats.get("steps", ""),
                     "rhs_evaluations": res.stats.get("rhs_evaluations", ""),
                     "max_error": err,
                     "max_residual": float(system.constraint_residual(res.states).max())
                     if len(res.t) else "",
                     "energy_drift": finite_max(relative_energy(
                         rl.fourbar_energy, e_rest, res["A.q"], res["A.qd"]))
                     if len(res.t) else "",
                     "failure": failure or "", "reference_floor": floor, "t_end": t_end})
        r = rows[-1]
        print(f"{form:15s} {method:13s} {label:14s} wall {wall:7.4f} s error "
              f"{r['max_error']:.2e} residual {_g(r['max_residual'])}"
              + (f"  FAILED: {failure}" if failure else ""), flush=True)
    return rows


# -- part 3: drift over a long run --------------------------------------------------------------
def raw_idas(system, t_end, n_points, rtol, atol):
    """The partition's full states as IDAS returns them, before ``simulate``'s polish: the
    same compiled equations and options that ``simulate`` hands IDAS."""
    p = system.param_vector()
    x0, z0 = system.initial_full_p(p)
    rate0 = tuple(float(v) for v in np.asarray(system.f_dae(0.0, x0, z0, p)[0]).ravel())
    grid = np.linspace(0.0, t_end, n_points)
    integ = ca.integrator("raw_idas", "idas", compiled(system).dae({"stats": {}}, True), 0.0,
                          [float(g) for g in grid[1:]],
                          dict(reltol=rtol, abstol=atol, calc_ic=False, init_xdot=rate0))
    out = integ(x0=x0, z0=z0, p=p)
    return np.vstack([np.concatenate([x0, z0]),
                      np.vstack([np.asarray(out["xf"]), np.asarray(out["zf"])]).T])


def part_drift(quick, systems):
    t_end = 20.0 if quick else 1000.0
    n = 201 if quick else 2001
    e_rest = rest_energy(rl.fourbar_energy)
    settings = dict(rtol=DRIFT_RTOL, atol=DRIFT_RTOL / 100)
    runs = [("partition", "idas"), ("projected", "cvodes-adams"),
            ("baumgarte a=10", "cvodes-adams"), ("baumgarte a=0", "cvodes-adams")]
    rows, curves = [], {}
    for form, method in runs:
        system = systems[form]
        run_once(system, 1.0, 11, method, **settings)             # JIT, integrator: untimed
        wall, (res, failure) = seconds(lambda: run_once(system, t_end, n, method, **settings))
        residual = system.constraint_residual(res.states)
        rel = relative_energy(rl.fourbar_energy, e_rest, res["A.q"], res["A.qd"])
        label = f"{form} + {method}"
        rows.append(_drift_row(form, method, label, wall, res, residual, rel, failure, t_end))
        curves[label + (" (polished)" if form == "partition" else "")] = (res.t, residual, rel)
        if form == "partition":
            system = systems[form]
            wall_raw, X = seconds(lambda: raw_idas(system, t_end, n, **settings))
            raw = system.constraint_residual(X)
            rel_raw = relative_energy(rl.fourbar_energy, e_rest, X[:, 0], X[:, 1])
            label_raw = "partition + idas, as IDAS holds it (no polish)"
            rows.append(_drift_row(form, "idas (raw)", label_raw, wall_raw, res, raw, rel_raw,
                                   None, t_end))
            curves[label_raw] = (res.t, raw, None)
    for r in rows:
        print(f"{r['setting']:50s} wall {r['wall_s']:6.2f} s residual max {r['max_residual']:.2e}"
              f" final {r['final_residual']:.2e}  energy max {r['energy_drift']:.2e} final "
              f"{r['final_energy_error']:+.2e}" + (f" FAILED {r['failure']}" if r["failure"]
                                                    else ""), flush=True)
    return rows, curves, t_end


def _drift_row(form, method, label, wall, res, residual, rel, failure, t_end):
    return {"part": "drift", "model": "fourbar", "formulation": form, "method": method,
            "setting": label, "rtol": DRIFT_RTOL, "wall_s": wall,
            "steps": res.stats.get("steps", "") if method != "idas (raw)" else "",
            "max_residual": float(np.max(residual)), "final_residual": float(residual[-1]),
            "first_residual": float(residual[1]) if len(residual) > 1 else "",
            "energy_drift": finite_max(rel), "final_energy_error": float(rel[-1]),
            "failure": failure or "", "t_end": t_end}


# -- part 4: N four-bars ------------------------------------------------------------------------
def part_chain(quick):
    rows = []
    for n in (CHAIN_QUICK if quick else CHAIN):
        builds = [seconds(lambda: ls.fourbar_chain(n).compile()) for _ in range(3)]
        build_s = statistics.median(b[0] for b in builds)
        system = builds[-1][1]
        size = system.size()
        jac = system.jacobian_function().n_instructions()
        npts = int(round(CHAIN_T / 0.01)) + 1
        first, (res, failure) = seconds(lambda: run_once(system, CHAIN_T, npts, "idas",
                                                         rtol=CHAIN_RTOL,
                                                         atol=CHAIN_RTOL / 100))
        warm = statistics.median(
            seconds(lambda: run_once(system, CHAIN_T, npts, "idas", rtol=CHAIN_RTOL,
                                     atol=CHAIN_RTOL / 100))[0] for _ in range(3))
        steps = res.stats.get("steps", 0)
        rows.append({"part": "chain", "model": f"fourbar_chain{n}", "N": n,
                     "formulation": size["formulation"], "method": "idas",
                     "setting": f"rtol {_tol(CHAIN_RTOL)}", "states": size["states"],
                     "algebraic": size["algebraic"], "operations": size["operations"],
                     "loop_equations": size["loop_equations"],
                     "redundant_equations": size["redundant_equations"],
                     "jacobian_instructions": jac,
                     "jacobian_compiled": jac <= JACOBIAN_JIT_LIMIT, "build_s": build_s,
                     "first_s": first, "first_jit_s": res.stats.get("jit_seconds", ""),
                     "wall_s": warm, "steps": steps,
                     "jacobian_evaluations": res.stats.get("jacobian_evaluations", ""),
                     "us_per_step": warm / steps * 1e6 if steps else "",
                     "max_residual": float(system.constraint_residual(res.states).max()),
                     "failure": failure or "", "t_end": CHAIN_T})
        r = rows[-1]
        print(f"N={n:3d} states {r['states']:3d} alg {r['algebraic']:3d} ops "
              f"{r['operations']:6d} jac {jac:8d} build {build_s:6.3f} s first {first:6.2f} s "
              f"warm {warm:6.3f} s steps {steps}", flush=True)
    return rows


def slope(x, y):
    x, y = np.asarray(x, float), np.asarray(y, float)
    return float(np.polyfit(np.log(x), np.log(y), 1)[0]) if len(x) > 1 else float("nan")


# -- charts ---------------------------------------------------------------------------------
SERIES = {("partition", "idas"): dict(color="C0"),
          ("projected", "cvodes-adams"): dict(color="C4"),
          ("projected", "dop853"): dict(color="C4", linestyle="--"),
          ("partition", "collocation"): dict(color="C0", linestyle="--"),
          ("baumgarte a=10", "idas"): dict(color="C1", linestyle="--"),
          ("baumgarte a=10", "cvodes-adams"): dict(color="C1"),
          ("baumgarte a=10", "dop853"): dict(color="C2"),
          ("baumgarte a=0", "cvodes-adams"): dict(color="C3", linestyle=":")}


def chart_precision(rows):
    """Log-log, as ``common.chart``, with the legend beside the axes (the curves fill them)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(10.5, 5.5), layout="constrained")
    for (form, method), style in SERIES.items():
        pick = [r for r in rows if r["formulation"] == form and r["method"] == method
                and np.isfinite(r["max_error"]) and r["max_error"] > 0]
        if not pick:
            continue
        what = "steps 0.05 .. 0.003 s" if method == "collocation" else "rtol 1e-4 .. 1e-12"
        ax.loglog([r["wall_s"] for r in pick], [r["max_error"] for r in pick], marker="o",
                  markersize=3.5, label=f"{form} + {method}\n({what})", **style)
    floor = rows[0]["reference_floor"]
    if floor != "":
        ax.axhline(floor, color="0.5", linewidth=0.8,
                   label="reference floor\n(1e-12 vs 1e-13 reference)")
    ax.set_xlabel("wall time of one run [s] (median of repeats after a warm-up, JIT on)")
    ax.set_ylabel("max |crank angle − reference| over 10 s [rad]")
    ax.set_title("Four-bar, θ0 = 1 rad, undamped, 10 s: work-precision of the loop "
                 "formulations\n(partition: 2 states + 3 algebraic; projected: 5 states; "
                 "Baumgarte: 8 states; "
                 "atol = rtol / 100)")
    ax.grid(True, which="major", alpha=0.4)
    ax.grid(True, which="minor", alpha=0.12)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), labelspacing=0.9)
    fig.savefig(RESULTS / "study_loops_precision.png", dpi=110)
    plt.close(fig)


def chart_drift(curves, t_end, window):
    """Max over each ``window`` seconds of the residual and of |relative energy error|."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(2, 1, figsize=(10, 7.5), sharex=True, layout="constrained")
    styles = {"partition + idas (polished)": dict(color="C0", linewidth=2.0),
              "partition + idas, as IDAS holds it (no polish)": dict(color="C0", linewidth=1.0,
                                                                     linestyle="--"),
              "projected + cvodes-adams": dict(color="C4", linewidth=1.4),
              "baumgarte a=10 + cvodes-adams": dict(color="C1", linewidth=1.4),
              "baumgarte a=0 + cvodes-adams": dict(color="C3", linewidth=1.4)}
    for label, (t, residual, rel) in curves.items():
        per = max(1, int(round(window / (t[1] - t[0]))))
        k = (len(t) - 1) // per
        t_win = t[1:1 + k * per].reshape(k, per)[:, -1]
        env = lambda v: np.abs(v[1:1 + k * per]).reshape(k, per).max(axis=1)  # noqa: E731
        axes[0].semilogy(t_win, np.maximum(env(residual), FLOOR), label=label,
                         **styles.get(label, {}))
        if rel is not None:
            axes[1].semilogy(t_win, np.maximum(env(rel), FLOOR), label=label,
                             **styles.get(label, {}))
    axes[0].set_ylabel(f"max over {window:g} s of\nmax |closure residual| [m]")
    axes[1].set_ylabel(f"max over {window:g} s of\n|E(t) − E(0)| / (E(0) − E_rest)")
    axes[0].set_title(f"closure residual (polished partition: ~1e-16 or 0, drawn at "
                      f"{FLOOR:g})", fontsize=10)
    axes[1].set_title("energy error (reference energy on the kinetwork crank angle and speed)",
                      fontsize=10)
    for ax in axes:
        ax.grid(True, which="major", alpha=0.4)
        ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    axes[1].set_xlabel("time [s]")
    axes[1].set_xlim(0, t_end)
    fig.suptitle(f"Undamped four-bar (θ0 = 1 rad), {t_end:g} s at rtol {_tol(DRIFT_RTOL)}, "
                 f"atol {_tol(DRIFT_RTOL / 100)}")
    fig.savefig(RESULTS / "study_loops_drift.png", dpi=110)
    plt.close(fig)


def chart_chain(rows, fits):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    N = [r["N"] for r in rows]
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.8), layout="constrained")
    counts = {"operations per evaluation (DAE)": ("operations", "C0"),
              "exact Jacobian instructions": ("jacobian_instructions", "C4"),
              "states + algebraic variables": (None, "C2")}
    for label, (key, color) in counts.items():
        y = [r["states"] + r["algebraic"] for r in rows] if key is None else \
            [r[key] for r in rows]
        axes[0].loglog(N, y, marker="o", markersize=4, color=color,
                       label=f"{label}  (slope {slope(N, y):.2f})")
    axes[0].axhline(JACOBIAN_JIT_LIMIT, color="C4", linestyle=":", linewidth=1)
    axes[0].text(N[0], JACOBIAN_JIT_LIMIT * 1.3, "JACOBIAN_JIT_LIMIT: above it, no compiled "
                 "Jacobian", fontsize=7.5, color="C4")
    axes[0].set_ylim(0.5, JACOBIAN_JIT_LIMIT * 30)
    axes[0].set_ylabel("count")
    axes[0].set_title("size", fontsize=10)
    times = {"simulation, warm (median of 3)": ("wall_s", dict(color="C0")),
             "first simulation (cold JIT cache: gcc)": ("first_s", dict(color="C3",
                                                                         linestyle="--")),
             "build (model + compile, median of 3)": ("build_s", dict(color="C1"))}
    for label, (key, style) in times.items():
        y = [r[key] for r in rows]
        axes[1].loglog(N, y, marker="o", markersize=4, label=f"{label}  (slope "
                       f"{slope(N, y):.2f})", **style)
    axes[1].set_ylabel("wall time [s]")
    axes[1].set_title(f"time ({CHAIN_T:g} s simulated, partition + idas, rtol "
                      f"{_tol(CHAIN_RTOL)})", fontsize=10)
    for ax in axes:
        ax.set_xlabel("four-bars in the chain N")
        ax.set_xticks(N, [str(n) for n in N])
        ax.minorticks_off()
        ax.grid(True, which="major", alpha=0.4)
        ax.legend(fontsize=7.5, loc="lower right")
    fig.suptitle("N four-bars hung one from the other (fourbar_chain): N degrees of freedom, "
                 "N loops; slopes: log-log fit over all N")
    fig.savefig(RESULTS / "study_loops_chain.png", dpi=110)
    plt.close(fig)


# -- report -------------------------------------------------------------------------------------
def _g(x, spec=".1e"):
    return "—" if x == "" or x is None else format(x, spec)


def report(models, forms, drift, t_drift, chain, fits, total, quick, refusal):
    m = {r["model"]: r for r in models}
    body1 = [[r["model"], r["formulation"], r["method"], r["states"], r["algebraic"],
              r["operations"], f"{r['build_s'] * 1e3:.0f}", f"{r['first_s']:.3f}",
              _g(r["first_jit_s"], ".3f"), f"{r['wall_s']:.3f}", r["steps"], _g(r["max_residual"]),
              _g(r.get("max_error", "")), _g(r.get("energy_drift", ""))] for r in models]
    fb, sc = m["fourbar"], m["slider_crank"]
    by = {}
    for r in forms:
        by.setdefault((r["formulation"], r["method"]), []).append(r)
    body2 = [[f, mth, r["setting"], f"{r['wall_s'] * 1e3:.1f}", _g(r["steps"], ".0f")
              if r["steps"] != "" else "—", _g(r["max_error"]), _g(r["max_residual"]),
              _g(r["energy_drift"])] for (f, mth), rs in by.items() for r in rs]
    floor = forms[0]["reference_floor"]
    sizes = {}
    for r in forms:
        sizes.setdefault(r["formulation"], f"{r['states']} states, {r['algebraic']} algebraic, "
                                           f"{r['operations']} operations")
    body3 = [[r["setting"], f"{r['wall_s']:.2f}", r["steps"] if r["steps"] != "" else "—",
              _g(r["max_residual"]), _g(r["final_residual"]), _g(r["energy_drift"]),
              f"{r['final_energy_error']:+.1e}"] for r in drift]
    body4 = [[r["N"], r["states"], r["algebraic"], r["operations"],
              r["jacobian_instructions"], "yes" if r["jacobian_compiled"] else "no (FD)",
              f"{r['build_s'] * 1e3:.0f}", f"{r['first_s']:.2f}", _g(r["first_jit_s"], ".2f"),
              f"{r['wall_s']:.3f}", r["steps"], r["jacobian_evaluations"],
              f"{r['us_per_step']:.0f}", _g(r["max_residual"])] for r in chain]
    quick_note = " (quick smoke run)" if quick else ""
    lines = [f"## Loops: the partition, projected and Baumgarte formulations{quick_note}",
             "", f"{machine()}; {load()}. Study wall time {total:.0f} s. JIT on throughout, "
             f"with an empty cache folder of the study's own: a \"first\" run includes the C "
             f"compiler. Crank-angle errors against `reference_loops` (sympy-derived reduced "
             f"Lagrangian, DOP853 at rtol = atol = 1e-12). Energy error = (E(t) − E(0)) / "
             f"(E(0) − E_rest), the references' energy on kinetwork's crank angle and speed, "
             f"E_rest the minimum of the potential. `simulate` Newton-polishes the "
             f"partition's algebraic variables at the output points, so its residual there is "
             f"~1e-15 by construction; part 3 also shows what IDAS itself held.", "",
             "### 1. The loop models at their own settings", "",
             "`kn.simulate(system)` with each model's simulation block (10 s, 1001 points; "
             "fourbar and slider_crank rtol 1e-12, the others 1e-10; dzhanibekov 20 s). "
             "Build: model construction + `compile()`, median of 3. First: the first "
             "`simulate` on the System (JIT compile, integrator); warm: median of 3 more. "
             "Operations: `system.size()` (partition: the DAE's ode + alg; tree: the ODE).", "",
             table(["model", "formulation", "method", "states", "algebraic", "operations",
                    "build [ms]", "first [s]", "of it JIT [s]", "warm [s]", "steps",
                    "max residual",
                    "max crank error [rad]", "energy error"], body1), "",
             f"- fourbar: crank angle within {fb['max_error']:.1e} rad of the reference over "
             f"10 s, energy error {fb['energy_drift']:.1e}; slider_crank: "
             f"{sc['max_error']:.1e} rad, {sc['energy_drift']:.1e}. Both at rtol 1e-12 take "
             f"{fb['steps']} and {sc['steps']} IDAS steps "
             f"({fb['wall_s'] * 1e3:.0f} and {sc['wall_s'] * 1e3:.0f} ms).",
             f"- The planar four-bar and slider-crank keep 3 of 12 closure equations "
             f"(the 9 others, out-of-plane and rotation rows of the 3-D revolute cut, are "
             f"dropped as redundant); the spatial four-bar keeps the 3 of its Spherical cut, "
             f"none redundant, and costs {m['spatial_fourbar']['operations']} operations "
             f"against {fb['operations']} for the planar one.", "",
             f"### 2. Formulations compared on the four-bar (θ0 = {THETA0:g} rad, undamped)", "",
             f"10 s, output every {SPACING} s, no probes; wall time: median of repeats after a "
             f"warm-up run; atol = rtol / 100. Residual: max closure residual at the outputs. "
             f"Sizes: partition {sizes['partition']}; projected {sizes['projected']}; "
             f"Baumgarte {sizes['baumgarte a=10']}. "
             + (f"Reference floor: the reference at 1e-12 and at 1e-13 differ by "
                f"{floor:.1e} rad; errors near it are not resolved." if floor != "" else ""),
             "", table(["formulation", "method", "setting", "wall [ms]", "steps",
                        "max crank error [rad]", "max residual", "energy error"], body2), "",
             "![work-precision](study_loops_precision.png)", ""]
    lines += findings_precision(by, forms)
    lines += ["", f"### 3. Drift over {t_drift:g} s", "",
              f"The four-bar of part 2 over {t_drift:g} s at rtol {_tol(DRIFT_RTOL)}, atol "
              f"{_tol(DRIFT_RTOL / 100)}. \"No polish\": the same IDAS run without `simulate`'s "
              f"Newton correction of the algebraic variables at the outputs (same differential "
              f"states). Wall: one run, JIT compiled beforehand.", "",
              table(["run", "wall [s]", "steps", "max residual", "final residual",
                     "max |energy error|", "final energy error"], body3), "",
              "![drift](study_loops_drift.png)", ""]
    lines += findings_drift(drift, t_drift)
    lines += ["", "### 4. Growth with N four-bars", "",
              f"`fourbar_chain(N)`: N four-bars, each hung from the rocker tip of the one "
              f"before; {CHAIN_T:g} s at rtol {_tol(CHAIN_RTOL)} (atol {_tol(CHAIN_RTOL / 100)}), "
              f"partition + idas, 201 output points. Build: median of 3. First: the first "
              f"run (JIT compile of the DAE and, when under `JACOBIAN_JIT_LIMIT` = "
              f"{JACOBIAN_JIT_LIMIT:,} instructions, its exact Jacobian; otherwise IDAS "
              f"differentiates the compiled DAE by finite differences, \"FD\"). Warm: median "
              f"of 3.", "",
              table(["N", "states", "algebraic", "operations", "Jacobian instr.",
                     "Jacobian compiled", "build [ms]", "first [s]", "of it JIT [s]",
                     "warm [s]", "steps", "Jacobian evals", "us / step", "max residual"],
                    body4), "",
              "Log-log slopes against N (least squares over all N"
              + (", and over N ≤ 8" if any(r["N"] > 8 for r in chain) else "") + "):", "",
              table(["quantity", "slope"] + (["slope N ≤ 8"] if "ops_8" in fits else []),
                    [[k, f"{v[0]:.2f}"] + ([f"{v[1]:.2f}"] if len(v) > 1 else [])
                     for k, v in fits["table"].items()]), "",
              "![chain](study_loops_chain.png)", ""]
    lines += findings_chain(chain, fits)
    lines += ["", "### Where each formulation fails or costs more", ""]
    lines += summary(by, drift, t_drift, refusal)
    write_markdown("study_loops", "\n".join(lines))


def findings_precision(by, forms):
    out = ["Findings:", ""]

    def at(form, method, key, value):
        return next((r for r in by.get((form, method), []) if r[key] == value), None)

    for rtol in (1e-8, 1e-12):
        runs = [(f, mth, at(f, mth, "rtol", rtol)) for f, mth in
                (("partition", "idas"), ("projected", "cvodes-adams"),
                 ("projected", "dop853"), ("baumgarte a=10", "idas"),
                 ("baumgarte a=10", "cvodes-adams"),
                 ("baumgarte a=10", "dop853"), ("baumgarte a=0", "cvodes-adams"))]
        runs = [(f, mth, r) for f, mth, r in runs if r]
        if runs:
            out.append(f"- At rtol {_tol(rtol)}: " + "; ".join(
                f"{f} + {mth} {r['max_error']:.1e} rad in {r['wall_s'] * 1e3:.1f} ms "
                f"(residual {r['max_residual']:.0e})" for f, mth, r in runs) + ".")
    ratios = []
    for (f, mth), rs in by.items():
        ratio = [r["max_error"] / r["rtol"] for r in rs
                 if r["rtol"] != "" and np.isfinite(r["max_error"])]
        if ratio:
            ratios.append(f"{f} + {mth} {min(ratio):.0e} .. {max(ratio):.0e}")
    if ratios:
        out.append("- Crank-angle error / rtol: " + "; ".join(ratios) + ". Every method's "
                   "global error is one to five orders of magnitude above its rtol; the "
                   "motion (the crank swings from 1 rad to −4.4 rad and back at up to "
                   "16 rad/s, short of going over the top) is a likely reason.")
    same = [(a, b) for a in by.get(("partition", "idas"), [])
            for b in by.get(("baumgarte a=10", "idas"), []) if a["rtol"] == b["rtol"]]
    if same:
        q = [a["max_error"] / b["max_error"] for a, b in same]
        out.append(f"- Same integrator (IDAS), same rtol: the partition's crank error is "
                   f"{min(q):.1f}× to {max(q):.0f}× the Baumgarte ODE's (median "
                   f"{statistics.median(q):.1f}×); wall-time ratio partition / Baumgarte: "
                   + ", ".join(f"{a['wall_s'] / b['wall_s']:.1f} ({_tol(a['rtol'])})"
                               for a, b in same) + ".")
    for target in TARGETS:
        best = []
        for (f, mth), rs in by.items():
            ok = [r for r in rs if r["max_error"] <= target]
            if ok:
                r = min(ok, key=lambda r: r["wall_s"])
                best.append((r["wall_s"], f"{f} + {mth} {r['wall_s'] * 1e3:.1f} ms "
                                          f"({r['setting']})"))
        if best:
            out.append(f"- Cheapest run with crank error ≤ {target:.0e} rad: "
                       + "; ".join(b for _, b in sorted(best)) + ".")
    coll = by.get(("partition", "collocation"), [])
    if coll:
        best = min(coll, key=lambda r: r["max_error"])
        errs = ", ".join(f"{r['max_error']:.0e}" for r in coll)
        hs = ", ".join(f"{r['step']:g}" for r in coll)
        ms = ", ".join(f"{r['wall_s'] * 1e3:.0f}" for r in coll)
        cheap = _cheapest(forms, best["max_error"])
        out.append(f"- partition + collocation: {errs} rad at steps {hs} s, {ms} ms"
                   + (f"; its best ({best['max_error']:.0e} rad) costs "
                      f"{best['wall_s'] / cheap:.0f} times the cheapest variable-step run "
                      f"at least as accurate." if np.isfinite(cheap) else
                      "; no variable-step run here is as accurate as its best."))
    zero = by.get(("baumgarte a=0", "cvodes-adams"), [])
    ten = by.get(("baumgarte a=10", "cvodes-adams"), [])
    if zero and ten:
        out.append("- Baumgarte residual at the outputs, a = 10 against a = 0 (cvodes-adams): "
                   + ", ".join(f"rtol {_tol(a['rtol'])}: {a['max_residual']:.0e} / "
                               f"{b['max_residual']:.0e}" for a, b in zip(ten, zero)) + ".")
    return out


def _cheapest(forms, error):
    ok = [r["wall_s"] for r in forms if r["method"] != "collocation"
          and r["max_error"] <= error]
    return min(ok) if ok else float("nan")


def ode_refusal(system):
    """What an ODE method says to the partition (DAE) model: the ModelError, or None."""
    try:
        kn.simulate(system, t_end=0.1, n_points=3, method="cvodes-adams")
    except kn.ModelError as exc:
        return str(exc)
    return None


def _cheapest_run(rows, target):
    ok = [r for r in rows if r["max_error"] <= target]
    return min(ok, key=lambda r: r["wall_s"]) if ok else None


def summary(by, drift, t_end, refusal):
    d = {row["setting"]: row for row in drift}
    part, raw = d["partition + idas"], d["partition + idas, as IDAS holds it (no polish)"]
    b10, b0 = d["baumgarte a=10 + cvodes-adams"], d["baumgarte a=0 + cvodes-adams"]
    out = []
    for target in TARGETS:
        p = _cheapest_run(by.get(("partition", "idas"), []), target)
        c = _cheapest_run(by.get(("partition", "collocation"), []), target)
        b = _cheapest_run(by.get(("baumgarte a=10", "cvodes-adams"), []), target)
        if p and b:
            out.append(f"- Cost at crank error ≤ {target:.0e} rad over 10 s: partition + idas "
                       f"{p['wall_s'] * 1e3:.1f} ms ({p['setting']}), "
                       f"{p['wall_s'] / b['wall_s']:.1f}× Baumgarte a = 10 + cvodes-adams "
                       f"({b['wall_s'] * 1e3:.1f} ms, {b['setting']})"
                       + (f"; partition + collocation {c['wall_s'] * 1e3:.0f} ms "
                          f"({c['wall_s'] / b['wall_s']:.0f}×)" if c else "") + ".")
    pr = d["projected + cvodes-adams"]
    for target in TARGETS:
        p = _cheapest_run(by.get(("partition", "idas"), []), target)
        j = _cheapest_run(by.get(("projected", "cvodes-adams"), []), target)
        if p and j:
            out.append(f"- Projected + cvodes-adams at crank error ≤ {target:.0e} rad: "
                       f"{j['wall_s'] * 1e3:.1f} ms ({j['setting']}), "
                       f"{p['wall_s'] / j['wall_s']:.1f}× faster than partition + idas.")
    out += [f"- Projected: 5 states (the 3 dependent coordinates carried as Newton starts); "
            f"the closure holds to {pr['max_residual']:.0e} over {t_end:g} s and the energy "
            f"error ends at {pr['final_energy_error']:+.1e}; any ODE method takes it."]
    out += [f"- Partition: the closure holds to {part['max_residual']:.0e} at the outputs "
            f"(polished) and to {raw['max_residual']:.0e} as IDAS held it, over {t_end:g} s; "
            f"its energy error after {t_end:g} s, {part['final_energy_error']:+.1e}, is "
            f"{abs(part['final_energy_error'] / b10['final_energy_error']):.0f}× Baumgarte "
            f"a = 10's ({b10['final_energy_error']:+.1e}) at the same rtol. It takes only the "
            f"DAE methods (idas, collocation)"
            + (": an ODE method is refused (ModelError: \"" + refusal.split(";")[0].strip()
               + "\")." if refusal else "."),
            f"- Baumgarte a = 10: 8 states against 2 + 3 algebraic; the residual stays near "
            f"the tolerance ({b10['max_residual']:.0e} max over {t_end:g} s at rtol "
            f"{_tol(DRIFT_RTOL)}), not at round-off.",
            f"- Baumgarte a = 0 (plain index reduction): the residual grows from "
            f"{_first_window(b0)} to {b0['final_residual']:.0e} over {t_end:g} s and the "
            f"energy error reaches {b0['energy_drift']:.0e}."]
    target = TARGETS[-1]
    z = _cheapest_run(by.get(("baumgarte a=0", "cvodes-adams"), []), target) or \
        _cheapest_run(by.get(("baumgarte a=0", "cvodes-adams"), []), TARGETS[0])
    t = _cheapest_run(by.get(("baumgarte a=10", "cvodes-adams"), []), z["max_error"]) \
        if z else None
    if z and t:
        out[-1] = out[-1][:-1] + (
            f"; over the 10 s of part 2 the cheapest run to a crank error ≤ "
            f"{z['max_error']:.0e} rad takes {z['wall_s'] * 1e3:.1f} ms with a = 0 and "
            f"{t['wall_s'] * 1e3:.1f} ms with a = 10: the drift costs on long runs, not "
            f"short ones.")
    return out


def _first_window(row):
    return f"{row['first_residual']:.0e} (first output)" if row.get("first_residual") else "~0"


def findings_drift(drift, t_end):
    r = {row["setting"]: row for row in drift}
    part = r["partition + idas"]
    raw = r["partition + idas, as IDAS holds it (no polish)"]
    b10, b0 = r["baumgarte a=10 + cvodes-adams"], r["baumgarte a=0 + cvodes-adams"]
    pr = r["projected + cvodes-adams"]
    return ["Findings:", "",
            f"- Projected + cvodes-adams: residual {pr['max_residual']:.0e} (max), energy "
            f"error {pr['energy_drift']:.1e} (final {pr['final_energy_error']:+.1e}), "
            f"{pr['wall_s']:.2f} s ({pr['steps']} steps).",
            f"- Closure residual over {t_end:g} s: partition polished {part['max_residual']:.0e}"
            f" (by construction), as IDAS held it {raw['max_residual']:.0e} (max), "
            f"{raw['final_residual']:.0e} at the end; Baumgarte a = 10 {b10['max_residual']:.0e} "
            f"(bounded); a = 0 grows to {b0['final_residual']:.0e} at {t_end:g} s.",
            f"- Energy error over {t_end:g} s: partition + idas {part['energy_drift']:.1e} "
            f"(final {part['final_energy_error']:+.1e}), Baumgarte a = 10 "
            f"{b10['energy_drift']:.1e} (final {b10['final_energy_error']:+.1e}), a = 0 "
            f"{b0['energy_drift']:.1e}.",
            f"- Wall: partition + idas {part['wall_s']:.2f} s ({part['steps']} steps), "
            f"Baumgarte a = 10 {b10['wall_s']:.2f} s ({b10['steps']} steps), a = 0 "
            f"{b0['wall_s']:.2f} s ({b0['steps']} steps)."]


def findings_chain(chain, fits):
    last = chain[-1]
    out = ["Findings:", "",
           f"- Operations grow as N^{fits['table']['operations'][0]:.2f}, the exact "
           f"Jacobian as N^{fits['table']['Jacobian instructions'][0]:.2f}, the warm "
           f"simulation time as N^{fits['table']['simulation (warm)'][0]:.2f} (IDAS steps as "
           f"N^{fits['table']['IDAS steps'][0]:.2f}, time per step as "
           f"N^{fits['table']['time per step'][0]:.2f}). "
           f"At N = {last['N']}: {last['operations']} operations, {last['wall_s']:.2f} s for "
           f"{CHAIN_T:g} s simulated, build {last['build_s'] * 1e3:.0f} ms."]
    fd = [r for r in chain if not r["jacobian_compiled"]]
    ok = [r for r in chain if r["jacobian_compiled"]]
    if fd and ok:
        a, b = ok[-1], fd[0]
        out.append(f"- From N = {a['N']} to N = {b['N']} the warm time jumps "
                   f"{b['wall_s'] / a['wall_s']:.0f}× ({a['us_per_step']:.0f} → "
                   f"{b['us_per_step']:.0f} us per step): the exact Jacobian "
                   f"({b['jacobian_instructions']:,} instructions) is over "
                   f"JACOBIAN_JIT_LIMIT, so IDAS's {b['jacobian_evaluations']} Jacobian "
                   f"evaluations are finite differences of the compiled DAE "
                   f"({b['states'] + b['algebraic']} columns each).")
    slow = max(chain, key=lambda r: r["first_s"])
    out.append(f"- First run (cold cache): up to {slow['first_s']:.1f} s at N = {slow['N']}, "
               f"{_g(slow['first_jit_s'], '.1f')} s of it JIT (code generation and gcc on the "
               f"DAE" + (f" and its exact Jacobian, {slow['jacobian_instructions']:,} "
                         f"instructions)." if slow["jacobian_compiled"] else ")."))
    return out


def chain_fits(chain):
    N = [r["N"] for r in chain]
    keys = {"operations": "operations", "Jacobian instructions": "jacobian_instructions",
            "build": "build_s", "simulation (warm)": "wall_s", "IDAS steps": "steps",
            "time per step": "us_per_step"}
    small = [r for r in chain if r["N"] <= 8]
    table_ = {}
    for name, key in keys.items():
        v = [slope(N, [r[key] for r in chain])]
        if len(small) < len(chain) and len(small) > 1:
            v.append(slope([r["N"] for r in small], [r[key] for r in small]))
        table_[name] = v
    fits = {"table": table_}
    if len(small) < len(chain):
        fits["ops_8"] = True
    return fits


def main(quick=False):
    clock = time.perf_counter()
    saved = os.environ.get("KINETWORK_CACHE")
    try:
        with tempfile.TemporaryDirectory(prefix="kinetwork_loops_") as folder:
            os.environ["KINETWORK_CACHE"] = folder        # jit.cache_dir() reads it per call
            print("-- 1. loop models", flush=True)
            models = part_models(quick)
            systems = fourbar_systems()
            refusal = ode_refusal(systems["partition"])
            print("-- 2. formulations compared", flush=True)
            forms = part_formulations(quick, systems)
            print("-- 3. drift", flush=True)
            drift, curves, t_drift = part_drift(quick, systems)
            print("-- 4. N four-bars", flush=True)
            chain = part_chain(quick)
    finally:
        if saved is None:
            os.environ.pop("KINETWORK_CACHE", None)
        else:
            os.environ["KINETWORK_CACHE"] = saved
    rows = models + forms + drift + chain
    keys = list(dict.fromkeys(k for r in rows for k in r))
    write_csv("study_loops", [{k: r.get(k, "") for k in keys} for r in rows])
    fits = chain_fits(chain)
    chart_precision(forms)
    chart_drift(curves, t_drift, window=10.0 if t_drift > 100 else 1.0)
    chart_chain(chain, fits)
    total = time.perf_counter() - clock
    report(models, forms, drift, t_drift, chain, fits, total, quick, refusal)
    print(f"study_loops: {total:.1f} s")


# -- part 5: the Pareto front at 1e-6 (issue 18, item 3) --------------------------------------
PARETO_TARGET = 1e-6
PARETO_RTOLS = tuple(10.0 ** -k for k in range(3, 12))
PARETO_STEPS = (0.05, 0.025, 0.0125, 0.00625, 0.003125)
#: (formulation, method): every kinetwork combination that runs the loops
#: the closure residual the issue asks a loop run to keep (max at the outputs)
PARETO_RESIDUAL = 1e-10
#: (formulation, method); (None, "auto") is what a user gets: ``compile()``, ``method="auto"``
PARETO_COMBOS = ((None, "auto"), ("partition", "idas"), ("partition", "collocation"),
                 ("projected", "cvodes-adams"), ("projected", "cvodes"), ("projected", "dop853"),
                 ("projected", "idas"), ("baumgarte", "cvodes-adams"), ("baumgarte", "idas"))


def _pareto_references(t):
    """Crank angle on ``t`` per model: the sympy-derived references for the planar loops; the
    spatial four-bar has none, so kinetwork's Baumgarte ODE (all 8 coordinates, another
    formulation than the default's) under scipy's DOP853 at 1e-13: its closure residual stays
    below 2e-13, and it agrees with the projected ODE under DOP853 to 1.4e-11."""
    spatial = kn.simulate(ls.spatial_fourbar(probes=False).compile(loops="baumgarte"),
                          t_end=t[-1], n_points=len(t), method="dop853", rtol=1e-13,
                          atol=1e-15, jit=True)
    return {"fourbar": ("A.q", rl.fourbar_simulate(THETA0, 0.0, t, rtol=1e-13,
                                                   atol=1e-13)["theta"]),
            "slider_crank": ("O.q", rl.slider_crank_simulate(0.5, 3.0, t, rtol=1e-13,
                                                             atol=1e-13)["theta"]),
            "spatial_fourbar": ("A.q", spatial["A.q"])}


def part_pareto(quick):
    """For each loop model and combination: the cheapest run whose crank-angle error over
    10 s is within PARETO_TARGET (rtol swept 1e-3 .. 1e-11, atol = rtol / 100, or the
    collocation step halved), its wall time (median of repeats after a warm-up), closure
    residual and state count. The tolerances are the user's: ``simulate`` maps them
    (``tolerance.py``)."""
    t_end, n = T_PRECISION, int(round(T_PRECISION / SPACING)) + 1
    t = np.linspace(0.0, t_end, n)
    refs = _pareto_references(t)
    builders = {"fourbar": lambda: ls.fourbar(THETA0, probes=False),
                "slider_crank": lambda: ls.slider_crank(probes=False),
                "spatial_fourbar": lambda: ls.spatial_fourbar(probes=False)}
    rows = []
    for model, build in builders.items():
        joint, ref = refs[model]
        for form, method in PARETO_COMBOS:
            system = build().compile() if form is None else build().compile(loops=form)
            if form is None:
                form = f"default ({system.formulation})"
            fixed = method == "collocation"
            sweep = [dict(step=h) for h in PARETO_STEPS] if fixed else \
                [dict(rtol=r, atol=r / 100) for r in PARETO_RTOLS]
            run_once(system, 1.0, 21, method, **(sweep[0] if fixed else
                                                  dict(rtol=1e-6, atol=1e-8)))
            best = None
            for settings in sweep:
                wall, (res, failure) = timed(
                    lambda: run_once(system, t_end, n, method, **settings), budget=0.3,
                    max_repeats=3 if quick else 5)
                ok = failure is None and len(res.t) == n
                err = finite_max(res[joint] - ref) if ok else float("inf")
                if err <= PARETO_TARGET:
                    size = system.size()
                    best = {"part": "pareto", "model": model, "formulation": form,
                            "method": method, "setting": ", ".join(
                                f"{k} {_tol(v) if k != 'step' else f'{v:g} s'}"
                                for k, v in settings.items() if k != "atol"),
                            "wall_s": wall, "max_error": err, "ran": res.settings["method"],
                            "max_residual": float(system.constraint_residual(res.states).max()),
                            "states": size["states"], "algebraic": size["algebraic"]}
                    break
                if wall > (0.5 if quick else 3.0):
                    break
            rows.append(best or {"part": "pareto", "model": model, "formulation": form,
                                 "method": method, "setting": "not reached", "wall_s": "",
                                 "max_error": "", "max_residual": "",
                                 "states": system.size()["states"],
                                 "algebraic": system.size()["algebraic"]})
            r = rows[-1]
            print(f"{model:16s} {form:10s} {method:13s} {r['setting']:14s} "
                  f"{_g(r['wall_s'])} s error {_g(r['max_error'])}", flush=True)
    return rows


def report_pareto(rows, wall):
    body = [[r["model"], r["formulation"], r["method"], r["states"], r["algebraic"],
             r["setting"], f"{r['wall_s'] * 1e3:.1f}" if r["wall_s"] != "" else "—",
             _g(r["max_error"]), _g(r["max_residual"])] for r in rows]
    lines = ["## Loops on the Pareto front: the cheapest run to 1e-6", "",
             f"{machine()}; {load()}. Study wall time {wall:.0f} s. Each loop model over "
             f"{T_PRECISION:g} s, output every {SPACING:g} s, no probes, JIT on. For every "
             f"formulation + method: the first run of the sweep (rtol 1e-3 .. 1e-11, atol = "
             f"rtol / 100, as a user asks them: `simulate` tightens them for CVODES and IDAS, "
             f"`kinetwork/solver/tolerance.py`; collocation: step 0.05 s halved) whose "
             f"max crank-angle error is within {PARETO_TARGET:g} rad of the reference "
             f"(`reference_loops` for the planar two; for the spatial four-bar, which has "
             f"none, kinetwork's Baumgarte ODE under DOP853 at 1e-13), its wall time (median "
             f"of repeats after a warm-up) and max closure residual at the outputs.", "",
             table(["model", "formulation", "method", "states", "algebraic", "reached at",
                    "wall [ms]", "max crank error", "max residual"], body), ""]
    out = [f"Fastest to 1e-6 per model among the combinations that keep the closure residual "
           f"below {PARETO_RESIDUAL:g}. The default is `compile()` with `method=\"auto\"`; "
           f"its twin, the row of the formulation and method it runs, is the very same run "
           f"timed again (their ratio is the timing noise), so it is compared with the "
           f"fastest of the others:", ""]
    for model in dict.fromkeys(r["model"] for r in rows):
        done = [r for r in rows if r["model"] == model and r["wall_s"] != ""
                and r["max_residual"] <= PARETO_RESIDUAL]
        default = next(r for r in rows if r["model"] == model
                       and r["formulation"].startswith("default"))
        twin = (default["formulation"][len("default ("):-1], default.get("ran"))
        others = [r for r in done if not r["formulation"].startswith("default")
                  and (r["formulation"], r["method"]) != twin]
        best = min(others, key=lambda r: r["wall_s"])
        out.append(f"- {model}: fastest other {best['formulation']} + {best['method']} "
                   f"{best['wall_s'] * 1e3:.1f} ms; the {default['formulation']} + auto "
                   f"(runs {default.get('ran')}) "
                   + (f"{default['wall_s'] * 1e3:.1f} ms ({default['wall_s'] / best['wall_s']:.2f}"
                      f" x), {default['states']} states, closure residual "
                      f"{_g(default['max_residual'])}" if default["wall_s"] != ""
                      else "did not reach it") + ".")
    write_markdown("study_loops_pareto", "\n".join(lines + out))


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true",
                        help="smoke test: rtol 1e-4 and 1e-8, 20 s drift run, N = 1, 2")
    parser.add_argument("--pareto", action="store_true",
                        help="only part 5: the cheapest run of each formulation + method to "
                             "1e-6 on the three loop models (results/study_loops_pareto.md)")
    args = parser.parse_args()
    if args.pareto:
        clock = time.perf_counter()
        report_pareto(part_pareto(args.quick), time.perf_counter() - clock)
    else:
        main(args.quick)
