"""What the ``kinetwork`` subcommands share: exit codes, argument types, the help layout, how
a model is loaded (a file or an example by name) and how an output is written."""

import argparse
import os
import signal
import sys

import kinetwork as kn

from ..util import finite, quote

EXIT_MODEL, EXIT_USAGE, EXIT_SIMULATION = 1, 2, 3
#: signals that stop a run with its partial results written, exiting 128 + the signal
STOPPING = (signal.SIGINT, signal.SIGTERM)
#: what ``validate`` prints of long texts and lists: a summary, not the model again
SHOWN_CHARACTERS, SHOWN_ITEMS = 500, 20


def parameter_arg(text):
    """argparse type of ``--param NAME=VALUE``: a number, or a number with a unit
    (``c="2 N*m/rad"``: converted and checked by the model, which knows where it is used)."""
    from ..graph.quantities import is_quantity
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


def positive(kind):
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


class HelpFormatter(argparse.HelpFormatter):
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


def add_library(parser):
    """The ``--library DIR`` option of a command that loads a model with subsystems."""
    parser.add_argument("--library", action="append", default=[], metavar="DIR",
                        help="a folder of subsystem files (TYPE.json), searched after the "
                             "model's own definitions and folder (repeat for several; "
                             "KINETWORK_LIBRARY adds more)")


def error(message):
    print(f"kinetwork: error: {message}", file=sys.stderr)


def load_model(path, library=None, validate=True):
    """The model in the file ``path``, or the shipped example of that name (a file wins)."""
    from .. import examples
    if not os.path.exists(path):
        if example_name(path):
            path = str(examples.path(path))
        elif (not path.endswith(".json") or "/" not in path) and examples.close_names(path):
            raise kn.ModelError(f"{path}: no such file, nor an example of that name (did you "
                                f"mean {' or '.join(examples.close_names(path))}?)")
    try:
        return kn.load(path, library=library, validate=validate)
    except OSError as exc:
        raise kn.ModelError(f"cannot read {path}: {exc.strerror or exc}") from None


def example_name(text):
    """Whether ``text`` names a shipped example (``double_pendulum``, ``engine_v6/EngineV6``)."""
    from .. import examples
    key = text[:-len(".json")] if text.endswith(".json") else text
    return key in examples.names()


def write_output(path, write, what, quiet=False):
    """Write one output, making its folder; an OSError becomes a message naming the file."""
    try:
        os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
        write(path)
    except OSError as exc:
        raise kn.ModelError(f"cannot write {path}: {exc.strerror or exc}") from None
    if not quiet:
        print(f"wrote {what} {path}")


def listing(items, limit=SHOWN_ITEMS):
    """Items joined by commas, the first ``limit`` of a longer list and how many in all."""
    items = list(items)
    shown = ", ".join(map(str, items[:limit]))
    return shown if len(items) <= limit else f"{shown}, ... ({len(items)} in all)"


def shown(text, limit=SHOWN_CHARACTERS):
    """Free text, cut to ``limit`` characters with the length said."""
    return text if len(text) <= limit else f"{text[:limit]}... ({len(text)} characters)"
