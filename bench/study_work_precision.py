"""Work-precision: max joint-angle error against wall time, every kinetwork method and three peers.

Scenes: seed, chaotic (first 3 s only), chain2, chain16, chain128, spatial6 (``scenes.py``).
Error: the max joint-angle difference from a reference on the output grid (0.01 s spacing):
the closed form (``reference.seed_reference``) for seed and chaotic, pinocchio's ABA with DOP853
at rtol 1e-13 for the chains and the spatial chain; the summary gives the agreement of each
reference with kinetwork's most accurate run and, for the closed forms, with pinocchio's.

Curves: kinetwork's ``auto`` with and without JIT, every other method in ``kn.METHODS`` with JIT
(but ``LEFT_OUT_LARGE`` at N = 128); variable-step methods over rtol 1e-3..1e-12 with
atol = rtol * 1e-2, fixed-step ones over steps 1e-2..1e-5 s. Peers: pinocchio + scipy (DOP853,
RK45), MuJoCo (RK4, implicit, implicitfast at fixed steps), sympy Kane + lambdify + DOP853
(derivation given ``SYMPY_TIMEOUT`` s).

Timing: wall time of one run (integration and output grid), median of repeats; every model is
built and every integrator called once beforehand, so JIT compilation, integrator creation and
the peers' builds are not in the times. A curve stops at the first run slower than the per-run
budget (``CAP``), before a run predicted to take over 1.5 times that, and once its error is at
the references' floor or stops falling; a run Python can interrupt (scipy, MuJoCo) is stopped
at ``LIMIT`` times the budget. The sympy derivations run in the background of the untimed
preparation, two at a time, each in its own process.

Writes ``results/work_precision.{csv,md}`` and ``results/work_precision_<scene>.png``.
Run: ``python bench/study_work_precision.py [--quick]``; ``--casadi``, ``--overheads``,
``--point-masses`` and ``--choice`` run one part alone (see ``--help``).
"""

import argparse
import math
import signal
import sys
import threading
import time

import numpy as np

import kinetwork as kn

import common
from scenes import chains as scenes
from common import machine, max_error, table, timed, write_csv, write_markdown
from scenes.reference import seed_reference

sys.path.insert(0, str(common.HERE / "peers"))
import casadi_peer
import mujoco_peer
import pinocchio_peer
import sympy_peer

NAME = "work_precision"
SCENES = ("seed", "chaotic", "chain2", "chain16", "chain128", "spatial6")
#: the chaotic scene separates from its references after ~3 s (round-off grows like e^(λt))
HORIZON = {"chaotic": 3.0}
SPACING = 0.01
STEPS = (1e-2, 5e-3, 2e-3, 1e-3, 5e-4, 2e-4, 1e-4, 5e-5, 2e-5, 1e-5)
#: at N >= 64 every other decade (and the tightest), to keep within the time budget
RTOLS_LARGE = (1e-3, 1e-4, 1e-6, 1e-8, 1e-10, 1e-12)
REF_RTOL = 1e-13
SYMPY_TIMEOUT = 60.0
TARGETS = (1e-3, 1e-6, 1e-9)
#: per-run budget [s]: N >= 64 gets more; a run is interrupted (where Python gets control
#: back: scipy, MuJoCo) at LIMIT times the budget
CAP, CAP_LARGE, LIMIT = 2.0, 5.0, 3.0
#: a curve stops once its error is below this (the references agree to ~1e-13)
FLOOR = 1e-12
#: left out at N >= 64: Newton methods whose one run at the loosest setting takes far over the
#: budget there, as measured when this study was written (2 cores). At N = 128 the 256 x 256
#: Jacobian has 2.6 M instructions, over the JIT limit, so CasADi's VM evaluates it.
LEFT_OUT_LARGE = {
    "bdf": "scipy BDF factorises the dense 256x256 iteration matrix, its Jacobian evaluated "
           "in CasADi's VM (too large to JIT-compile): one run at rtol 1e-3 took 35-55 s",
    "collocation": "Newton on the collocation equations with the 256x256 Jacobian in "
                   "CasADi's VM (too large to JIT-compile): one run at step 1e-2 took over 6 min",
    "midpoint": "CasADi's Newton rootfinder with the 256x256 Jacobian in its VM (too large "
                "to JIT-compile): 0.44 s per 0.1 s at step 1e-2, ~45 s a run",
}
#: the scenes of the hand-written route (``casadi_peer``), and the accuracies it is compared at
CASADI_SCENES = ("chain2", "chain16", "chain128")
CASADI_ACCURACIES = tuple(10.0 ** -k for k in range(4, 11))
#: kinetwork's other methods in that comparison: would another choice beat the peer's Adams?
#: (BDF: the stiffness the chains gain with N; DOP853: an explicit method of high order)
CASADI_OTHERS = ("cvodes", "dop853")
#: peers: pinocchio in oranges, MuJoCo in greens, sympy in red, the hand-written route in purple
PEER_COLOUR = {casadi_peer.NAME: "#6a3d9a",
               "pinocchio+scipy DOP853": "#e6550d", "pinocchio+scipy RK45": "#fdae6b",
               "MuJoCo RK4": "#006d2c", "MuJoCo implicit": "#41ab5d",
               "MuJoCo implicitfast": "#a1d99b", "sympy+DOP853": "#cb181d"}


class Curve:
    """One line of a chart: a tool's method over its settings, and how to run one setting."""

    def __init__(self, tool, method, settings, run, label=None):
        self.tool, self.method, self.settings, self.run = tool, method, settings, run
        self.label = label or f"{tool} {method}"
        self.rows = []
        self.note = ""

    def points(self):
        return [(r["time_s"], r["error"]) for r in self.rows if r["status"] == "ok"]


def setting_text(s):
    return " ".join(f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}" for k, v in s.items())


def kinetwork_curves(system, horizon, n, quick):
    """auto (JIT and VM) and every other method with JIT; ``LEFT_OUT_LARGE`` get a note
    instead of settings at N >= 64."""
    points = round(horizon / SPACING) + 1
    rtols = [1e-4, 1e-8] if quick else RTOLS_LARGE if n >= 64 else common.TOLERANCES
    steps = [1e-2, 1e-3] if quick else STEPS

    def runner(method, jit):
        def run(s):
            return scenes.joint_angles(kn.simulate(system, t_end=horizon, n_points=points,
                                                   method=method, jit=jit, **s))
        return run

    curves = [Curve("kinetwork", "auto (JIT)", [], runner("auto", True)),
              Curve("kinetwork", "auto (VM)", [], runner("auto", False))]
    curves += [Curve("kinetwork", m, [], runner(m, True)) for m in kn.METHODS if m != "auto"]
    for c in curves:
        name = c.method.split()[0]
        c.settings = [{"step": h} for h in steps] if kn.METHODS[name].fixed else \
            [{"rtol": r, "atol": r * 1e-2} for r in rtols]
        if n >= 64 and name in LEFT_OUT_LARGE:
            c.settings = []
            c.note = f"left out at N = {n}: {LEFT_OUT_LARGE[name]}"
    return curves


def peer_curves(built, n, quick):
    """pinocchio + scipy, MuJoCo and sympy on the output grid ``built["t"]``."""
    rtols = [1e-4, 1e-8] if quick else RTOLS_LARGE if n >= 64 else pinocchio_peer.RTOLS
    steps = [1e-2, 1e-3] if quick else mujoco_peer.TIMESTEPS
    t = built["t"]

    def runner(peer, model):
        return lambda s: peer.run(model, t, **s)

    curves = [Curve(pinocchio_peer.NAME, m, [{"method": m, "rtol": r} for r in rtols],
                    runner(pinocchio_peer, built["pinocchio"])) for m in ("DOP853", "RK45")]
    curves += [Curve(mujoco_peer.NAME, i, [{"integrator": i, "timestep": h} for h in steps
                                           if i != "RK4" or h >= 5e-5],
                     runner(mujoco_peer, built["mujoco"]))
               for i in ("RK4", "implicit", "implicitfast")]
    if built.get("casadi") is not None:
        curves.append(Curve(casadi_peer.NAME, "Adams", [{"rtol": r} for r in rtols],
                            runner(casadi_peer, built["casadi"]), label=casadi_peer.NAME))
    sym = Curve(sympy_peer.NAME, "DOP853", [{"method": "DOP853", "rtol": r} for r in rtols],
                runner(sympy_peer, built["sympy"]), label=sympy_peer.NAME)
    if isinstance(built["sympy"], str):
        sym.settings, sym.note = [], built["sympy"]
    return curves + [sym]


class SympyBuilds(threading.Thread):
    """sympy derivations one after the other, in the background of the preparation.

    Each derivation runs in its own process (``sympy_peer.build``); nothing is timed meanwhile.
    Chains go in order of length, and once one cannot be derived in time the longer ones are
    not tried.
    """

    def __init__(self, specs, timeout, built):
        super().__init__(daemon=True)
        self.specs, self.timeout, self.built = specs, timeout, built

    def run(self):
        too_long = None
        for name, spec in sorted(self.specs.items(), key=lambda item: item[1].n):
            if too_long:
                self.built[name] = (f"not tried: {too_long} could not be derived in "
                                    f"{self.timeout:g} s")
                continue
            start = time.perf_counter()
            try:
                self.built[name] = sympy_peer.build(spec, timeout=self.timeout)
                print(f"  sympy {name}: derived in {time.perf_counter() - start:.1f} s",
                      flush=True)
            except TimeoutError:
                self.built[name] = f"could not derive in {self.timeout:g} s"
                too_long = f"{name} (N = {spec.n})"
                print(f"  sympy {name}: {self.built[name]}", flush=True)


def prepare(names, quick):
    """Models, references, peers' builds and a first call of every kinetwork curve."""
    specs = {name: scenes.SCENES[name][1]() for name in names}
    # two workers, chains in one and the rest in the other, so that the two slow
    # derivations (chain16, spatial6) overlap
    derived = {}
    workers = [SympyBuilds({k: v for k, v in specs.items() if k.startswith("chain") == chains},
                           SYMPY_TIMEOUT, derived) for chains in (True, False)]
    for w in workers:
        w.start()
    prepared = {}
    for name in names:
        builder, _, horizon = scenes.SCENES[name]
        horizon = HORIZON.get(name, horizon)
        spec = specs[name]
        t = np.linspace(0.0, horizon, round(horizon / SPACING) + 1)
        start = time.perf_counter()
        system = builder().compile()
        pin = pinocchio_peer.build(spec)
        built = {"t": t, "pinocchio": pin, "mujoco": mujoco_peer.build(spec),
                 "casadi": casadi_peer.build(spec) if name in CASADI_SCENES else None}
        q_pin = pinocchio_peer.run(pin, t, method="DOP853", rtol=REF_RTOL, atol=REF_RTOL * 1e-2)
        info = {"horizon": horizon, "n": spec.n, "first_calls": {}}
        if name in ("seed", "chaotic"):
            x0 = np.concatenate([spec.q0, spec.qd0])
            ref = seed_reference(t, x0=x0, d=float(spec.damping[0]))[:, :2]
            info["reference"] = "closed form (numpy M, V, G), DOP853 at rtol 1e-13"
            info["pinocchio_vs_reference"] = max_error(q_pin, ref)
            if name == "chaotic":
                t10 = np.linspace(0.0, 10.0, 1001)
                info["references_10s"] = max_error(
                    pinocchio_peer.run(pin, t10, method="DOP853", rtol=REF_RTOL,
                                       atol=REF_RTOL * 1e-2),
                    seed_reference(t10, x0=x0, d=0.0)[:, :2])
        else:
            ref = q_pin
            info["reference"] = "pinocchio ABA + scipy DOP853 at rtol 1e-13"
        curves = kinetwork_curves(system, horizon, spec.n, quick)
        for c in curves:        # JIT compilation and integrator creation, untimed
            if c.settings:
                t0 = time.perf_counter()
                try:
                    c.run(c.settings[0])
                except kn.SimulationError:
                    pass
                info["first_calls"][c.method] = time.perf_counter() - t0
        prepared[name] = {"ref": ref, "built": built, "curves": curves, "info": info}
        print(f"  prepared {name} in {time.perf_counter() - start:.1f} s", flush=True)
    start = time.perf_counter()
    for w in workers:
        w.join()
    print(f"  waited {time.perf_counter() - start:.1f} s for sympy", flush=True)
    for name, p in prepared.items():
        p["built"]["sympy"] = derived[name]
        p["curves"] += peer_curves(p["built"], specs[name].n, quick)
    return prepared


class RunTooLong(Exception):
    """Raised by the alarm that ends a run past its limit."""


def _alarm(signum, frame):
    raise RunTooLong


def sweep(curve, ref, cap, budget):
    """Run ``curve`` over its settings, loosest first; stop at the first run over ``cap`` s,
    or when the next is predicted to be, or when the error is at ``FLOOR`` or stops falling."""
    previous, stop, errors = None, None, []
    signal.signal(signal.SIGALRM, _alarm)
    for s in curve.settings:
        row = {"setting": setting_text(s), "time_s": math.nan, "error": math.nan}
        if stop:
            curve.rows.append({**row, "status": stop})
            continue
        start = time.perf_counter()
        signal.setitimer(signal.ITIMER_REAL, LIMIT * cap)
        try:
            seconds, q = timed(lambda s=s: curve.run(s), budget=budget, max_repeats=7)
            row.update(time_s=seconds, error=max_error(q, ref), status="ok")
        except RunTooLong:
            seconds = time.perf_counter() - start
            row["status"] = f"interrupted after {seconds:.0f} s"
        except Exception as exc:  # noqa: BLE001 -- a failed run is a result: record why, go on
            seconds = time.perf_counter() - start
            message = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
            row["status"] = f"failed: {message[:160]}"
        finally:
            signal.setitimer(signal.ITIMER_REAL, 0)
        curve.rows.append(row)
        growth = max(seconds / previous, 1.0) if previous else 1.0
        previous = seconds
        if np.isfinite(row["error"]):
            errors.append(row["error"])
        if seconds > cap:
            stop = f"skipped: a looser setting took {seconds:.1f} s > {cap:g} s"
        elif seconds * growth > 1.5 * cap:
            stop = f"skipped: predicted {seconds * growth:.1f} s > {cap:g} s"
        elif errors and errors[-1] <= FLOOR:
            stop = f"skipped: error already below {FLOOR:.0e}"
        elif len(errors) >= 3 and 0.5 * errors[-3] < min(errors[-2:]) < 1e-8:
            stop = "skipped: the error stopped falling"


def time_to(points, target):
    """Time to reach ``target`` along the Pareto front of ``points`` (log-log interpolation)."""
    front = []
    for t, e in sorted(p for p in points if np.isfinite(p[0]) and np.isfinite(p[1])):
        e = max(e, 1e-16)
        if not front or e < front[-1][1]:
            front.append((t, e))
    for i, (t, e) in enumerate(front):
        if e <= target:
            if i == 0:
                return t
            t0, e0 = front[i - 1]
            f = (math.log(target) - math.log(e0)) / (math.log(e) - math.log(e0))
            return math.exp(math.log(t0) + f * (math.log(t) - math.log(t0)))
    return None


def fmt_time(t):
    if t is None:
        return "—"
    return f"{t * 1e3:.3g} ms" if t < 1 else f"{t:.3g} s"


#: kinetwork's methods: blue hues told apart by marker; the default darkest and thickest
BLUES = ("#08306b", "#6baed6", "#1f77b4", "#17becf", "#3949ab", "#0d47a1", "#42a5f5",
         "#00838f", "#7986cb", "#26a6c6", "#1565c0", "#5c8dbf", "#283593")
MARKERS = "os^vD<>pPXh*d"


def _style(c, k):
    if c.tool != "kinetwork":
        return {"ls": "--", "lw": 1.7, "marker": "x", "ms": 5.5,
                "color": PEER_COLOUR.get(c.label, "0.4")}
    if c.method == "auto (JIT)":
        return {"color": BLUES[0], "lw": 3.2, "marker": "o", "ms": 6.5, "zorder": 5}
    return {"color": BLUES[k % len(BLUES)], "lw": 1.3, "marker": MARKERS[k % len(MARKERS)],
            "ms": 5}


def plot(name, curves, info):
    """Two panels: every kinetwork method; kinetwork's default against the peers."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2, figsize=(15, 7.2), sharex=True, sharey=True,
                             layout="constrained")
    panels = ([c for c in curves if c.tool == "kinetwork"],
              [c for c in curves if c.tool != "kinetwork" or c.method.startswith("auto")])
    titles = ("kinetwork's methods (JIT unless VM)", "kinetwork's default against the peers")
    styles = {c.label: _style(c, k) for k, c in enumerate(panels[0])}
    for ax, panel, title, prefix in zip(axes, panels, titles, (False, True)):
        for target in TARGETS:
            ax.axhline(target, color="0.6", lw=0.8, ls=":", zorder=0)
        for c in panel:
            pts = [(r["time_s"], max(r["error"], 1e-16)) for r in c.rows if r["status"] == "ok"]
            label = c.label if prefix or c.tool != "kinetwork" else c.method
            if pts:     # in the order of the settings, loosest first
                ax.loglog(*np.array(pts).T, label=label, **styles.get(c.label, _style(c, 0)))
            else:
                why = c.note.split(":")[0] if c.note else "no run"
                ax.plot([], [], label=f"{label}: {why}", **styles.get(c.label, _style(c, 0)))
        ax.set_title(title, fontsize=11)
        ax.set_xlabel("wall time of one run [s]")
        ax.grid(True, which="major", alpha=0.4)
        ax.grid(True, which="minor", alpha=0.1)
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.1), ncol=3, fontsize=8.5,
                  frameon=False)
    axes[0].set_ylabel("max joint-angle error [rad]")
    fig.suptitle(f"Work-precision, {name} (N = {info['n']}, {info['horizon']:g} s); "
                 f"dotted: 1e-3, 1e-6, 1e-9", fontsize=12)
    path = common.RESULTS / f"{NAME}_{name}.png"
    common.RESULTS.mkdir(exist_ok=True)
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path


def notes(rows):
    """Failed and interrupted runs, and where and why the sweep stopped."""
    out = [f"{r['setting']}: {r['status']}" for r in rows
           if not r["status"].startswith(("ok", "skipped"))]
    skipped = [r for r in rows if r["status"].startswith("skipped")]
    if skipped:
        out.append(f"stopped before {skipped[0]['setting']} "
                   f"({skipped[0]['status'].removeprefix('skipped: ')})")
    return "; ".join(out)


def scene_section(name, p):
    info, curves = p["info"], p["curves"]
    best = min(((r["error"], c.method, r["setting"]) for c in curves if c.tool == "kinetwork"
                for r in c.rows if r["status"] == "ok"), default=(math.nan, "—", "—"))
    agreement = (f"Reference: {info['reference']}. Kinetwork's most accurate run "
                 f"({best[1]}, {best[2]}) is {best[0]:.1e} rad from it.")
    lines = [f"## {name} (N = {info['n']}, {info['horizon']:g} s)", "", agreement]
    if "pinocchio_vs_reference" in info:
        lines[-1] += (f" Pinocchio + DOP853 at rtol 1e-13 is {info['pinocchio_vs_reference']:.1e}"
                      f" rad from it.")
    if "references_10s" in info:
        lines[-1] += (f" Over 10 s the two references differ by {info['references_10s']:.1e} "
                      f"rad (the motion is chaotic), hence the 3 s horizon.")
    rows = []
    for c in curves:
        pts = c.points()
        note = c.note or notes(c.rows)
        rows.append([c.label] + [fmt_time(time_to(pts, e)) for e in TARGETS]
                    + [f"{min(e for _, e in pts):.1e}" if pts else "—", note])
    lines += ["", table(["curve", *(f"to {e:.0e}" for e in TARGETS), "best error", "notes"],
                        rows)]
    slow = {m: s for m, s in info["first_calls"].items() if s > 0.5}
    if slow:
        lines += ["", "First calls, not in the times (JIT compilation, integrator creation): "
                  + ", ".join(f"{m} {s:.1f} s" for m, s in slow.items()) + "."]
    lines += ["", f"![work-precision {name}]({NAME}_{name}.png)", ""]
    return lines


def default_against_peers(prepared):
    """Ratios of the best peer to auto (JIT), and where auto (JIT) loses, 1e-3..1e-10."""
    lines = ["## Best peer against kinetwork's default", "",
             "Time to the accuracy (log-log interpolation on each curve's Pareto front) of the",
             "fastest peer, divided by that of `auto` with JIT; above 1: kinetwork is faster.", ""]
    rows = []
    for name in ("chain2", "chain16", "chain128"):
        if name not in prepared:
            continue
        curves = prepared[name]["curves"]
        ours = next(c for c in curves if c.method == "auto (JIT)").points()
        row = [name]
        for e in (1e-6, 1e-9):
            peers = [(time_to(c.points(), e), c.label) for c in curves if c.tool != "kinetwork"]
            peers = [p for p in peers if p[0] is not None]
            mine = time_to(ours, e)
            if not peers or mine is None:
                row += [f"{min(peers)[1] if peers else '—'}", "—"]
                continue
            t, label = min(peers)
            row += [f"{label} {fmt_time(t)}", f"{t / mine:.2f} (auto {fmt_time(mine)})"]
        rows.append(row)
    if rows:
        lines += [table(["scene", "best peer to 1e-6", "ratio", "best peer to 1e-9", "ratio"],
                        rows), ""]
    losses, checked = [], 0
    for name in ("seed", "chain2", "chain16", "chain128"):
        if name not in prepared:
            continue
        curves = prepared[name]["curves"]
        ours = next(c for c in curves if c.method == "auto (JIT)").points()
        for k in range(3, 11):
            e = 10.0 ** -k
            mine = time_to(ours, e)
            for c in curves:
                if c.tool == "kinetwork" or (t := time_to(c.points(), e)) is None:
                    continue
                checked += 1
                if mine is None or t < mine:
                    losses.append((name, e, c.label, t, mine))
    lines.append("Is `auto` (JIT) faster than every peer at every accuracy 1e-3..1e-10 on "
                 f"seed and the chains? {'Yes' if not losses else 'No'} ({checked} comparisons"
                 f", {len(losses)} lost).")
    if losses:
        header = ["scene", "accuracy", "faster peer", "peer", "auto (JIT)", "peer/auto"]
        lines += ["", table(header, [[n, f"{e:.0e}", lab, fmt_time(t), fmt_time(m),
                                      f"{t / m:.2f}" if m else "auto never reaches it"]
                                     for n, e, lab, t, m in losses])]
    return lines


def against_hand_written(curves_of):
    """kinetwork's default against the same route by hand (``casadi_peer``), side by side:
    time to each accuracy 1e-4..1e-10 of both and their ratio (target: auto/peer <= 1.2)."""
    rows, worst = [], []
    for name in CASADI_SCENES:
        if name not in curves_of:
            continue
        curves = {c.label: c for c in curves_of[name]}
        peer, auto = curves.get(casadi_peer.NAME), curves.get("kinetwork auto (JIT)")
        if peer is None or auto is None:
            continue
        adams = curves.get("kinetwork cvodes-adams")
        others = [c for c in curves.values() if c.tool == "kinetwork" and c is not auto]
        for e in CASADI_ACCURACIES:
            mine, theirs = time_to(auto.points(), e), time_to(peer.points(), e)
            ratio = mine / theirs if mine and theirs else None
            if ratio is not None:
                worst.append((ratio, name, e))
            best = min(((t, c.method) for c in others
                        if (t := time_to(c.points(), e)) is not None), default=None)
            rows.append([name, f"{e:.0e}", fmt_time(mine), fmt_time(theirs),
                         f"{ratio:.2f}" if ratio else "—",
                         fmt_time(time_to(adams.points(), e)) if adams else "—",
                         f"{best[1]} {fmt_time(best[0])} ({best[0] / theirs:.2f})"
                         if best and theirs else "—"])
    if not rows:
        return []
    lines = ["## kinetwork's default against the same route by hand", "",
             f"`{casadi_peer.NAME}` (``peers/casadi_peer.py``): Featherstone's ABA in CasADi SX, "
             "compiled by gcc -O1, one CVODES Adams call over the whole output grid. Time to "
             "each accuracy on each curve's Pareto front; ratio = auto / by hand (target "
             "<= 1.2; below 1: kinetwork is faster); the last column: kinetwork's fastest "
             "method to that accuracy other than auto (of cvodes-adams, "
             f"{', '.join(CASADI_OTHERS)}; JIT) and its ratio to the hand-written route.", "",
             table(["scene", "accuracy", "auto (JIT)", "by hand", "auto / by hand",
                    "kinetwork cvodes-adams", "fastest other (/ by hand)"], rows), ""]
    if worst:
        r, name, e = max(worst)
        lines.append(f"Worst ratio: {r:.2f} ({name}, {e:.0e}); "
                     f"{sum(1 for w in worst if w[0] <= 1.2)} of {len(worst)} within 1.2.")
        lines.append("")
    lines += method_choice(curves_of)
    return lines


def method_choice(curves_of):
    """Would another of kinetwork's methods beat the hand-written route's Adams where Adams
    is slow (the chain's stiffness grows with N)? Each scene's fastest kinetwork method at
    each accuracy, and what the loosest run of each took."""
    lines = []
    for name in CASADI_SCENES:
        curves = {c.method: c for c in curves_of.get(name, []) if c.tool == "kinetwork"}
        if "cvodes-adams" not in curves:
            continue
        wins = {}
        for e in CASADI_ACCURACIES:
            times = {m: t for m, c in curves.items() if m != "auto (JIT)"
                     and (t := time_to(c.points(), e)) is not None}
            if times:
                wins.setdefault(min(times, key=times.get), []).append(f"{e:.0e}")
        loosest = ", ".join(f"{m} {fmt_time(c.rows[0]['time_s'])} (error "
                            f"{c.rows[0]['error']:.1e})" for m, c in curves.items()
                            if c.rows and np.isfinite(c.rows[0]["time_s"]))
        lines.append(f"- {name}: fastest of kinetwork's methods (auto aside): "
                     + "; ".join(f"{m} at {', '.join(es)}" for m, es in wins.items())
                     + f". Loosest runs: {loosest}.")
    if lines:
        lines = ["Which of kinetwork's methods is fastest to each accuracy 1e-4..1e-10 (time "
                 "to it on each curve's front):", ""] + lines + [""]
    return lines


def counts_table(scene, system, built, horizon, rtols):
    """Per rtol, one run of auto (JIT) and of the hand-written route at the tolerances
    kinetwork hands CVODES for it (``tolerance.solver_tolerances``: the same method at the
    same tolerances): wall time (least of 3), steps and right-hand-side evaluations, so that
    a difference in time reads as a difference in count or in cost per evaluation."""
    from kinetwork.solver.tolerance import solver_tolerances
    t = built["t"]
    rows = []
    for r in rtols:
        res, mine = None, math.inf
        for _ in range(3):
            start = time.perf_counter()
            res = kn.simulate(system, t_end=horizon, n_points=len(t), rtol=r, atol=r * 1e-2,
                              jit=True)
            mine = min(mine, time.perf_counter() - start)
        srt, sat = solver_tolerances(kn.METHODS[res.settings["method"]], system, r,
                                     r * 1e-2)[:2]
        integ = casadi_peer.integrator(built["casadi"], t, srt, sat)
        integ(x0=built["casadi"].x0)                  # a new integrator's first call
        theirs = math.inf
        for _ in range(3):
            start = time.perf_counter()
            integ(x0=built["casadi"].x0)
            theirs = min(theirs, time.perf_counter() - start)
        st = integ.stats()
        n_k, n_p = res.stats.get("rhs_evaluations", 0), int(st["nfevals"])
        rows.append([scene, f"{r:.0e} ({srt:.0e})", res.settings["method"], fmt_time(mine),
                     res.stats.get("steps", ""), n_k,
                     f"{mine / n_k * 1e6:.2f}" if n_k else "—", fmt_time(theirs),
                     int(st["nsteps"]), n_p, f"{theirs / n_p * 1e6:.2f}" if n_p else "—"])
    return rows


def paired_sweep(curves, ref, cap, repeats):
    """Every curve's k-th setting in turn, round robin, ``repeats`` times; each keeps the
    least wall time of its repeats. Curves compared side by side share the machine's load
    alike (a shared machine's load changes over the minutes a curve-by-curve sweep takes);
    a curve stops after a run over ``cap`` s."""
    active = list(curves)
    for k in range(max(len(c.settings) for c in curves)):
        best, values = {}, {}
        for _ in range(repeats):
            for c in active:
                start = time.perf_counter()
                try:
                    values[c] = c.run(c.settings[k])
                except Exception as exc:  # noqa: BLE001 -- a failed run is a result
                    values[c] = exc
                best[c] = min(best.get(c, math.inf), time.perf_counter() - start)
        for c in curves:
            row = {"setting": setting_text(c.settings[k]), "time_s": math.nan,
                   "error": math.nan, "status": "skipped: a looser setting took over "
                                                f"{cap:g} s"}
            if c in best:
                if isinstance(values[c], Exception):
                    row["status"] = f"failed: {str(values[c]).strip()[:160]}"
                else:
                    row.update(time_s=best[c], error=max_error(values[c], ref), status="ok")
            c.rows.append(row)
        active = [c for c in active if best[c] <= cap]


def casadi_study(quick):
    """``--casadi``: chain2, chain16, chain128; auto (JIT), cvodes-adams, cvodes (BDF) and
    dop853 (JIT) and the hand-written route at every decade of rtol; writes
    ``results/work_precision_casadi.md``."""
    start = time.perf_counter()
    # from 1e-1: kinetwork hands CVODES 100 times tighter tolerances than asked
    # (tolerance.py), so its loosest runs must be looser than 1e-3 for its front to span the
    # same errors as the hand-written route's (a front's time to an accuracy interpolates
    # between its points: one that starts 10 times more accurate is charged for it)
    rtols = [1e-4, 1e-8] if quick else [1e-1, 1e-2] + common.TOLERANCES
    names = CASADI_SCENES[:2] if quick else CASADI_SCENES
    curves_of, counts, notes_of = {}, [], []
    for name in names:
        builder, spec_of, horizon = scenes.SCENES[name]
        spec = spec_of()
        t = np.linspace(0.0, horizon, round(horizon / SPACING) + 1)
        system = builder().compile()
        t0 = time.perf_counter()
        built = {"t": t, "casadi": casadi_peer.build(spec)}
        build_s = time.perf_counter() - t0
        ref = pinocchio_peer.run(pinocchio_peer.build(spec), t, method="DOP853", rtol=REF_RTOL,
                                 atol=REF_RTOL * 1e-2)
        agree = max_error(casadi_peer.run(built["casadi"], t, rtol=1e-12), ref)
        curves = [c for c in kinetwork_curves(system, horizon, spec.n, quick)
                  if c.method in ("auto (JIT)", "cvodes-adams") + CASADI_OTHERS]
        curves.append(Curve(casadi_peer.NAME, "Adams", [],
                            lambda s, b=built["casadi"], t=t: casadi_peer.run(b, t, **s),
                            label=casadi_peer.NAME))
        for c in curves:
            c.settings = [{"rtol": r, "atol": r * 1e-2} for r in rtols]
            if c.tool != "kinetwork":
                c.settings = [{"rtol": r} for r in rtols]
            c.run(c.settings[0])                 # JIT compilation, integrator creation
        cap = CAP_LARGE if spec.n >= 64 else CAP
        paired_sweep(curves, ref, cap, repeats=5 if spec.n >= 64 else 7)
        curves_of[name] = curves
        counts += counts_table(name, system, built, horizon, rtols)
        notes_of.append(f"{name}: the hand-written route built (SX, C, gcc) in {build_s:.1f} s; "
                        f"at rtol 1e-12 it is {agree:.1e} rad from the pinocchio reference")
        print(f"  {name}: {time.perf_counter() - t0:.1f} s", flush=True)
    total = time.perf_counter() - start
    lines = ["# Work-precision: kinetwork's default against its own route by hand", "",
             f"{machine()}; {common.load()}. Study run time {total:.0f} s. Error: max "
             f"joint-angle difference from pinocchio ABA + DOP853 at rtol {REF_RTOL:g} on the "
             f"{SPACING:g} s grid over 10 s; time: the least wall time of repeated runs (7, "
             f"5 at N = 128) after a first call, the curves' runs of one setting taken in "
             f"turn; rtol 1e-1..1e-12, atol = rtol * 1e-2 for both."
             + (" Quick mode: chain2 and chain16, rtol 1e-4 and 1e-8." if quick else ""), ""]
    lines += ["- " + n for n in notes_of] + [""]
    lines += against_hand_written(curves_of)
    lines += ["## Where the time goes", "",
              "Per rtol asked of kinetwork, and in brackets the solver's rtol it maps it to "
              "(``kinetwork/solver/tolerance.py``), at which the hand-written route runs "
              "here too (the same method at the same tolerances): the least wall time of 3 "
              "runs, steps and right-hand-side evaluations (kinetwork's counted by CVODES), "
              "and wall time per evaluation (the whole run divided by the evaluations: "
              "integration and per-run overhead).", "",
              table(["scene", "rtol (solver)", "auto ran", "auto", "steps", "rhs evals",
                     "us/eval",
                     "by hand", "steps", "rhs evals", "us/eval"], counts), ""]
    rows = []
    for name, curves in curves_of.items():
        for c in curves:
            rows += [[name, c.label, r["setting"], fmt_time(r["time_s"])
                      if np.isfinite(r["time_s"]) else "—",
                      f"{r['error']:.1e}" if np.isfinite(r["error"]) else "—", r["status"]]
                     for r in c.rows]
    lines += ["## Every run", "", table(["scene", "curve", "setting", "time", "error",
                                          "status"], rows)]
    write_markdown(f"{NAME}_casadi", "\n".join(lines))
    print(f"done in {total:.0f} s", flush=True)


def overheads(rtols=(1e-4, 1e-7)):
    """``--overheads``: where a run of ``auto`` spends the time the hand-written route does not.

    For chain2, chain16 and chain128 at each rtol: one ``simulate`` (least of 3), its
    integrator calls (``advance``, the driver's chunks: how many, the evaluations they took),
    the output evaluation on the grid (``System.outputs_p``), the rest (settings, checks,
    results); then kinetwork's own compiled DAE in one CasADi integrator call over the whole
    grid at the same solver tolerances (no chunks) and the hand-written route there. The
    kinetwork functions are wrapped to be timed: a diagnostic, not a benchmark."""
    import casadi as ca
    from kinetwork.equations import system as system_module
    from kinetwork.solver import methods
    from kinetwork.solver.compiled import compiled
    from kinetwork.solver.tolerance import solver_tolerances
    clocks = {}

    def wrap(owner, name):
        inner = getattr(owner, name)

        def timed_call(*args, **kwargs):
            start = time.perf_counter()
            try:
                return inner(*args, **kwargs)
            finally:
                clocks.setdefault(name, []).append(time.perf_counter() - start)
        setattr(owner, name, timed_call)
        return inner
    saved = [(methods._CasadiRun, "advance", wrap(methods._CasadiRun, "advance")),
             (system_module.System, "outputs_p", wrap(system_module.System, "outputs_p"))]
    rows = []
    try:
        for name in CASADI_SCENES:
            builder, spec_of, horizon = scenes.SCENES[name]
            spec, system = spec_of(), builder().compile()
            t = np.linspace(0.0, horizon, round(horizon / SPACING) + 1)
            hand = casadi_peer.build(spec)
            adams = kn.METHODS["cvodes-adams"]
            for rtol in rtols:
                kw = {"t_end": horizon, "n_points": len(t), "rtol": rtol, "atol": rtol * 1e-2,
                      "jit": True, "method": "cvodes-adams"}
                kn.simulate(system, **kw)
                best = None
                for _ in range(3):
                    clocks.clear()
                    start = time.perf_counter()
                    res = kn.simulate(system, **kw)
                    total = time.perf_counter() - start
                    if best is None or total < best[0]:
                        best = (total, {k: list(v) for k, v in clocks.items()}, res.stats)
                total, spent, stats = best
                srt, sat = solver_tolerances(adams, system, rtol, rtol * 1e-2)[:2]
                dae = compiled(system).dae({"stats": {}}, False)
                whole = ca.integrator("whole", "cvodes", dae, 0.0, (t[1:] - t[0]).tolist(),
                                      {**adams.options, "reltol": srt, "abstol": sat})
                p = np.append(system.param_vector(), t[0])
                one = min(timed(lambda w=whole, x=system.x0, p=p:
                                np.asarray(w(x0=x, z0=[], p=p)["xf"]), budget=0.0)[0]
                          for _ in range(3))
                hand_s = min(timed(lambda h=hand, t=t, r=srt, a=sat:
                                   casadi_peer.run(h, t, rtol=r, atol=a), budget=0.0)[0]
                             for _ in range(3))
                integ = casadi_peer.integrator(hand, t, srt, sat)
                advance, outputs = sum(spent.get("advance", [])), sum(spent.get("outputs_p", []))
                rows.append([name, f"{rtol:.0e} ({srt:.0e})", fmt_time(total),
                             f"{len(spent.get('advance', []))}: {fmt_time(advance)}",
                             stats.get("rhs_evaluations", ""), fmt_time(outputs),
                             fmt_time(total - advance - outputs),
                             f"{fmt_time(one)}, {int(whole.stats()['nfevals'])}",
                             f"{fmt_time(hand_s)}, {int(integ.stats()['nfevals'])}"])
                print("  ", rows[-1], flush=True)
    finally:
        for owner, name, inner in saved:
            setattr(owner, name, inner)
    lines = ["# Where kinetwork's run spends what the hand-written route does not", "",
             f"{machine()}; {common.load()}. Per scene and rtol (the solver's, tightened by "
             "kinetwork, in brackets; both routes at that one): one `simulate` with "
             "cvodes-adams (what `auto` runs on these undamped chains; least of 3), its "
             "integrator calls (the driver's chunks: number and time; one for a run that "
             "nothing watches, see ``kinetwork/solver/driver.py``), CVODES' "
             "right-hand-side evaluations over them, the probes' evaluation on the output "
             "grid (`System.outputs_p`; these chains have no probe), the rest; then "
             "kinetwork's own compiled DAE in one integrator call over the whole grid, and the "
             "hand-written route (time, evaluations).", "",
             table(["scene", "rtol (solver)", "simulate", "chunks: time", "evaluations",
                    "outputs_p", "rest", "one call: time, evaluations",
                    "by hand: time, evaluations"], rows)]
    write_markdown(f"{NAME}_casadi_overheads", "\n".join(lines))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="seed only, two settings per curve")
    parser.add_argument("--casadi", action="store_true",
                        help="only kinetwork's default against the hand-written route "
                             "(chain2, chain16, chain128; results/work_precision_casadi.md)")
    parser.add_argument("--overheads", action="store_true",
                        help="where auto's run spends the time the hand-written route does "
                             "not (results/work_precision_casadi_overheads.md)")
    parser.add_argument("--point-masses", action="store_true",
                        help="only the point-mass chains with a damper (planar and 3-D, N = 2, "
                             "16, 128): auto against the hand-written route, pinocchio and "
                             "MuJoCo RK4 in CPU time (results/work_precision_points.md)")
    parser.add_argument("--sizes", type=int, nargs="+",
                        help="with --point-masses: these N instead (results/"
                             "work_precision_points_sizes.md; 32 64: between the issue's)")
    parser.add_argument("--choice", action="store_true",
                        help="only auto's choice where stability holds the step, against Adams "
                             "(results/work_precision_choice.md)")
    args = parser.parse_args()
    if args.choice:
        import work_precision_points
        return work_precision_points.choice()
    if args.point_masses:
        import work_precision_points
        return work_precision_points.study(args.quick, args.sizes)
    if args.overheads:
        return overheads()
    if args.casadi:
        return casadi_study(args.quick)
    names = ("seed",) if args.quick else SCENES
    budget = 0.03 if args.quick else 0.06
    start = time.perf_counter()
    print("preparing (models, references, first calls, sympy derivations)", flush=True)
    prepared = prepare(names, args.quick)
    csv_rows = []
    for name in names:
        p = prepared[name]
        cap = CAP_LARGE if p["info"]["n"] >= 64 else CAP
        t0 = time.perf_counter()
        for c in p["curves"]:
            sweep(c, p["ref"], cap, budget)
            key = {"scene": name, "tool": c.tool, "method": c.method}
            csv_rows += [{**key, **r} for r in c.rows]
            if c.note:
                csv_rows.append({**key, "setting": "", "time_s": math.nan, "error": math.nan,
                                 "status": c.note})
        plot(name, p["curves"], p["info"])
        print(f"  {name}: swept in {time.perf_counter() - t0:.1f} s", flush=True)
    write_csv(NAME, csv_rows)
    total = time.perf_counter() - start
    lines = [f"""# Work-precision: error against wall time

{machine()}. Study run time {total:.0f} s.

- Error: max joint-angle difference from the reference on the 0.01 s output grid. Time: wall
  time of one run, median of repeats, after a first call (JIT compilation, integrator creation
  and the peers' builds are not included).
- Variable-step methods: rtol 1e-3..1e-12 (every other decade at N = 128), atol = rtol * 1e-2,
  for kinetwork and the scipy peers alike. Fixed-step methods: steps 1e-2..1e-5 s.
- A curve stops at its first run over {CAP:g} s ({CAP_LARGE:g} s at N = 128), before a run
  predicted to be over 1.5 times that, and once its error is below {FLOOR:.0e} or stops falling
  below 1e-8; a scipy or MuJoCo run is interrupted at {LIMIT:g} times the budget (a CasADi
  integrator cannot be).
- `auto (VM)` is the default without JIT (CasADi's virtual machine); every other kinetwork
  method runs with JIT.
- sympy: the derivation runs in its own process with a {SYMPY_TIMEOUT:g} s limit (wall time; two
  derivations side by side, next to the untimed preparation); a longer chain is not tried once
  a shorter one failed.
- Times to an accuracy are interpolated in log-log along each curve's Pareto front; when a
  curve's fastest run is already more accurate than the target, that run's time is given."""]
    if args.quick:
        lines.append("- Quick mode (a smoke test): the seed scene only, rtol 1e-4 and 1e-8, "
                     "steps 1e-2 and 1e-3 s.")
    lines.append("")
    for name in names:
        lines += scene_section(name, prepared[name])
    lines += default_against_peers(prepared)
    lines += [""] + against_hand_written({n: p["curves"] for n, p in prepared.items()})
    write_markdown(NAME, "\n".join(lines))
    print(f"done in {total:.0f} s", flush=True)


if __name__ == "__main__":
    main()
