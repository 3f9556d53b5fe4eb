"""Scaling: what an N-link chain costs to build, to compile and to evaluate, N = 2 .. 128.

For each chain (``scenes.chain(n)``: N uniform rods on revolute joints): states and
right-hand-side operations (``system.size()``); model construction and build time (model ->
compiled System, no C compilation) as medians of repeated builds; JIT compilation of the
right-hand side cold (an empty cache folder) and warm (a new System of the same model, the
library found in the cache): the cold one timed once around ``compiled(system).rhs(jit)``, the
warm one as the median of repeated ``jit.external`` calls (what that call does on a hit); and
the cost of one right-hand-side evaluation from Python: kinetwork compiled C and CasADi's
virtual machine, both through ``kinetwork.simulation.compiled.numeric`` (~0.5 us of call overhead included),
pinocchio's ``aba`` and MuJoCo's ``mj_forward`` on the peers' models of the same chain. Each
per-evaluation time is the median over batches of repeated calls on one state.

Exponents are log-log least-squares slopes from N = 8 to N = 128.

Run: ``.venv/bin/python bench/study_scaling.py [--quick]``; writes results/study_scaling.csv,
.md, study_scaling.png (evaluation cost) and study_scaling_build.png (build and JIT times).
"""

import argparse
import os
import statistics
import tempfile
import time

import casadi as ca
import numpy as np

from common import RESULTS, STYLE, chart, load, machine, table, timed, write_csv, write_markdown

from scenes import chains as scenes
import kinetwork as kn
from kinetwork.graph.topology import analyze
from kinetwork.simulation import jit
from kinetwork.simulation.compiled import compiled as compiled_of, numeric

SIZES = (2, 4, 8, 16, 32, 64, 128)
FIT_FROM = 8
BATCH_SECONDS = 0.02
BATCHES = 11


def per_call(fn, batches=BATCHES):
    """Median time of one ``fn()`` call: batches of calls sized to ~BATCH_SECONDS each."""
    fn()
    n, start = 1, time.perf_counter()
    while time.perf_counter() - start < BATCH_SECONDS / 10:
        fn()
        n += 1
    calls = max(1, int(n * 10 * BATCH_SECONDS / max(time.perf_counter() - start, 1e-9)) // 10)
    times = []
    for _ in range(batches):
        start = time.perf_counter()
        for _ in range(calls):
            fn()
        times.append((time.perf_counter() - start) / calls)
    return statistics.median(times)


def peers():
    """name -> (build(spec), evaluator(built) -> zero-argument callable), for what imports."""
    found = {}
    try:
        import pinocchio as pin
        from peers import pinocchio_peer

        def aba(built):
            rng = np.random.default_rng(0)
            q, v = rng.uniform(-0.5, 0.5, built.n), rng.uniform(-0.5, 0.5, built.n)
            tau = np.zeros(built.n)
            return lambda: pin.aba(built.model, built.data, q, v, tau)
        found["pinocchio aba"] = (pinocchio_peer.build, aba)
    except ImportError:
        pass
    try:
        import mujoco
        from peers import mujoco_peer

        def forward(built):
            rng = np.random.default_rng(0)
            built.data.qpos[:] = rng.uniform(-0.5, 0.5, built.n)
            built.data.qvel[:] = rng.uniform(-0.5, 0.5, built.n)
            return lambda: mujoco.mj_forward(built.model, built.data)
        found["MuJoCo mj_forward"] = (mujoco_peer.build, forward)
    except ImportError:
        pass
    return found


def main(quick=False):
    clock = time.perf_counter()
    sizes = (2, 8, 16) if quick else SIZES
    tools = peers()
    rows = []
    saved_cache = os.environ.get("KINETWORK_CACHE")
    try:
        for n in sizes:
            rows.append(measure(n, tools))
            r = rows[-1]
            print(f"N={n:4d} ops {r['operations']:6d} build {r['build_s'] * 1e3:7.1f} ms "
                  f"jit cold {r['jit_cold_s']:6.2f} s warm {r['jit_warm_s'] * 1e3:6.1f} ms  "
                  f"C {r['rhs_c_us']:7.2f} us  VM {r['rhs_vm_us']:8.2f} us  "
                  + "  ".join(f"{k} {r[_key(k)]:7.2f} us" for k in tools))
    finally:
        if saved_cache is None:
            os.environ.pop("KINETWORK_CACHE", None)
        else:
            os.environ["KINETWORK_CACHE"] = saved_cache
    write_csv("study_scaling", rows)
    fits = exponents(rows, tools)
    charts(rows, tools)
    total = time.perf_counter() - clock
    report(rows, fits, tools, total, quick)
    print(f"study_scaling: {total:.1f} s")


def _key(tool):
    return {"pinocchio aba": "aba_us", "MuJoCo mj_forward": "mj_forward_us"}[tool]


def measure(n, tools):
    model_s, model = timed(lambda: scenes.chain(n), budget=0.3, max_repeats=7)
    # validate and assemble afresh each time: model.compile() would hand back its System
    build_s, system = timed(lambda: kn.System(model, topology=analyze(model)), budget=1.0,
                            max_repeats=7)
    size = system.size()
    with tempfile.TemporaryDirectory() as folder:
        os.environ["KINETWORK_CACHE"] = folder       # jit.cache_dir() reads it on each call
        start, stats = time.perf_counter(), {}
        compiled = compiled_of(system).rhs({"stats": stats})
        cold = time.perf_counter() - start
        gcc = stats.get("jit_seconds", float("nan"))
        again, stats = scenes.chain(n).compile(), {}       # a new model: a new System
        compiled_of(again).rhs({"stats": stats})
        assert stats.get("jit_cached"), "a new System missed the cache"
        # what that call did, repeated for a median: generate and hash the C, load the library
        warm, _ = timed(lambda: jit.external(again.f_rhs, False, {}), budget=0.3)
        p = system.param_vector()
        x = np.random.default_rng(0).uniform(-0.5, 0.5, 2 * n)
        c_rhs = numeric(compiled, p, system.n_states)
        vm_rhs = numeric(system.f_rhs, p, system.n_states)
        assert np.allclose(c_rhs(0.0, x), vm_rhs(0.0, x), rtol=1e-10, atol=1e-10)
        # the same call path around a Function that does nothing but copy x: the overhead
        t_, x_, p_ = (ca.SX.sym(name, system.f_rhs.size1_in(i))
                      for i, name in enumerate("txp"))
        empty = numeric(ca.Function("copy", [t_, x_, p_], [x_]), p, system.n_states)
        row = {"N": n, "states": size["states"], "operations": size["operations"],
               "model_s": model_s, "build_s": build_s, "jit_cold_s": cold,
               "jit_cold_compiler_s": gcc, "jit_warm_s": warm,
               "rhs_c_us": per_call(lambda: c_rhs(0.0, x)) * 1e6,
               "call_overhead_us": per_call(lambda: empty(0.0, x)) * 1e6,
               "rhs_vm_us": per_call(lambda: vm_rhs(0.0, x)) * 1e6}
    spec = scenes.chain_spec(n)
    for tool, (build, evaluator) in tools.items():
        row[_key(tool)] = per_call(evaluator(build(spec))) * 1e6
    return row


def slope(rows, key):
    pick = [r for r in rows if r["N"] >= FIT_FROM]
    if len(pick) < 2:
        pick = rows
    return float(np.polyfit(np.log([r["N"] for r in pick]),
                            np.log([r[key] for r in pick]), 1)[0])


def exponents(rows, tools):
    for r in rows:
        r["rhs_c_net_us"] = max(r["rhs_c_us"] - r["call_overhead_us"], 1e-3)
    keys = {"operations": "operations", "model construction": "model_s", "build": "build_s",
            "JIT cold": "jit_cold_s", "JIT warm": "jit_warm_s", "rhs compiled C": "rhs_c_us",
            "rhs compiled C, call overhead taken off": "rhs_c_net_us",
            "rhs CasADi VM": "rhs_vm_us", **{t: _key(t) for t in tools}}
    return {name: slope(rows, key) for name, key in keys.items()}


def charts(rows, tools):
    N = [r["N"] for r in rows]
    series = {"kinetwork compiled C (numeric)": dict(x=N, y=[r["rhs_c_us"] for r in rows],
                                                    style=STYLE["kinetwork"]),
              "kinetwork CasADi VM (numeric)": dict(x=N, y=[r["rhs_vm_us"] for r in rows],
                                                   style={**STYLE["kinetwork"],
                                                          "linestyle": "--"}),
              "operations / 1000 (right-hand side)": dict(
                  x=N, y=[r["operations"] / 1e3 for r in rows],
                  style=dict(color="0.5", linestyle=":"))}
    for tool in tools:
        family = "pinocchio" if tool.startswith("pinocchio") else "mujoco"
        series[tool] = dict(x=N, y=[r[_key(tool)] for r in rows], style=STYLE[family])
    chart(RESULTS / "study_scaling.png", series, "links N",
          "one right-hand-side evaluation from Python [us]",
          "Chain of N rods: cost of one evaluation of the dynamics\n(from Python, median "
          "over batches of calls; each tool's call overhead included)")
    build = {"build (model -> System)": dict(x=N, y=[r["build_s"] for r in rows],
                                             style=STYLE["kinetwork"]),
             "model construction (scenes.chain)": dict(x=N, y=[r["model_s"] for r in rows],
                                                       style=dict(color="C4")),
             "JIT compile, cold cache": dict(x=N, y=[r["jit_cold_s"] for r in rows],
                                             style=dict(color="C3")),
             "JIT, cache hit (new System)": dict(x=N, y=[r["jit_warm_s"] for r in rows],
                                                 style=dict(color="C3", linestyle="--"))}
    chart(RESULTS / "study_scaling_build.png", build, "links N", "wall time [s]",
          "Chain of N rods: build and JIT compilation time\n(build and cache hit: medians "
          "of repeats; cold compile: one run)")


def report(rows, fits, tools, total, quick):
    last = rows[-1]
    body = [[r["N"], r["states"], r["operations"], f"{r['model_s'] * 1e3:.1f}",
             f"{r['build_s'] * 1e3:.1f}", f"{r['jit_cold_s']:.2f}",
             f"{r['jit_warm_s'] * 1e3:.1f}", f"{r['rhs_c_us']:.2f}", f"{r['rhs_vm_us']:.1f}",
             *(f"{r[_key(t)]:.2f}" for t in tools)] for r in rows]
    header = ["N", "states", "rhs operations", "model [ms]", "build [ms]", "JIT cold [s]",
              "JIT hit [ms]", "rhs C [us]", "rhs VM [us]", *(f"{t} [us]" for t in tools)]
    lines = [f"## Scaling: chains of N rods{' (quick smoke run)' if quick else ''}", "",
             f"{machine()}; {load()}. Build: median of repeated `model.compile()` "
             f"(validate, assemble, "
             f"CasADi Functions; no C). JIT cold: `compiled(system).rhs(jit)` with an empty "
             f"cache folder (code generation + gcc -O1); JIT hit: what the same call does "
             f"for a new System of the same model (code generation and hashing, then loading "
             f"the cached library), median of repeats. Per-evaluation times from Python, "
             f"median over batches of calls; they are noisy when the load average is over "
             f"the core count. "
             f"Study wall time {total:.0f} s.", "",
             table(header, body), "",
             f"Log-log slopes from N = {FIT_FROM} to {last['N']}:", "",
             table(["quantity", "exponent"], [[k, f"{v:.2f}"] for k, v in fits.items()]), "",
             "![evaluation cost](study_scaling.png)", "",
             "![build and JIT time](study_scaling_build.png)", "", "### Findings", "",
             f"- Right-hand-side cost grows as N^{fits['rhs compiled C']:.2f} compiled "
             f"(N^{fits['rhs compiled C, call overhead taken off']:.2f} once the "
             f"{last['call_overhead_us']:.1f} us of the Python call is taken off), "
             f"N^{fits['rhs CasADi VM']:.2f} in CasADi's VM, operations "
             f"N^{fits['operations']:.2f}; target exponent ≤ 1.2. At N = {last['N']}: "
             f"{last['rhs_c_us']:.1f} us compiled, {last['rhs_vm_us']:.0f} us in the VM"
             + "".join(f", {last[_key(t)]:.1f} us {t}" for t in tools) + ".",
             f"- Build at N = {last['N']}: {last['build_s']:.2f} s (target < 1 s), "
             f"exponent {fits['build']:.2f}; constructing the model itself (adding and "
             f"connecting {3 * last['N'] + 1} components): {last['model_s'] * 1e3:.0f} ms, "
             f"exponent {fits['model construction']:.2f}.",
             f"- JIT at N = {last['N']}: {last['jit_cold_s']:.2f} s cold "
             f"({last['jit_cold_compiler_s']:.2f} s of it in the compiler), "
             f"{last['jit_warm_s'] * 1e3:.0f} ms on a cache hit "
             f"({last['jit_warm_s'] / last['build_s'] * 100:.0f} % of the build); the hit's "
             f"cost is regenerating and hashing the C source, not the lookup."]
    write_markdown("study_scaling", "\n".join(lines))


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="smoke test: N = 2, 8, 16")
    main(parser.parse_args().quick)
