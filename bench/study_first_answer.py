"""The first answer: whole-process wall time of ``import kinetwork`` and ``kinetwork run``.

What a user waits for at the shell, measured as they meet it: each command is a fresh Python
process (subprocess), timed from its start to its exit, the median of repeated runs with the
caches warm (the JIT library of the model compiled, Python's bytecode written), after one
untimed run. One cold figure per model: an empty JIT cache folder (``KINETWORK_CACHE``), so
the C code is generated, compiled and loaded once.

Commands: ``python -c "import kinetwork"``; ``kinetwork run models/double_pendulum.json --out
x.csv`` with and without ``--plot x.png`` (the seed: 8 panels, 2160 x 825 px); the same for
``models/fourbar.json`` (a loop). ``kinetwork`` is run as its console script does it
(``from kinetwork.cli import main; main()``), so the command line's own process is measured.

``--baseline DIR`` times another copy of kinetwork (a source tree: its ``kinetwork`` package
is put first on ``PYTHONPATH``) side by side: the two trees alternate run by run, so both meet
the same load on this shared machine; their ratio is the figure to read, more than either time.
CPU time (user + system, the process and its children) is reported beside wall time: the
wall time of a run that draws in a second process (the baseline's) is less than its CPU time.

Bytecode: an environment with PYTHONDONTWRITEBYTECODE recompiles every module of kinetwork in
every process (0.3-0.6 s here); a user's install has its bytecode written. The study writes
it to a temporary folder (PYTHONPYCACHEPREFIX) for both trees.

Run: ``.venv/bin/python bench/study_first_answer.py [--quick] [--baseline DIR]``; writes
results/study_first_answer.csv and .md, and the seed's plot file as the command draws it
(Pillow) and as matplotlib does: results/first_answer_plot_light.png and _matplotlib.png.
"""

import argparse
import json
import os
import pathlib
import resource
import statistics
import subprocess
import sys
import tempfile
import time

from common import HERE, load, machine, table, write_csv, write_markdown

REPO = HERE.parent
CONSOLE = "import sys; from kinetwork.cli import main; sys.argv[0] = 'kinetwork'; sys.exit(main())"
MODELS = {"seed": "models/double_pendulum.json", "four-bar": "models/fourbar.json"}


def commands(out):
    """(label, argv after the interpreter) of every command timed, outputs in ``out``."""
    found = [("python -c 'import kinetwork'", ["-c", "import kinetwork"])]
    for name, model in MODELS.items():
        path = str(REPO / model)
        csv, png = str(out / f"{name}.csv"), str(out / f"{name}.png")
        found += [(f"kinetwork run {model} --out", ["-c", CONSOLE, "run", path, "--out", csv]),
                  (f"kinetwork run {model} --out --plot",
                   ["-c", CONSOLE, "run", path, "--out", csv, "--plot", png])]
    return found


def environment(tree, pycache, jit_cache):
    env = {k: v for k, v in os.environ.items()
           if k not in ("PYTHONDONTWRITEBYTECODE", "MPLBACKEND", "DISPLAY", "WAYLAND_DISPLAY")}
    env.update(PYTHONPATH=str(tree), PYTHONPYCACHEPREFIX=str(pycache),
               KINETWORK_CACHE=str(jit_cache))
    return env


#: the names of the phases of the PNG and of matplotlib's route (prefix)
PILLOW = "import Pillow (kinetwork.quickplot)"
DRAW = "plot: draw (Pillow: lines at 2x, reduced; texts)"
PNG = "plot: PNG (rows unfiltered, zlib level 1)"
MPL = "matplotlib route: "

#: the phases of ``kinetwork run --plot`` on the seed, each timed (CPU) in a fresh process, one
#: after the other as the command runs them: load, build, run, CSV, then the PNG drawn with
#: Pillow; then matplotlib's route to the same file (what the command used before, and still
#: uses for other formats), for comparison
PHASES = f"PILLOW, DRAW, PNG, MPL = {(PILLOW, DRAW, PNG, MPL)!r}\n" + """
import json, sys, time
done, clock = {}, time.process_time()
def lap(name):
    global clock
    done[name] = time.process_time() - clock
    clock = time.process_time()
import numpy; lap("import numpy")
import casadi; lap("import casadi")
import networkx; lap("import networkx")
import kinetwork as kn
from kinetwork.cli import load_model as _load
model = _load(sys.argv[1]); lap("import kinetwork's layers + load the model")
system = model.compile(); lap("build the System")
res = kn.simulate(system); lap("simulate (cached JIT library)")
res.to_csv("phases.csv"); lap("write the CSV")
from kinetwork import quickplot; lap(PILLOW)
image = quickplot.render(res, title=model.name); lap(DRAW)
open("phases.png", "wb").write(quickplot.png_bytes(image)); lap(PNG)
import matplotlib.figure, matplotlib.backends.backend_agg; lap(MPL + "import matplotlib")
from kinetwork.plot import save_plot
save_plot(res, "phases_mpl.png", title=model.name); lap(MPL + "figure, draw, PNG")
print(json.dumps(done))
"""


def phases(env, cwd, repeats):
    """CPU seconds of each phase of the seed's run with a plot (median of ``repeats``)."""
    runs = []
    for _ in range(repeats):
        done = subprocess.run([sys.executable, "-c", PHASES, str(REPO / MODELS["seed"])],
                              env=env, cwd=cwd, capture_output=True, text=True)
        if done.returncode != 0:
            sys.exit(f"phases failed:\n{done.stderr[-2000:]}")
        runs.append(json.loads(done.stdout.splitlines()[-1]))
    return {k: statistics.median(r[k] for r in runs) for k in runs[0]}


def command_path(split):
    """CPU seconds of the command's own phases: imports, load, build, run, CSV, PNG."""
    return sum(v for k, v in split.items() if not k.startswith(MPL))


def matplotlib_path(split):
    """CPU seconds of matplotlib's route from the run to the same PNG (import included)."""
    return sum(v for k, v in split.items() if k.startswith(MPL))


#: the seed's plot file both ways, side by side in results/ for the reader to compare
PICTURES = """
import sys
import kinetwork as kn
from kinetwork import quickplot
from kinetwork.cli import load_model as _load
from kinetwork.plot import save_plot
model = _load(sys.argv[1])
res = kn.simulate(model)
quickplot.save_png(res, sys.argv[2] + "_light.png", title=model.name)
save_plot(res, sys.argv[2] + "_matplotlib.png", title=model.name)
"""


def run_once(argv, env, cwd):
    """(wall s, CPU s) of one whole process; a failure stops the study with its output."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    done = subprocess.run([sys.executable, *argv], env=env, cwd=cwd, capture_output=True,
                          text=True)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        sys.exit(f"{' '.join(argv[-6:])} failed ({done.returncode}):\n{done.stderr[-2000:]}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="2 repeats instead of 5")
    parser.add_argument("--baseline", type=pathlib.Path, metavar="DIR",
                        help="another kinetwork source tree, timed side by side")
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    repeats = 2 if args.quick else args.repeats
    trees = {"this tree": REPO}
    if args.baseline:
        trees = {"baseline": args.baseline.resolve(), **trees}
    load_before = os.getloadavg()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        tmp = pathlib.Path(tmp)
        envs = {name: environment(tree, tmp / f"pyc-{k}", tmp / f"jit-{k}")
                for k, (name, tree) in enumerate(trees.items())}
        out = tmp / "out"
        out.mkdir()
        timed = {}
        for label, argv in commands(out):
            cold = {}
            for name, env in envs.items():       # cold: an empty JIT cache, bytecode written
                cold_env = dict(env, KINETWORK_CACHE=str(tmp / f"cold-{len(timed)}-{name}"))
                run_once(argv, env, out)          # bytecode and the warm JIT cache
                cold[name] = run_once(argv, cold_env, out)[0] if "run" in argv else None
            samples = {name: [] for name in envs}
            for _ in range(repeats):              # the trees alternate: the same load
                for name, env in envs.items():
                    samples[name].append(run_once(argv, env, out))
            timed[label] = samples
            for name in envs:
                walls = [w for w, _ in samples[name]]
                cpus = [c for _, c in samples[name]]
                rows.append({"command": label, "tree": name,
                             "wall_median_s": statistics.median(walls),
                             "wall_min_s": min(walls), "wall_max_s": max(walls),
                             "cpu_median_s": statistics.median(cpus),
                             "cold_jit_wall_s": cold[name], "repeats": repeats})
                print(f"{label:58s} {name:10s} wall {statistics.median(walls):6.3f} s "
                      f"(min {min(walls):.3f}, max {max(walls):.3f}), CPU "
                      f"{statistics.median(cpus):6.3f} s"
                      + (f", cold JIT {cold[name]:.2f} s" if cold[name] else ""), flush=True)
        split = phases(envs["this tree"], out, repeats)
        # the interpreter's start: the CPU of ``import kinetwork``, the first command
        start = statistics.median(c for _, c in timed[commands(out)[0][0]]["this tree"])
        subprocess.run([sys.executable, "-c", PICTURES, str(REPO / MODELS["seed"]),
                        str(HERE / "results" / "first_answer_plot")], env=envs["this tree"],
                       cwd=out, check=True)
    estimate = start + command_path(split)
    light = split[PILLOW] + split[DRAW] + split[PNG]
    seed_plot = next(label for label in timed if "double_pendulum" in label and "plot" in label)
    baseline_cpu = statistics.median(c for _, c in timed[seed_plot].get("baseline", [(0, 0)]))
    baseline_note = "" if len(trees) == 1 else (
        f" The baseline forks a drawing process that imports matplotlib while the model "
        f"runs: its CPU time, {baseline_cpu:.2f} s, is more than its wall time on an idle "
        f"machine, which the study of that commit put at about 1.6 s (the drawing process's "
        f"path).")
    write_csv("study_first_answer", rows)
    names = list(trees)
    header = ["command"] + [f"{n}: wall (s)" for n in names] + \
        ([f"ratio {names[1]} / {names[0]}"] if len(names) > 1 else []) + \
        [f"{n}: CPU (s)" for n in names] + [f"{names[-1]}: cold JIT wall (s)"]
    lines = []
    for label in timed:
        by = {r["tree"]: r for r in rows if r["command"] == label}
        walls = [by[n]["wall_median_s"] for n in names]
        cold = by[names[-1]]["cold_jit_wall_s"]
        lines.append([label] + [f"{w:.2f}" for w in walls]
                     + ([f"{walls[1] / walls[0]:.2f}"] if len(names) > 1 else [])
                     + [f"{by[n]['cpu_median_s']:.2f}" for n in names]
                     + [f"{cold:.2f}" if cold else ""])
    text = f"""# The first answer: whole-process wall times of `import kinetwork` and `kinetwork run`

Machine: {machine()}; load average {load_before[0]:.1f} (1 min) at the start, {load()}.
Each command a fresh process from this study (subprocess), median of {repeats} runs with warm
caches after one untimed run{", the trees alternating run by run" if len(names) > 1 else ""};
CPU = user + system time of the process and its children. Cold JIT: one run with an empty JIT
cache folder.{f" Baseline: `{trees['baseline']}`." if args.baseline else ""}

{table(header, lines)}

Where the time of the seed's `run --plot` goes (this tree; CPU seconds per phase, each phase
after the one before in one fresh process, median of {repeats}): the command draws the PNG
itself, with Pillow, after the run (kinetwork/quickplot.py); matplotlib's route to the same
file, timed after it in the same process, is what the command took before (and still takes
for other formats, in a drawing process forked at its start).

{table(["phase", "CPU (s)"], [[k, f"{v:.3f}"] for k, v in split.items()])}

The PNG costs {light:.2f} s of CPU with Pillow (import, drawing, file) against
{matplotlib_path(split):.2f} s with matplotlib (import, figure, drawing, file): ratio
{matplotlib_path(split) / light:.1f}.
On an idle machine the seed's `run --plot` would take about {estimate:.2f} s: the
interpreter's start ({start:.3f} s, `import kinetwork`'s CPU) and the command's path
({command_path(split):.2f} s, one process). An estimate from CPU times, which the load does
not inflate as it does wall times; measured wall times above are what this machine gave under
its load.{baseline_note}

Bytecode: measured with kinetwork's bytecode written (PYTHONPYCACHEPREFIX, for both trees), as
an installed package has it; a source tree run with PYTHONDONTWRITEBYTECODE recompiles every
module of kinetwork in every process (`python -m compileall kinetwork` once avoids that).

Targets (issue 18, item 4): `kinetwork run` of the seed with `--plot` under 1.0 s wall, and
`import kinetwork` under 0.25 s, as whole processes.
"""
    write_markdown("study_first_answer", text)


if __name__ == "__main__":
    main()
