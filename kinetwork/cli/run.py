"""``kinetwork run MODEL.json``: simulate a model file and write its probe signals (CSV) and
probe plots; what a failed or stopped run computed is written all the same."""

import argparse
import contextlib
import os
import sys
import time

import kinetwork as kn

from ..util import quote
from .common import (EXIT_SIMULATION, EXIT_USAGE, STOPPING, add_library, error, listing,
                     load_model, parameter_arg, positive, write_output)


def add(sub):
    """The ``run`` subcommand's parser; {name: handler}."""
    from ..solver.methods import METHODS
    parser = sub.add_parser(
        "run", help="simulate a model and write its probe signals",
        description="Simulate MODEL.json and write its probe signals (CSV) and probe plots. "
                    "Options not given come from the model's 'simulation' block.")
    parser.add_argument("model", metavar="MODEL.json",
                        help="model file, or the name of an example (kinetwork examples)")
    parser.add_argument("--t-end", type=float, metavar="T", help="end time [s]")
    parser.add_argument("--method", type=str.lower, choices=list(METHODS), metavar="M",
                        help=f"integrator: {', '.join(METHODS)}")
    parser.add_argument("--rtol", type=float, metavar="R", help="relative tolerance")
    parser.add_argument("--atol", type=float, metavar="A", help="absolute tolerance")
    parser.add_argument("--step", type=float, metavar="H",
                        help="largest step [s] of the fixed-step methods (rk, collocation, "
                             "midpoint; default: the output spacing)")
    parser.add_argument("--max-step", type=float, metavar="H",
                        help="largest step [s] of every method (the variable-step ones too: "
                             "an input no event announces cannot be stepped over)")
    parser.add_argument("--jit", action=argparse.BooleanOptionalAction,
                        help="compile the equations to C with the system's compiler, cached on "
                             "disk (default: when a compiler is found)")
    parser.add_argument("--n-points", type=int, metavar="N", help="points on the output grid")
    parser.add_argument("--loops", choices=["projected", "partition", "baumgarte"],
                        default="projected",
                        help="formulation of kinematic loops: projected (default: an ODE, "
                             "CVODES Adams), partition (the fewest states: a DAE for IDAS) or "
                             "baumgarte")
    parser.add_argument("--param", type=parameter_arg, action="append", default=[],
                        metavar="NAME=VALUE",
                        help="set a model parameter for this run (repeat for several), a number "
                             "in SI or with a unit (c='2 N*m/rad'); a path (cyl1.phi0) sets a "
                             "value of a subsystem")
    parser.add_argument("--error-estimate", action="store_true",
                        help="estimate each probe signal's global error (two more runs at "
                             "tighter tolerances) and show it in the summary")
    parser.add_argument("--max-steps", type=positive(int), metavar="N",
                        help="step budget per output interval of the variable-step methods")
    parser.add_argument("--time-limit", type=positive(float), metavar="S",
                        help="wall-clock limit of the integration [s]")
    parser.add_argument("--quiet", "-q", action="store_true",
                        help="print nothing but errors (on stderr)")
    parser.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                        help="a progress bar on stderr (default: when stderr is a terminal and "
                             "not --quiet)")
    parser.add_argument("--out", metavar="FILE.csv", help="write t and the probe signals as CSV")
    parser.add_argument("--plot", metavar="FILE.png",
                        help="write the probe plots (format from the extension: png, pdf, svg)")
    parser.add_argument("--plot-signals", nargs="+", default=[], metavar="NAME",
                        help="plot only these probes or signals (probe1, probe2.torque)")
    parser.add_argument("--hide-flat", action="store_true",
                        help="leave constant signals out of the plots (named under the figure)")
    add_library(parser)
    return {"run": run}


def run(args):
    clash = _clashing_paths(args)
    if clash:
        error(clash)
        return EXIT_USAGE
    model = load_model(args.model, args.library)
    if args.plot:
        from ..plot import check_plot_path
        check_plot_path(args.plot)
    # a subsystem's value by path ("cyl1.phi0") is a constant of its instance: set on the
    # model before it is compiled; model parameters go to the integrator
    from ..graph.settings import check_output, check_settings
    from ..solver.driver import DEFAULTS

    params = {}
    for name, value in args.param:
        if "." in name:
            model.set_parameter(name, value)
        else:
            params[name] = value
    given = {"t_end": args.t_end, "n_points": args.n_points, "method": args.method,
             "rtol": args.rtol, "atol": args.atol, "step": args.step,
             "max_step": args.max_step}
    settings = {**DEFAULTS, **model.simulation,
                **{k: v for k, v in given.items() if v is not None}}
    problems = check_settings(settings)     # before building anything
    if problems:
        raise kn.ModelError(problems)
    start = time.perf_counter()
    system = model.compile(loops=args.loops)
    compiled = time.perf_counter()
    n_values = 1 + system.n_states + system.n_algebraic + sum(sig.size for sig in system.signals)
    problem = check_output(settings["n_points"], n_values)
    if problem:
        raise kn.ModelError(problem)
    try:
        with _progress_bar(args, model, settings["t_end"]) as progress:
            results = kn.simulate(system, t_end=args.t_end, n_points=args.n_points,
                                  method=args.method, rtol=args.rtol, atol=args.atol,
                                  step=args.step, max_step=args.max_step, jit=args.jit,
                                  params=params,
                                  max_steps=args.max_steps, time_limit=args.time_limit,
                                  progress=progress, error_estimate=args.error_estimate)
    except kn.SimulationError as exc:
        error(exc)
        stopped = exc.signal in STOPPING
        if exc.results is not None and len(exc.results.t):
            what = "interrupted" if stopped else "failed"
            try:
                _outputs(args, exc.results, f"{model.name} ({what} at t = {exc.t_reached:g} s)")
            except kn.ModelError as write_exc:
                error(write_exc)
        return 128 + int(exc.signal) if stopped else EXIT_SIMULATION
    done = time.perf_counter()
    if args.quiet:
        _outputs(args, results, model.name)
        return 0
    t = results.t
    print(f"{model.name}: {system.n_states} states ({listing(system.state_names)})")
    if args.param:
        print("parameters set: " + ", ".join(f"{k} = {v:g}" for k, v in args.param))
    stats = results.stats
    code = ("C, cached" if stats.get("jit_cached") else
            f"C, compiled in {stats['jit_seconds']:.2g} s" if "jit_seconds" in stats else
            "C" if stats.get("jit") else "CasADi virtual machine")
    work = ", ".join([f"{stats[k]} {k.replace('_', ' ')}" for k in ("steps", "rhs_evaluations")
                      if k in stats] + [f"{n} {what}" for what, n in (
                          ("events", len(stats.get("events", ()))),
                          ("time events", stats.get("time_events", 0))) if n])
    print(f"simulated t = {t[0]:g} .. {t[-1]:g} s ({len(t)} points) with {results.method} "
          f"({code}{'; ' + work if work else ''}) in {done - compiled:.3g} s wall time "
          f"(build {compiled - start:.3g} s)")
    if "error_estimate" in stats:
        from ..solver.estimate import summary
        print("\n".join(summary(stats["error_estimate"], results.signal_names)))
    _outputs(args, results, model.name)
    return 0


def _outputs(args, results, title):
    quiet = getattr(args, "quiet", False)
    if args.out:
        write_output(args.out, results.to_csv,
               f"{len(results.t)} points x {len(results.columns()[0])} columns to", quiet)
    if args.plot:
        write_output(args.plot, lambda path: _save_plot(args, results, path, title),
               "probe plots to", quiet)


def _save_plot(args, results, path, title):
    """The probe plots into ``path``: a PNG drawn here with Pillow when the light renderer
    draws what it holds (no matplotlib to import: the quick first answer), else matplotlib's
    ``save_plot``, in the drawing process forked for other formats when there is one."""
    from .. import quickplot
    names, hide_flat = args.plot_signals, args.hide_flat
    if quickplot.drawable(path, results, names):
        return quickplot.save_png(results, path, *names, title=title, hide_flat=hide_flat)
    from ..plot import save_plot
    worker = getattr(args, "plot_worker", None)
    draw = save_plot if worker is None else worker.save     # the same call, elsewhere
    return draw(results, path, *names, title=title, hide_flat=hide_flat)


@contextlib.contextmanager
def _progress_bar(args, model, t_end):
    """A tqdm bar on stderr while the run goes, or None. It writes to a duplicate of the
    terminal's descriptor: the integrators' own output is captured meanwhile."""
    show = args.progress if args.progress is not None else \
        (not args.quiet and sys.stderr.isatty())
    if not show:
        yield None
        return
    from tqdm import tqdm
    terminal = os.fdopen(os.dup(sys.stderr.fileno()), "w")
    bar = tqdm(total=round(t_end, 9), file=terminal, unit="s", desc=f"{model.name}",
               bar_format="{desc}: {percentage:3.0f}%|{bar}| t = {n:.3g} of {total:g} s "
                          "[{elapsed}<{remaining}]", leave=False)
    try:
        yield lambda t: bar.update(max(0.0, t - bar.n))
    finally:
        bar.close()
        terminal.close()


def _clashing_paths(args):
    """Why the outputs of a run would overwrite its model or each other, or None."""
    named = [("the model file", args.model), ("--out", args.out), ("--plot", args.plot)]
    named = [(what, path) for what, path in named if path]
    for i, (what_a, a) in enumerate(named):
        for what_b, b in named[i + 1:]:
            if _same_file(a, b):
                return (f"{what_b} {quote(b)} is {what_a} {'itself' if a == b else quote(a)}"
                        f": choose another path, nothing was run")
    return None


def _same_file(a, b):
    """Whether two paths name one file: the same after links are resolved, or (existing) the
    same file by device and inode (a hard link)."""
    if os.path.realpath(a) == os.path.realpath(b):
        return True
    try:
        return os.path.samefile(a, b)
    except OSError:                 # one does not exist yet: not the same file
        return False
