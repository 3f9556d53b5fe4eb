"""The analysis subcommands of ``kinetwork``: ``linearize`` (print A, B, C, D) and ``fit``
(estimate parameters from a measured CSV). ``kinetwork.cli`` registers them and hands each
the loaded model."""

import argparse
import json
import sys

import numpy as np

from ..errors import ModelError


def add_commands(sub):
    """Add ``linearize`` and ``fit`` to the subparsers ``sub``; returns their parsers."""
    lin = sub.add_parser(
        "linearize", help="print the state-space model A, B, C, D at an operating point",
        description="Linearise MODEL.json exactly (CasADi's derivatives) at its initial "
                    "state, at a time of its run (--at-time) or at rest (--at-rest: every "
                    "speed 0 and the coordinates as given), and print A, B, C, D with named, "
                    "unit-carrying states, inputs and outputs, and the modes.")
    lin.add_argument("model", metavar="MODEL.json",
                     help="model file, or the name of an example (kinetwork examples)")
    lin.add_argument("--input", action="append", default=[], metavar="NAME", dest="inputs",
                     help="an input: an open signal input (motor.u) or a signals.Input "
                          "block (repeat for several)")
    lin.add_argument("--output", action="append", default=None, metavar="NAME",
                     dest="outputs", help="an output: a probe quantity (probe1.angle) or a "
                                          "state (repeat; default: every probe quantity)")
    at = lin.add_mutually_exclusive_group()
    at.add_argument("--at-time", type=float, metavar="T",
                    help="linearise at the state the model's run reaches at T [s]")
    at.add_argument("--at-state", metavar="NAME=VALUE,...",
                    help="linearise at these state values (the others initial)")
    lin.add_argument("--param", type=_parameter, action="append", default=[],
                     metavar="NAME=VALUE", help="a model parameter value (repeat)")
    lin.add_argument("--json", action="store_true", help="print JSON instead of tables")

    fitp = sub.add_parser(
        "fit", help="estimate model parameters from measured probe signals",
        description="Fit parameters of MODEL.json to a CSV of measured probe signals (t, "
                    "then columns named as 'kinetwork run --out' names them) by least "
                    "squares with exact gradients; prints the estimates with 95 %% "
                    "confidence intervals.")
    fitp.add_argument("model", metavar="MODEL.json",
                      help="model file, or the name of an example (kinetwork examples)")
    fitp.add_argument("--data", required=True, metavar="FILE.csv", help="measured signals")
    fitp.add_argument("--fit", action="append", required=True, metavar="NAME[=LOW:HIGH]",
                      type=_bounded, dest="params",
                      help="a parameter to fit, with optional bounds (c=0:10; repeat)")
    fitp.add_argument("--column", action="append", default=None, metavar="NAME",
                      dest="columns", help="a measured column to fit (repeat; default: "
                                           "every column the model has a probe for)")
    fitp.add_argument("--param", type=_parameter, action="append", default=[],
                      metavar="NAME=VALUE", help="another model parameter's value (repeat)")
    fitp.add_argument("--json", action="store_true", help="print JSON instead of a table")
    return lin, fitp


def _parameter(text):
    name, sep, value = text.partition("=")
    try:
        if not sep or not name.strip():
            raise ValueError
        return name.strip(), float(value)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected NAME=VALUE, got {text!r:.60}") from None


def _bounded(text):
    """NAME or NAME=LOW:HIGH (either side may be empty: no bound)."""
    name, sep, spec = text.partition("=")
    if not name.strip():
        raise argparse.ArgumentTypeError(f"expected NAME[=LOW:HIGH], got {text!r:.60}")
    if not sep:
        return name.strip(), None
    low, colon, high = spec.partition(":")
    try:
        if not colon:
            raise ValueError
        return name.strip(), (float(low) if low.strip() else None,
                              float(high) if high.strip() else None)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected NAME=LOW:HIGH, got {text!r:.60}") from None


def run_linearize(args, model):
    from .linear import linearize
    from .modal import modes
    """``kinetwork linearize``: prints A, B, C, D (and the modes)."""
    at = args.at_time
    if args.at_state:
        at = {}
        for item in args.at_state.split(","):
            name, sep, value = item.partition("=")
            try:
                at[name.strip()] = float(value)
            except ValueError:
                raise ModelError(f"--at-state: expected NAME=VALUE, got {item!r:.60}") from None
    lin = linearize(model, at=at, inputs=args.inputs, outputs=args.outputs,
                    params=dict(args.param))
    found = modes(lin)
    if args.json:
        json.dump({"t": lin.t, "states": lin.state_names, "state_units": lin.state_units,
                   "inputs": lin.input_names, "input_units": lin.input_units,
                   "outputs": lin.output_names, "output_units": lin.output_units,
                   "A": lin.A.tolist(), "B": lin.B.tolist(), "C": lin.C.tolist(),
                   "D": lin.D.tolist(),
                   "modes": [{"frequency": m.frequency, "damping": m.damping,
                              "eigenvalue": [m.eigenvalue.real, m.eigenvalue.imag]}
                             for m in found]}, sys.stdout, indent=1)
        print()
        return 0
    print(f"{model.name}: linearised at t = {lin.t:g} s\n")
    print(lin.text())
    if found:
        print("\nmodes (natural frequency, damping ratio, eigenvalue):")
        for m in found:
            lam = m.eigenvalue
            print(f"  {m.frequency:12.6g} rad/s  {m.damping:9.4g}   "
                  f"{lam.real:.6g} {'+' if lam.imag >= 0 else '-'} {abs(lam.imag):.6g}j")
    return 0


def run_fit(args, model):
    from .fitting import fit
    """``kinetwork fit``: prints the estimates and their intervals."""
    result = fit(model, args.data, dict(args.params), columns=args.columns,
                 values=dict(args.param))
    if args.json:
        json.dump({"params": result.params, "stderr": _finite(result.stderr),
                   "interval": {k: [_finite(v) for v in pair]
                                for k, pair in result.interval.items()},
                   "level": result.level, "rms": result.rms, "columns": result.columns,
                   "success": result.success}, sys.stdout, indent=1)
        print()
    else:
        print(result.text())
    return 0


def _finite(value):
    """JSON has no infinity: an interval that is not finite (not identifiable) is null."""
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    return float(value) if np.isfinite(value) else None
