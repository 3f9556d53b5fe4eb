"""The first answer of a model built before, with and without the derived Systems kept on disk
(``kinetwork/equations/stored.py``).

Each scene of ``scaling_first.SCENES`` (EngineV6, the 1024-rod chain; ``--all`` adds the 3-D
128-link chain) runs in fresh processes on one cache folder: first cold (an empty folder:
the System derived and kept, the C compiled; the process then waits for the optimised library,
as ``scaling_first`` does), then the cached runs, alternating ``KINETWORK_BUILD_CACHE=1``
(the System loaded) and ``=0`` (derived again, the compiled code cached: how every process
started before the System was kept), ``--repeats`` times each. Each process times import +
build (``model.compile()``, the scene's model made first: the chain's Python, EngineV6's
file) and its first ``kn.simulate``, wall and CPU, and the load average (1 min) with it; the
medians are reported, and the ratio of the two cached kinds, which met the same load.

Run: ``.venv/bin/python bench/study_build_cache.py [--repeats 3] [--all]``; writes
results/study_build_cache.csv and .md.
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

from common import HERE, machine, table, write_csv, write_markdown
import scaling_first

REPO = HERE.parent
def process(make, settings, wait):
    return scaling_first.PROCESS.format(make=make, settings=repr(settings), wait=wait)


def run(script, env):
    done = subprocess.run([sys.executable, "-c", script], cwd=REPO, env=env,
                          capture_output=True, text=True)
    if done.returncode != 0:
        sys.exit(f"a process failed:\n{done.stderr[-3000:]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def scene(name, make, settings, repeats):
    """{"cold": run, "kept": [runs], "derived": [runs]} of one scene."""
    with tempfile.TemporaryDirectory() as cache:
        env = {**os.environ, "KINETWORK_CACHE": cache, "KINETWORK_BUILD_CACHE": "1"}
        env.pop("KINETWORK_JIT_LEVEL", None)
        out = {"cold": run(process(make, settings, True), env), "kept": [], "derived": []}
        for _ in range(repeats):
            for kind, flag in (("kept", "1"), ("derived", "0")):
                out[kind].append(run(process(make, settings, False),
                                     {**env, "KINETWORK_BUILD_CACHE": flag}))
    return out


def median(runs, key):
    return statistics.median(r[key] for r in runs)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--all", action="store_true", help="the 3-D 128-link chain too")
    args = parser.parse_args()
    subprocess.run([sys.executable, "-m", "compileall", "-q", "kinetwork"], cwd=REPO,
                   check=True, stdout=subprocess.DEVNULL)
    scenes = {k: v for k, v in scaling_first.SCENES.items() if args.all or "128" not in k}
    start, rows, body = time.perf_counter(), [], []
    for name, (make, settings) in scenes.items():
        runs = scene(name, make, settings, args.repeats)
        cold = runs["cold"]
        row = {"scene": name, "operations": cold["operations"],
               "cold_build_wall": cold["build_wall"], "cold_build_cpu": cold["build_cpu"],
               "cold_first_wall": cold["first_wall"], "cold_first_cpu": cold["first_cpu"],
               "cold_load": cold["load"]}
        for kind in ("kept", "derived"):
            for key in ("build_wall", "build_cpu", "first_wall", "first_cpu", "load"):
                row[f"{kind}_{key}"] = median(runs[kind], key)
        rows.append(row)
        print(json.dumps(row), flush=True)
        body.append([name, f"{row['cold_build_wall']:.2f} / {row['cold_build_cpu']:.2f}",
                     f"{row['cold_first_wall']:.2f} / {row['cold_first_cpu']:.2f}",
                     f"{row['derived_build_wall']:.2f} / {row['derived_build_cpu']:.2f}",
                     f"{row['derived_first_wall']:.2f} / {row['derived_first_cpu']:.2f}",
                     f"{row['kept_build_wall']:.2f} / {row['kept_build_cpu']:.2f}",
                     f"{row['kept_first_wall']:.2f} / {row['kept_first_cpu']:.2f}",
                     f"{row['derived_build_cpu'] / row['kept_build_cpu']:.1f}",
                     f"{row['cold_load']:.1f} / {row['derived_load']:.1f} / "
                     f"{row['kept_load']:.1f}"])
    write_csv("study_build_cache", rows)
    load = os.getloadavg()
    text = "\n".join([
        "## The first answer of a model built before: derived Systems kept on disk", "",
        f"{machine()}; load average {load[0]:.1f} (1 min), "
        f"{load[1]:.1f} (5 min) at the end. Study wall time "
        f"{time.perf_counter() - start:.0f} s.", "",
        "Fresh processes on one cache folder per scene: cold (empty folder), then cached "
        f"runs alternating the System derived again (`KINETWORK_BUILD_CACHE=0`, the C "
        f"cached: how every process ran before Systems were kept) and the System loaded, "
        f"{args.repeats} of each, medians. Build: import + the scene's model + "
        "`model.compile()`; first answer: that and the first `kn.simulate`. Wall / CPU "
        "seconds of the process (compilers not counted); the load average (1 min) with "
        "each kind of run: on a shared machine wall times stretch with it. What is left "
        "of a loaded first answer beyond the build is the run itself (`kn.simulate`: for "
        "EngineV6 its event handling, about 340 crossings in 1.01 s).", "",
        table(["scene", "cold: build [s]", "cold: first answer [s]",
               "derived again: build [s]", "derived again: first answer [s]",
               "loaded: build [s]", "loaded: first answer [s]",
               "build CPU, derived / loaded", "load cold / derived / loaded"], body)])
    write_markdown("study_build_cache", text)


if __name__ == "__main__":
    main()
