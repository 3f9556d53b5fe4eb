"""Run every study of bench/, one after another, each in its own process; write a summary.

The studies are ``seed_scene.py`` and every ``study_*.py`` in this folder. Each one's output
goes to ``results/<study>.log``; its markdown (``results/<study>.md``, with or without the
``study_`` prefix) is gathered into ``results/summary.md`` under the machine and the times.
A study that runs past ``--timeout`` is stopped with its child processes. The exit code is
nonzero if any study failed or was stopped.

Run: ``python bench/run.py [--quick] [--timeout S] [study ...]``; ``--gather`` runs nothing and
writes the summary from every study's latest results (each says its own machine and date).
"""

import argparse
import os
import re
import signal
import subprocess
import sys
import threading
import time

from common import HERE, RESULTS, machine


def studies(only=()):
    found = ([HERE / "seed_scene.py"] if (HERE / "seed_scene.py").exists() else []) \
        + sorted(HERE.glob("study_*.py"))
    return [p for p in found if not only or p.stem in only or
            p.stem.removeprefix("study_") in only]


def run_study(path, quick, timeout):
    """(status, seconds) of one study; its output is echoed indented and kept in
    ``results/<stem>.log``."""
    cmd = [sys.executable, str(path)] + (["--quick"] if quick else [])
    start = time.perf_counter()
    with open(RESULTS / f"{path.stem}.log", "w") as log:
        # a session of its own, so that a timeout stops the study's children too
        proc = subprocess.Popen(cmd, cwd=HERE.parent, stdout=subprocess.PIPE,
                                stderr=subprocess.STDOUT, text=True, start_new_session=True)
        echo = threading.Thread(target=_echo, args=(proc.stdout, log), daemon=True)
        echo.start()
        try:
            code = proc.wait(timeout=timeout)
            status = "ok" if code == 0 else f"failed (exit code {code})"
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGTERM)
            try:
                proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                os.killpg(proc.pid, signal.SIGKILL)
                proc.wait()
            status = f"stopped after the {timeout:g} s timeout"
        echo.join(timeout=5)
    return status, time.perf_counter() - start


def _echo(stream, log):
    for line in stream:
        log.write(line)
        print("    " + line, end="", flush=True)


def markdown_of(path, since):
    """The study's markdown written after ``since`` (epoch s), or None."""
    for name in (path.stem, path.stem.removeprefix("study_")):
        md = RESULTS / f"{name}.md"
        if md.exists() and md.stat().st_mtime >= since:
            return under_title(md.read_text())
    return None


def under_title(text):
    """``text`` with its headings shifted so that the topmost is level 2 (under the title)."""
    levels = [len(h) for h in re.findall(r"^(#+) ", text, flags=re.MULTILINE)]
    shift = 2 - min(levels, default=2)
    return re.sub(r"^(#+) ", lambda m: "#" * max(1, len(m[1]) + shift) + " ", text,
                  flags=re.MULTILINE)


def gather():
    """results/summary.md from the results already there: every study's markdown files (its
    own, then the extra ones it writes, ``<stem>_*.md``), in the order ``run.py`` runs them."""
    lines = ["# kinetwork benchmarks", "",
             f"Gathered from each study's latest results on {machine()} (`bench/run.py "
             f"--gather`); every study says when and under which load it ran.", "",
             "| study | results |", "| --- | --- |"]
    sections = []
    for path in studies():
        stem = path.stem.removeprefix("study_")
        mds = sorted({*RESULTS.glob(f"{path.stem}*.md"), *RESULTS.glob(f"{stem}*.md")} -
                     {RESULTS / "summary.md"})
        if not mds:
            continue
        lines.append(f"| {path.name} | {', '.join(f'`{md.name}`' for md in mds)} |")
        sections += ["", *(under_title(md.read_text()).rstrip() for md in mds)]
    (RESULTS / "summary.md").write_text("\n".join(lines + sections) + "\n")
    print(f"summary of {len(lines) - 6} studies in {RESULTS / 'summary.md'}", flush=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true",
                        help="each study's smoke-test mode (under a minute in all)")
    parser.add_argument("--timeout", type=float, default=None,
                        help="seconds before a study is stopped (default 600, quick 120)")
    parser.add_argument("--gather", action="store_true",
                        help="run nothing: gather every study's latest results into the "
                             "summary (studies run at different times, each dated)")
    parser.add_argument("only", nargs="*", help="run only these studies (by file stem)")
    args = parser.parse_args()
    if args.gather:
        gather()
        return
    timeout = args.timeout or (120.0 if args.quick else 600.0)
    RESULTS.mkdir(exist_ok=True)
    todo = studies(args.only)
    if not todo:
        sys.exit(f"no study matches {args.only}")
    start = time.perf_counter()
    done = []
    for i, path in enumerate(todo, 1):
        print(f"[{i}/{len(todo)}] {path.name}{' --quick' if args.quick else ''} ...", flush=True)
        began = time.time()
        status, seconds = run_study(path, args.quick, timeout)
        print(f"[{i}/{len(todo)}] {path.name}: {status} in {seconds:.0f} s", flush=True)
        done.append((path, status, seconds, began))
    total = time.perf_counter() - start
    flag = " --quick" if args.quick else ""
    lines = [f"# kinetwork benchmarks{' (quick mode)' if args.quick else ''}", "",
             f"{machine()}. Total time {total:.0f} s (`bench/run.py{flag}`).", "",
             "| study | status | time (s) |", "| --- | --- | ---: |"]
    lines += [f"| {p.name} | {status} | {s:.0f} |" for p, status, s, _ in done]
    for path, status, _, began in done:
        md = markdown_of(path, began)
        lines += ["", md.rstrip() if md else f"## {path.stem}\n\nNo markdown written in "
                  f"this run ({status}); see `{path.stem}.log`."]
    (RESULTS / "summary.md").write_text("\n".join(lines) + "\n")
    failed = [p.name for p, status, _, _ in done if status != "ok"]
    print(f"{len(done) - len(failed)} of {len(done)} studies ok in {total:.0f} s; "
          f"summary in {RESULTS / 'summary.md'}", flush=True)
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
