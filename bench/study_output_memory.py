"""Memory of long output grids against the estimate that bounds them (issue 26).

``simulate`` refuses, before building anything, a run whose results would pass 2 GiB:
``graph.settings.check_output`` estimates 8 bytes per value (time, states, probe signals) and
POINT_OVERHEAD bytes per output time for the integrator's copies of the grid. This study runs
the seed's double pendulum (13 values per point) at growing grids, each in a fresh process,
and measures the peak resident memory the run adds (``ru_maxrss`` after, less before) and the
CPU time, with and without the CSV written; the ratio measured / estimated must stay below 1
for the 2 GiB cap to hold. Issue 26 measured 1e7 points at 7.9 GB before, when the check
counted 13 x 8 bytes a point (1.04 GB).

Run: ``.venv/bin/python bench/study_output_memory.py [--quick]``; writes
results/study_output_memory.md and .csv.
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile

from common import HERE, machine, table, write_csv, write_markdown

PROBE = r"""
import json, os, resource, sys, time
import kinetwork as kn
from kinetwork.graph.settings import check_output, POINT_OVERHEAD
from kinetwork.solver.driver import output_values
n, csv = int(sys.argv[1]), sys.argv[2]
model = kn.load(os.path.join(sys.argv[3], "models", "double_pendulum.json"))
system = model.compile()
kn.simulate(system, t_end=0.01, n_points=11)               # everything imported and built
before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
cpu = time.process_time()
res = kn.simulate(system, n_points=n)
run_cpu = time.process_time() - cpu
if csv != "-":
    res.to_csv(csv)
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
values = output_values(system)
print(json.dumps({"points": n, "values": values, "added": peak - before,
                  "estimate": n * (8 * values + POINT_OVERHEAD), "run_cpu": run_cpu,
                  "total_cpu": time.process_time() - cpu}))
"""


def measure(n, csv):
    with tempfile.TemporaryDirectory() as folder:
        out = os.path.join(folder, "out.csv") if csv else "-"
        env = dict(os.environ, KINETWORK_JIT="0")        # the same on any machine
        done = subprocess.run([sys.executable, "-c", PROBE, str(n), out, str(HERE.parent)],
                              capture_output=True, text=True, env=env, check=True)
        return json.loads(done.stdout.strip().splitlines()[-1])


def main(quick=False):
    sizes = [100_000, 300_000] if quick else [100_000, 1_000_000, 3_000_000, 10_000_000]
    rows = []
    for n in sizes:
        for csv in (False, True):
            if csv and n > 3_000_000:
                continue                        # minutes of formatting text: nothing new
            r = measure(n, csv)
            r.update(csv=csv, ratio=r["added"] / r["estimate"])
            rows.append(r)
            print(f"{n:>10} points{' + CSV' if csv else '      '}: {r['added'] / 2**20:8.1f} "
                  f"MiB added, estimate {r['estimate'] / 2**20:8.1f} MiB, ratio "
                  f"{r['ratio']:.2f}, {r['total_cpu']:.1f} s CPU", flush=True)
    write_csv("study_output_memory", rows)
    report(rows)


def report(rows):
    """The markdown of the study from its rows."""
    body = [[f"{int(r['points']):,}", "yes" if r["csv"] else "no",
             f"{r['added'] / 2**20:.0f}", f"{r['estimate'] / 2**20:.0f}",
             f"{r['ratio']:.2f}", f"{r['run_cpu']:.1f}", f"{r['total_cpu']:.1f}"]
            for r in rows]
    runs = sorted((r for r in rows if not r["csv"]), key=lambda r: r["points"])
    small, large = runs[0], runs[-1]
    # what a run holds whatever its grid (the integrator, the mapped functions, buffers),
    # and what each further output time adds
    per_point = (large["added"] - small["added"]) / (large["points"] - small["points"])
    fixed = small["added"] - per_point * small["points"]
    estimate = large["estimate"] / large["points"]
    write_markdown("study_output_memory", "\n".join([
        "## Memory of long output grids", "",
        f"{machine()}. The seed (13 values per output point), CasADi's virtual machine; peak "
        f"resident memory a run adds (ru_maxrss after less before, the model built and run "
        f"once before), against the estimate the 2 GiB cap is checked with (8 bytes per "
        f"value and 64 per output time).", "",
        table(["points", "CSV written", "added [MiB]", "estimate [MiB]", "measured / "
               "estimate", "run CPU [s]", "with CSV [s]"], body), "",
        f"Each output time adds {per_point:.0f} bytes ({per_point / estimate:.2f} of the "
        f"{estimate:.0f} estimated), beside {fixed / 2**20:.0f} MiB any run holds (the "
        f"integrator, the mapped functions): at the cap, {int(2**31 // estimate):,} points, "
        f"a run holds about {(fixed + per_point * (2**31 // estimate)) / 2**30:.2f} GiB. "
        f"Writing the CSV adds nothing (blocks of {4096} rows). At {int(large['points']):,} "
        f"points: {large['added'] / 2**20:.0f} MiB, where issue 26 measured 7.9 GB before "
        f"(states joined from blocks, probe signals converted from one DM, the CSV built as "
        f"one text)."]))


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    main(parser.parse_args().quick)
