"""``kinetwork export MODEL --fmu out.fmu``: the command line's way to ``kn.export_fmu``."""

from .build import KINDS, export_fmu

INTERFACES = {"both": "Model Exchange and Co-Simulation", "me": "Model Exchange",
              "cs": "Co-Simulation"}


def add_command(sub):
    """The ``export`` subcommand on the parser's subparsers ``sub``; returns it."""
    ex = sub.add_parser(
        "export", help="export a model as an FMU (FMI 2.0)",
        description="Export MODEL.json as an FMI 2.0 Functional Mock-up Unit: Model Exchange "
                    "and Co-Simulation in one file, for Simulink, Modelica tools, "
                    "co-simulation masters and HIL rigs. The model's parameters are tunable "
                    "parameters, its signals.Input blocks inputs, its probes outputs. The "
                    "binary is compiled for this machine; the C sources ship inside so it "
                    "can be rebuilt for another. An existing FMU at the path is replaced, "
                    "any other file is not.")
    ex.add_argument("model", metavar="MODEL.json", help="model file or example name")
    ex.add_argument("--fmu", metavar="FILE.fmu", required=True, help="the FMU to write")
    ex.add_argument("--kind", choices=KINDS, default="both",
                    help="the interfaces offered: Model Exchange, Co-Simulation, or both "
                         "(default: both)")
    ex.add_argument("--name", metavar="NAME",
                    help="the model's name in the FMU (default: the model's own)")
    return ex


def run_command(args, model):
    """Write the FMU; the exit code."""
    path = export_fmu(model, args.fmu, kind=args.kind, name=args.name)
    print(f"wrote the FMU of {model.name} (FMI 2.0 {INTERFACES[args.kind]}) to {path}")
    return 0
