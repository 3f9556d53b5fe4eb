"""The small ``kinetwork`` subcommands: ``schema`` (the JSON Schema of model files),
``cache`` (the compiled models), ``methods`` (the integrators), ``bench`` (the studies of a
source checkout) and ``examples`` (list or copy the shipped models)."""

import sys
import textwrap

import kinetwork as kn


def add(sub):
    """The parsers of ``schema``, ``cache``, ``methods``, ``bench`` and ``examples``;
    {name: handler}."""
    sub.add_parser("schema", help="print the JSON Schema of model files",
                   description="Print the JSON Schema (draft 2020-12) of the model format, "
                               "generated from the component declarations: point an editor "
                               "at it for completion and checks.")
    parser = sub.add_parser(
        "cache", help="show or empty the cache of compiled models",
        description="Show the folder of compiled models (the JIT cache), how many libraries it "
                    "holds and their size, the most recently used first; --clear empties it "
                    "of what kinetwork wrote there.")
    parser.add_argument("--clear", action="store_true", help="remove every compiled library")
    sub.add_parser("methods", help="list the integration methods",
                   description="List the integration methods a model can be run with.")
    parser = sub.add_parser(
        "bench", help="run the speed-against-accuracy studies (from a source checkout)",
        description="Run the benchmark studies of bench/ (work-precision against pinocchio, "
                    "MuJoCo and sympy; stiffness; long runs; chaos; scaling), writing CSV, "
                    "charts and bench/results/summary.md. Needs a source checkout and the "
                    "'bench' extras.")
    parser.add_argument("--quick", action="store_true", help="a smoke test of every study")
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
    return {"schema": schema, "cache": cache, "methods": methods, "bench": bench,
            "examples": examples}


def schema(args):
    import json
    print(json.dumps(kn.schema(), indent=2))
    return 0


def cache(args):
    from ..equations import stored
    from ..solver import jit
    if args.clear:
        removed = jit.clear_cache()
        print(f"removed {removed} file{'s' * (removed != 1)} from {jit.cache_dir()}")
        return 0
    info = jit.cache_info()
    print(f"{info['folder']}: {info['entries']} compiled librar"
          f"{'y' if info['entries'] == 1 else 'ies'}, {info['bytes'] / 2**20:.1f} MiB "
          f"(at most {jit.MAX_CACHE_BYTES / 2**20:.0f} MiB are kept)")
    print(f"  and {info['systems']} derived System{'s' * (info['systems'] != 1)} kept, "
          f"{info['systems_bytes'] / 2**20:.1f} MiB (at most "
          f"{stored.MAX_BYTES / 2**20:.0f} MiB)")
    for name, size, _ in info["libraries"][:20]:
        print(f"  {name}  {size / 1024:.0f} KiB")
    if info["entries"] > 20:
        print(f"  ... and {info['entries'] - 20} more")
    return 0


def methods(args):
    from ..solver.driver import DEFAULTS, METHODS
    width = max(map(len, METHODS))
    print(f"default: {DEFAULTS['method']}, rtol {DEFAULTS['rtol']:g}, atol {DEFAULTS['atol']:g}")
    for name, method in METHODS.items():
        kind = "fixed step" if method.fixed else "variable step"
        events = " and ".join(method.events)
        print(f"  {name:<{width}}  {kind:<13}  " + textwrap.fill(
            f"{method.doc}; events: {events}", 88, initial_indent=" " * (width + 19),
            subsequent_indent=" " * (width + 19)).lstrip())
    return 0


def bench(args):
    import pathlib
    import subprocess
    script = pathlib.Path(__file__).resolve().parents[2] / "bench" / "run.py"
    if not script.exists():
        raise kn.ModelError("bench: the studies live in the source checkout's bench/ folder, "
                            "which this installation does not have")
    return subprocess.call([sys.executable, str(script), *(["--quick"] if args.quick else [])])


def examples(args):
    from .. import examples as shipped
    if args.action == "copy":
        written = shipped.copy(args.name, args.folder)
        print(f"copied {args.name} to {written[0]}"
              + (f" (with {len(written) - 1} definition file{'s' if len(written) > 2 else ''})"
                 if len(written) > 1 else ""))
        print(f"run it: kinetwork run {written[0]}")
        return 0
    listed = shipped.summaries()
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
