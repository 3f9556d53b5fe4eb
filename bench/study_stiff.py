"""Stiffness: which methods survive the seed's shoulder spring-damper made k times harder.

Scenes stiff1e4 / stiff1e5 / stiff1e6 (c = d = k), 10 s, output every 0.01 s. Every method of
``kn.METHODS`` at rtol 1e-6 (atol 1e-8), the fixed-step ones (and MuJoCo's integrators) at
steps of 1e-2 .. 1e-4 s (the explicit ones down to 1e-5 s, where RK4 becomes stable at
k = 1e4). For each: success or failure (the SimulationError's reason and the
time reached), steps and right-hand-side evaluations, wall time, and the max joint-angle
error against an independent reference (scipy Radau at rtol 1e-12 on the paper's closed-form
M, V, G with c = d = k, written below).

No single run may take much longer than CAP seconds: each run is first timed on 0.01 s, then
on each longer horizon of HORIZONS while the last run's time, scaled to it, fits in CAP.
Runs cut short this way report their counts and times scaled linearly to 10 s and say so
("horizon" column, "extrapolated" flag); their error is over the horizon run only. The
linear scaling is sound here because an explicit method's step on these scenes is set by
stability (|h lambda| < ~3 with lambda ~ -4k 1/s, the fastest decay, that ``auto``'s test
reports) after a transient of ~1/|lambda| <= 3e-5 s, so its step count grows in proportion
to the horizon.

Run: ``.venv/bin/python bench/study_stiff.py [--quick]``; writes results/study_stiff.csv,
.md and .png, and results/study_stiff_fixed.png.
"""

import argparse
import contextlib
import math
import os
import sys
import textwrap
import time

import numpy as np
from scipy.integrate import solve_ivp

import common
from common import RESULTS, load, machine, table, timed, write_csv, write_markdown
from scenes.reference import PAPER, seed_mvg

import kinetwork as kn
from scenes import chains as scenes
from kinetwork.solver.stiffness import STIFF_HORIZON_STEPS, STIFF_RATIO

RTOL, ATOL = 1e-6, 1e-8
SPACING = 0.01
T_END = 10.0
HORIZONS = (10.0, 3.0, 1.0, 0.3, 0.1, 0.03, 0.01)
CAP = 2.0                        # s: longest single run we accept
STEPS = (1e-2, 1e-3, 1e-4)
EXPLICIT_STEPS = STEPS + (1e-5,)          # RK4's stability limit at k = 1e4 is ~7e-5 s
MUJOCO_INTEGRATORS = ("RK4", "implicit", "implicitfast")
WRONG = 0.1                      # rad: a run that completes this far off has gone unstable


@contextlib.contextmanager
def quiet():
    """Silence C-level stdout and stderr: CasADi's rk plugin warns once per NaN output and
    MuJoCo prints each instability it resets; both are recorded in the results instead."""
    import ctypes
    libc = ctypes.CDLL(None)
    sys.stdout.flush()
    sys.stderr.flush()
    saved = [os.dup(1), os.dup(2)]
    with open(os.devnull, "w") as null:
        os.dup2(null.fileno(), 1)
        os.dup2(null.fileno(), 2)
        try:
            yield
        finally:
            libc.fflush(None)
            for fd, copy in zip((1, 2), saved):
                os.dup2(copy, fd)
                os.close(copy)


def reference(k, t_end, rtol=1e-12):
    """Angles on the 0.01 s grid from the closed form with c = d = k, scipy Radau."""
    p = {**PAPER, "c": k, "d": k}

    def rhs(_, x):
        M, V, G = seed_mvg(x[:2], x[2:], **p, sin=math.sin, cos=math.cos,
                           array=lambda rows: rows)
        (a, b), (c, d) = M
        f0, f1 = -(V[0] + G[0]), -(V[1] + G[1])
        det = a * d - b * c
        return [x[2], x[3], (d * f0 - b * f1) / det, (a * f1 - c * f0) / det]

    t = grid(t_end)
    sol = solve_ivp(rhs, (0.0, t_end), [0.05, 0.05, 0.0, 0.0], method="Radau", t_eval=t,
                    rtol=rtol, atol=1e-14)
    assert sol.success, sol.message
    return sol.y[:2].T


def grid(t_end):
    return np.linspace(0.0, t_end, int(round(t_end / SPACING)) + 1)


def kinetwork_run(system, method, t_end, step=None):
    """One simulate call: a dict of what happened (never raises on a failed integration)."""
    n = len(grid(t_end))
    with quiet():
        try:
            res = kn.simulate(system, t_end=t_end, n_points=n, method=method, rtol=RTOL,
                              atol=ATOL, step=step, jit=True)
            reason, reached = "", t_end
        except kn.SimulationError as err:
            res, reason, reached = err.results, str(err), err.t_reached
    return {"ok": not reason, "reason": reason, "t_reached": reached,
            "q": scenes.joint_angles(res), "stats": res.stats, "ran": res.method}


def mujoco_run(built, integrator, t_end, step):
    """One MuJoCo run; unstable when MuJoCo flagged a bad qpos, qvel or qacc (it then resets
    the state to qpos0 and carries on, so the angles alone would not show it)."""
    import mujoco
    from peers import mujoco_peer
    bad = [mujoco.mjtWarning.mjWARN_BADQPOS, mujoco.mjtWarning.mjWARN_BADQVEL,
           mujoco.mjtWarning.mjWARN_BADQACC]
    t = grid(t_end)
    with quiet():
        # the peer raises on a bad qacc only (its message then reads a field MjWarningStat
        # does not have); the warnings are read here instead
        try:
            q = mujoco_peer.run(built, t, integrator=integrator, timestep=step)
        except (RuntimeError, AttributeError):
            q = None
    flagged = [w for w in bad if built.data.warning[w].number]
    if flagged or q is None or not np.all(np.isfinite(q)):
        # the reset puts the angles at exactly qpos0 = 0: the first output there
        zero = [] if q is None else np.flatnonzero(np.all(q[1:] == 0.0, axis=1))
        reached = float(t[zero[0]]) if len(zero) else float("nan")
        return {"ok": False, "t_reached": reached, "q": None, "stats": {},
                "reason": f"unstable: MuJoCo flagged "
                          f"{'/'.join(mujoco.mjtWarning(w).name[7:] for w in flagged)} "
                          f"and reset the state"}
    return {"ok": True, "reason": "", "t_reached": t_end, "q": q, "stats": {}}


def capped(run, cap):
    """(horizon, wall time, outcome) on the longest horizon within ``cap`` seconds.

    Runs 0.01 s first, then each longer horizon while the last run's time, scaled to it,
    stays within ``cap``; a fast final run is repeated for a median (``common.timed``).
    """
    ladder = sorted(HORIZONS)
    horizon, took, out = ladder[0], *_clock(run, ladder[0])
    for longer in ladder[1:]:
        if took * longer / horizon > cap:
            break
        horizon, (took, out) = longer, _clock(run, longer)
    if took < 0.3:
        took, out = timed(lambda: run(horizon), budget=0.3, max_repeats=5)
    return horizon, took, out


def _clock(run, horizon):
    start = time.perf_counter()
    out = run(horizon)
    return time.perf_counter() - start, out


def record(tool, scene, k, method, step, horizon, wall, out, ref):
    scale = T_END / horizon
    stats = out["stats"]
    steps = stats.get("steps")
    if steps is None and method.startswith("mujoco"):
        steps = round(horizon / step) if out["ok"] else None
    rhs = stats.get("rhs_evaluations")
    if rhs is None and method in ("rk", "mujoco RK4") and steps:
        rhs = 4 * steps
    q = out["q"]
    err = common.max_error(q, ref[:len(q)]) if out["ok"] and q is not None else float("nan")
    verdict = "failed" if not out["ok"] else "wrong" if not err <= WRONG else "ok"
    return {"tool": tool, "scene": scene, "k": k, "method": method,
            "step": step if step else "", "ran": out.get("ran", method),
            "ok": out["ok"], "verdict": verdict, "horizon_s": horizon,
            "extrapolated": horizon < T_END,
            "t_reached_s": out["t_reached"], "wall_s": wall, "wall_10s": wall * scale,
            "steps_10s": steps * scale if steps else "",
            "rhs_10s": rhs * scale if rhs else "",
            "jacobian_evaluations": stats.get("jacobian_evaluations", ""),
            "max_angle_error": err,
            "auto_stiff": stats.get("stiff", ""), "auto_decay_rate": stats.get("decay_rate", ""),
            "auto_motion_rate": stats.get("motion_rate", ""),
            "reason": out["reason"].replace("\n", " ")}


def main(quick=False):
    global HORIZONS, T_END
    clock = time.perf_counter()
    ks = (1e4,) if quick else (1e4, 1e5, 1e6)
    cap = 0.3 if quick else CAP
    steps, explicit_steps = ((1e-3, 1e-4),) * 2 if quick else (STEPS, EXPLICIT_STEPS)
    if quick:
        T_END, HORIZONS = 0.1, (0.1, 0.03, 0.01)
    try:
        from peers import mujoco_peer
    except ImportError:
        mujoco_peer = None
    rows = []
    ref_time = 0.0
    for k in ks:
        scene = f"stiff{k:.0e}".replace("+0", "")
        build, spec, _ = scenes.SCENES[scene]
        start = time.perf_counter()
        ref = reference(k, T_END, rtol=1e-10 if quick else 1e-12)
        ref_time += time.perf_counter() - start
        system = build().compile()
        for method, m in kn.METHODS.items():
            for step in ((None,) if not m.fixed else explicit_steps if not m.newton
                         else steps):
                horizon, wall, out = capped(
                    lambda h: kinetwork_run(system, method, h, step), cap)
                rows.append(record("kinetwork", scene, k, method, step, horizon, wall, out, ref))
                _print(rows[-1])
        if mujoco_peer is None:
            continue
        built = mujoco_peer.build(spec())
        for integrator in MUJOCO_INTEGRATORS:
            for step in (explicit_steps if integrator == "RK4" else steps):
                horizon, wall, out = capped(
                    lambda h: mujoco_run(built, integrator, h, step), cap)
                rows.append(record("mujoco", scene, k, f"mujoco {integrator}", step, horizon,
                                   wall, out, ref))
                _print(rows[-1])
    write_csv("study_stiff", rows)
    charts(rows, ks)
    total = time.perf_counter() - clock
    report(rows, ks, total, ref_time, quick)
    print(f"study_stiff: {total:.1f} s")


def _print(r):
    status = "ok  " if r["ok"] else "FAIL"
    step = f" h={r['step']:g}" if r["step"] else ""
    print(f"{r['scene']:9s} {r['method'] + step:26s} {status} horizon {r['horizon_s']:5g} s "
          f"wall {r['wall_s']:8.3f} s  err {r['max_angle_error']:.1e}  {r['reason'][:90]}")


def _fmt(x, spec=".2g"):
    if x == "" or x is None or (isinstance(x, float) and not np.isfinite(x)):
        return "—"
    return format(x, spec)


def charts(rows, ks):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    variable = [m for m, v in kn.METHODS.items() if not v.fixed]
    fig, axes = plt.subplots(1, 2, figsize=(12, 5.2), layout="constrained")
    for i, method in enumerate(variable):
        runs = [r for r in rows if r["tool"] == "kinetwork" and r["method"] == method]
        style = dict(color=f"C{i}", marker="os^vD<>ph"[i % 9])
        for ax, key in zip(axes, ("wall_10s", "rhs_10s")):
            ok = [r for r in runs if r["ok"] and r[key] != ""]
            ax.plot([r["k"] for r in ok], [r[key] for r in ok], label=method,
                    linestyle="-", markersize=6, markerfacecolor="white",
                    **style)
            full = [r for r in ok if not r["extrapolated"]]
            ax.plot([r["k"] for r in full], [r[key] for r in full], linestyle="none",
                    markersize=6, **style)
        for r in (r for r in runs if not r["ok"]):
            axes[0].plot(r["k"], max(r["wall_s"], 1e-4), linestyle="none", marker="X",
                         markersize=12, color=style["color"], markeredgecolor="black")
            axes[0].annotate(f"{method} failed", (r["k"], max(r["wall_s"], 1e-4)),
                             textcoords="offset points", xytext=(-8, 0), ha="right",
                             va="center", fontsize=8, color=style["color"])
    for ax, ylabel in zip(axes, ("wall time for 10 s [s]",
                                 "right-hand-side evaluations for 10 s")):
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xticks(ks, [f"{k:.0e}" for k in ks])
        ax.set_xlabel("shoulder stiffness and damping k (c = d = k)")
        ax.set_ylabel(ylabel)
        ax.grid(True, which="major", alpha=0.4)
        ax.grid(True, which="minor", alpha=0.12)
    axes[0].set_title("Wall time (filled: measured over 10 s; hollow: scaled from a shorter "
                      "run;\nX: failed, at the time spent until the failure)", fontsize=9.5)
    axes[1].set_title("Right-hand-side evaluations (filled/hollow as on the left)",
                      fontsize=9.5)
    axes[1].legend(fontsize=8, ncol=2, loc="upper left")
    fig.suptitle(f"Stiff seed: variable-step methods at rtol {RTOL:g}, atol {ATOL:g}")
    fig.savefig(RESULTS / "study_stiff.png", dpi=110)
    plt.close(fig)

    fixed = [m for m, v in kn.METHODS.items() if v.fixed] + \
        [f"mujoco {i}" for i in MUJOCO_INTEGRATORS]
    fig, axes = plt.subplots(1, len(ks), figsize=(4.3 * len(ks) + 1, 4.8), sharey=True,
                             layout="constrained", squeeze=False)
    ceiling = 1e3           # above: one row of failure marks per method
    for ax, k in zip(axes[0], ks):
        for i, method in enumerate(fixed):
            runs = [r for r in rows if r["k"] == k and r["method"] == method]
            if not runs:
                continue
            style = dict(color=f"C{i}", marker="os^vD<"[i % 6])
            ok = [r for r in runs if r["ok"]]
            ax.loglog([r["step"] for r in ok], [max(r["max_angle_error"], 1e-16) for r in ok],
                      label=method, markersize=5, **style)
            bad = [r for r in runs if not r["ok"]]
            ax.plot([r["step"] for r in bad], [ceiling * 2.2 ** (i + 1) for _ in bad],
                    linestyle="none", marker="X", markersize=9, color=style["color"],
                    markeredgecolor="black")
        ax.axhline(ceiling, color="0.5", linewidth=0.8, linestyle=":")
        ax.axhspan(WRONG, ceiling, color="red", alpha=0.06, linewidth=0)
        ax.set_ylim(None, ceiling * 2.2 ** (len(fixed) + 1.5))
        ax.set_title(f"k = {k:.0e}")
        ax.set_xlabel("step h [s]")
        ax.grid(True, which="major", alpha=0.4)
    axes[0][0].set_ylabel(f"max joint-angle error [rad]\n(shaded: ≥ {WRONG:g} rad, unstable; "
                          f"X above the line: raised a failure)", fontsize=9)
    axes[0][-1].legend(fontsize=8, loc="lower right")
    fig.suptitle("Stiff seed: fixed-step methods against the step (10 s or a scaled-down "
                 "horizon, see study_stiff.md)", fontsize=10.5)
    fig.savefig(RESULTS / "study_stiff_fixed.png", dpi=110)
    plt.close(fig)


def report(rows, ks, total, ref_time, quick):
    lines = [f"## Stiffness: the seed with c = d = k{' (quick smoke run)' if quick else ''}", "",
             f"{machine()}; {load()}. {T_END:g} s, output every {SPACING} s; rtol {RTOL:g}, atol "
             f"{ATOL:g}; error = max joint-angle error against scipy Radau at rtol 1e-12 on "
             f"the closed-form M, V, G. A run whose time scaled from a shorter run exceeds "
             f"{CAP:g} s runs on the longest of {', '.join(f'{h:g}' for h in HORIZONS)} s that "
             f"fits (scaling from the previous, shorter run); its counts and wall time are then "
             f"scaled linearly to {T_END:g} s (marked *), its error is over that horizon. "
             f"Study wall time "
             f"{total:.0f} s (references {ref_time:.0f} s).", ""]
    for k in ks:
        lines += [f"### k = {k:.0e}", ""]
        body = []
        for r in rows:
            if r["k"] != k:
                continue
            star = "*" if r["extrapolated"] else ""
            name = r["method"] + (f" h={r['step']:g}" if r["step"] else "")
            if r["method"] == "auto":
                name += f" → {r['ran']}"
            outcome = {"ok": "ok", "wrong": "**completed, no error raised, but unstable**",
                       "failed": _failure(r)}[r["verdict"]]
            body.append([name, outcome, f"{r['horizon_s']:g}",
                         _fmt(r["steps_10s"], ".3g") + (star if r["steps_10s"] != "" else ""),
                         _fmt(r["rhs_10s"], ".3g") + (star if r["rhs_10s"] != "" else ""),
                         _fmt(r["wall_10s"], ".3g") + star, _fmt(r["max_angle_error"], ".1e")])
        lines += [table(["method", "outcome", "horizon [s]", f"steps /{T_END:g} s",
                         f"rhs evals /{T_END:g} s", f"wall /{T_END:g} s [s]",
                         "max angle error"], body), ""]
    auto = [r for r in rows if r["method"] == "auto"]
    lines += ["### What `auto` chose", "",
              table(["scene", "ran", "stiff", "decay rate σ [1/s]", "motion rate ω [1/s]",
                     "σ·T", "σ/ω"],
                    [[r["scene"], r["ran"], r["auto_stiff"], _fmt(r["auto_decay_rate"], ".3g"),
                      _fmt(r["auto_motion_rate"], ".3g"),
                      _fmt(r["auto_decay_rate"] * r["horizon_s"], ".3g"),
                      _fmt(r["auto_decay_rate"] / r["auto_motion_rate"], ".3g")]
                     for r in auto]), ""]
    lines += ["![variable-step methods](study_stiff.png)", "",
              "![fixed-step methods](study_stiff_fixed.png)", "", "### Findings", ""]
    lines += findings(rows, ks)
    write_markdown("study_stiff", "\n".join(lines))


def _short(reason):
    reason = reason.split("): ", 1)[-1]
    return textwrap.shorten(reason.replace("|", "/"), width=140, placeholder=" …")


def _failure(r):
    when = "" if not np.isfinite(r["t_reached_s"]) else f" at t = {r['t_reached_s']:g} s"
    return f"failed{when}: {_short(r['reason'])}"


def findings(rows, ks):
    """Sentences built from the measured rows (so they cannot drift from the tables)."""
    out = []
    kin = [r for r in rows if r["tool"] == "kinetwork"]
    for method in ("cvodes-adams", "rk45", "dop853"):
        runs = [r for r in kin if r["method"] == method]
        parts = []
        for r in runs:
            if r["ok"]:
                parts.append(f"k = {r['k']:.0e}: {_fmt(r['rhs_10s'], '.2g')} rhs evaluations, "
                             f"{_fmt(r['wall_10s'], '.2g')} s for 10 s"
                             + (" (scaled)" if r["extrapolated"] else ""))
            else:
                parts.append(f"k = {r['k']:.0e}: failed ({_short(r['reason'])})")
        out.append(f"- {method}: " + "; ".join(parts) + ".")
    late = [r for r in kin if r["verdict"] == "failed" and r["t_reached_s"] >= r["horizon_s"]]
    for r in late:
        out.append(f"- {r['method']} at k = {r['k']:.0e} raised a failure although its "
                   f"results reach t = {r['t_reached_s']:g} s: the run over the whole horizon "
                   f"failed and kinetwork's interval-by-interval retry, which keeps what can "
                   f"be computed, got to the end.")
    auto = [r for r in kin if r["method"] == "auto"]
    if auto:
        out.append("- auto ran " + ", ".join(sorted({r["ran"] for r in auto})) + " at every "
                   f"k: σ·T from {min(r['auto_decay_rate'] for r in auto) * T_END:.1e} to "
                   f"{max(r['auto_decay_rate'] for r in auto) * T_END:.1e} (stiff above "
                   f"{STIFF_HORIZON_STEPS:g}) and σ/ω from "
                   f"{min(r['auto_decay_rate'] / r['auto_motion_rate'] for r in auto):.1e} "
                   f"(stiff above {STIFF_RATIO:g}).")
    for method in ("auto", "cvodes", "idas", "radau", "bdf", "lsoda"):
        runs = [r for r in kin if r["method"] == method]
        if runs and all(r["ok"] for r in runs):
            out.append(f"- {method}: succeeded at every k with "
                       + ", ".join(f"{_fmt(r['rhs_10s'], '.3g')}" for r in runs)
                       + " rhs evaluations and "
                       + ", ".join(f"{_fmt(r['wall_10s'], '.2g')}" for r in runs)
                       + " s; max error " + ", ".join(_fmt(r["max_angle_error"], ".1e")
                                                       for r in runs) + ".")
    for method in ("rk", "collocation", "midpoint", "mujoco RK4", "mujoco implicit",
                   "mujoco implicitfast"):
        runs = [r for r in rows if r["method"] == method]
        if not runs:
            continue
        per_k = []
        for k in ks:
            def at(verdict):
                return ", ".join(f"{r['step']:g}" for r in sorted(runs, key=lambda r: r["step"])
                                 if r["k"] == k and r["verdict"] == verdict)
            per_k.append(f"k = {k:.0e}: stable (error < {WRONG:g} rad) at h = "
                         f"{at('ok') or 'none'}"
                         + (f"; raised a failure at {at('failed')}" if at("failed") else "")
                         + (f"; completed without complaint but {WRONG:g} rad or more off "
                            f"(unstable) at {at('wrong')}" if at("wrong") else ""))
        out.append(f"- {method}: " + "; ".join(per_k) + ".")
    return out


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="smoke test: k = 1e4, 0.1 s")
    main(parser.parse_args().quick)
