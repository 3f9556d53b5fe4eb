"""``kinetwork import ROBOT.urdf -o MODEL.json``."""

from .load import from_urdf


def cli_import(args):
    """``kinetwork import ROBOT.urdf -o MODEL.json``: write the model; the exit code."""
    gravity = (0.0, 0.0, -9.81) if args.gravity is None else tuple(args.gravity)
    model = from_urdf(args.source, probes=args.probes, floating=args.floating, gravity=gravity,
                      limits=not getattr(args, "no_limits", False))
    model.save(args.out)
    parts = model.components.values()
    states = sum(c.dof for c in parts if c.role == "joint")
    bodies = sum(1 for c in parts if c.role == "body" and c.mass != 0)
    print(f"{args.out}: {model.name!r}, {states} degrees of freedom, {bodies} bodies, "
          f"{len(model.components)} components")
    return 0
