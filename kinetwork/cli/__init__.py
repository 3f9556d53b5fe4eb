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

import argparse
import os
import sys

import kinetwork as kn

from .. import plotworker
from . import check, equations, faces, run, tools
from .common import EXIT_MODEL, HelpFormatter, error, load_model

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
    try:
        return command(args)
    except kn.ModelError as exc:
        error(exc)
        return EXIT_MODEL
    except KeyboardInterrupt:
        error("interrupted")
        return 130
    except BrokenPipeError:
        # the reader went away (kinetwork equations ... | head): stop quietly, and keep
        # Python from complaining again when it flushes stdout at exit
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return EXIT_MODEL


__all__ = ["COMMANDS", "build_parser", "load_model", "main"]
