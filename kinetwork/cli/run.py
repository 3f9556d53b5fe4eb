"""``kinetwork run MODEL.json``: simulate a model file and write its probe signals (CSV) and
probe plots; what a failed or stopped run computed is written all the same."""

import argparse
import contextlib
import sys
import time

import kinetwork as kn

from ..outputs import OutputRefused, StopFlag, catching_signals, check_all, model_files, plot_kind
from .common import (EXIT_SIMULATION, EXIT_USAGE, STOPPING, add_force, add_library, error,
                     listing, load_model, parameter_arg, positive, write_output)

#: seconds the outputs of a run still get to be written once it was stopped, or once its
#: time limit has passed (within "about a second" of a stop, with what was reached)
WRITE_GRACE = 0.5


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
                        help="step budget of the whole run (the variable-step methods)")
    parser.add_argument("--time-limit", type=positive(float), metavar="S",
                        help="wall-clock limit [s] of the run: C compilation, integration, "
                             "probe signals and writing the outputs (what was reached is "
                             "written)")
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
    add_force(parser)
    add_library(parser)
    return {"run": run}


def run(args):
    from ..solver.csvio import sidecar
    outputs = [("--out", args.out, "csv"), ("--plot", args.plot, plot_kind(args.plot or "")),
               ("--out's sidecar", args.out and sidecar(args.out), "meta")]
    try:                                # by name, before anything is read or run
        check_all(outputs, [("the model file", args.model)], args.force)
    except OutputRefused as exc:
        error(f"{exc}: nothing was run")
        return EXIT_USAGE
    model = load_model(args.model, args.library)
    try:                                # nor the definition files the model places
        check_all(outputs, model_files(model), args.force)
    except OutputRefused as exc:
        error(f"{exc}: nothing was run")
        return EXIT_USAGE
    if args.plot:
        from ..plot import check_plot_path
        check_plot_path(args.plot)
    # a subsystem's value by path ("cyl1.phi0") is a constant of its instance: set on the
    # model before it is compiled; model parameters go to the integrator
    from ..graph.settings import check_output, check_settings
    from ..solver.driver import DEFAULTS, output_values

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
    problem = check_output(settings["n_points"], output_values(system),
                           3 if args.error_estimate else 1)
    if problem:
        raise kn.ModelError(problem)
    # the limit counts from the run (its C compilation included) to the last output written
    deadline = None if args.time_limit is None else time.monotonic() + args.time_limit
    try:
        with _progress_bar(args, model, 0.0, settings["t_end"]) as progress:
            results = kn.simulate(system, t_end=args.t_end, n_points=args.n_points,
                                  method=args.method, rtol=args.rtol, atol=args.atol,
                                  step=args.step, max_step=args.max_step, jit=args.jit,
                                  params=params,
                                  max_steps=args.max_steps, time_limit=args.time_limit,
                                  progress=progress, error_estimate=args.error_estimate)
    except kn.SimulationError as exc:
        error(exc)
        stopped = exc.signal in STOPPING
        flag = None
        if exc.results is not None and len(exc.results.t):
            what = "interrupted" if stopped else "failed"
            try:
                flag = _outputs(args, exc.results,
                                f"{model.name} ({what} at t = {exc.t_reached:g} s)", deadline,
                                stopped)
            except kn.ModelError as write_exc:
                error(write_exc)
        signum = exc.signal if stopped else getattr(flag, "signum", None)
        return 128 + int(signum) if signum else EXIT_SIMULATION
    done = time.perf_counter()
    if not args.quiet:
        _summary(args, model, system, results, start, compiled, done)
    flag = _outputs(args, results, model.name, deadline)
    if flag.cut is not None:            # the run is whole; its outputs were cut short
        error(f"{flag.cut} while the outputs were written"
              + (": the CSV ends with a line saying where" if args.out else ""))
    if flag.signum is not None:
        return 128 + int(flag.signum)
    return EXIT_SIMULATION if flag.cut is not None else 0


def _summary(args, model, system, results, start, compiled, done):
    """What ``run`` prints about a finished run (not with --quiet)."""
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


def _outputs(args, results, title, deadline=None, stopped=False):
    """Write the CSV and the plots of ``results``; returns the ``StopFlag`` that says why
    writing stopped early (a signal, the time limit), if it did.

    The time limit covers writing too; once it has passed, or after the run was ``stopped``
    (a signal), the outputs get WRITE_GRACE seconds more. The CSV stops between blocks of
    rows, keeping the rows written, its sidecar saying where; a plot is drawn whole or
    not at all."""
    quiet = getattr(args, "quiet", False)
    now = time.monotonic()
    if stopped:
        flag = StopFlag(deadline=now + WRITE_GRACE,
                        late=f"the run was stopped, and writing gets {WRITE_GRACE:g} s")
    else:
        flag = StopFlag(deadline=None if deadline is None else
                        max(deadline, now + WRITE_GRACE))
    flag.cut = None                     # why an output was cut short or not drawn
    with catching_signals(flag):
        if args.out:
            why = write_output(args.out, lambda path: results.to_csv(
                path, overwrite=args.force, stop=flag))
            flag.cut = why
            if not quiet:
                rows = f"{len(results.t)} points" if why is None else \
                    f"the first rows ({why}: cut short, said in its sidecar)"
                print(f"wrote {rows} x {len(results.column_names())} columns to {args.out}")
        if args.plot:
            why = flag()
            if why is not None:
                flag.cut = why
                error(f"--plot {args.plot} not drawn: {why}")
            else:
                write_output(args.plot, lambda path: _save_plot(args, results, path, title))
                if not quiet:
                    print(f"wrote probe plots to {args.plot}")
    return flag


def _save_plot(args, results, path, title):
    """The probe plots into ``path``: a PNG drawn here with Pillow when the light renderer
    draws what it holds (no matplotlib to import: the quick first answer), else matplotlib's
    ``save_plot``, in the drawing process forked for other formats when there is one."""
    from .. import quickplot
    names, hide_flat = args.plot_signals, args.hide_flat
    if quickplot.drawable(path, results, names):
        return quickplot.save_png(results, path, *names, title=title, hide_flat=hide_flat,
                                  overwrite=args.force)
    from ..plot import save_plot
    worker = getattr(args, "plot_worker", None)
    draw = save_plot if worker is None else worker.save     # the same call, elsewhere
    return draw(results, path, *names, title=title, hide_flat=hide_flat,
                overwrite=args.force)


@contextlib.contextmanager
def _progress_bar(args, model, t_start, t_end):
    """A tqdm bar on stderr while the run goes (``solver.progress``), or None."""
    show = args.progress if args.progress is not None else \
        (not args.quiet and sys.stderr.isatty())
    if not show:
        yield None
        return
    from ..solver.progress import progress_bar
    with progress_bar(t_start, t_end, desc=model.name) as report:
        yield report
