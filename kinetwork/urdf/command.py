"""``kinetwork import ROBOT.urdf -o MODEL.json``."""

import os

from ..errors import ModelError
from ..graph.io import dumps
from ..outputs import check, filler, write
from .load import from_urdf


def cli_import(args):
    """``kinetwork import ROBOT.urdf -o MODEL.json``: write the model; the exit code."""
    gravity = (0.0, 0.0, -9.81) if args.gravity is None else tuple(args.gravity)
    force = getattr(args, "force", False)
    reads = [("the URDF", args.source)]
    check(args.out, "model", what="-o", reads=reads, force=force)   # before reading it
    model = from_urdf(args.source, probes=args.probes, floating=args.floating, gravity=gravity,
                      limits=not getattr(args, "no_limits", False))
    text = dumps(model, os.path.dirname(os.path.abspath(args.out))).encode("utf-8")

    try:
        write(args.out, filler(text), "model", what="-o", reads=reads, force=force)
    except OSError as exc:
        raise ModelError(f"cannot write {args.out}: {exc.strerror or exc}") from None
    parts = model.components.values()
    states = sum(c.dof for c in parts if c.role == "joint")
    bodies = sum(1 for c in parts if c.role == "body" and c.mass != 0)
    print(f"{args.out}: {model.name!r}, {states} degrees of freedom, {bodies} bodies, "
          f"{len(model.components)} components")
    return 0
