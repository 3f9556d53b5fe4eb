"""The ``kinetwork`` subcommands whose work another module does: ``animate`` (animation),
``diagram`` (diagram), ``studio`` (studio), ``import`` (urdf), ``sweep``, ``linearize`` and
``fit`` (analysis), ``export`` (fmu). Each is imported when its command runs: the faces load only when asked
for."""

import kinetwork as kn

from .common import EXIT_SIMULATION, add_library, error, load_model, positive


def add(sub):
    """The parsers of the commands other modules carry out (``animate``, ``diagram``,
    ``studio``, ``import``, ``sweep``, ``linearize``, ``fit``); {name: handler}."""
    from ..analysis import commands
    from ..analysis.sweep_cli import add_command as add_sweep
    from ..fmu import command as fmu_command
    parser = sub.add_parser(
        "animate", help="write a 3-D animation of a model's motion",
        description="Simulate MODEL.json and write its motion as a self-contained HTML file "
                    "(three.js inlined: play, pause, scrub, speed, orbiting camera; opens "
                    "without a network), and optionally a GIF or MP4.")
    parser.add_argument("model", metavar="MODEL.json", help="model file")
    parser.add_argument("--html", metavar="FILE.html", help="the animation page")
    parser.add_argument("--gif", metavar="FILE.gif", help="also a GIF")
    parser.add_argument("--mp4", metavar="FILE.mp4", help="also an MP4 video")
    parser.add_argument("--t-end", type=float, metavar="T", help="end time [s]")
    parser.add_argument("--fps", type=positive(int), default=30, metavar="N",
                        help="frames per second of the animation (default 30)")
    add_library(parser)
    parser = sub.add_parser(
        "diagram", help="draw a model's wiring diagram as SVG",
        description="Draw MODEL.json as blocks with their ports and wires, domains coloured "
                    "as in Modelica, placed by the file's layout or an automatic layered "
                    "layout where it has none.")
    parser.add_argument("model", metavar="MODEL.json", help="model file")
    parser.add_argument("-o", "--out", metavar="FILE.svg", required=True, help="the SVG file")
    add_library(parser)
    parser = sub.add_parser(
        "studio", help="open the browser studio",
        description="Start the studio on this machine (127.0.0.1, a free port, a token in the "
                    "URL) and open it in the browser: place, wire, run and watch models. "
                    "Files are read and written only inside the folder it was started in.")
    parser.add_argument("model", nargs="?", metavar="MODEL.json", help="model to open")
    parser.add_argument("--port", type=positive(int), metavar="N",
                        help="port (default: a free one)")
    parser.add_argument("--no-browser", action="store_true",
                        help="print the address, do not open a browser")
    add_library(parser)
    parser = sub.add_parser(
        "import", help="turn a URDF robot description into a kinetwork model file",
        description="Read ROBOT.urdf (links, joints, inertials, limits, visuals) and write "
                    "the kinetwork model of the robot: a Ground, its joints and bodies, and "
                    "with --probes a probe on every joint.")
    parser.add_argument("source", metavar="ROBOT.urdf", help="URDF file")
    parser.add_argument("-o", "--out", metavar="MODEL.json", required=True, help="model file")
    parser.add_argument("--probes", action="store_true", help="a probe on every joint")
    parser.add_argument("--floating", action="store_true",
                        help="a free-floating base (default: the root link fixed to the ground)")
    parser.add_argument("--no-limits", action="store_true",
                        help="leave the joints' position limits out (default: hard end stops)")
    parser.add_argument("--gravity", type=float, nargs=3, metavar=("GX", "GY", "GZ"),
                        default=None, help="gravity of the ground (default 0 0 -9.81)")
    add_sweep(sub)
    for parser in commands.add_commands(sub):        # linearize, fit
        add_library(parser)
    add_library(fmu_command.add_command(sub))        # export --fmu
    return {"animate": animate, "diagram": diagram, "studio": studio, "import": import_urdf,
            "sweep": sweep, "linearize": linearize, "fit": fit, "export": export}


def animate(args):
    from ..animation import cli_animate        # the faces load only when asked for
    return cli_animate(args, load_model(args.model, args.library))


def diagram(args):
    from ..diagram import cli_diagram
    return cli_diagram(args, load_model(args.model, args.library, validate=False))


def studio(args):
    from ..studio import cli_studio
    return cli_studio(args)


def import_urdf(args):
    from ..urdf import cli_import
    return cli_import(args)


def export(args):
    from ..fmu import command as fmu_command
    return fmu_command.run_command(args, load_model(args.model, args.library))


def sweep(args):
    from ..analysis.sweep_cli import run_command
    return run_command(args, load_model(args.model, args.library))


def linearize(args):
    from ..analysis import commands
    return commands.run_linearize(args, load_model(args.model, args.library))


def fit(args):
    from ..analysis import commands
    try:
        return commands.run_fit(args, load_model(args.model, args.library))
    except kn.SimulationError as exc:
        error(exc)
        return EXIT_SIMULATION
