"""Sweeps: runs per second of a 1000-member Monte Carlo sweep, against a Python loop of
``kn.simulate`` and MuJoCo's ``rollout`` (trajectories stepped in C threads), at equal accuracy.

Scenes: the seed (``models/double_pendulum.json`` with its own settings: 10 s, 1001 points,
rtol 1e-8, atol 1e-10, auto), shoulder spring c ~ U(0.5, 2) N m/rad and damper
d ~ U(0.2, 1.5) N m s/rad drawn; a 16-link chain (``scenes.chains.chain(16)``, 2 s, 201
points, rtol 1e-8, atol 1e-10) with gravity g ~ U(9, 10) m/s^2 drawn.

Ways to run the members:

- ``loop``: ``kn.simulate`` once per member (JIT, warm), timed over the first members;
- ``kn.sweep`` in this process with 1 and 2 worker threads (JIT, warm): each member the
  plan's own integrator with its own error control, mapped over the members of a call in
  CasADi's threads (``kinetwork/solver/batch.py``), default batch;
- ``kn.sweep`` through a Dask LocalCluster of 2 worker processes (warm: the workers have
  compiled the model once before; the cold call, cluster start and compilation included,
  is reported too);
- MuJoCo ``rollout`` with 1 and 2 threads, RK4 at the largest step (of those dividing the
  0.01 s output spacing) whose error is within the sweep's, one MjModel per member (its
  spring, damper or gravity), advanced an output interval at a time.

Error: the largest joint-angle difference on the output grid from an independent reference,
over the first ``CHECKED`` members: the closed form of the paper (numpy M, V, G, DOP853 at
rtol 1e-13) for the seed, pinocchio's ABA with DOP853 at rtol 1e-13 for the chain. Memory:
bytes of the result per member (the Dataset: every state and probe signal on the grid).

Run: ``python bench/study_sweep.py [--quick]``; writes ``results/study_sweep.md``.
"""

import argparse
import json
import statistics
import sys
import time

import mujoco
import mujoco.rollout
import numpy as np
from common import load, machine, table, write_markdown
from peers import mujoco_peer, pinocchio_peer
from scenes import chains
from scenes.reference import seed_reference

import kinetwork as kn

MEMBERS = 1000
#: the loop and the local sweeps are timed this many times, in turns; medians reported
REPEATS = 3
CHECKED = 6                 # members whose error is measured against the reference
SPACING = 0.01
#: MuJoCo's rollout is timed over this many members (it runs ~10^4 steps per member)
MUJOCO_MEMBERS = 100


def chain_with_gravity(n):
    """``chains.chain(n)`` with its gravity a model parameter g (so members can differ)."""
    data = json.loads(kn.dumps(chains.chain(n)))
    data["parameters"] = {"g": chains.G}
    for comp in data["components"]:
        if comp["type"] == "multibody.Ground":
            comp["params"]["gravity"] = [0, "-g", 0]
    return kn.loads(json.dumps(data))


def scenes(members, seed=1):
    rng = np.random.default_rng(seed)
    seed_model = kn.load(chains.SEED_FILE)
    c, d = rng.uniform(0.5, 2.0, members), rng.uniform(0.2, 1.5, members)
    g = rng.uniform(9.0, 10.0, members)
    return [
        {"name": "seed", "model": seed_model, "settings": {},
         "draws": {"c": c, "d": d}, "t_end": 10.0,
         "spec": lambda k: chains.seed_spec(c=c[k], d=d[k]),
         "reference": lambda k, t: seed_reference(t, c=c[k], d=d[k])[:, :2]},
        {"name": "chain16", "model": chain_with_gravity(16),
         "settings": {"t_end": 2.0, "n_points": 201, "rtol": 1e-8, "atol": 1e-10},
         "draws": {"g": g}, "t_end": 2.0,
         "spec": lambda k: _gravity(chains.chain_spec(16), g[k]),
         "reference": lambda k, t: pinocchio_peer.run(
             pinocchio_peer.build(_gravity(chains.chain_spec(16), g[k])), t, method="DOP853",
             rtol=1e-13, atol=1e-15)},
    ]


def _gravity(spec, g):
    spec.gravity = np.array([0.0, -g, 0.0])
    return spec


def angles(ds, k, n):
    names = [v for v in ds.data_vars if v.endswith(".q")][:n]
    return np.column_stack([ds[name].values[k] for name in names])


def errors(ds, scene, t, refs):
    n = refs[0].shape[1]
    return max(float(np.max(np.abs(angles(ds, k, n) - refs[k]))) for k in range(len(refs)))


def rollout_states(specs, t, timestep, threads, chunk=100):
    """Joint angles (members, len(t), N) from MuJoCo's rollout at RK4 ``timestep``: the whole
    horizon in one call per ``chunk`` members (rollout records every step; the grid's are
    kept)."""
    models = []
    for spec in specs:
        m = mujoco.MjModel.from_xml_string(mujoco_peer.mjcf(spec))
        m.opt.timestep = timestep
        m.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
        models.append(m)
    datas = [mujoco.MjData(models[0]) for _ in range(threads)]
    what = mujoco.mjtState.mjSTATE_FULLPHYSICS
    size = mujoco.mj_stateSize(models[0], what)
    state = np.empty((len(specs), size))
    d = mujoco.MjData(models[0])
    for k, spec in enumerate(specs):
        mujoco.mj_resetData(models[k], d)
        d.qpos[:], d.qvel[:] = spec.q0, spec.qd0
        mujoco.mj_getState(models[k], d, state[k], what)
    nq = models[0].nq
    steps = round((t[1] - t[0]) / timestep)
    nstep = steps * (len(t) - 1)
    q = np.empty((len(specs), len(t), nq))
    q[:, 0] = state[:, 1:1 + nq]
    buffer = np.empty((min(chunk, len(specs)), nstep, size))
    for a in range(0, len(specs), chunk):
        b = min(len(specs), a + chunk)
        out, _ = mujoco.rollout.rollout(models[a:b], datas, state[a:b], nstep=nstep,
                                        state=buffer[:b - a], persistent_pool=True)
        q[a:b, 1:] = out[:, steps - 1::steps, 1:1 + nq]
    return q


def mujoco_step(specs, t, refs, target):
    """The largest RK4 step dividing the output spacing whose error on the checked members
    is within ``target``: (step, error)."""
    for h in mujoco_peer.TIMESTEPS:
        if abs(SPACING / h - round(SPACING / h)) > 1e-9:
            continue
        q = rollout_states(specs[:len(refs)], t, h, 1)
        err = max(float(np.max(np.abs(q[k] - refs[k]))) for k in range(len(refs)))
        if err <= target:
            return h, err
    return None, float("nan")


def timed_once(fn):
    start = time.perf_counter()
    value = fn()
    return time.perf_counter() - start, value


def study(scene, members, quick):
    name, model = scene["name"], scene["model"]
    system = model.compile()
    settings = scene["settings"]
    draws = {k: v[:members] for k, v in scene["draws"].items()}
    t = np.linspace(0.0, scene["t_end"], round(scene["t_end"] / SPACING) + 1)
    refs = [scene["reference"](k, t) for k in range(CHECKED)]
    rows = []
    run = lambda **kw: kn.sample(system, draws, n=members, progress=False,
                                 **settings, **kw)

    # the loop (simulate per member, over the first members) and kn.sweep in threads, taken
    # in turns REPEATS times (the machine's load changes: each way sees the same), medians
    block = max(1, (40 if quick else (70 if name == "seed" else 20)))
    kn.simulate(system, **settings)                     # warm: JIT, integrators
    compile_s, _ = timed_once(lambda: kn.sample(system, {p: v[:4] for p, v in draws.items()},
                                                n=4, progress=False, workers=1, batch=64,
                                                **settings))
    batches = {w: None for w in (1, 2)}        # the default: calls of a fraction of a second
    for w, b in batches.items():
        run(workers=w, batch=b)                 # warm: the integrators are built once
    times = {"loop": [], 1: [], 2: []}
    loop_err, results = 0.0, {}
    for rep in range(REPEATS):
        start = time.perf_counter()
        for k in range(rep * block, (rep + 1) * block):
            res = kn.simulate(system, params={p: float(v[k]) for p, v in draws.items()},
                              **settings)
            if k < CHECKED:
                loop_err = max(loop_err, float(np.max(np.abs(
                    res.states[:, :refs[k].shape[1]] - refs[k]))))
        times["loop"].append((time.perf_counter() - start) / block)
        for w, b in batches.items():
            seconds, results[w] = timed_once(lambda w=w, b=b: run(workers=w, batch=b))
            times[w].append(seconds / members)
    loop_rate = 1 / statistics.median(times["loop"])
    rows.append(("Python loop of kn.simulate (JIT)", loop_rate, loop_err, None,
                 f"{REPEATS} x {block} members"))
    for w, ds in results.items():
        assert ds.attrs["failed"] == 0, ds.reason.values
        rows.append((f"kn.sweep, {w} thread{'s' * (w > 1)} (JIT)",
                     1 / statistics.median(times[w]), errors(ds, scene, t, refs),
                     ds.nbytes / members, "default batch"))
    sweep_err = errors(results[2], scene, t, refs)

    # Dask: a LocalCluster of 2 processes
    from distributed import Client, LocalCluster
    cold, ds = timed_once(lambda: _dask_cold(system, draws, members, settings))
    rows.append(("kn.sweep on a Dask LocalCluster (2 processes), cold", members / cold,
                 errors(ds, scene, t, refs), ds.nbytes / members,
                 "cluster start and compilation in the workers included"))
    with LocalCluster(n_workers=2, threads_per_worker=1, dashboard_address=":0") as cluster, \
            Client(cluster) as client:
        run(scheduler=client)                              # workers compile once
        seconds, ds = timed_once(lambda: run(scheduler=client))
    rows.append(("kn.sweep on a Dask LocalCluster (2 processes), warm", members / seconds,
                 errors(ds, scene, t, refs), ds.nbytes / members,
                 "default blocks (a task each)"))

    # MuJoCo rollout at the sweep's accuracy
    specs = [scene["spec"](k) for k in range(min(members, MUJOCO_MEMBERS))]
    h, mj_err = mujoco_step(specs, t, refs, sweep_err)
    if h is None:
        rows.append(("MuJoCo rollout RK4", float("nan"), float("nan"), None,
                     f"no step down to {mujoco_peer.TIMESTEPS[-1]:g} s reaches {sweep_err:.1e}"))
    else:
        for threads in (1, 2):
            seconds, q = timed_once(lambda n=threads: rollout_states(specs, t, h, n))
            label = f"MuJoCo rollout RK4 h = {h:g} s, {threads} thread{'s' * (threads > 1)}"
            note = (f"angles and speeds on the grid; timed over {len(specs)} members, "
                    f"MjModels built from MJCF included")
            rows.append((label, len(specs) / seconds, mj_err, q.nbytes * 2 / len(specs), note))
    return {"name": name, "rows": rows, "loop": loop_rate, "compile": compile_s,
            "members": members, "states": system.n_states}


def _dask_cold(system, draws, members, settings):
    return kn.sample(system, draws, n=members, progress=False, scheduler="local", **settings)


def section(result):
    loop = result["loop"]
    body = [(label, f"{rate:,.0f}", f"{rate / loop:.1f}x" if np.isfinite(rate) else "—",
             f"{err:.1e}" if np.isfinite(err) else "—",
             f"{mem / 1024:.0f} KiB" if mem else "—", note)
            for label, rate, err, mem, note in result["rows"]]
    return (f"## {result['name']} ({result['states']} states, {result['members']} members)\n\n"
            + table(["way", "runs/s", "vs loop", "max error [rad]", "memory/member", "note"],
                    body)
            + f"\n\nFirst sweep of this model after its first run (4 members: the "
              f"integrators and the mapped output function built): "
              f"{result['compile']:.1f} s.\n")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="100 members, the seed only")
    args = parser.parse_args()
    members = 100 if args.quick else MEMBERS
    head = (f"# Sweeps: runs per second\n\n{machine()}. {members} members drawn per scene; "
            f"the loop and the local sweeps timed {REPEATS} times in turns (medians), the "
            f"others once; see bench/sweep.py for what each way runs.\n")
    out = [head]
    for scene in scenes(members)[:1 if args.quick else None]:
        start = time.perf_counter()
        result = study(scene, members, args.quick)
        out.append(section(result))
        print(section(result), flush=True)
        print(f"  ({time.perf_counter() - start:.0f} s)", flush=True)
    out.append(f"\n{load()}.\n")
    write_markdown("study_sweep", "\n".join(out))


if __name__ == "__main__":
    sys.exit(main())
