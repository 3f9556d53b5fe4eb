"""What every study shares: timing, references, CSV and markdown output, log-log charts."""

import csv
import os
import pathlib
import platform
import statistics
import sys
import time

import numpy as np

HERE = pathlib.Path(__file__).resolve().parent
RESULTS = HERE / "results"
sys.path.insert(0, str(HERE))
# the scenes and the independent references are shared with the tests: the package
# tests/scenes (``from scenes import chains``); this is the one place bench puts it on the path
sys.path.insert(1, str(HERE.parent / "tests"))

#: 1e-3 ... 1e-12: the tolerances a variable-step method is swept over
TOLERANCES = [10.0 ** -k for k in range(3, 13)]


def timed(fn, budget=0.3, max_repeats=15):
    """(median wall time [s], last value) of ``fn()``, repeated while within ``budget`` s.

    The first call is a warm-up when it is fast (caches, page faults); a call slower than the
    budget is timed once.
    """
    start = time.perf_counter()
    value = fn()
    first = time.perf_counter() - start
    if first > budget:
        return first, value
    times = []
    while len(times) < max_repeats and sum(times) < budget:
        start = time.perf_counter()
        value = fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times), value


def max_error(q, q_ref):
    """Max absolute joint-angle difference over the run; inf if the run is short or not finite."""
    q, q_ref = np.asarray(q), np.asarray(q_ref)
    if q.shape != q_ref.shape or not np.all(np.isfinite(q)):
        return float("inf")
    return float(np.max(np.abs(q - q_ref)))


def write_csv(name, rows):
    """``rows`` (list of dicts with the same keys) to ``results/<name>.csv``; returns the path."""
    RESULTS.mkdir(exist_ok=True)
    path = RESULTS / f"{name}.csv"
    with open(path, "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    return path


def write_markdown(name, text):
    RESULTS.mkdir(exist_ok=True)
    path = RESULTS / f"{name}.md"
    path.write_text(text.rstrip() + "\n")
    return path


def table(header, rows):
    """A markdown table."""
    lines = ["| " + " | ".join(header) + " |",
             "| " + " | ".join("---" if i == 0 else "---:" for i in range(len(header))) + " |"]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(lines)


def load():
    """The machine's load while the study ran: other processes share its cores."""
    one, five, _ = os.getloadavg()
    return f"load average {one:.1f} (1 min), {five:.1f} (5 min) at the end"


def machine():
    """One line on where the numbers come from: the processor's model too (platform.processor
    is only "x86_64" on Linux): the machine the studies run on changes between rounds, and
    its speed with it (EngineV6's cached run, the same code: 1.59 s of CPU in one round, 0.59 s
    in the next)."""
    import casadi
    return (f"{platform.processor() or platform.machine()} ({_cpu_model()}), "
            f"{os.cpu_count()} cores, Python {platform.python_version()}, "
            f"CasADi {casadi.__version__}, {time.strftime('%Y-%m-%d')}")


def _cpu_model():
    """The processor's model name and family, as Linux reports it, or "model unknown"."""
    try:
        with open("/proc/cpuinfo") as f:
            info = dict(line.split(":", 1) for line in f if ":" in line)
    except OSError:
        return "model unknown"
    info = {k.strip(): v.strip() for k, v in info.items()}
    return " ".join(f"{label} {info[k]}" if label else info[k] for k, label in
                    (("model name", ""), ("cpu family", "family"), ("model", "model"))
                    if k in info) or "model unknown"


#: one look per tool family, so charts read the same everywhere
STYLE = {"kinetwork": dict(color="C0"), "pinocchio": dict(color="C1"),
         "mujoco": dict(color="C2"), "sympy": dict(color="C3")}


def chart(path, series, xlabel, ylabel, title, note=None):
    """A log-log chart, one line per series.

    ``series``: label -> dict(x=..., y=..., style=dict(...)) (matplotlib line keywords).
    """
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(8, 5.5), layout="constrained")
    for label, s in series.items():
        x, y = np.asarray(s["x"], float), np.asarray(s["y"], float)
        keep = np.isfinite(x) & np.isfinite(y) & (x > 0) & (y > 0)
        if keep.any():
            ax.loglog(x[keep], y[keep], marker="o", markersize=3.5, label=label,
                      **s.get("style", {}))
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(True, which="major", alpha=0.4)
    ax.grid(True, which="minor", alpha=0.12)
    ax.legend(fontsize=7.5, ncol=2)
    if note:
        fig.text(0.01, 0.005, note, fontsize=7, color="0.4")
    RESULTS.mkdir(exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
