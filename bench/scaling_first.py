"""The scaling study's first answers, evaluation costs once optimised, and long point-mass
chains (``study_scaling.py --first``).

First answers: each scene in a process of its own, from an empty JIT cache (cold), then
again in a second process with the cache as the first left it (cached): import, build
(``model.compile()``) and the first ``kn.simulate`` of the scene's run, wall time and the
process's CPU time, and the compilers' CPU time. After its answer, the cold process waits
for the optimised library (``jit.wait``: its background build's wall and CPU time) and runs
again in the optimised code.

Evaluation costs: one right-hand-side evaluation of the same chain, from the quick library
(-O0), from the optimised one (-O1), by the hand-written CasADi ABA route
(``peers/casadi_peer.py``, gcc -O1, one file) and by pinocchio's ``aba``, in rounds
interleaved in one process, CPU time per call (the median over the rounds).

Long chains: planar point-mass chains of 256, 512 and 1024 links (a damper on each joint)
run for 1 s by ``kn.simulate`` at rtol 1e-6 and 1e-9, against pinocchio + DOP853 at rtol
1e-12 (256, 512: pinocchio's Data holds nv^3 tensors, 8.6 GB at 512, 69 GB at 1024) and the
hand-written ABA in CasADi's virtual machine + DOP853 at rtol 1e-12 (every N): the largest
joint-angle difference at the end.
"""

import json
import multiprocessing
import os
import statistics
import subprocess
import sys
import tempfile
import textwrap
import time

import casadi as ca
import numpy as np

from common import load
from scenes import chains
import kinetwork as kn
from kinetwork.solver import jit
from kinetwork.solver.compiled import compiled as compiled_of, numeric

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
#: scene -> (the Python that makes its model, the run's settings)
SCENES = {
    "3-D point-mass chain, 128 links": (
        "from scenes import chains; model = chains.point_masses(128, planar=False)", {}),
    "EngineV6 (6 loops, subsystems), MSL's 1.01 s": (
        "model = kn.load('models/engine_v6/EngineV6.json')", {}),
    "chain of 1024 rods, 1 s": (
        "from scenes import chains; model = chains.chain(1024)",
        {"t_end": 1.0, "n_points": 101}),
}
#: one process's first answer of a scene (its JSON on the last line of its output)
PROCESS = textwrap.dedent("""
    import json, os, resource, sys, time
    sys.path.insert(0, "tests")
    def cpu():
        return time.process_time()
    def children():
        u = resource.getrusage(resource.RUSAGE_CHILDREN)
        return u.ru_utime + u.ru_stime
    w0, c0 = time.perf_counter(), cpu()
    import kinetwork as kn
    from kinetwork.solver import jit
    {make}
    system = model.compile()
    w1, c1 = time.perf_counter(), cpu()
    res = kn.simulate(system, **{settings})
    w2, c2, k2 = time.perf_counter(), cpu(), children()
    out = dict(build_wall=w1 - w0, build_cpu=c1 - c0, run_wall=w2 - w1, run_cpu=c2 - c1,
               first_wall=w2 - w0, first_cpu=c2 - c0, compilers_cpu=k2,
               tier=res.stats.get("jit_tier"), steps=res.stats.get("steps"),
               operations=system.size()["operations"], load=os.getloadavg()[0])
    if {wait}:
        w3 = time.perf_counter()
        out["swapped"] = sorted(set(jit.wait().values()))
        out["optimise_wall"], out["optimise_cpu"] = time.perf_counter() - w3, children() - k2
        w4, c4 = time.perf_counter(), cpu()
        kn.simulate(system, **{settings})
        out["again_wall"], out["again_cpu"] = time.perf_counter() - w4, cpu() - c4
    print(json.dumps(out))
""")


def first_answers(scenes=SCENES):
    """{scene: {"cold": ..., "cached": ...}}, each scene in fresh processes on one cache."""
    # kinetwork's bytecode current, as an installed package has it (a source tree run under
    # PYTHONDONTWRITEBYTECODE would compile its modules again in every process)
    subprocess.run([sys.executable, "-m", "compileall", "-q", "kinetwork"], cwd=REPO,
                   check=True, stdout=subprocess.DEVNULL)
    out = {}
    for name, (make, settings) in scenes.items():
        with tempfile.TemporaryDirectory() as cache:
            env = {**os.environ, "KINETWORK_CACHE": cache}
            env.pop("KINETWORK_JIT_LEVEL", None)
            runs = {}
            for label, wait in (("cold", True), ("cached", False)):
                script = PROCESS.format(make=make, settings=repr(settings), wait=wait)
                done = subprocess.run([sys.executable, "-c", script], cwd=REPO, env=env,
                                      capture_output=True, text=True, check=True)
                runs[label] = json.loads(done.stdout.strip().splitlines()[-1])
            out[name] = runs
        cold, cached = runs["cold"], runs["cached"]
        print(f"  {name}: cold first answer {cold['first_wall']:.1f} s wall, "
              f"{cold['first_cpu']:.1f} + {cold['compilers_cpu']:.1f} s CPU ({cold['tier']}); "
              f"optimised after {cold.get('optimise_wall', 0):.1f} s; cached "
              f"{cached['first_wall']:.2f} s wall, {cached['first_cpu']:.2f} s CPU; load "
              f"{cold['load']:.1f}/{cached['load']:.1f}", flush=True)
    return out


def _cpu_per_call(fn, seconds=0.05):
    """CPU seconds per call of ``fn``, over a batch of about ``seconds``."""
    fn()
    n, start = 1, time.process_time()
    while time.process_time() - start < seconds / 10:
        fn()
        n += 1
    calls = max(1, int(n * 10))
    start = time.process_time()
    for _ in range(calls):
        fn()
    return (time.process_time() - start) / calls


def evaluation_costs(spec, rounds=9):
    """{tool: us per right-hand-side evaluation (CPU time)} of the chain ``spec``, each tool's
    batches interleaved with the others' over ``rounds`` rounds."""
    from peers import casadi_peer
    n = spec.n
    x = np.random.default_rng(0).uniform(-0.5, 0.5, 2 * n)
    calls = {}
    saved = os.environ.get("KINETWORK_CACHE"), os.environ.get("KINETWORK_JIT_LEVEL")
    try:
        for level in ("quick", "optimised"):
            os.environ["KINETWORK_CACHE"] = tempfile.mkdtemp()
            os.environ["KINETWORK_JIT_LEVEL"] = level
            system, stats = chains.chain_model(spec).compile(), {}
            f = compiled_of(system).rhs({"stats": stats, "required": True})
            rhs = numeric(f, system.param_vector(), system.n_states)
            if level == "optimised" or stats["jit_tier"] == "quick":   # a small one: -O1 only
                calls[f"kinetwork {'-O0 (quick tier)' if level == 'quick' else '-O1 (optimised)'}"] \
                    = (lambda rhs=rhs: rhs(0.0, x))
    finally:
        for key, value in zip(("KINETWORK_CACHE", "KINETWORK_JIT_LEVEL"), saved):
            if value is None:
                os.environ.pop(key, None)
            else:
                os.environ[key] = value
    hand = casadi_peer.build(spec)
    xs, ts, ps = ca.MX.sym("x", 2 * n), ca.MX.sym("t"), ca.MX.sym("p", 0)
    wrapped = numeric(ca.Function("hand", [ts, xs, ps], [hand.rhs(xs)]), [], 2 * n)
    calls["hand-written CasADi ABA (gcc -O1)"] = lambda: wrapped(0.0, x)
    try:
        import pinocchio as pin
        from peers import pinocchio_peer
        built = pinocchio_peer.build(spec)
        q, v, tau = x[:n], x[n:], -spec.damping * x[n:]
        calls["pinocchio aba"] = lambda: pin.aba(built.model, built.data, q, v, tau)
    except ImportError:
        pass
    times = {name: [] for name in calls}
    for _ in range(rounds):
        for name, fn in calls.items():
            times[name].append(_cpu_per_call(fn))
    return {name: statistics.median(t) * 1e6 for name, t in times.items()}


def long_chains(sizes=(256, 512, 1024), t_end=1.0, rtols=(1e-6, 1e-9)):
    """Rows of the planar point-mass chains of ``sizes`` links, each against its references."""
    rows = []
    for n in sizes:
        spec = chains.point_mass_spec(n)
        refs = {}
        with multiprocessing.get_context("fork").Pool(1) as pool:   # their memory apart
            refs["hand ABA (VM) + DOP853"] = pool.apply(_hand_reference, (n, t_end))
        if n <= 512:
            with multiprocessing.get_context("fork").Pool(1) as pool:
                refs["pinocchio + DOP853"] = pool.apply(_pinocchio_reference, (n, t_end))
        system = chains.chain_model(spec).compile()
        for rtol in rtols:
            start, cpu = time.perf_counter(), time.process_time()
            res = kn.simulate(system, t_end=t_end, n_points=11, rtol=rtol, atol=rtol * 1e-2)
            wall, cpu = time.perf_counter() - start, time.process_time() - cpu
            q = res.states[-1, :n]
            row = {"N": n, "rtol": rtol, "wall_s": wall, "cpu_s": cpu,
                   "steps": res.stats.get("steps"), "method": res.settings["method"],
                   "load": os.getloadavg()[0]}
            for name, ref in refs.items():
                row[name] = float(np.max(np.abs(q - ref)))
            rows.append(row)
            print(f"  point masses N={n} rtol={rtol:g}: {wall:.1f} s wall, {cpu:.1f} s CPU; "
                  + ", ".join(f"{k} {row[k]:.1e} rad" for k in refs), flush=True)
        jit.wait()
    return rows


def _hand_reference(n, t_end):
    """Joint angles at ``t_end`` by the hand-written ABA (``peers/casadi_peer.aba``) in
    CasADi's virtual machine, integrated by DOP853 at rtol 1e-12."""
    from scipy.integrate import solve_ivp
    from peers import casadi_peer
    spec = chains.point_mass_spec(n)
    x = ca.SX.sym("x", 2 * n)
    q, qd = x[:n], x[n:]
    f = ca.Function("hand", [x], [ca.vertcat(qd, casadi_peer.aba(
        spec, q, qd, -ca.DM(spec.damping) * qd))])
    t_, x_, p_ = ca.SX.sym("t"), ca.SX.sym("x", 2 * n), ca.SX.sym("p", 0)
    rhs = numeric(ca.Function("rhs", [t_, x_, p_], [f(x_)]), [], 2 * n)
    sol = solve_ivp(rhs, (0.0, t_end), np.concatenate([spec.q0, spec.qd0]), method="DOP853",
                    rtol=1e-12, atol=1e-14)
    assert sol.success, sol.message
    return sol.y[:n, -1]


def _pinocchio_reference(n, t_end):
    from peers import pinocchio_peer
    built = pinocchio_peer.build(chains.point_mass_spec(n))
    q, _ = pinocchio_peer.trajectory(built, [0.0, t_end], rtol=1e-12, atol=1e-14)
    return q[-1]


def lines(first, costs, long_rows):
    """The markdown of the three parts."""
    from common import table
    out = ["", "### First answers, cold and cached", "",
           "Each scene in a fresh process (import, `model.compile()`, the first "
           "`kn.simulate`): cold from an empty JIT cache, cached in a second process after "
           "the first left its libraries (the optimised one included). CPU: the process's, "
           "then its compilers' (the quick tier's, or -O1 at once for functions up to "
           f"{jit.QUICK_STATEMENTS:,} statements). Optimised: how long after its first answer "
           "the cold process waited for the background build, and its compilers' CPU; again: "
           "the same run in that process once the optimised code is in. The load average "
           "(1 min) of each run beside it: on a shared machine wall times stretch with it.", ""]
    body = []
    for name, runs in first.items():
        c, k = runs["cold"], runs["cached"]
        body.append([name, c["operations"], c["tier"], f"{c['build_wall']:.2f}",
                     f"{c['first_wall']:.2f}", f"{c['first_cpu']:.2f} + {c['compilers_cpu']:.2f}",
                     f"{c.get('optimise_wall', float('nan')):.1f} / "
                     f"{c.get('optimise_cpu', float('nan')):.1f}",
                     f"{c.get('again_wall', float('nan')):.2f}", f"{k['first_wall']:.2f}",
                     f"{k['first_cpu']:.2f}", f"{c['load']:.1f} / {k['load']:.1f}"])
    out += [table(["scene", "rhs operations", "first tier", "cold: import + build [s]",
                   "cold: first answer [s]", "cold CPU: process + compilers [s]",
                   "optimised build: wait / CPU [s]", "run again, optimised [s]",
                   "cached: first answer [s]", "cached CPU [s]", "load cold / cached"], body)]
    for label, (spec_name, cost) in costs.items():
        hand = cost.get("hand-written CasADi ABA (gcc -O1)")
        out += ["", f"One right-hand-side evaluation, {label} ({spec_name}), CPU time per call "
                f"from Python, interleaved rounds, median; {load()}:", "",
                table(["tool", "us per evaluation", "hand route / tool"],
                      [[name, f"{us:.1f}", f"{hand / us:.2f}" if hand else ""]
                       for name, us in cost.items()])]
    if long_rows:
        refs = [k for k in long_rows[0] if "DOP853" in k]
        out += ["", "### Long planar point-mass chains against independent references", "",
                "1 s of each chain (a damper of 0.1 N m s/rad on every joint), default method; "
                "the largest joint-angle difference at the end against each reference "
                "(pinocchio up to 512 links: its Data needs 69 GB at 1024). The first rtol's "
                "run of each N pays the JIT and `auto`'s stiffness test (the eigenvalues of a "
                "2N x 2N Jacobian: most of the 1024-link run's CPU).", "",
                table(["N", "rtol", "method", "steps", "wall [s]", "CPU [s]", "load",
                       *(f"vs {k} [rad]" for k in refs)],
                      [[r["N"], f"{r['rtol']:g}", r["method"], r["steps"], f"{r['wall_s']:.1f}",
                        f"{r['cpu_s']:.1f}", f"{r['load']:.1f}",
                        *(f"{r[k]:.1e}" if k in r else "—" for k in refs)]
                       for r in long_rows])]
    return out
