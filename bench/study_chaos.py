"""Chaos: how long a trajectory of the chaotic double pendulum can be computed at all.

The chaotic scene (the seed at q0 = 2.5, 2.0 rad, damper removed), 30 s, output every 0.01 s.
Three references: the paper's closed form with DOP853 at rtol 1e-13 (A, the reference) and
1e-12 (B), and kinetwork's model with DOP853 at rtol 1e-13 (C). Where they disagree by more
than 1e-6 rad, no comparison against them means anything finer than that. Then auto and
dop853 at rtol 1e-4 .. 1e-10 (atol = rtol / 100): the max joint-angle error against A over
time, the time from which it exceeds 1e-2 rad (the run is useless from there), and the
exponential growth rate of the error (an estimate of the largest Lyapunov exponent) fitted on
each curve where it grows freely: from 100 x rtol (past the tolerance's own level) to 1e-2 rad
(before saturation, which comes at ~1 rad).

Run: ``.venv/bin/python bench/study_chaos.py [--quick]``; writes results/study_chaos.csv (one
row per run), .md and .png.
"""

import argparse
import time

import numpy as np

from common import RESULTS, load, machine, table, timed, write_csv, write_markdown
from scenes.reference import seed_reference

import kinetwork as kn
from scenes import chains as scenes

Q0 = (2.5, 2.0)
SPACING = 0.01
TOLERANCES = (1e-4, 1e-6, 1e-8, 1e-10)
AGREE = 1e-6        # rad: the references must agree this well for a comparison to count
USELESS = 1e-2      # rad: an error past this is no longer the trajectory asked for


def first_above(t, err, level):
    """First time the error exceeds ``level``; None if it never does."""
    above = np.flatnonzero(err > level)
    return float(t[above[0]]) if len(above) else None


def growth_rate(t, err, low, high=USELESS):
    """Slope of log(running max of err) against t while it climbs from ``low`` to ``high``.

    The running max removes the dips of an oscillating error; None when that window spans
    less than a second.
    """
    env = np.maximum.accumulate(err)
    window = (env > low) & (env <= high)
    if not window.any() or np.ptp(t[window]) < 1.0:
        return None, None
    return float(np.polyfit(t[window], np.log(env[window]), 1)[0]), \
        (float(t[window][0]), float(t[window][-1]))


def main(quick=False):
    clock = time.perf_counter()
    t_end = 5.0 if quick else 30.0
    tolerances = (1e-4, 1e-8) if quick else TOLERANCES
    t = np.linspace(0.0, t_end, int(round(t_end / SPACING)) + 1)
    x0 = (*Q0, 0.0, 0.0)
    start = time.perf_counter()
    A = seed_reference(t, x0=x0, rtol=1e-13, atol=1e-14, d=0.0)[:, :2]
    ref_time = time.perf_counter() - start
    B = seed_reference(t, x0=x0, rtol=1e-12, atol=1e-14, d=0.0)[:, :2]
    system = scenes.chaotic().compile()
    C = scenes.joint_angles(kn.simulate(system, t_end=t_end, n_points=len(t), method="dop853",
                                        rtol=1e-13, atol=1e-14, jit=True))
    diffs = {"A vs B (closed form 1e-12)": np.max(np.abs(A - B), axis=1),
             "A vs C (kinetwork dop853 1e-13)": np.max(np.abs(A - C), axis=1)}
    agree = {name: first_above(t, d, AGREE) for name, d in diffs.items()}
    spread = np.maximum(*diffs.values())
    horizon = first_above(t, spread, AGREE) or t_end
    rows, curves = [], {}
    for name, d in diffs.items():
        rate, span = growth_rate(t, d, 1e-10)
        rows.append(_row("reference", name, None, "", 0.0, t, d, rate, span, horizon))
        curves[name] = d
    for rtol in tolerances:
        for method in ("auto", "dop853"):
            def run(method=method, rtol=rtol):
                return kn.simulate(system, t_end=t_end, n_points=len(t), method=method,
                                   rtol=rtol, atol=rtol / 100, jit=True)
            wall, res = timed(run, budget=0.3, max_repeats=5)
            err = np.max(np.abs(scenes.joint_angles(res) - A), axis=1)
            rate, span = growth_rate(t, err, 100 * rtol)
            label = f"{method} rtol {rtol:.0e}".replace("e-0", "e-")
            rows.append(_row("kinetwork", label, rtol, res.method, wall, t, err, rate, span,
                             horizon))
            curves[label] = err
            r = rows[-1]
            print(f"{label:18s} ran {res.method:12s} wall {wall:6.3f} s  > 1e-2 rad from "
                  f"{r['useless_from_s']} s  growth {r['growth_rate_per_s']}")
    write_csv("study_chaos", rows)
    chart(t, curves, horizon, t_end)
    total = time.perf_counter() - clock
    report(rows, agree, horizon, t_end, total, ref_time, quick)
    print(f"study_chaos: {total:.1f} s")


def _row(kind, label, rtol, ran, wall, t, err, rate, span, horizon):
    upto = t <= horizon + 1e-9
    return {"kind": kind, "run": label, "rtol": rtol if rtol else "", "ran": ran,
            "wall_s": wall,
            "above_1e-6_from_s": first_above(t, err, 1e-6) or "",
            "useless_from_s": first_above(t, err, USELESS) or "",
            "max_error_within_horizon": float(np.max(err[upto])),
            "growth_rate_per_s": rate if rate is not None else "",
            "fit_from_s": span[0] if span else "", "fit_to_s": span[1] if span else ""}


def chart(t, curves, horizon, t_end):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(10, 5.8), layout="constrained")
    colours = {1e-4: "C3", 1e-6: "C1", 1e-8: "C2", 1e-10: "C0"}
    for name, err in curves.items():
        if name.startswith("A vs"):
            style = dict(color="0.35" if name.startswith("A vs C") else "0.7", linewidth=1.6)
        else:
            rtol = float(name.split()[-1])
            style = dict(color=colours.get(rtol, "C4"), linewidth=1.0,
                         linestyle="-" if name.startswith("dop853") else "--")
        ax.semilogy(t, np.maximum(err, 1e-16), label=name, **style)
    ax.axhline(USELESS, color="black", linewidth=0.8, linestyle=":")
    ax.text(t_end * 0.995, USELESS * 1.4, f"{USELESS:g} rad: useless", ha="right",
            fontsize=8)
    ax.axhline(AGREE, color="black", linewidth=0.6, linestyle=":")
    ax.axvspan(horizon, t_end, color="0.5", alpha=0.08, linewidth=0)
    ax.text(horizon + 0.2, 3e-15, f"references differ by > {AGREE:g} rad\nfrom "
            f"t = {horizon:g} s", fontsize=8, color="0.3")
    ax.set_ylim(1e-15, 1e1)
    ax.set_xlim(0, t_end)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("max joint-angle difference from reference A [rad]")
    ax.set_title("Chaotic double pendulum (q0 = 2.5, 2.0 rad, undamped): error against "
                 "closed-form DOP853 at rtol 1e-13\n(solid: dop853, dashed: auto; grey: the "
                 "other references)", fontsize=10)
    ax.grid(True, which="major", alpha=0.4)
    ax.legend(fontsize=7.5, loc="center left", bbox_to_anchor=(1.01, 0.5))
    fig.savefig(RESULTS / "study_chaos.png", dpi=110)
    plt.close(fig)


def _g(x, spec=".3g"):
    return "—" if x == "" or x is None else format(x, spec)


def report(rows, agree, horizon, t_end, total, ref_time, quick):
    runs = [r for r in rows if r["kind"] == "kinetwork"]
    rates = [r["growth_rate_per_s"] for r in rows if r["growth_rate_per_s"] != ""]
    body = [[r["run"], r["ran"] or "—", _g(r["above_1e-6_from_s"]), _g(r["useless_from_s"]),
             _g(r["max_error_within_horizon"], ".1e"), _g(r["growth_rate_per_s"], ".2f"),
             f"{_g(r['fit_from_s'], '.1f')}–{_g(r['fit_to_s'], '.1f')}"
             if r["fit_from_s"] != "" else "—", f"{r['wall_s']:.3g}" if r["wall_s"] else "—"]
            for r in rows]
    lines = [f"## Chaos: divergence of the chaotic double pendulum"
             f"{' (quick smoke run)' if quick else ''}", "",
             f"{machine()}; {load()}. Chaotic scene (q0 = 2.5, 2.0 rad, d = 0), "
             f"{t_end:g} s, output "
             f"every {SPACING} s. Reference A: closed form, DOP853 rtol 1e-13 "
             f"({ref_time:.1f} s); B: closed form, DOP853 rtol 1e-12; C: kinetwork, DOP853 "
             f"rtol 1e-13. Error: max joint-angle difference from A. Growth rate: slope of "
             f"log(running max of the error) between 100 × rtol (1e-10 for the references) "
             f"and {USELESS:g} rad. Study wall time {total:.0f} s.", "",
             "References agree within 1e-6 rad up to: "
             + "; ".join(f"{name}: {_g(v) if v else f'beyond {t_end:g}'} s"
                         for name, v in agree.items())
             + f". Comparisons below are meaningful to ~{AGREE:g} rad up to t = {horizon:g} s "
               f"and to the size of the grey curves after that.", "",
             table(["run", "ran", "> 1e-6 rad from [s]", f"> {USELESS:g} rad from [s]",
                    f"max error to {horizon:g} s", "growth rate [1/s]", "fit window [s]",
                    "wall [s]"], body), "",
             "![error against time](study_chaos.png)", "", "### Findings", ""]
    if rates:
        lines.append(f"- Largest Lyapunov exponent estimate: {np.median(rates):.2f} 1/s "
                     f"(median of {len(rates)} fitted growth rates, range "
                     f"{min(rates):.2f}–{max(rates):.2f}): an error grows tenfold every "
                     f"~{np.log(10) / np.median(rates):.1f} s.")
    lines.append("- Time from which the error exceeds 1e-2 rad: " + "; ".join(
        f"{r['run']}: {_g(r['useless_from_s'])} s" for r in runs) + ".")
    lines.append(f"- The two rtol 1e-13 references, with different right-hand sides in "
                 f"the same integrator, part by 1e-6 rad at "
                 f"{_g(agree['A vs C (kinetwork dop853 1e-13)']) or f'> {t_end:g}'} s and by "
                 f"1e-2 rad at {_g(rows[1]['useless_from_s']) or f'> {t_end:g}'} s: past "
                 f"that, no run here can be checked against them even to 1e-2 rad.")
    write_markdown("study_chaos", "\n".join(lines))


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="smoke test: 5 s, two tolerances")
    main(parser.parse_args().quick)
