"""The peers agree with kinetwork, and what each costs on chain16.

1. Agreement: on seed, chain2, chain8, spatial6 and spatial2, each peer at its tightest
   setting against kinetwork (DOP853, rtol 1e-12, atol 1e-14), max joint-angle error over
   10 s. Next to it, each side's own integration error, estimated against a tighter run of
   itself, so that a disagreement larger than both is a modelling difference, not integration
   error. The seed is also compared with the paper's closed form (``tests/scenes/reference.py``).
2. Model checks: MuJoCo's 1e-15 kg m^2 point inertia on the seed (measured with pinocchio, with
   and without it), the pinocchio and MuJoCo energy helpers on the same states, and their
   energy drift over 10 s of chain8 (undamped).
3. chain16: per right-hand-side cost, and the wall time of each peer's cheapest setting
   that reaches a max angle error of 1e-6 over 10 s.

    python bench/peers/check.py
"""

import pathlib
import statistics
import sys
import time

import numpy as np

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

import common  # noqa: E402, F401  (puts tests/ on the path, for the scenes)
import kinetwork as kn  # noqa: E402
from scenes import chains as scenes  # noqa: E402
from scenes.reference import seed_reference  # noqa: E402
from peers import mujoco_peer, pinocchio_peer, sympy_peer  # noqa: E402

#: name -> (kinetwork model, spec); spatial2 is there for sympy, which cannot derive spatial6
SCENES = {name: scenes.SCENES[name][:2] for name in ("seed", "chain2", "chain8", "spatial6")}
SCENES["spatial2"] = (lambda: scenes.spatial(2)), (lambda: scenes.spatial_spec(2))
#: sympy derivation timeouts [s]: generous where it is known to finish (chain8: 4 s on a quiet
#: machine), short where it is known not to (spatial6, chain16: > 10 min; sympy_growth.py)
SYMPY_TIMEOUT, SYMPY_HOPELESS = 90.0, 10.0
TARGET = 1e-6
#: (peer, its tightest setting, a tighter one to estimate the tightest one's own error)
PEERS = (
    (pinocchio_peer, pinocchio_peer.TIGHTEST, {"method": "DOP853", "rtol": 1e-13, "atol": 1e-15}),
    (mujoco_peer, mujoco_peer.TIGHTEST, {"integrator": "RK4", "timestep": 5e-5}),
    (sympy_peer, sympy_peer.TIGHTEST, {"method": "DOP853", "rtol": 1e-13, "atol": 1e-15}),
)


def kinetwork_angles(name, rtol=1e-12, atol=1e-14):
    """Times and joint angles of kinetwork's run of scene ``name``."""
    model = SCENES[name][0]() if name in SCENES else scenes.SCENES[name][0]()
    res = kn.simulate(model, t_end=10, n_points=1001, method="dop853", rtol=rtol, atol=atol)
    return res.t, scenes.joint_angles(res)


def build(peer, spec, timeout):
    """``peer.build(spec)``, with ``timeout`` for the sympy peer."""
    if peer is sympy_peer:
        return peer.build(spec, timeout=timeout)
    return peer.build(spec)


def fmt(setting):
    return " ".join(f"{k}={v}" for k, v in setting.items() if k != "atol")


def agreement():
    print("1. Max joint-angle error over 10 s against kinetwork (DOP853, rtol 1e-12, atol 1e-14)")
    print("   own error: against a tighter run of the same tool "
          "(kinetwork and scipy peers: rtol 1e-13, atol 1e-15; MuJoCo: RK4 h=5e-5)\n")
    print(f"{'scene':9s} {'tool':16s} {'setting':28s} {'vs kinetwork':>12s} {'own error':>10s}"
          f" {'wall s':>7s}")
    for name in SCENES:
        t, ref = kinetwork_angles(name)
        _, tighter = kinetwork_angles(name, 1e-13, 1e-15)
        print(f"{name:9s} {'kinetwork':16s} {'DOP853 rtol=1e-12':28s} {'':>12s} "
              f"{np.abs(ref - tighter).max():10.1e}")
        if name == "seed":
            closed = seed_reference(t)[:, :2]
            print(f"{'':9s} {'closed form':16s} {'DOP853 rtol=1e-13':28s} "
                  f"{np.abs(closed - ref).max():12.1e}")
        spec = SCENES[name][1]()
        timeout = SYMPY_HOPELESS if name == "spatial6" else SYMPY_TIMEOUT
        for peer, tightest, tighter_setting in PEERS:
            try:
                built = build(peer, spec, timeout)
            except TimeoutError:
                print(f"{'':9s} {peer.NAME:16s} derivation > {timeout:.0f} s, not run")
                continue
            start = time.perf_counter()
            q = peer.run(built, t, **tightest)
            wall = time.perf_counter() - start
            own = np.abs(q - peer.run(built, t, **tighter_setting)).max()
            print(f"{'':9s} {peer.NAME:16s} {fmt(tightest):28s} {np.abs(q - ref).max():12.1e} "
                  f"{own:10.1e} {wall:7.2f}")


def model_checks():
    print("\n2. Model checks")
    t = np.linspace(0, 10, 1001)
    spec = scenes.seed_spec()
    exact = pinocchio_peer.run(pinocchio_peer.build(spec), t, **pinocchio_peer.TIGHTEST)
    spec.inertia = np.array([mujoco_peer.POINT_INERTIA * np.eye(3)] * spec.n)
    padded = pinocchio_peer.run(pinocchio_peer.build(spec), t, **pinocchio_peer.TIGHTEST)
    print(f"   seed, point masses with MuJoCo's {mujoco_peer.POINT_INERTIA:.0e} kg m^2 inertia:"
          f" angles change by {np.abs(padded - exact).max():.1e} rad over 10 s (pinocchio)")

    rng = np.random.default_rng(0)
    for name, spec in (("seed", scenes.seed_spec()), ("chain8", scenes.chain_spec(8))):
        pb, mb = pinocchio_peer.build(spec), mujoco_peer.build(spec)
        q, qd = rng.uniform(-1, 1, (5, spec.n)), rng.uniform(-1, 1, (5, spec.n))
        gap = np.abs(pinocchio_peer.energy(pb, q, qd) - mujoco_peer.energy(mb, q, qd)).max()
        print(f"   {name}, energy helpers on 5 random states: pinocchio - MuJoCo = {gap:.1e} J")
    # chain8 is undamped: its energy is conserved
    for peer, built, setting in ((pinocchio_peer, pb, pinocchio_peer.TIGHTEST),
                                 (mujoco_peer, mb, mujoco_peer.TIGHTEST)):
        e = peer.energy(built, *peer.trajectory(built, t, **setting))
        print(f"   chain8, {peer.NAME} {fmt(setting)}: energy drift over 10 s "
              f"{np.abs(e - e[0]).max():.1e} J (E0 = {e[0]:.3f} J)")


def per_call_us(fn, number=2000, repeat=5):
    """Best of ``repeat`` mean times of ``number`` calls, microseconds."""
    best = np.inf
    for _ in range(repeat):
        start = time.perf_counter()
        for _ in range(number):
            fn()
        best = min(best, (time.perf_counter() - start) / number)
    return best * 1e6


def wall(fn, budget=0.5):
    """Result of ``fn()`` and its wall time: the median of 3 runs if one is under ``budget``."""
    start = time.perf_counter()
    result = fn()
    times = [time.perf_counter() - start]
    if times[0] < budget:
        for _ in range(2):
            start = time.perf_counter()
            fn()
            times.append(time.perf_counter() - start)
    return result, statistics.median(times)


def chain16():
    import mujoco
    import pinocchio as pin

    print(f"\n3. chain16: cost per right-hand side, and the cheapest setting of each method to "
          f"reach {TARGET:.0e} rad over 10 s")
    spec = scenes.chain_spec(16)
    start = time.perf_counter()
    pb = pinocchio_peer.build(spec)
    pin_build = time.perf_counter() - start
    start = time.perf_counter()
    mb = mujoco_peer.build(spec)
    mj_build = time.perf_counter() - start
    rng = np.random.default_rng(1)
    q, v = rng.uniform(-1, 1, spec.n), rng.uniform(-1, 1, spec.n)
    x, tau = np.concatenate([q, v]), np.zeros(spec.n)
    rhs = pinocchio_peer.rhs_function(pb)
    m, d = mb.model, mb.data
    d.qpos[:], d.qvel[:] = q, v
    calls = {"pin.aba from Python": lambda: pin.aba(pb.model, pb.data, q, v, tau),
             "pinocchio peer rhs(t, x)": lambda: rhs(0.0, x),
             "mujoco.mj_forward from Python": lambda: mujoco.mj_forward(m, d)}
    for label, fn in calls.items():
        print(f"   {label:34s} {per_call_us(fn):6.2f} us")
    for integrator in ("Euler", "RK4"):
        mujoco_peer.trajectory(mb, np.linspace(0, 0.01, 2), integrator=integrator, timestep=1e-3)
        us = per_call_us(lambda: mujoco.mj_step(m, d, 1000), number=5, repeat=3) / 1000
        print(f"   {'mj_step ' + integrator + ' (nstep=1000), per step':34s} {us:6.2f} us")
    print(f"   build: pinocchio {pin_build * 1e3:.1f} ms, MuJoCo (MJCF compile) "
          f"{mj_build * 1e3:.1f} ms")
    try:
        sympy_peer.build(spec, timeout=SYMPY_HOPELESS)
    except TimeoutError as err:
        print(f"   {err}")

    t, ref = kinetwork_angles("chain16")
    print(f"\n   {'tool':16s} {'setting':34s} {'max error':>9s} {'wall s':>7s}")
    for peer, built, key in ((pinocchio_peer, pb, "method"), (mujoco_peer, mb, "integrator")):
        groups = {}
        for setting in peer.variants():
            groups.setdefault(setting[key], []).append(setting)
        for settings in groups.values():
            print("   " + cheapest(peer, built, t, ref, settings))


def cheapest(peer, built, t, ref, settings, budget=3.0):
    """The first of ``settings`` (coarse to fine) whose error is below TARGET, as a table row.

    A fixed-step method that has not got there within ``budget`` seconds of runs is
    extrapolated from its last two steps (error ~ h^p, time ~ 1/h) instead.
    """
    spent, last = 0.0, None
    for setting in settings:
        q, seconds = wall(lambda: peer.run(built, t, **setting))
        spent += seconds * (3 if seconds < 0.5 else 1)
        err = np.abs(q - ref).max()
        if err <= TARGET:
            return f"{peer.NAME:16s} {fmt(setting):34s} {err:9.1e} {seconds:7.3f}"
        if spent > budget and last and "timestep" in setting:
            h, (h0, err0) = setting["timestep"], last
            order = np.log(err0 / err) / np.log(h0 / h)
            h_needed = h * (TARGET / err) ** (1 / order)
            return (f"{peer.NAME:16s} {fmt(setting):34s} {err:9.1e} {seconds:7.3f}  -> needs h = "
                    f"{h_needed:.1e}, ~{seconds * h / h_needed:.0f} s (order {order:.2f}, "
                    f"extrapolated)")
        last = setting.get("timestep"), err
    return (f"{peer.NAME:16s} {fmt(setting):34s} {err:9.1e} {seconds:7.3f}  "
            f"(finest setting, {TARGET:.0e} not reached)")


def main():
    start = time.perf_counter()
    agreement()
    model_checks()
    chain16()
    print(f"\ncheck.py: {time.perf_counter() - start:.0f} s")


if __name__ == "__main__":
    main()
