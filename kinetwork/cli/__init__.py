"""The ``kinetwork`` command: run, validate and derive the equations of a model file; list
the integration methods; run the benchmark studies.

Exit codes: 0 success, 1 a refused model or an unwritable output, 2 a usage error (argparse,
or outputs that would overwrite the model or each other), 3 a failed integration (whatever
was computed before the failure is still written), 128 + the signal number when SIGINT or
SIGTERM stopped a run (130, 143; what was computed is written all the same).

One module per command (or group of small ones): each ``add(sub)`` makes its parsers and
returns its handlers by name; ``COMMANDS`` lists them in the order ``--help`` shows them.
The rest of kinetwork (numpy, CasADi, networkx, the model layers) is imported where a
command needs it: ``kinetwork run --plot`` forks its drawing process before that (see
plotworker), and ``--help`` or ``--version`` answer at once.
"""

import os
import signal
import sys


def _started_as_command():
    """True in the ``kinetwork`` command's own process (its console script, ``python -m
    kinetwork`` or ``python -m kinetwork.cli``), not when a Python program imports this
    module."""
    main_module = sys.modules.get("__main__")
    spec = getattr(main_module, "__spec__", None)
    if spec is not None:
        return spec.name in ("kinetwork.__main__", "kinetwork.cli", "kinetwork.cli.__main__")
    name = os.path.basename(getattr(main_module, "__file__", None) or "")
    return name.removesuffix(".exe").removesuffix("-script.py") == "kinetwork"


#: SIGINT or SIGTERM that reached the command while it was starting (importing its modules,
#: reading its arguments): recorded, never raised there (that would be a raw traceback from
#: an import, or the signal lost when it was started with them ignored), and answered by
#: ``main`` as soon as it can: exit 128 + the signal, nothing run
_EARLY = {"signum": None, "saved": {}}


def _record_early(signum, frame):
    if _EARLY["signum"] is None:
        _EARLY["signum"] = signum


if _started_as_command():
    for _sig in (signal.SIGINT, signal.SIGTERM):
        try:
            _EARLY["saved"][_sig] = signal.signal(_sig, _record_early)
        except (ValueError, OSError):
            pass

# imported after the early handlers: a signal while importing is kept, not a traceback
import argparse  # noqa: E402
import contextlib  # noqa: E402
import threading  # noqa: E402

import kinetwork as kn  # noqa: E402

from .. import plotworker  # noqa: E402
from ..outputs import OutputRefused, Stopped  # noqa: E402
from . import check, equations, faces, run, tools  # noqa: E402
from .common import (EXIT_MODEL, EXIT_USAGE, STOPPING, HelpFormatter, error,  # noqa: E402
                     interrupted, load_model)

#: the modules of the subcommands, in the order ``kinetwork --help`` lists them
COMMANDS = (run, check, equations, tools, faces)


def build_parser():
    """The argument parser of the ``kinetwork`` command, and its handlers by command name
    (``parser.handlers``)."""
    parser = argparse.ArgumentParser(
        prog="kinetwork",
        description="Acausal multibody models: simulate a model file, check it, or print "
                    "its equations of motion.",
        epilog="Run 'kinetwork COMMAND --help' for the options of one command. Exit codes: "
               "0 done, 1 model refused or output not writable, 2 usage error, 3 integration "
               "failed (what was computed before the failure is still written).",
        formatter_class=HelpFormatter)
    parser.add_argument("--version", action="version", version=f"kinetwork {kn.__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    parser.handlers = {}
    for module in COMMANDS:
        parser.handlers.update(module.add(sub))
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
    parser = build_parser()
    args = parser.parse_args(argv)
    args.plot_worker = worker
    command = parser.handlers[args.command]
    caught = {"signum": None}
    if args.command == "studio":      # the studio's server answers signals itself
        for sig, handler in _EARLY["saved"].items():
            signal.signal(sig, handler)
    if _EARLY["signum"] is not None:  # stopped while starting: nothing run
        return interrupted(_EARLY["signum"])
    try:
        with contextlib.nullcontext() if args.command == "studio" else _stopping(caught):
            return command(args)
    except OutputRefused as exc:
        error(exc)
        return EXIT_USAGE
    except kn.ModelError as exc:
        error(exc)
        return EXIT_MODEL
    except KeyboardInterrupt as exc:
        return interrupted(getattr(exc, "signum", None) or caught["signum"] or signal.SIGINT)
    except (SystemError, RuntimeError):
        # a signal that arrived inside CasADi comes out of it as one of these
        if caught["signum"] is not None:
            return interrupted(caught["signum"])
        raise
    except BrokenPipeError:
        # the reader went away (kinetwork equations ... | head): stop quietly, and keep
        # Python from complaining again when it flushes stdout at exit
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return EXIT_MODEL


@contextlib.contextmanager
def _stopping(caught):
    """While a command runs, SIGINT and SIGTERM stop it as a KeyboardInterrupt that names its
    signal (``outputs.Stopped``): files being written are left whole and their temporaries
    removed on the way out, and the command exits 128 + the signal. A run installs its own
    handlers while it integrates (it keeps its partial results). Signals the command was
    started with ignored are honoured too."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def stop(signum, frame):
        caught["signum"] = signum
        raise Stopped(signum)
    saved = {}
    # also when started with them ignored, as a script's background job is: the command is
    # the program, and a signal sent to it asks it to stop (it was swallowed, exit 0)
    for sig in STOPPING:
        with contextlib.suppress(ValueError, OSError):
            saved[sig] = signal.signal(sig, stop)
    try:
        yield
    finally:
        for sig, handler in saved.items():
            signal.signal(sig, handler)


__all__ = ["COMMANDS", "build_parser", "load_model", "main"]
