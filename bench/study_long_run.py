"""Long runs: the energy of the undamped seed over 1000 s, symplectic against the rest.

The seed double pendulum with its damper removed (d = 0, spring c = 1 kept: conservative),
released at the seed's 0.05, 0.05 rad, output every 0.5 s for 1000 s. The energy is computed
from the paper's closed form on each method's states: T = 1/2 qd^T M(q) qd with ``seed_mvg``'s
M, V = gravity of the two point masses at mid-link (angles from the downward vertical)
+ c q1^2 / 2. The error reported is relative to the energy of the motion,
(E(t) - E(0)) / (E(0) - E_rest), E_rest being the energy at rest hanging straight down: the
potential's zero is arbitrary, the energy put into the swing is not.

Methods: kinetwork's midpoint (symplectic) and rk (RK4) at steps 0.05, 0.02, 0.01 s; dop853,
rk45 and cvodes-adams at rtol 1e-6 and 1e-8 (atol = rtol / 100); MuJoCo's RK4 and its default
semi-implicit Euler at 0.01 s, stepped here so that velocities are recorded too.

Run: ``.venv/bin/python bench/study_long_run.py [--quick]``; writes
results/study_long_run.csv (one row per run), .md and .png.
"""

import argparse
import time

import numpy as np

from common import RESULTS, load, machine, table, timed, write_csv, write_markdown
from scenes.reference import PAPER, seed_mvg

import kinetwork as kn
from scenes import chains as scenes

SPACING = 0.5
PARAMS = {**PAPER, "d": 0.0}
CHECKPOINTS = (10.0, 100.0, 1000.0)
STEPS = (0.05, 0.02, 0.01)
RTOLS = (1e-6, 1e-8)


def energy(q, qd, p=PARAMS):
    """Total energy along a trajectory (q, qd: (n_points, 2)), from the closed form."""
    q1, q2, w1, w2 = q[:, 0], q[:, 1], qd[:, 0], qd[:, 1]
    (a, b), (c, d) = seed_mvg((q1, q2), (w1, w2), **p, array=lambda rows: rows)[0]
    kinetic = 0.5 * (a * w1**2 + (b + c) * w1 * w2 + d * w2**2)
    g, L1, L2, m1, m2 = p["g"], p["L1"], p["L2"], p["m1"], p["m2"]
    height = m1 * (-L1 / 2 * np.cos(q1)) + m2 * (-L1 * np.cos(q1) - L2 / 2 * np.cos(q1 + q2))
    return kinetic + g * height + p["c"] * q1**2 / 2


def rest_energy(p=PARAMS):
    return float(energy(np.zeros((1, 2)), np.zeros((1, 2)), p)[0])


def mujoco_states(integrator, step, t):
    """MuJoCo's angles and rates on ``t``, from the peer's model of the same pendulum."""
    import mujoco
    from peers import mujoco_peer
    built = mujoco_peer.build(scenes.seed_spec(c=PARAMS["c"], d=0.0))
    m, d = built.model, built.data
    m.opt.timestep = step
    m.opt.integrator = getattr(mujoco.mjtIntegrator, f"mjINT_{integrator.upper()}")
    k = int(round((t[1] - t[0]) / step))

    def run():
        mujoco.mj_resetData(m, d)
        d.qpos[:], d.qvel[:] = built.q0, built.qd0
        q, qd = np.empty((len(t), 2)), np.empty((len(t), 2))
        q[0], qd[0] = d.qpos, d.qvel
        for j in range(1, len(t)):
            mujoco.mj_step(m, d, k)
            q[j], qd[j] = d.qpos, d.qvel
        return q, qd
    return run


def main(quick=False):
    clock = time.perf_counter()
    t_end = 20.0 if quick else 1000.0
    steps = (0.05,) if quick else STEPS
    rtols = (1e-6,) if quick else RTOLS
    t = np.linspace(0.0, t_end, int(round(t_end / SPACING)) + 1)
    system = scenes.seed(d=0.0).compile()
    e_rest = rest_energy()
    runs = [("midpoint", dict(step=h), f"h = {h:g} s") for h in steps]
    runs += [("rk", dict(step=h), f"h = {h:g} s") for h in steps]
    runs += [(m, dict(rtol=r, atol=r / 100), f"rtol {r:g}") for m in ("dop853", "rk45",
                                                                      "cvodes-adams")
             for r in rtols]
    curves, rows = {}, []
    for method, settings, label in runs:
        def simulate(method=method, settings=settings):
            res = kn.simulate(system, t_end=t_end, n_points=len(t), method=method, jit=True,
                              **settings)
            return res.states[:, :2], res.states[:, 2:], res.stats
        wall, (q, qd, stats) = timed(simulate, budget=0.5, max_repeats=5)
        steps_taken = stats.get("steps", "")
        rows.append(_row("kinetwork", method, label, wall, q, qd, e_rest, t, steps_taken,
                         stats.get("rhs_evaluations", "")))
        curves[f"{method} {label}"] = rows[-1].pop("curve")
        _print(rows[-1])
    try:
        import peers.mujoco_peer  # noqa: F401  (the peer's model is what gets stepped)
        mujoco_runs = [("RK4", 0.01), ("Euler", 0.01)]
    except ImportError:
        mujoco_runs = []
    for integrator, h in mujoco_runs:
        wall, (q, qd) = timed(mujoco_states(integrator, h, t), budget=0.5, max_repeats=5)
        rows.append(_row("mujoco", f"mujoco {integrator}", f"h = {h:g} s", wall, q, qd, e_rest,
                         t, round(t_end / h), 4 * round(t_end / h) if integrator == "RK4"
                         else round(t_end / h)))
        curves[f"mujoco {integrator} h = {h:g} s"] = rows[-1].pop("curve")
        _print(rows[-1])
    write_csv("study_long_run", rows)
    chart(t, curves, t_end)
    total = time.perf_counter() - clock
    report(rows, t_end, total, quick)
    print(f"study_long_run: {total:.1f} s")


def _row(tool, method, label, wall, q, qd, e_rest, t, steps, rhs):
    E = energy(q, qd)
    rel = (E - E[0]) / (E[0] - e_rest)
    row = {"tool": tool, "method": method, "setting": label, "wall_s": wall,
           "steps": steps, "rhs_evaluations": rhs, "motion_energy_J": E[0] - e_rest}
    for c in CHECKPOINTS:
        upto = t <= c + 1e-9
        row[f"max_rel_error_to_{c:g}s"] = float(np.max(np.abs(rel[upto]))) \
            if c <= t[-1] + 1e-9 else ""
    row["final_rel_error"] = float(rel[-1])
    # least-squares slope of the relative error: a drift shows, a bounded wobble fits to ~0
    row["drift_per_1000s"] = float(np.polyfit(t, rel, 1)[0] * 1000.0)
    row["curve"] = rel
    return row


def _print(r):
    print(f"{r['method']:14s} {r['setting']:12s} wall {r['wall_s']:7.3f} s  "
          f"final {r['final_rel_error']:+.2e}  drift/1000 s {r['drift_per_1000s']:+.2e}")


FAMILY = {"midpoint": "C0", "rk": "C1", "dop853": "C2", "rk45": "C3", "cvodes-adams": "C4",
          "mujoco RK4": "C5", "mujoco Euler": "C6"}


def _style(name):
    family = next(f for f in sorted(FAMILY, key=len, reverse=True) if name.startswith(f))
    dash = {"0.05": "-", "0.02": "--", "1e-06": "-", "1e-08": "--"}
    key = next((k for k in dash if k in name), None)
    if family.startswith("mujoco"):      # thin, so kinetwork's rk at the same step shows
        return dict(color=FAMILY[family], linestyle="-.", linewidth=1.1)
    return dict(color=FAMILY[family], linestyle=dash.get(key, ":"),
                linewidth=2.4 if key is None else 1.4)


def chart(t, curves, t_end, window=10.0):
    """|error| as its max over each ``window`` seconds: a bounded wobble reads as a flat band,
    a drift as a rising line (the raw curves oscillate too fast to see either at 1000 s)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    per = max(1, int(round(window / (t[1] - t[0]))))
    n = (len(t) - 1) // per
    t_win = t[1:1 + n * per].reshape(n, per)[:, -1]
    fig, axes = plt.subplots(2, 1, figsize=(10, 8), sharex=True, layout="constrained")
    groups = ({n: c for n, c in curves.items() if " h = " in n},
              {n: c for n, c in curves.items() if " h = " not in n})
    for ax, group, title in zip(axes, groups, ("fixed-step", "variable-step")):
        for name, rel in group.items():
            env = np.abs(rel[1:1 + n * per]).reshape(n, per).max(axis=1)
            ax.semilogy(t_win, env, label=name, **_style(name))
        ax.set_ylim(1e-10, 1.0)
        ax.set_ylabel(f"max over {window:g} s of\n|E(t) − E(0)| / (E(0) − E_rest)")
        ax.set_title(f"{title} methods", fontsize=10)
        ax.grid(True, which="major", alpha=0.4)
        ax.legend(fontsize=8, loc="center left", bbox_to_anchor=(1.01, 0.5))
    axes[-1].set_xlabel("time [s]")
    axes[-1].set_xlim(0, t_end)
    fig.suptitle(f"Undamped seed (d = 0, c = 1), {t_end:g} s: relative energy error")
    fig.savefig(RESULTS / "study_long_run.png", dpi=110)
    plt.close(fig)


def _g(x, spec=".1e"):
    return "—" if x == "" else format(x, spec)


def report(rows, t_end, total, quick):
    checks = [c for c in CHECKPOINTS if c <= t_end]
    body = [[r["method"], r["setting"], *(_g(r[f"max_rel_error_to_{c:g}s"]) for c in checks),
             f"{r['drift_per_1000s']:+.1e}", _g(r["steps"], ".3g"), f"{r['wall_s']:.3g}"]
            for r in rows]
    mid = [r for r in rows if r["method"] == "midpoint"]
    rest = [r for r in rows if r["method"] != "midpoint"]
    last = f"max_rel_error_to_{checks[-1]:g}s"
    best_other = min(rest, key=lambda r: r[last])
    lines = [f"## Long run: energy of the undamped seed{' (quick smoke run)' if quick else ''}",
             "", f"{machine()}; {load()}. Seed with d = 0, c = 1, from 0.05, 0.05 rad; "
             f"{t_end:g} s, "
             f"output every {SPACING} s. Relative energy error = (E(t) − E(0)) / (E(0) − "
             f"E_rest), energy of the motion E(0) − E_rest = "
             f"{rows[0]['motion_energy_J']:.4g} J, "
             f"from the closed form on each method's states. Columns \"≤ t\": max |error| "
             f"over [0, t]; drift: least-squares slope of the error, per 1000 s. MuJoCo: "
             f"the peer's model stepped here, recording velocities. Study wall time "
             f"{total:.0f} s.", "",
             table(["method", "setting", *(f"≤ {c:g} s" for c in checks),
                    "drift /1000 s", "steps", "wall [s]"], body), "",
             "![energy error](study_long_run.png)", "", "### Findings", "",
             f"- midpoint: max relative energy error over {checks[-1]:g} s "
             + ", ".join(f"{r[last]:.1e} ({r['setting']})" for r in mid)
             + f", fitted drift within ±{max(abs(r['drift_per_1000s']) for r in mid):.0e} "
             f"per 1000 s: bounded.",
             f"- the others over {checks[-1]:g} s: from {best_other[last]:.1e} "
             f"({best_other['method']} {best_other['setting']}) to "
             f"{max(r[last] for r in rest):.1e}; "
             + "; ".join(f"{r['method']} {r['setting']} drifts {r['drift_per_1000s']:+.1e}"
                         for r in rest) + " per 1000 s."]
    tight = min(mid, key=lambda r: r[last])
    ahead = [r for r in rest if r[last] < tight[last] and r["drift_per_1000s"]]
    if ahead:
        lines.append(f"- still below midpoint {tight['setting']}'s bound {tight[last]:.1e} "
                     f"at {checks[-1]:g} s: " + "; ".join(
                         f"{r['method']} {r['setting']} ({r[last]:.1e}), which at its fitted "
                         f"drift passes it after "
                         f"~{tight[last] / abs(r['drift_per_1000s']) * 1e3:.0f} s"
                         for r in ahead) + ".")
    write_markdown("study_long_run", "\n".join(lines))


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="smoke test: 20 s, few methods")
    main(parser.parse_args().quick)
