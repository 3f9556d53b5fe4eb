"""The ``kinetwork`` command: run, validate and derive the equations of a model file; list
the integration methods; run the benchmark studies.

Exit codes: 0 success, 1 a refused model or an unwritable output, 2 a usage error (argparse,
or outputs that would overwrite the model or each other), 3 a failed integration (whatever
was computed before the failure is still written), 128 + the signal number when SIGINT or
SIGTERM stopped a run (130, 143; what was computed is written all the same).
"""

import argparse
import collections
import contextlib
import os
import signal
import sys
import textwrap
import time

import kinetwork as kn

from . import plotworker
from .util import finite, quote

# The rest of kinetwork (numpy, CasADi, networkx, the model layers) is imported where a
# command needs it: ``kinetwork run --plot`` forks its drawing process before that (see
# plotworker), and ``--help`` or ``--version`` answer at once.

EXIT_MODEL, EXIT_USAGE, EXIT_SIMULATION = 1, 2, 3
#: signals that stop a run with its partial results written, exiting 128 + the signal
STOPPING = (signal.SIGINT, signal.SIGTERM)
#: what ``validate`` prints of long texts and lists: a summary, not the model again
SHOWN_CHARACTERS, SHOWN_ITEMS = 500, 20


def _parameter(text):
    """argparse type of ``--param NAME=VALUE``: a number, or a number with a unit
    (``c="2 N*m/rad"``: converted and checked by the model, which knows where it is used)."""
    from .graph.quantities import is_quantity
    name, sep, value = text.partition("=")
    try:
        if not sep or not name.strip():
            raise ValueError
        number = float(value)
    except ValueError:
        if sep and name.strip() and is_quantity(value.strip()):
            return name.strip(), value.strip()
        raise argparse.ArgumentTypeError(f"expected NAME=VALUE with a number or a number "
                                         f"with a unit ('2 N*m/rad'), got "
                                         f"{quote(text)}") from None
    if not finite(number):
        raise argparse.ArgumentTypeError(f"{quote(name.strip())}: must be a finite number, "
                                         f"got {value.strip()}")
    return name.strip(), number


def _positive(kind):
    """argparse type of a finite number > 0 (``kind`` int or float)."""
    def parse(text):
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(
                f"expected {'an integer' if kind is int else 'a number'}, got "
                f"{quote(text)}") from None
        if not finite(value) or value <= 0:
            raise argparse.ArgumentTypeError(f"must be a finite number > 0, got "
                                             f"{quote(text, 40)}")
        return value
    parse.__name__ = kind.__name__       # argparse names the type in its messages
    return parse


class _HelpFormatter(argparse.HelpFormatter):
    """argparse's formatter, leaving room for the indented subcommand names.

    Before Python 3.13 argparse measures subcommands without their extra indent, which pushes
    the help of the longest one ("equations") onto its own line.
    """

    def __init__(self, prog):
        super().__init__(prog, max_help_position=30)

    def add_argument(self, action):
        super().add_argument(action)
        if action.nargs == argparse.PARSER:
            self._action_max_length += self._indent_increment


def build_parser():
    """The argument parser of the ``kinetwork`` command."""
    from .analysis import commands as analysis_commands
    from .analysis.sweep import add_command as add_sweep
    from .solver.methods import METHODS

    parser = argparse.ArgumentParser(
        prog="kinetwork",
        description="Acausal multibody models: simulate a model file, check it, or print "
                    "its equations of motion.",
        epilog="Run 'kinetwork COMMAND --help' for the options of one command. Exit codes: "
               "0 done, 1 model refused or output not writable, 2 usage error, 3 integration "
               "failed (what was computed before the failure is still written).",
        formatter_class=_HelpFormatter)
    parser.add_argument("--version", action="version", version=f"kinetwork {kn.__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    run = sub.add_parser(
        "run", help="simulate a model and write its probe signals",
        description="Simulate MODEL.json and write its probe signals (CSV) and probe plots. "
                    "Options not given come from the model's 'simulation' block.")
    run.add_argument("model", metavar="MODEL.json",
                     help="model file, or the name of an example (kinetwork examples)")
    run.add_argument("--t-end", type=float, metavar="T", help="end time [s]")
    run.add_argument("--method", type=str.lower, choices=list(METHODS), metavar="M",
                     help=f"integrator: {', '.join(METHODS)}")
    run.add_argument("--rtol", type=float, metavar="R", help="relative tolerance")
    run.add_argument("--atol", type=float, metavar="A", help="absolute tolerance")
    run.add_argument("--step", type=float, metavar="H",
                     help="largest step [s] of the fixed-step methods (rk, collocation, "
                          "midpoint; default: the output spacing)")
    run.add_argument("--jit", action=argparse.BooleanOptionalAction,
                     help="compile the equations to C with the system's compiler, cached on "
                          "disk (default: when a compiler is found)")
    run.add_argument("--n-points", type=int, metavar="N", help="points on the output grid")
    run.add_argument("--loops", choices=["projected", "partition", "baumgarte"],
                     default="projected",
                     help="formulation of kinematic loops: projected (default: an ODE, "
                          "CVODES Adams), partition (the fewest states: a DAE for IDAS) or "
                          "baumgarte")
    run.add_argument("--param", type=_parameter, action="append", default=[],
                     metavar="NAME=VALUE",
                     help="set a model parameter for this run (repeat for several), a number "
                          "in SI or with a unit (c='2 N*m/rad'); a path (cyl1.phi0) sets a "
                          "value of a subsystem")
    run.add_argument("--error-estimate", action="store_true",
                     help="estimate each probe signal's global error (two more runs at "
                          "tighter tolerances) and show it in the summary")
    run.add_argument("--max-steps", type=_positive(int), metavar="N",
                     help="step budget per output interval of the variable-step methods")
    run.add_argument("--time-limit", type=_positive(float), metavar="S",
                     help="wall-clock limit of the integration [s]")
    run.add_argument("--quiet", "-q", action="store_true",
                     help="print nothing but errors (on stderr)")
    run.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                     help="a progress bar on stderr (default: when stderr is a terminal and "
                          "not --quiet)")
    run.add_argument("--out", metavar="FILE.csv", help="write t and the probe signals as CSV")
    run.add_argument("--plot", metavar="FILE.png",
                     help="write the probe plots (format from the extension: png, pdf, svg)")
    run.add_argument("--plot-signals", nargs="+", default=[], metavar="NAME",
                     help="plot only these probes or signals (probe1, probe2.torque)")
    run.add_argument("--hide-flat", action="store_true",
                     help="leave constant signals out of the plots (named under the figure)")

    val = sub.add_parser(
        "validate", help="check a model and summarise it",
        description="Check MODEL.json and summarise it: components, connections, degrees of "
                    "freedom, loops, parameters. The equations are not built unless "
                    "--compile asks for them (states, equation size).")
    val.add_argument("model", metavar="MODEL.json", help="model file")
    val.add_argument("--compile", action="store_true",
                     help="also build the equations and summarise them: states, algebraic "
                          "variables, equation size (takes longer on large models)")
    val.add_argument("--loops", choices=["projected", "partition", "baumgarte"],
                     default="projected",
                     help="formulation of kinematic loops: projected (default: an ODE, "
                          "CVODES Adams), partition (the fewest states: a DAE for IDAS) or "
                          "baumgarte")

    sub.add_parser("schema", help="print the JSON Schema of model files",
                   description="Print the JSON Schema (draft 2020-12) of the model format, "
                               "generated from the component declarations: point an editor "
                               "at it for completion and checks.")
    cache = sub.add_parser(
        "cache", help="show or empty the cache of compiled models",
        description="Show the folder of compiled models (the JIT cache), how many libraries it "
                    "holds and their size, the most recently used first; --clear empties it "
                    "of what kinetwork wrote there.")
    cache.add_argument("--clear", action="store_true", help="remove every compiled library")
    sub.add_parser("methods", help="list the integration methods",
                   description="List the integration methods a model can be run with.")

    bench = sub.add_parser(
        "bench", help="run the speed-against-accuracy studies (from a source checkout)",
        description="Run the benchmark studies of bench/ (work-precision against pinocchio, "
                    "MuJoCo and sympy; stiffness; long runs; chaos; scaling), writing CSV, "
                    "charts and bench/results/summary.md. Needs a source checkout and the "
                    "'bench' extras.")
    bench.add_argument("--quick", action="store_true", help="a smoke test of every study")

    eqs = sub.add_parser(
        "equations", help="print the mass matrix M and force vectors V, G",
        description="Print the equations of motion M(q) qdd + V(q, qd) + G(q) = 0 of "
                    "MODEL.json in closed form, in its joint coordinates and parameters.")
    eqs.add_argument("model", metavar="MODEL.json", help="model file")
    eqs.add_argument("--format", choices=["text", "pretty", "latex"], default="text",
                     help="plain expressions, 2-D pretty print, or LaTeX (default: text)")
    eqs.add_argument("--simplify", action=argparse.BooleanOptionalAction,
                     help="simplify into the paper's form, or print the Newton-Euler "
                          "expressions as built, with shared parts named (default: simplify "
                          "when that takes seconds, not hours)")
    anim = sub.add_parser(
        "animate", help="write a 3-D animation of a model's motion",
        description="Simulate MODEL.json and write its motion as a self-contained HTML file "
                    "(three.js inlined: play, pause, scrub, speed, orbiting camera; opens "
                    "without a network), and optionally a GIF or MP4.")
    anim.add_argument("model", metavar="MODEL.json", help="model file")
    anim.add_argument("--html", metavar="FILE.html", help="the animation page")
    anim.add_argument("--gif", metavar="FILE.gif", help="also a GIF")
    anim.add_argument("--mp4", metavar="FILE.mp4", help="also an MP4 video")
    anim.add_argument("--t-end", type=float, metavar="T", help="end time [s]")
    anim.add_argument("--fps", type=_positive(int), default=30, metavar="N",
                      help="frames per second of the animation (default 30)")

    dia = sub.add_parser(
        "diagram", help="draw a model's wiring diagram as SVG",
        description="Draw MODEL.json as blocks with their ports and wires, domains coloured "
                    "as in Modelica, placed by the file's layout or an automatic layered "
                    "layout where it has none.")
    dia.add_argument("model", metavar="MODEL.json", help="model file")
    dia.add_argument("-o", "--out", metavar="FILE.svg", required=True, help="the SVG file")

    studio = sub.add_parser(
        "studio", help="open the browser studio",
        description="Start the studio on this machine (127.0.0.1, a free port, a token in the "
                    "URL) and open it in the browser: place, wire, run and watch models. "
                    "Files are read and written only inside the folder it was started in.")
    studio.add_argument("model", nargs="?", metavar="MODEL.json", help="model to open")
    studio.add_argument("--port", type=_positive(int), metavar="N",
                        help="port (default: a free one)")
    studio.add_argument("--no-browser", action="store_true",
                        help="print the address, do not open a browser")
    ex = sub.add_parser(
        "examples", help="list the example models, or copy one out",
        description="List the example models that ship with kinetwork (run one by name: "
                    "'kinetwork run double_pendulum'), or copy one, with the subsystem files it "
                    "places, into a folder to edit it. Nothing is overwritten.")
    exsub = ex.add_subparsers(dest="action", metavar="ACTION")
    excopy = exsub.add_parser("copy", help="copy an example into a folder",
                              description="Copy the example NAME (and the definition files it "
                                          "places) into DIR; refuses if a file exists there.")
    excopy.add_argument("name", metavar="NAME", help="example name (see 'kinetwork examples')")
    excopy.add_argument("folder", metavar="DIR", nargs="?", default=".",
                        help="destination folder (default: the current one)")

    add_sweep(sub)
    imp = sub.add_parser(
        "import", help="turn a URDF robot description into a kinetwork model file",
        description="Read ROBOT.urdf (links, joints, inertials, limits, visuals) and write "
                    "the kinetwork model of the robot: a Ground, its joints and bodies, and "
                    "with --probes a probe on every joint.")
    imp.add_argument("source", metavar="ROBOT.urdf", help="URDF file")
    imp.add_argument("-o", "--out", metavar="MODEL.json", required=True, help="model file")
    imp.add_argument("--probes", action="store_true", help="a probe on every joint")
    imp.add_argument("--floating", action="store_true",
                     help="a free-floating base (default: the root link fixed to the ground)")
    imp.add_argument("--no-limits", action="store_true",
                     help="leave the joints' position limits out (default: hard end stops)")
    imp.add_argument("--gravity", type=float, nargs=3, metavar=("GX", "GY", "GZ"),
                     default=None, help="gravity of the ground (default 0 0 -9.81)")
    lin, fit = analysis_commands.add_commands(sub)
    for command in (run, val, eqs, anim, dia, studio, lin, fit):
        command.add_argument("--library", action="append", default=[], metavar="DIR",
                             help="a folder of subsystem files (TYPE.json), searched after "
                                  "the model's own definitions and folder (repeat for "
                                  "several; KINETWORK_LIBRARY adds more)")
    return parser


def main(argv=None):
    """Run the ``kinetwork`` command; returns the exit code."""
    # the command line's own process (not a call from Python), plotting into a file that is
    # not a PNG: draw it in a second process, importing matplotlib while this one loads and
    # runs the model (PNGs are drawn here, with Pillow, after the run)
    worker = plotworker.PlotWorker.start() if argv is None and \
        plotworker.wanted(sys.argv[1:]) else None
    try:
        return _main(argv, worker)
    finally:
        if worker is not None:
            worker.close()


def _main(argv, worker):
    args = build_parser().parse_args(argv)
    args.plot_worker = worker
    command = {"run": _run, "validate": _validate, "equations": _equations,
               "methods": _methods, "bench": _bench, "schema": _schema,
               "cache": _cache, "animate": _animate, "diagram": _diagram,
               "studio": _studio, "import": _import, "sweep": _sweep,
               "examples": _examples, "linearize": _linearize, "fit": _fit}[args.command]
    try:
        return command(args)
    except kn.ModelError as exc:
        _error(exc)
        return EXIT_MODEL
    except KeyboardInterrupt:
        _error("interrupted")
        return 130
    except BrokenPipeError:
        # the reader went away (kinetwork equations ... | head): stop quietly, and keep
        # Python from complaining again when it flushes stdout at exit
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return EXIT_MODEL


def _linearize(args):
    from .analysis import commands
    return commands.run_linearize(args, _load(args.model, args.library))


def _fit(args):
    from .analysis import commands
    try:
        return commands.run_fit(args, _load(args.model, args.library))
    except kn.SimulationError as exc:
        _error(exc)
        return EXIT_SIMULATION


def _sweep(args):
    from .analysis.sweep import run_command
    return run_command(args, _load(args.model, args.library))


def _error(message):
    print(f"kinetwork: error: {message}", file=sys.stderr)


def _load(path, library=None, validate=True):
    """The model in the file ``path``, or the shipped example of that name (a file wins)."""
    from . import examples
    if not os.path.exists(path):
        if _example_name(path):
            path = str(examples.path(path))
        elif (not path.endswith(".json") or "/" not in path) and examples.close_names(path):
            raise kn.ModelError(f"{path}: no such file, nor an example of that name (did you "
                                f"mean {' or '.join(examples.close_names(path))}?)")
    try:
        return kn.load(path, library=library, validate=validate)
    except OSError as exc:
        raise kn.ModelError(f"cannot read {path}: {exc.strerror or exc}") from None


def _example_name(text):
    """Whether ``text`` names a shipped example (``double_pendulum``, ``engine_v6/EngineV6``)."""
    from . import examples
    key = text[:-len(".json")] if text.endswith(".json") else text
    return key in examples.names()


def _write(path, write, what, quiet=False):
    """Write one output, making its folder; an OSError becomes a message naming the file."""
    try:
        os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
        write(path)
    except OSError as exc:
        raise kn.ModelError(f"cannot write {path}: {exc.strerror or exc}") from None
    if not quiet:
        print(f"wrote {what} {path}")


def _outputs(args, results, title):
    quiet = getattr(args, "quiet", False)
    if args.out:
        _write(args.out, results.to_csv,
               f"{len(results.t)} points x {len(results.columns()[0])} columns to", quiet)
    if args.plot:
        _write(args.plot, lambda path: _save_plot(args, results, path, title),
               "probe plots to", quiet)


def _save_plot(args, results, path, title):
    """The probe plots into ``path``: a PNG drawn here with Pillow when the light renderer
    draws what it holds (no matplotlib to import: the quick first answer), else matplotlib's
    ``save_plot``, in the drawing process forked for other formats when there is one."""
    from . import quickplot
    names, hide_flat = args.plot_signals, args.hide_flat
    if quickplot.drawable(path, results, names):
        return quickplot.save_png(results, path, *names, title=title, hide_flat=hide_flat)
    from .plot import save_plot
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


def _run(args):
    clash = _clashing_paths(args)
    if clash:
        _error(clash)
        return EXIT_USAGE
    model = _load(args.model, args.library)
    if args.plot:
        from .plot import check_plot_path
        check_plot_path(args.plot)
    # a subsystem's value by path ("cyl1.phi0") is a constant of its instance: set on the
    # model before it is compiled; model parameters go to the integrator
    from .graph.settings import check_output, check_settings
    from .solver.driver import DEFAULTS

    params = {}
    for name, value in args.param:
        if "." in name:
            model.set_parameter(name, value)
        else:
            params[name] = value
    given = {"t_end": args.t_end, "n_points": args.n_points, "method": args.method,
             "rtol": args.rtol, "atol": args.atol, "step": args.step}
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
                                  step=args.step, jit=args.jit, params=params,
                                  max_steps=args.max_steps, time_limit=args.time_limit,
                                  progress=progress, error_estimate=args.error_estimate)
    except kn.SimulationError as exc:
        _error(exc)
        stopped = exc.signal in STOPPING
        if exc.results is not None and len(exc.results.t):
            what = "interrupted" if stopped else "failed"
            try:
                _outputs(args, exc.results, f"{model.name} ({what} at t = {exc.t_reached:g} s)")
            except kn.ModelError as write_exc:
                _error(write_exc)
        return 128 + int(exc.signal) if stopped else EXIT_SIMULATION
    done = time.perf_counter()
    if args.quiet:
        _outputs(args, results, model.name)
        return 0
    t = results.t
    print(f"{model.name}: {system.n_states} states ({_listing(system.state_names)})")
    if args.param:
        print("parameters set: " + ", ".join(f"{k} = {v:g}" for k, v in args.param))
    stats = results.stats
    code = ("C, cached" if stats.get("jit_cached") else
            f"C, compiled in {stats['jit_seconds']:.2g} s" if "jit_seconds" in stats else
            "C" if stats.get("jit") else "CasADi virtual machine")
    work = ", ".join(f"{stats[k]} {k.replace('_', ' ')}" for k in ("steps", "rhs_evaluations")
                     if k in stats)
    print(f"simulated t = {t[0]:g} .. {t[-1]:g} s ({len(t)} points) with {results.method} "
          f"({code}{'; ' + work if work else ''}) in {done - compiled:.3g} s wall time "
          f"(build {compiled - start:.3g} s)")
    if "error_estimate" in stats:
        from .solver.estimate import summary
        print("\n".join(summary(stats["error_estimate"], results.signal_names)))
    _outputs(args, results, model.name)
    return 0


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


def _listing(items, limit=SHOWN_ITEMS):
    """Items joined by commas, the first ``limit`` of a longer list and how many in all."""
    items = list(items)
    shown = ", ".join(map(str, items[:limit]))
    return shown if len(items) <= limit else f"{shown}, ... ({len(items)} in all)"


def _shown(text, limit=SHOWN_CHARACTERS):
    """Free text, cut to ``limit`` characters with the length said."""
    return text if len(text) <= limit else f"{text[:limit]}... ({len(text)} characters)"


def _validate(args):
    model = _load(args.model, args.library)   # reading validates: one ModelError lists all
    if model.exposed:
        print("\n".join(_definition_summary(model, args.model)))
        return 0
    topo = model.validate()             # the same Topology again, not a second analysis
    kinds = collections.Counter(c.type_name for c in model.components.values())
    groups = collections.Counter(g.kind for g in topo.oned)
    lines = [
        f"model {model.name!r} ({args.model}): valid",
        *([textwrap.fill(f"description: {_shown(model.description)}", 88,
                         subsequent_indent="  ", break_on_hyphens=False)]
          if model.description else []),
        f"components: {len(model.components)} ("
        + ", ".join(f"{n} {kind}" for kind, n in kinds.most_common()) + ")",
        f"connections: {len(model.connections)}",
        *_subsystems_summary(model),
    ]
    loops = f"loops: {len(topo.loops) or 'none'}" + "".join(
        f"\n  {' - '.join(cut.loop)} (cut at {cut.component.name})"
        for cut in topo.cuts[:SHOWN_ITEMS]) + (
        f"\n  ... ({len(topo.cuts)} in all)" if len(topo.cuts) > SHOWN_ITEMS else "")
    if args.compile:
        lines += _compiled_summary(model.compile(loops=args.loops), topo, loops)
    elif any(port.domain == "electrical" for c in model.components.values()
             for port in c.ports.values()):
        # a circuit's states are chosen by its structure (index reduction): compiled to say
        # which, as validation of a circuit is about which energy stores are independent
        lines += _compiled_summary(model.compile(loops=args.loops), topo, loops)
    else:
        # the joints' degrees of freedom and the free 1-D groups' are exact without the
        # equations; loops take away as many as their independent closure equations
        dof = topo.dof + groups["free"]
        lines += [f"degrees of freedom: {dof}" if not topo.loops else
                  f"degrees of freedom: at most {dof}, less one per independent closure "
                  f"equation of the loops (--compile counts them)", loops]
    if not args.compile and groups:
        lines.append("1-D rigid groups: " + ", ".join(
            f"{groups[k]} {what}" for k, what in (
                ("joint", "on joint axes"), ("free", "free (an angle and a speed each)"),
                ("massless", "massless"), ("prescribed", "prescribed"), ("fixed", "fixed"))
            if groups[k]))
    lines.append(f"parameters: {len(model.parameters)}" + (
        " (" + _listing(f"{k} = {v:g}" for k, v in model.parameters.items()) + ")"
        if model.parameters else ""))
    if model.simulation:
        lines.append("simulation: " + ", ".join(f"{k} = {v}"
                                                for k, v in model.simulation.items()))
    print("\n".join(lines))
    return 0


def _subsystems_summary(model):
    """Lines naming each subsystem definition, where it comes from and its instances by
    path; nothing for a flat model."""
    from .graph.subsystem import subsystem_instances
    placed = subsystem_instances(model)
    if not placed:
        return []
    flat = model.flat()
    lines = [f"subsystems: {len(placed)} definition{'s' if len(placed) > 1 else ''}, "
             f"{sum(len(p) for _, p in placed.values())} instances; flat: "
             f"{len(flat.components)} components, {len(flat.connections)} connections"]
    for name, (definition, paths) in placed.items():
        origin = definition.origin
        where = "inline" if origin is None else f"{origin[1]} {os.path.relpath(origin[0])}"
        ports = ", ".join(definition.exposed)
        lines.append(f"  {name} ({where}; ports {ports or 'none'}): "
                     + _listing(paths))
    return lines


def _definition_summary(model, path):
    """``validate`` of a definition file: its ports and parameters (it is wired where it is
    placed, so its wiring is checked there)."""
    kinds = collections.Counter(c.type_name for c in model.components.values())
    ports = [f"{name} -> {ref.path} ({ref.domain})" for name, ref in model.exposed.items()]
    return [
        f"subsystem definition {model.name!r} ({path}): values valid; its wiring is checked "
        f"where it is placed",
        f"ports: {_listing(ports)}",
        f"components: {len(model.components)} ("
        + ", ".join(f"{n} {kind}" for kind, n in kinds.most_common()) + ")",
        f"connections: {len(model.connections)}",
        *_subsystems_summary(model)[1:],
        f"parameters: {len(model.parameters)}" + (
            " (" + _listing(f"{k} = {v:g}" for k, v in model.parameters.items()) + ")"
            if model.parameters else ""),
    ]


def _compiled_summary(system, topo, loops):
    """The lines of ``validate --compile`` from the equations: degrees of freedom, states,
    algebraic variables, the ``loops`` line, formulation, 1-D network, equation size."""
    units = dict(zip(system.state_names, system.state_units))
    n_values = sum(sig.size for sig in system.signals)
    size = system.size()
    network = system.asm.net.summary(topo)
    return [
        f"degrees of freedom: {system.dof}",
        f"states: {system.n_states}"
        + (" (" + _listing(f"{s} [{units[s]}]" if units[s] else s
                           for s in system.state_names) + ")" if system.n_states else ""),
        *([f"algebraic: {system.n_algebraic} ("
           + _listing(f"{s} [{u}]" if u else s for s, u in
                      zip(system.algebraic_names, system.algebraic_units)) + ")"]
          if system.n_algebraic else []),
        loops,
        *([textwrap.fill(f"why these states: {system.formulation_note}", 88,
                         subsequent_indent="  ")] if system.formulation_note else []),
        *([textwrap.fill(network, 88, subsequent_indent="  ")] if network else []),
        *[textwrap.fill(f"demoted by index reduction: {name} ({why})", 88,
                        subsequent_indent="  ") for name, why in system.demoted_states.items()],
        f"equations: {size['states']} states, {size['algebraic']} algebraic variables, "
        f"{len(system.signal_names)} probe signals ({n_values} values); right-hand side "
        f"{size['operations']} operations per evaluation ("
        + {"tree": "articulated-body algorithm, O(N)",
           "hybrid": "articulated-body algorithm with the prescribed accelerations, O(N)"}.get(
            system.formulation, "mass matrix projected on the independent speeds") + ")",
    ]


def _animate(args):
    from .animation import cli_animate        # the faces load only when asked for
    return cli_animate(args, _load(args.model, args.library))


def _diagram(args):
    from .diagram import cli_diagram
    return cli_diagram(args, _load(args.model, args.library, validate=False))


def _studio(args):
    from .studio import cli_studio
    return cli_studio(args)


def _import(args):
    from .urdf import cli_import
    return cli_import(args)


def _examples(args):
    from . import examples
    if args.action == "copy":
        written = examples.copy(args.name, args.folder)
        print(f"copied {args.name} to {written[0]}"
              + (f" (with {len(written) - 1} definition file{'s' if len(written) > 2 else ''})"
                 if len(written) > 1 else ""))
        print(f"run it: kinetwork run {written[0]}")
        return 0
    listed = examples.summaries()
    if not listed:
        print("no examples are installed with this copy of kinetwork")
        return 0
    width = max(map(len, listed))
    for name, line in listed.items():
        print(f"{name:<{width}}  {line}")
    first = "double_pendulum" if "double_pendulum" in listed else next(iter(listed))
    print(f"\nrun one: kinetwork run {first} --plot plot.png;  "
          f"copy one: kinetwork examples copy NAME DIR")
    return 0


def _schema(args):
    import json
    print(json.dumps(kn.schema(), indent=2))
    return 0


def _cache(args):
    from .solver import jit
    if args.clear:
        removed = jit.clear_cache()
        print(f"removed {removed} file{'s' * (removed != 1)} from {jit.cache_dir()}")
        return 0
    info = jit.cache_info()
    print(f"{info['folder']}: {info['entries']} compiled librar"
          f"{'y' if info['entries'] == 1 else 'ies'}, {info['bytes'] / 2**20:.1f} MiB "
          f"(at most {jit.MAX_CACHE_BYTES / 2**20:.0f} MiB are kept)")
    for name, size, _ in info["libraries"][:20]:
        print(f"  {name}  {size / 1024:.0f} KiB")
    if info["entries"] > 20:
        print(f"  ... and {info['entries'] - 20} more")
    return 0


def _methods(args):
    from .solver.driver import DEFAULTS, METHODS
    width = max(map(len, METHODS))
    print(f"default: {DEFAULTS['method']}, rtol {DEFAULTS['rtol']:g}, atol {DEFAULTS['atol']:g}")
    for name, method in METHODS.items():
        kind = "fixed step" if method.fixed else "variable step"
        print(f"  {name:<{width}}  {kind:<13}  " + textwrap.fill(
            method.doc, 88, initial_indent=" " * (width + 19),
            subsequent_indent=" " * (width + 19)).lstrip())
    return 0


def _bench(args):
    import pathlib
    import subprocess
    script = pathlib.Path(__file__).resolve().parents[1] / "bench" / "run.py"
    if not script.exists():
        raise kn.ModelError("bench: the studies live in the source checkout's bench/ folder, "
                            "which this installation does not have")
    return subprocess.call([sys.executable, str(script), *(["--quick"] if args.quick else [])])


def _equations(args):
    import sympy as sp

    from .symbolic import equations_sympy

    model = _load(args.model, args.library)
    system = model.compile()
    eq = equations_sympy(system, simplified=args.simplify)     # ModelError for a Table's call
    mats = {key: eq[key] for key in ("M", "V", "G")}
    shared = eq["shared"]
    if not eq["simplified"] and args.simplify is None:
        print(f"kinetwork: note: M, V, G have {eq['size']} operations, too many to simplify "
              f"quickly: printed as built, shared parts named w0, w1, ... (--simplify "
              f"forces it)", file=sys.stderr)
    coords = ", ".join(f"{s} = {c}" for s, c in zip(eq["q"], system.coordinate_names))

    if args.format == "latex":
        names = {s: _latex_name(s.name, prefix) for prefix in ("q", "qd") for s in eq[prefix]}

        def show(expr):
            return sp.latex(expr, symbol_names=names, mat_str="bmatrix", mat_delim="",
                            full_prec=False)
        print(f"% {model.name}: M(q) \\ddot q + V(q, \\dot q) + G(q) = 0; {coords}")
        for key, expr in [*shared, *mats.items()]:
            print(f"{show(sp.Symbol(str(key)))} = {show(expr)}")
        return 0

    print(f"{model.name}: M(q)*qdd + V(q, qd) + G(q) = 0")
    print(f"coordinates: {coords}" if coords else "coordinates: none (no degrees of freedom)")
    print("speeds: " + (", ".join(str(s) for s in eq["qd"]) or "none"))
    print("parameters: " + (", ".join(eq["params"]) or "none"))
    if system.topology.cuts:
        print(f"loops: cut at {', '.join(c.component.name for c in system.topology.cuts)}; "
              f"M, V, G are those of the open tree, and the {system.eq.loop_rows} independent "
              f"closure equations phi(q) = 0 add J(q)^T lambda to the right-hand side")
    blocks = [[(str(w), expr) for w, expr in shared]] if shared else []
    comma = "," if len(eq["q"]) > 9 else ""       # M1011 would be ambiguous: M10,11
    for key, mat in mats.items():
        blocks.append([(f"{key}{i + 1}{comma}{j + 1}" if key == "M" else f"{key}{i + 1}",
                        mat[i, j]) for i in range(mat.rows) for j in range(mat.cols)])
    for block in blocks:
        print()
        for label, expr in block:
            if args.format == "pretty":
                print(sp.pretty(sp.Eq(sp.Symbol(_subscript(label)), expr, evaluate=False),
                                use_unicode=True, wrap_line=False, full_prec=False))
            else:
                print(f"{label} = {sp.sstr(expr, full_prec=False)}")
    return 0


def _subscript(label):
    """M12 -> M_12, so pretty printing sets the index as a subscript."""
    return label[0] + "_" + label[1:]


def _latex_name(name, prefix):
    """q_shoulder -> q_{\\mathrm{shoulder}}, qd_shoulder -> \\dot{q}_{\\mathrm{shoulder}}."""
    rest = name[len(prefix) + 1:].replace("_", r"\_")
    base = r"\dot{q}" if prefix == "qd" else "q"
    return f"{base}_{{\\mathrm{{{rest}}}}}"


if __name__ == "__main__":
    sys.exit(main())
