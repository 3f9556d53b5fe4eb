"""Scaling: what an N-link chain costs to build, to compile and to evaluate, N = 2 .. 1024.

For each chain (``scenes.chain(n)``: N uniform rods on revolute joints): states and
right-hand-side operations (``system.size()``); model construction and build time (model ->
compiled System, no C compilation) as medians of repeated builds; JIT compilation of the
right-hand side cold (an empty cache folder) and warm (a new System of the same model, the
library found in the cache): the cold one timed once around ``compiled(system).rhs(jit)``, the
warm one as the median of repeated ``jit.external`` calls (what that call does on a hit); and
the cost of one right-hand-side evaluation from Python: kinetwork compiled C and CasADi's
virtual machine, both through ``kinetwork.solver.compiled.numeric`` (~0.5 us of call overhead included),
pinocchio's ``aba`` and MuJoCo's ``mj_forward`` on the peers' models of the same chain. Each
per-evaluation time is the median over batches of repeated calls on one state.

Also per N: a cached run (a new System of the same model simulated for 1 s, 101 points, its
library found in the cache: what a second process pays), and the study process's peak resident
memory after that N (``ru_maxrss``: sizes go up, so each row's peak is its own N's).

The chain of eight four-bar loops in both loop formulations (build, the first run's cold JIT
from an empty cache, the run again; the default formulation is marked), and what -O0 costs at
run time: a 256-link chain's right-hand side compiled at -O1 and at -O0 (the two tiers).

Setting up CVODES (``--setup``, its own run: results/study_scaling_setup.md): the time CasADi
takes to build the DAE's Jacobian function and a CVODES integrator around a chain's compiled
right-hand side, which the default method hides its derivatives from (``Compiled.dae``).

JIT strategies (``--strategies``, and in the quick run): the 1024-link right-hand side and the
eight-four-bar chain's DAE Jacobian compiled one file at -O1 (before), in parts at -O1 side by
side (``jit.SPLIT_STATEMENTS``), and in parts at -O0; compiler CPU time, wall time, and the
cost of one evaluation. And the eight-four-bar chain's first run from a cold cache.

Exponents are log-log least-squares slopes from N = 8 to the largest N.

Run: ``.venv/bin/python bench/study_scaling.py [--quick]``; writes results/study_scaling.csv,
.md, study_scaling.png (evaluation cost) and study_scaling_build.png (build and JIT times).
"""

import argparse
import multiprocessing
import os
import resource
import statistics
import sys
import tempfile
import time

import casadi as ca
import numpy as np

from common import RESULTS, STYLE, chart, load, machine, table, timed, write_csv, write_markdown

from scenes import chains as scenes
import kinetwork as kn
from kinetwork.graph.topology import analyze
from kinetwork.solver import jit
from kinetwork.solver.compiled import compiled as compiled_of, numeric

SIZES = (2, 4, 8, 16, 32, 64, 128, 256, 512, 1024)
FIT_FROM = 8
BATCH_SECONDS = 0.02
BATCHES = 11


def per_call(fn, batches=BATCHES):
    """Median CPU time of one ``fn()`` call: batches of calls sized to ~BATCH_SECONDS each
    (CPU time: on a machine shared past its core count, wall time counts the others' work)."""
    fn()
    n, start = 1, time.process_time()
    while time.process_time() - start < BATCH_SECONDS / 10:
        fn()
        n += 1
    calls = max(1, int(n * 10 * BATCH_SECONDS / max(time.process_time() - start, 1e-9)) // 10)
    times = []
    for _ in range(batches):
        start = time.process_time()
        for _ in range(calls):
            fn()
        times.append((time.process_time() - start) / calls)
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


def main(quick=False, only_strategies=False, sizes=None):
    clock = time.perf_counter()
    if only_strategies:
        saved_cache = os.environ.get("KINETWORK_CACHE")
        try:
            rows, loops = strategies(quick)
        finally:
            if saved_cache is None:
                os.environ.pop("KINETWORK_CACHE", None)
            else:
                os.environ["KINETWORK_CACHE"] = saved_cache
        first = {"function": loops["model"], "instructions": "",
                 "strategy": "first run, cold cache", "compiler_cpu_s": "",
                 "wall_s": loops["first_run_s"], "eval_us": ""}
        write_csv("study_scaling_jit", rows + [first])
        text = "\n".join([f"## JIT strategies{' (quick)' if quick else ''}", "",
                          f"{machine()}; {load()}."] + strategy_lines(rows, loops))
        write_markdown("study_scaling_jit", text)
        print(f"study_scaling --strategies: {time.perf_counter() - clock:.1f} s")
        return
    sizes = sizes or ((2, 8, 16) if quick else SIZES)
    tools = peers()
    rows = []
    saved_cache = os.environ.get("KINETWORK_CACHE")
    # on a loaded machine the N = 1024 compilers outlast jit's 300 s: the study waits
    jit.COMPILE_TIMEOUT = max(jit.COMPILE_TIMEOUT, 1800.0)
    try:
        for n in sizes:
            rows.append(measure(n, tools))
            write_csv("study_scaling", rows)            # what is measured survives a crash
            r = rows[-1]
            print(f"N={n:4d} CPU build {r['build_cpu_s']:.1f} s, JIT (Python) "
                  f"{r['jit_cold_cpu_s']:.1f} s, compilers {r['jit_cold_compilers_cpu_s']:.1f} s;"
                  f" cached run {r['cached_run_s']:.2f} s; peak RSS {r['peak_rss_mb']:.0f} MB",
                  flush=True)
            print(f"N={n:4d} ops {r['operations']:6d} build {r['build_s'] * 1e3:7.1f} ms "
                  f"jit cold {r['jit_cold_s']:6.2f} s warm {r['jit_warm_s'] * 1e3:6.1f} ms  "
                  f"C {r['rhs_c_us']:7.2f} us  VM {r['rhs_vm_us']:8.2f} us  "
                  + "  ".join(f"{k} {r[_key(k)]:7.2f} us" for k in tools), flush=True)
        fourbars = fourbar_rows(2 if quick else 8)
        write_csv("study_scaling_fourbar", fourbars)
        cost = o0_cost(16 if quick else 256)
        # the strategies take minutes at full size: their own run (--strategies)
        extra = strategies(quick) if quick else None
    finally:
        if saved_cache is None:
            os.environ.pop("KINETWORK_CACHE", None)
        else:
            os.environ["KINETWORK_CACHE"] = saved_cache
    write_csv("study_scaling", rows)
    fits = exponents(rows, tools)
    charts(rows, tools)
    total = time.perf_counter() - clock
    report(rows, fits, tools, total, quick, extra, fourbar_lines(fourbars, cost))
    print(f"study_scaling: {total:.1f} s")


# -- JIT strategies on the largest functions ------------------------------------------------------
def _evaluator(f):
    """One call of ``f`` (any Function) on fixed random inputs, through its buffer."""
    rng = np.random.default_rng(0)
    buf, trigger = f.buffer()
    keep = []
    for i in range(f.n_in()):
        keep.append(rng.uniform(-0.5, 0.5, f.nnz_in(i)))
        buf.set_arg(i, memoryview(keep[-1]))
    for i in range(f.n_out()):
        keep.append(np.zeros(max(f.nnz_out(i), 1)))
        buf.set_res(i, memoryview(keep[-1]))
    return lambda _keep=(buf, keep): trigger()


#: a strategy's compilers are stopped after this long (s): the one-file -O1 build of the
#: 1024-link right-hand side ran past jit's own 300 s on the loaded machine
STRATEGY_TIMEOUT = 150.0


def _compile_with(f, jacobian, split, jacobian_o1, level):
    """(compiler CPU s, wall s, us per evaluation or None when stopped) of ``f`` compiled by
    ``jit`` in an empty cache with the given splitting, Jacobian threshold and
    ``KINETWORK_JIT_LEVEL`` (``optimised``: -O1 in the foreground; ``quick``: -O0, no
    background build)."""
    saved = (jit.SPLIT_STATEMENTS, jit.JACOBIAN_O1_STATEMENTS, jit.COMPILE_TIMEOUT,
             os.environ.get("KINETWORK_JIT_LEVEL"))
    jit.SPLIT_STATEMENTS, jit.JACOBIAN_O1_STATEMENTS = split, jacobian_o1
    jit.COMPILE_TIMEOUT = STRATEGY_TIMEOUT
    os.environ["KINETWORK_JIT_LEVEL"] = level
    try:
        with tempfile.TemporaryDirectory() as folder:
            os.environ["KINETWORK_CACHE"] = folder
            before = resource.getrusage(resource.RUSAGE_CHILDREN)
            start = time.perf_counter()
            try:
                g = jit.external(f, jacobian, {}, required=True)
            except kn.ModelError:           # stopped at STRATEGY_TIMEOUT
                g = None
            wall = time.perf_counter() - start
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
            # a stopped compiler's own child (cc1) is never reaped: its CPU is not known
            cpu = (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime) \
                if g is not None else float("nan")
            cost = None if g is None else \
                per_call(_evaluator(g.jacobian() if jacobian else g), batches=5) * 1e6
    finally:
        (jit.SPLIT_STATEMENTS, jit.JACOBIAN_O1_STATEMENTS, jit.COMPILE_TIMEOUT,
         level_before) = saved
        if level_before is None:
            os.environ.pop("KINETWORK_JIT_LEVEL", None)
        else:
            os.environ["KINETWORK_JIT_LEVEL"] = level_before
    return cpu, wall, cost


def strategies(quick):
    """The largest right-hand side and the largest Jacobian, each compiled three ways."""
    from scenes import fourbar_chain
    n, m = (128, 2) if quick else (1024, 8)
    never = sys.maxsize
    rhs = scenes.chain(n).compile().f_rhs
    # the partition's DAE and its Jacobian: what IDAS compiles (loops are projected by default)
    dae = fourbar_chain(m).compile(loops="partition").f_dae
    part = jit.PART_STATEMENTS
    cases = [(f"chain{n} right-hand side", rhs, False,
              [("one file, -O1", never, never, "optimised"),
               (f"parts of {part}, -O1, side by side (the optimised tier)",
                jit.SPLIT_STATEMENTS, never, "optimised"),
               (f"parts of {part}, -O0, side by side (the quick tier)", jit.SPLIT_STATEMENTS,
                never, "quick")]),
             (f"fourbar_chain{m} (partition) DAE + exact Jacobian", dae, True,
              [("one file each, -O1", never, never, "optimised"),
               ("parts, -O1, side by side", jit.SPLIT_STATEMENTS, never, "optimised"),
               ("parts, Jacobian at -O0, side by side (now)", jit.SPLIT_STATEMENTS,
                jit.JACOBIAN_O1_STATEMENTS, "optimised")])]
    rows = []
    for label, f, jacobian, ways in cases:
        size = (f.jacobian() if jacobian else f).n_instructions()
        for way, split, jac_o1, level in ways:
            cpu, wall, cost = _compile_with(f, jacobian, split, jac_o1, level)
            rows.append({"function": label, "instructions": size, "strategy": way,
                         "compiler_cpu_s": cpu, "wall_s": wall,
                         "eval_us": float("nan") if cost is None else cost})
            print(f"  {label} ({size} instructions), {way}: compiler CPU {cpu:.1f} s, wall "
                  f"{wall:.1f} s, one evaluation "
                  + (f"{cost:.1f} us" if cost else f"none: stopped at {STRATEGY_TIMEOUT:g} s"),
                  flush=True)
    # the eight-four-bar chain's first run from a cold cache, as a user meets it
    with tempfile.TemporaryDirectory() as folder:
        os.environ["KINETWORK_CACHE"] = folder
        start = time.perf_counter()
        system = fourbar_chain(m).compile(loops="partition")
        build = time.perf_counter() - start
        start = time.perf_counter()
        res = kn.simulate(system, t_end=2.0, n_points=201, method="idas", rtol=1e-6,
                          atol=1e-8)
        first = time.perf_counter() - start
        start = time.perf_counter()
        kn.simulate(system, t_end=2.0, n_points=201, method="idas", rtol=1e-6, atol=1e-8)
        warm = time.perf_counter() - start
    loops = {"model": f"fourbar_chain{m}", "build_s": build, "first_run_s": first,
             "jit_s": res.stats.get("jit_seconds", float("nan")), "warm_run_s": warm}
    print(f"  fourbar_chain{m}: build {build:.1f} s, first run {first:.1f} s "
          f"(JIT {loops['jit_s']:.1f} s), warm run {warm:.2f} s", flush=True)
    return rows, loops


def strategy_lines(rows, loops):
    if not rows:
        return []
    body = [[r["function"], r["instructions"], r["strategy"],
             f"{r['compiler_cpu_s']:.1f}" if np.isfinite(r["compiler_cpu_s"]) else "—",
             f"{r['wall_s']:.1f}", f"{r['eval_us']:.1f}" if np.isfinite(r["eval_us"]) else
             f"stopped at {STRATEGY_TIMEOUT:g} s"] for r in rows]
    return ["", "### JIT of the largest functions", "",
            f"Each compiled by `jit.external` into an empty cache on {jit._cores()} cores; wall "
            "time includes generating the C; compiler CPU is the compilers' user + system "
            "time; one evaluation through the Function's buffer (median over batches).", "",
            table(["function", "instructions", "strategy", "compiler CPU [s]", "wall [s]",
                   "one evaluation [us]"], body), "",
            f"{loops['model']} with the partition, as a user met it before loops were projected "
            f"by default, cold cache: build {loops['build_s']:.1f} s, "
            f"first run (2 s, idas, rtol 1e-6) {loops['first_run_s']:.1f} s of which JIT "
            f"{loops['jit_s']:.1f} s; the same run again {loops['warm_run_s']:.2f} s."]


# -- the eight-four-bar chain, and what -O0 costs at run time -------------------------------------
def fourbar_rows(m=8):
    """The chain of ``m`` four-bar loops in each loop formulation, as a user meets it: build,
    then a first run (2 s, default method, rtol 1e-6) from an empty cache, whose JIT time
    ``jit_seconds`` is the cold JIT of what that run compiles, then the same run again."""
    from scenes import fourbar_chain
    rows = []
    for loops in ("projected", "partition"):
        with tempfile.TemporaryDirectory() as folder:
            os.environ["KINETWORK_CACHE"] = folder
            cpu, start = time.process_time(), time.perf_counter()
            system = fourbar_chain(m).compile(loops=loops)
            build, build_cpu = time.perf_counter() - start, time.process_time() - cpu
            children, start = _children_cpu(), time.perf_counter()
            res = kn.simulate(system, t_end=2.0, n_points=201, rtol=1e-6, atol=1e-8)
            first = time.perf_counter() - start
            compilers = _children_cpu() - children
            start = time.perf_counter()
            kn.simulate(system, t_end=2.0, n_points=201, rtol=1e-6, atol=1e-8)
            again = time.perf_counter() - start
            f = system.f_rhs or system.f_dae
        rows.append({"model": f"fourbar_chain{m}", "loops": loops, "states": system.n_states,
                     "algebraic": system.n_algebraic, "instructions": f.n_instructions(),
                     "build_s": build, "build_cpu_s": build_cpu, "first_run_s": first,
                     "jit_cold_s": res.stats.get("jit_seconds", float("nan")),
                     "jit_compilers_cpu_s": compilers, "run_again_s": again,
                     "method": res.stats.get("method", "")})
        r = rows[-1]
        print(f"  fourbar_chain{m} loops={loops}: build {build:.2f} s, first run {first:.2f} s "
              f"(JIT {r['jit_cold_s']:.2f} s, compilers {compilers:.1f} s CPU), again "
              f"{again:.2f} s", flush=True)
    return rows


def o0_cost(n=256):
    """One right-hand-side evaluation of an ``n``-link chain from its optimised (-O1) and its
    quick (-O0) library (us), and each compiler's CPU time (s): what the quick tier trades."""
    system = scenes.chain(n).compile()
    p, x = system.param_vector(), np.random.default_rng(0).uniform(-0.5, 0.5, 2 * n)
    out, saved = {}, os.environ.get("KINETWORK_JIT_LEVEL")
    try:
        for label, level in (("-O1", "optimised"), ("-O0", "quick")):
            os.environ["KINETWORK_JIT_LEVEL"] = level
            with tempfile.TemporaryDirectory() as folder:
                os.environ["KINETWORK_CACHE"] = folder
                children = _children_cpu()
                f = jit.external(system.f_rhs, False, {}, required=True)
                cpu = _children_cpu() - children
                call = numeric(f, p, system.n_states)
                out[label] = (per_call(lambda: call(0.0, x)) * 1e6, cpu)
    finally:
        if saved is None:
            os.environ.pop("KINETWORK_JIT_LEVEL", None)
        else:
            os.environ["KINETWORK_JIT_LEVEL"] = saved
    print(f"  chain{n}: -O1 {out['-O1'][0]:.1f} us ({out['-O1'][1]:.1f} s CPU to compile), "
          f"-O0 {out['-O0'][0]:.1f} us ({out['-O0'][1]:.1f} s)", flush=True)
    return {"N": n, "instructions": system.f_rhs.n_instructions(), **{
        f"{k}_{what}": v[i] for k, v in out.items() for i, what in enumerate(("us", "cpu_s"))}}


def first_study(sizes=None):
    """``--first``: see ``scaling_first.py``; writes results/study_scaling_first.{csv,md}."""
    import scaling_first
    clock = time.perf_counter()
    first = scaling_first.first_answers()
    costs = {}
    for label, spec in (("3-D point-mass chain of 128 links",
                         scenes.point_mass_spec(128, planar=False)),
                        ("planar chain of 128 rods", scenes.chain_spec(128))):
        costs[label] = (f"{spec.n} links", scaling_first.evaluation_costs(spec))
        print(f"  {label}: " + ", ".join(f"{k} {v:.1f} us" for k, v in costs[label][1].items()),
              flush=True)
    long_rows = scaling_first.long_chains(tuple(sizes or (256, 512, 1024)))
    write_csv("study_scaling_first", [
        {"scene": name, "run": run, **values} for name, runs in first.items()
        for run, values in runs.items()])
    if long_rows:
        write_csv("study_scaling_long_chains", long_rows)
    text = "\n".join(["## Scaling: first answers, tiers and long chains", "",
                      f"{machine()}; {load()}. Study wall time "
                      f"{time.perf_counter() - clock:.0f} s.",
                      *scaling_first.lines(first, costs, long_rows)])
    write_markdown("study_scaling_first", text)


def integrator_setup(sizes=(64, 128, 256, 512)):
    """What CasADi's CVODES costs to set up around a chain's compiled right-hand side with the
    default method's options (Adams, functional iteration): it builds the DAE's Jacobian
    function at creation whether or not it will use it, by finite differences of the compiled
    code over a dense pattern. Before: the equations as they were handed over; now:
    ``Compiled.dae`` without Newton, its derivatives in x hidden (``stop_diff``)."""
    from kinetwork.solver.methods import METHODS
    opts = {**METHODS["cvodes-adams"].options, "reltol": 1e-7, "abstol": 1e-9}
    grid = [0.01 * k for k in range(1, 11)]
    rows = []
    for n in sizes:
        system = scenes.chain(n).compile()
        with tempfile.TemporaryDirectory() as folder:
            os.environ["KINETWORK_CACHE"] = folder
            c = compiled_of(system)
            rhs = c.rhs({"stats": {}})
            tau, x, pt = ca.MX.sym("tau"), ca.MX.sym("x", system.n_states), ca.MX.sym("p", 1)
            empty = ca.MX(0, 1)
            before = ca.Function("dae", [tau, x, ca.MX.sym("z", 0), pt, ca.MX.sym("u", 0)],
                                 [rhs(tau + pt[0], x, empty), empty, empty, empty],
                                 ca.dyn_in(), ca.dyn_out())
            row = {"N": n, "states": system.n_states}
            for label, dae in (("before", before), ("now", c.dae({"stats": {}}))):
                start = time.perf_counter()
                integ = ca.integrator("setup", "cvodes", dae, 0.0, grid, opts)
                row[f"{label}_s"] = time.perf_counter() - start
                out = np.asarray(integ(x0=system.x0, p=[0.0])["xf"])
                row[f"{label}_x"] = out
        row["same"] = float(np.max(np.abs(row.pop("before_x") - row.pop("now_x"))))
        rows.append(row)
        print(f"  chain{n}: a CVODES integrator set up in {row['before_s']:.2f} s before, "
              f"{row['now_s']:.3f} s now; largest difference of the states "
              f"{row['same']:.1e}", flush=True)
    return rows


def setup_lines(rows):
    fit = slope(rows, "before_s") if len(rows) > 1 else float("nan")
    return ["## Setting up CVODES around a large compiled right-hand side", "",
            f"{machine()}; {load()}. CasADi builds the DAE's Jacobian function when it "
            "creates a CVODES integrator, even for Adams with functional iteration (the default "
            "method), which never evaluates it: by finite differences of the compiled code over "
            "a dense pattern, a cost that grows faster than N^2 (the slope below). A run creates "
            "one integrator per "
            "length of its output-grid chunks (two or three for a plain run). Before: the "
            "equations handed over as they are; now: their derivatives in x hidden "
            "(`stop_diff`, `Compiled.dae` for a method without Newton). Both run the same "
            "0.1 s (the largest difference of the final states is given).", "",
            table(["N", "states", "set-up before [s]", "set-up now [s]",
                   "largest state difference"],
                  [[r["N"], r["states"], f"{r['before_s']:.2f}", f"{r['now_s']:.3f}",
                    f"{r['same']:.1e}"] for r in rows]), "",
            f"Log-log slope of the set-up before, from N = {FIT_FROM}: {fit:.2f}."]


def fourbar_lines(rows, cost):
    from kinetwork.graph.model import Model
    import inspect
    default = inspect.signature(Model.compile).parameters["loops"].default
    body = [[r["loops"] + (" (default)" if r["loops"] == default else ""), r["states"],
             r["algebraic"], r["instructions"], f"{r['build_s']:.2f}", f"{r['jit_cold_s']:.2f}",
             f"{r['jit_compilers_cpu_s']:.1f}", f"{r['first_run_s']:.2f}",
             f"{r['run_again_s']:.2f}"] for r in rows]
    mine = next((r for r in rows if r["loops"] == default), rows[0])
    return ["", f"### {rows[0]['model']}: a chain of eight four-bar loops", "",
            "Each formulation built, then run 2 s (default method, rtol 1e-6) from an empty "
            "cache: JIT cold is what that first run spends in `jit` (code generation and the "
            "compilers, whose CPU time is given beside it), then the same run again.", "",
            table(["loops", "states", "algebraic", "instructions (rhs or DAE)", "build [s]",
                   "JIT cold [s]", "compilers CPU [s]", "first run [s]", "run again [s]"],
                  body), "",
            f"The default formulation ({default}): cold JIT {mine['jit_cold_s']:.1f} s "
            f"(target < 5 s).", "",
            f"What the quick tier costs at run time until the optimised library is in: "
            f"the {cost['N']}-link chain's right-hand side ({cost['instructions']:,} "
            f"instructions) evaluates in {cost['-O1_us']:.1f} us at -O1 and "
            f"{cost['-O0_us']:.1f} us at -O0 ({cost['-O0_us'] / cost['-O1_us']:.1f}x), and "
            f"compiles in {cost['-O1_cpu_s']:.1f} s and {cost['-O0_cpu_s']:.1f} s of compiler "
            f"CPU ({cost['-O1_cpu_s'] / max(cost['-O0_cpu_s'], 1e-9):.1f}x)."]


def _key(tool):
    return {"pinocchio aba": "aba_us", "MuJoCo mj_forward": "mj_forward_us"}[tool]


def measure(n, tools):
    model_s, model = timed(lambda: scenes.chain(n), budget=0.3, max_repeats=7)
    # validate and assemble afresh each time: model.compile() would hand back its System
    cpu, start = time.process_time(), time.perf_counter()
    system = kn.System(model, topology=analyze(model))
    build_s, build_cpu = time.perf_counter() - start, time.process_time() - cpu
    if build_s < 1.0:                   # short: the median of repeats
        build_s, system = timed(lambda: kn.System(model, topology=analyze(model)),
                                budget=1.0, max_repeats=7)
    size = system.size()
    with tempfile.TemporaryDirectory() as folder:
        os.environ["KINETWORK_CACHE"] = folder       # jit.cache_dir() reads it on each call
        start, stats = time.perf_counter(), {}
        cpu, children = time.process_time(), _children_cpu()
        compiled = compiled_of(system).rhs({"stats": stats})
        cold = time.perf_counter() - start
        cold_cpu = time.process_time() - cpu
        cold_compilers = _children_cpu() - children
        gcc, tier = stats.get("jit_seconds", float("nan")), stats.get("jit_tier", "")
        p = system.param_vector()
        x = np.random.default_rng(0).uniform(-0.5, 0.5, 2 * n)
        c_rhs = numeric(compiled, p, system.n_states)
        # the quick tier's cost, then the background build's, once it is swapped in
        first_us = per_call(lambda: c_rhs(0.0, x)) * 1e6
        children, start = _children_cpu(), time.perf_counter()
        swapped = jit.wait()
        assert set(swapped.values()) <= {"optimised"}, swapped
        optimise_wait, optimise_cpu = time.perf_counter() - start, _children_cpu() - children
        again, stats = scenes.chain(n).compile(), {}       # a new model: a new System
        compiled_of(again).rhs({"stats": stats})
        assert stats.get("jit_cached"), "a new System missed the cache"
        # what that call did, repeated for a median: hash the serialisation, load the library
        warm, _ = timed(lambda: jit.external(again.f_rhs, False, {}), budget=0.3)
        third = scenes.chain(n).compile()
        start = time.perf_counter()
        kn.simulate(third, t_end=1.0, n_points=101)
        cached_run = time.perf_counter() - start
        vm_rhs = numeric(system.f_rhs, p, system.n_states)
        assert np.allclose(c_rhs(0.0, x), vm_rhs(0.0, x), rtol=1e-10, atol=1e-10)
        # the same call path around a Function that does nothing but copy x: the overhead
        t_, x_, p_ = (ca.SX.sym(name, system.f_rhs.size1_in(i))
                      for i, name in enumerate("txp"))
        empty = numeric(ca.Function("copy", [t_, x_, p_], [x_]), p, system.n_states)
        row = {"N": n, "states": size["states"], "operations": size["operations"],
               "tier": tier, "rhs_first_us": first_us, "optimise_wait_s": optimise_wait,
               "optimise_compilers_cpu_s": optimise_cpu, "model_s": model_s, "build_s": build_s, "jit_cold_s": cold,
               "jit_cold_compiler_s": gcc, "jit_warm_s": warm, "cached_run_s": cached_run,
               "build_cpu_s": build_cpu, "jit_cold_cpu_s": cold_cpu,
               "jit_cold_compilers_cpu_s": cold_compilers,
               "rhs_c_us": per_call(lambda: c_rhs(0.0, x)) * 1e6,
               "call_overhead_us": per_call(lambda: empty(0.0, x)) * 1e6,
               "rhs_vm_us": per_call(lambda: vm_rhs(0.0, x)) * 1e6}
    row["peak_rss_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    # the peers in a child process, so that their memory is not the study's peak
    with multiprocessing.get_context("fork").Pool(1) as pool:
        row.update(pool.apply(_peer_times, (n, list(tools))))
    return row


#: pinocchio's Data holds nv^3 tensors of second-order derivatives (the process grew by 1.2 GB
#: at 256 links, 8.6 GB at 512: N^3; the study's 24 GB at 1024 before it measured the peers
#: apart): not above this N
PEER_MAX_N = {"pinocchio aba": 256}


def _peer_times(n, names):
    """{row key: us per evaluation} of the peers ``names`` on the ``n``-link chain."""
    tools, spec, out = peers(), scenes.chain_spec(n), {}
    for tool in names:
        build, evaluator = tools[tool]
        if n > PEER_MAX_N.get(tool, n):
            print(f"  {tool} at N = {n}: not measured (memory, see PEER_MAX_N)", flush=True)
            out[_key(tool)] = float("nan")
            continue
        try:
            out[_key(tool)] = per_call(evaluator(build(spec))) * 1e6
        except ValueError as exc:       # MuJoCo's XML parser nests at most ~500 bodies
            print(f"  {tool} at N = {n}: {str(exc).strip().splitlines()[-1]}", flush=True)
            out[_key(tool)] = float("nan")
    return out


def _children_cpu():
    """User + system CPU time of the finished child processes (the compilers)."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def slope(rows, key):
    pick = [r for r in rows if r["N"] >= FIT_FROM and np.isfinite(r[key])]
    if len(pick) < 2:
        return float("nan")
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
                                                 style=dict(color="C3", linestyle="--")),
             "build + JIT cold (target < 30 s at N = 1024)": dict(
                 x=N, y=[r["build_s"] + r["jit_cold_s"] for r in rows],
                 style=dict(color="k", linestyle=":"))}
    chart(RESULTS / "study_scaling_build.png", build, "links N", "wall time [s]",
          "Chain of N rods: build and JIT compilation time\n(build and cache hit: medians "
          "of repeats; cold compile: one run)")


def report(rows, fits, tools, total, quick, extra=None, loops=()):
    last = rows[-1]
    body = [[r["N"], r["states"], r["operations"], r["tier"], f"{r['model_s'] * 1e3:.1f}",
             f"{r['build_s'] * 1e3:.1f}", f"{r['jit_cold_s']:.2f}",
             f"{r['jit_warm_s'] * 1e3:.1f}", f"{r['build_s'] + r['jit_cold_s']:.2f}",
             f"{r['build_cpu_s']:.2f} + {r['jit_cold_cpu_s']:.2f} + "
             f"{r['jit_cold_compilers_cpu_s']:.2f}",
             f"{r['cached_run_s']:.2f}", f"{r['peak_rss_mb']:.0f}",
             f"{r['rhs_first_us']:.2f}" if r["tier"] == "quick" else "",
             f"{r['optimise_compilers_cpu_s']:.1f}" if r["tier"] == "quick" else "",
             f"{r['rhs_c_us']:.2f}", f"{r['rhs_vm_us']:.1f}",
             *(f"{r[_key(t)]:.2f}" for t in tools)] for r in rows]
    header = ["N", "states", "rhs operations", "first tier", "model [ms]", "build [ms]",
              "JIT cold [s]", "JIT hit [ms]", "build + JIT cold [s]",
              "CPU: build + JIT (Python) + compilers [s]", "cached run 1 s [s]", "peak RSS [MB]",
              "rhs C quick [us]", "optimised build CPU [s]", "rhs C [us]", "rhs VM [us]",
              *(f"{t} [us]" for t in tools)]
    lines = [f"## Scaling: chains of N rods{' (quick smoke run)' if quick else ''}", "",
             f"{machine()}; {load()}. Build: median of repeated `model.compile()` "
             f"(validate, assemble, "
             f"CasADi Functions; no C). JIT cold: `compiled(system).rhs(jit)` with an empty "
             f"cache folder (code generation + gcc for the first tier: -O1 up to "
             f"{jit.QUICK_STATEMENTS:,} statements, else the quick tier, -O0, while the "
             f"optimised one is built in the background; functions over "
             f"{jit.SPLIT_STATEMENTS:,} statements in parts side by side). rhs C quick: one "
             f"evaluation from the quick library; optimised build CPU: the background "
             f"compilers' CPU time, waited for; rhs C: one evaluation once the optimised code "
             f"is swapped in. JIT hit: what the "
             f"same call does for a new System of the same model (hashing the Function's "
             f"serialisation, then loading the cached library), median of repeats. Cached run: "
             f"a third System of the same model simulated 1 s (101 points, default method), "
             f"JIT from the cache. Peak RSS: the study process's, after that N. CPU: the "
             f"process's CPU time for one build and for the cold JIT (code generation), and the "
             f"compilers' (children's) CPU time: on a shared machine whose load average is over "
             f"its core count, wall times stretch and these say what the work itself costs. "
             f"Per-evaluation times from Python, CPU time, "
             f"median over batches of calls (wall times are the others' too when the load "
             f"average is over the core count). "
             f"Study wall time {total:.0f} s.", "",
             table(header, body), "",
             *(strategy_lines(*extra) + [""] if extra else
               ["JIT of the largest functions, one file against parts, -O1 against -O0: "
                "[study_scaling_jit.md](study_scaling_jit.md) (`--strategies`).", ""]),
             *loops, "",
             "First answers of a 3-D 128-link point-mass chain, EngineV6 and 1024 rods, cold "
             "and cached; evaluation costs once optimised against the hand route and "
             "pinocchio; long point-mass chains against pinocchio: "
             "[study_scaling_first.md](study_scaling_first.md) (`--first`).", "",
             f"Log-log slopes from N = {FIT_FROM} to {last['N']}:", "",
             table(["quantity", "exponent"], [[k, f"{v:.2f}"] for k, v in fits.items()]), "",
             "![evaluation cost](study_scaling.png)", "",
             "![build and JIT time](study_scaling_build.png)", "", "### Findings", "",
             f"- Right-hand-side cost grows as N^{fits['rhs compiled C']:.2f} compiled "
             f"(N^{fits['rhs compiled C, call overhead taken off']:.2f} once the "
             f"{last['call_overhead_us']:.1f} us of the Python call is taken off), "
             f"N^{fits['rhs CasADi VM']:.2f} in CasADi's VM, operations "
             f"N^{fits['operations']:.2f}; target exponent ≤ 1.2. At N = {last['N']}: "
             f"{last['rhs_c_us']:.1f} us compiled (-O1; {last['rhs_first_us']:.1f} us from the "
             f"quick tier first), {last['rhs_vm_us']:.0f} us "
             f"in the VM" + "".join(f", {last[_key(t)]:.1f} us {t}" for t in tools
                                    if np.isfinite(last[_key(t)])) + ".",
             f"- Build at N = {last['N']}: {last['build_s']:.2f} s ({last['build_cpu_s']:.1f} s "
             f"of CPU)" + "".join(f"; at N = 128: {r['build_s']:.2f} s ({r['build_cpu_s']:.2f} s "
                                  f"of CPU; target < 1 s)" for r in rows if r["N"] == 128)
             + f"; exponent {fits['build']:.2f}; constructing the model itself (adding and "
             f"connecting {3 * last['N'] + 1} components): {last['model_s'] * 1e3:.0f} ms, "
             f"exponent {fits['model construction']:.2f}.",
             f"- JIT at N = {last['N']}: {last['jit_cold_s']:.2f} s cold "
             f"({last['jit_cold_compiler_s']:.2f} s of it in jit: code generation and the "
             f"compilers), "
             f"{last['jit_warm_s'] * 1e3:.0f} ms on a cache hit "
             f"({last['jit_warm_s'] / last['build_s'] * 100:.0f} % of the build): the "
             f"serialisation and its hash, no C generated.",
             f"- Build + cold JIT at N = {last['N']}: "
             f"{last['build_s'] + last['jit_cold_s']:.1f} s wall (target < 30 s); CPU "
             f"{last['build_cpu_s'] + last['jit_cold_cpu_s']:.1f} s in Python and "
             f"{last['jit_cold_compilers_cpu_s']:.1f} s in the compilers, which run "
             f"{jit._cores()} at a time; a cached run of "
             f"1 s {last['cached_run_s']:.1f} s; peak memory {last['peak_rss_mb']:.0f} MB.",
             "- Memory: the study process's peak is kinetwork's alone since the peers run in a "
             "child process: pinocchio's Data holds nv^3 tensors of second-order derivatives "
             "(1.2 GB at 256 links, 8.6 GB at 512), which were the 24 GB at which the 1024-link "
             "row was killed before; pinocchio is measured up to "
             f"{PEER_MAX_N['pinocchio aba']} links, MuJoCo's XML up to ~500 nested bodies.",
             "- The CVODES set-up that a run pays per chunk length (it built the DAE's Jacobian "
             "function, N^2.5, for Adams that never uses it; 24 s at 1024 links, 0.04 s now): "
             "[study_scaling_setup.md](study_scaling_setup.md) (`--setup`)."]
    write_markdown("study_scaling", "\n".join(lines))


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="smoke test: N = 2, 8, 16")
    parser.add_argument("--strategies", action="store_true",
                        help="only the JIT strategies on the largest functions "
                             "(results/study_scaling_jit.md)")
    parser.add_argument("--sizes", type=int, nargs="+", help="these N only")
    parser.add_argument("--first", action="store_true",
                        help="only the first answers (3-D 128-link point-mass chain, EngineV6, "
                             "1024 rods), evaluation costs once optimised against the hand "
                             "route and pinocchio, and long point-mass chains "
                             "(results/study_scaling_first.md)")
    parser.add_argument("--setup", action="store_true",
                        help="only what CVODES costs to set up around chains of --sizes "
                             "(results/study_scaling_setup.md)")
    args = parser.parse_args()
    if args.first:
        first_study(args.sizes)
    elif args.setup:
        found = integrator_setup(args.sizes or (64, 128, 256, 512))
        write_csv("study_scaling_setup", found)
        write_markdown("study_scaling_setup", "\n".join(setup_lines(found)))
    else:
        main(args.quick, args.strategies, args.sizes)
