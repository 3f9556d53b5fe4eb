"""Seed scene: 10 s of the double pendulum at rtol 1e-8, every method, and `kinetwork run`.

Times are medians of repeated runs in this process; accuracy is the max angle error against
the paper's closed form integrated independently (numpy + DOP853 at rtol 1e-13).
Writes bench/results/seed_scene.md and .csv.
"""

import csv
import pathlib
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

import common  # noqa: F401  (puts tests/ on the path, for the scenes)
import kinetwork as kn
from kinetwork.graph.topology import analyze
from scenes.reference import seed_reference

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parent
MODEL = ROOT / "models" / "double_pendulum.json"
RTOL, ATOL = 1e-8, 1e-10


def median_time(fn, repeats):
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def main():
    model = kn.load(MODEL)
    # validate and assemble afresh each time: model.compile() hands back the System it built
    build = median_time(lambda: kn.System(model, topology=analyze(model)), 5)
    system = model.compile()
    rows = []
    ref = None
    for method in kn.METHODS:
        first_start = time.perf_counter()
        res = kn.simulate(system, t_end=10.0, n_points=1001, method=method, rtol=RTOL, atol=ATOL)
        first = time.perf_counter() - first_start
        if ref is None:
            ref = seed_reference(res.t)
        err = np.max(np.abs(res.states[:, :2] - ref[:, :2]))
        repeats = 20 if method in ("cvodes", "idas") else 3
        t = median_time(lambda: kn.simulate(system, t_end=10.0, n_points=1001, method=method,
                                            rtol=RTOL, atol=ATOL), repeats)
        rows.append((method, t, first, err))
        print(f"{method:8s} {t * 1e3:8.2f} ms (first call {first * 1e3:7.2f} ms)  "
              f"max angle error {err:.2e}")
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [sys.executable, "-m", "kinetwork.cli", "run", str(MODEL),
               "--out", f"{tmp}/out.csv", "--plot", f"{tmp}/out.png"]
        run = median_time(lambda: subprocess.run(cmd, check=True, capture_output=True), 3)
    print(f"kinetwork run (load, compile, simulate, CSV, plot): {run:.2f} s")
    print(f"build (validate + assemble + compile): {build * 1e3:.1f} ms")

    out = HERE / "results"
    out.mkdir(exist_ok=True)
    with open(out / "seed_scene.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["method", "median_s", "first_call_s", "max_angle_error"])
        w.writerows(rows)
    lines = ["# Seed scene: double pendulum, 10 s, rtol 1e-8, atol 1e-10", "",
             f"Machine: {_cpu()}; median of repeated runs in one process.", "",
             "| method | integration + probes (ms) | first call (ms) | max angle error |",
             "| --- | ---: | ---: | ---: |"]
    lines += [f"| {m} | {t * 1e3:.2f} | {f * 1e3:.2f} | {e:.1e} |" for m, t, f, e in rows]
    lines += ["", f"- Build (validate + assemble + compile): {build * 1e3:.1f} ms",
              f"- `kinetwork run models/double_pendulum.json --out --plot` wall time: "
              f"{run:.2f} s (target < 1 s, issue 18)",
              "- Error reference: the paper's closed-form M, V, G in numpy, DOP853 at rtol 1e-13."]
    (out / "seed_scene.md").write_text("\n".join(lines) + "\n")


def _cpu():
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return "unknown CPU"


if __name__ == "__main__":
    sys.path.insert(0, str(HERE))
    main()
