"""The ``kinetwork sweep`` command: a grid of parameter values from the command line, a
line per member, the whole sweep as NetCDF."""

import math

import numpy as np

from ..errors import ModelError
from ..solver.methods import METHODS


def _values(text):
    """argparse type of ``--param NAME=V1,V2,...`` (numbers, or numbers with a unit: "2 kg")
    or ``NAME=START:STOP:COUNT``."""
    import argparse
    name, sep, rest = text.partition("=")
    try:
        if not sep or not name.strip():
            raise ValueError
        if rest.count(":") == 2:
            start, stop, count = rest.split(":")
            values = np.linspace(float(start), float(stop), int(count)).tolist()
        else:
            values = [_number_or_quantity(v) for v in rest.split(",")]
        if not values or not all(isinstance(v, str) or math.isfinite(v) for v in values):
            raise ValueError
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected NAME=V1,V2,... (numbers, or numbers with a unit) or "
            f"NAME=START:STOP:COUNT with finite numbers, got {text!r:.60}") from None
    return name.strip(), values


def _number_or_quantity(text):
    """A number, or the text of a number with a unit (the sweep reads and checks it)."""
    text = text.strip()
    if not text:
        raise ValueError
    try:
        return float(text)
    except ValueError:
        return text


def add_command(sub):
    """The ``kinetwork sweep`` subcommand."""
    import argparse
    cmd = sub.add_parser(
        "sweep", help="simulate a model over a grid of parameter values",
        description="Simulate MODEL.json for every combination of the --param values (one "
                    "compiled system; batches in parallel threads, or on a Dask cluster), "
                    "print a line per member (its final probe values, or why it failed) "
                    "and write the whole sweep as NetCDF (xarray).")
    cmd.add_argument("model", metavar="MODEL.json",
                     help="model file, or the name of an example (kinetwork examples)")
    cmd.add_argument("--param", type=_values, action="append", default=[], required=True,
                     metavar="NAME=V1,V2,...",
                     help="a swept parameter (a model parameter, or a component parameter "
                          "by path: spring.c) and its values (or START:STOP:COUNT); repeat "
                          "for a grid")
    cmd.add_argument("--t-end", type=float, metavar="T", help="end time [s]")
    cmd.add_argument("--n-points", type=int, metavar="N", help="points on the output grid")
    cmd.add_argument("--method", type=str.lower, choices=list(METHODS), metavar="M",
                     help=f"integrator: {', '.join(METHODS)}")
    cmd.add_argument("--rtol", type=float, metavar="R", help="relative tolerance")
    cmd.add_argument("--atol", type=float, metavar="A", help="absolute tolerance")
    cmd.add_argument("--max-step", type=float, metavar="H",
                     help="largest step [s] of every method (as kinetwork run's)")
    cmd.add_argument("--jit", action=argparse.BooleanOptionalAction,
                     help="compile the equations to C (default: when a compiler is found)")
    cmd.add_argument("--output", action="append", default=None, metavar="NAME",
                     dest="outputs", help="a probe signal or state to keep (repeat; default: "
                                          "all)")
    cmd.add_argument("--workers", type=int, metavar="N",
                     help="threads sharing the members (default: the cores)")
    cmd.add_argument("--batch", type=int, metavar="B",
                     help="members per mapped call (per task on Dask)")
    cmd.add_argument("--scheduler", metavar="ADDRESS",
                     help="run on Dask: 'local' (a LocalCluster on this machine) or a "
                          "scheduler's address, tcp://host:8786")
    cmd.add_argument("--out", metavar="FILE.nc", help="write the sweep as NetCDF")
    cmd.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                     help="a progress bar on stderr (default: when stderr is a terminal)")
    cmd.add_argument("--library", action="append", default=[], metavar="DIR",
                     help="a folder of subsystem files (TYPE.json)")
    return cmd


def run_command(args, model):
    """Run ``kinetwork sweep``; returns the exit code (3 when a member failed)."""
    import sys

    from .sweep import summary, sweep, to_netcdf
    grid = dict(args.param)
    if len(grid) != len(args.param):
        raise ModelError("--param: a parameter is given twice")
    progress = args.progress if args.progress is not None else sys.stderr.isatty()
    ds = sweep(model, grid, t_end=args.t_end, n_points=args.n_points, method=args.method,
               rtol=args.rtol, atol=args.atol, max_step=args.max_step, jit=args.jit,
               outputs=args.outputs, workers=args.workers,
               batch=args.batch, scheduler=args.scheduler, progress=progress)
    print(summary(ds))
    if args.out:
        try:
            to_netcdf(ds, args.out)
        except OSError as exc:
            raise ModelError(f"cannot write {args.out}: {exc.strerror or exc}") from None
        print(f"wrote {ds.attrs['members']} members to {args.out}")
    return 3 if ds.attrs["failed"] or ds.attrs["interrupted"] else 0

