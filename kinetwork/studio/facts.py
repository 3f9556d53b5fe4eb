"""What the page learns from the server instead of knowing it: the integration methods and
their docs, the simulation settings with their units, defaults and bounds, and the studio's
own limits (``GET /api/facts``)."""

from ..schema import schema
from ..solver.driver import DEFAULTS
from ..solver.methods import METHODS
from . import files, jobs, runs, work

#: the simulation settings shown in the model's panel, in order, with their unit and doc
SETTINGS = (("t_end", "s", "end time of the run"),
            ("n_points", "", "points of the output grid, the start and the end included"),
            ("method", "", "integration method"),
            ("rtol", "", "relative tolerance of the variable-step methods"),
            ("atol", "", "absolute tolerance of the variable-step methods"),
            ("step", "s", "largest step of the fixed-step methods (default: the output "
                          "spacing)"))


def facts():
    """``{"methods", "settings", "limits", "phases"}``."""
    properties = schema()["properties"]["simulation"]["properties"]
    settings = []
    for name, unit, doc in SETTINGS:
        spec = properties.get(name, {})
        settings.append({"name": name, "unit": unit, "doc": doc, "default": DEFAULTS.get(name),
                         "type": spec.get("type"),
                         "minimum": spec.get("minimum", spec.get("exclusiveMinimum")),
                         "exclusive": "exclusiveMinimum" in spec})
    methods = [{"name": name, "doc": method.doc, "fixed": bool(method.fixed),
                "dae": bool(method.dae)} for name, method in METHODS.items()]
    return {
        "methods": methods,
        "settings": settings,
        "phases": list(jobs.PHASES),
        "limits": {"values": work.MAX_VALUES, "sweep_members": work.MAX_MEMBERS,
                   "runs_at_once": runs.MAX_RUNNING, "file_bytes": files.MAX_FILE_SIZE,
                   "cancel_grace_s": dict(jobs.CANCEL_GRACE)},
    }
