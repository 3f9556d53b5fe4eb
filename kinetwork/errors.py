"""The records and exceptions every user-facing refusal, warning or failure goes through.

A diagnostic is a ``Problem``: its text for people, and its place as fields for programs
(the studio marks the block, port or wire from the fields, never from the text).
"""

#: the fields of a Problem besides its message, in the order of the studio's schema
FIELDS = ("component", "port", "parameter", "path", "hint", "severity")
SEVERITIES = ("error", "warning")


class Problem(str):
    """One diagnostic: the message (the string itself) and where it is.

    A ``str`` subclass, so every caller that read ``ModelError.problems`` as strings (``in``,
    ``startswith``, ``json.dumps``) keeps working; ``str(problem)`` is the message.

    Parameters
    ----------
    message : str
        The text for the person at the diagram, naming its place.
    component : str, optional
        The component it concerns, by its name in the model (a path such as
        ``"cyl1.piston"`` inside a subsystem).
    port : str, optional
        The port of that component.
    parameter : str, optional
        The parameter of that component (a model parameter: with ``component`` None).
    path : str, optional
        Where it is in the model's file, as a JSON path: ``"components[3].params.mass"``,
        ``"connections[2]"``, ``"parameters.L"``, ``"simulation.rtol"``.
    hint : str, optional
        What would fix it, when there is a likely fix (``"did you mean 'mass'?"``).
    severity : str
        "error" (refused) or "warning" (accepted, worth a look).
    """

    def __new__(cls, message, component=None, port=None, parameter=None, path=None,
                hint=None, severity="error"):
        if severity not in SEVERITIES:
            raise ValueError(f"severity must be one of {SEVERITIES}, got {severity!r}")
        self = super().__new__(cls, message)
        self.component, self.port, self.parameter = component, port, parameter
        self.path, self.hint, self.severity = path, hint, severity
        return self

    @property
    def message(self):
        return str.__str__(self)

    def __str__(self):
        return str.__str__(self)

    def __repr__(self):
        fields = ", ".join(f"{k}={getattr(self, k)!r}" for k in FIELDS
                           if getattr(self, k) is not None and k != "severity")
        return f"Problem({self.message!r}{', ' + fields if fields else ''})"

    def __reduce__(self):           # pickled whole: a ModelError crosses process pools
        return (type(self), (self.message, *(getattr(self, k) for k in FIELDS)))

    @classmethod
    def of(cls, problem, **fields):
        """``problem`` as a Problem (a string becomes one), its unset fields filled from
        ``fields``."""
        if not isinstance(problem, Problem):
            return cls(str(problem), **fields)
        return problem.where(**fields) if fields else problem

    def where(self, prefix="", **fields):
        """This problem with ``prefix`` before its message (unless it starts with it) and its
        unset fields filled from ``fields`` (a set field is kept: the nearer place knows
        best), but for ``severity``, which is set."""
        message = self.message
        if prefix and not message.startswith(prefix):
            message = f"{prefix}{message}"
        out = {k: getattr(self, k) for k in FIELDS}
        for key, value in fields.items():
            if value is None:
                continue
            if key == "severity":
                out[key] = value
            elif out[key] is None:
                out[key] = value
        return Problem(message, **out)

    def under(self, path):
        """This problem found inside the JSON object at ``path`` (an inline definition's
        ``"definitions.Arm"``): its own path, if any, joined after it."""
        fields = {k: getattr(self, k) for k in FIELDS}
        fields["path"] = f"{path}.{self.path}" if self.path else path
        return Problem(self.message, **fields)

    def to_dict(self):
        """``{"message", "component", "port", "parameter", "path", "hint", "severity"}``."""
        return {"message": self.message, **{k: getattr(self, k) for k in FIELDS}}


class ModelError(ValueError):
    """Bad input: a model, file or parameter that cannot be accepted.

    ``problems`` lists every diagnostic found, each a ``Problem`` (a string naming its place,
    with the place as fields too); the message joins them, so one raise reports all of them
    at once. ``ModelError("text", component="mass1", parameter="mass")`` gives its one
    problem fields.
    """

    def __init__(self, problems, **fields):
        if isinstance(problems, str):
            problems = [problems]
        self.problems = [Problem.of(p, **fields) for p in problems]
        if len(self.problems) == 1:
            message = self.problems[0].message
        else:
            message = f"{len(self.problems)} problems:\n" + "\n".join(
                f"  - {p.message}" for p in self.problems)
        super().__init__(message)


class SimulationError(RuntimeError):
    """A failed integration; ``results`` holds what was computed up to ``t_reached``."""

    def __init__(self, message, results=None, t_reached=None, reason=None, signal=None):
        super().__init__(message)
        self.results = results
        self.t_reached = t_reached
        #: why, in plain words (without the time and the solver's own message)
        self.reason = reason
        #: the signal (SIGINT, SIGTERM) that stopped the run, or None
        self.signal = signal


class KinetworkWarning(UserWarning):
    """Every warning kinetwork gives (a model accepted with a doubt, a slower path taken):
    ``warning.problem`` is its ``Problem`` (severity "warning"), ``str(warning)`` its
    message."""

    def __init__(self, problem, **fields):
        self.problem = Problem.of(problem, **fields).where(severity="warning")
        super().__init__(self.problem.message)


class IdealisedInertiaWarning(KinetworkWarning):
    """A body's inertia no rigid body has (principal moments breaking the triangle
    inequality), accepted as an idealisation: MSL's examples give parts that only turn about
    one axis inertias such as diag(2, 0, 0). The model simulates; a mass matrix made singular
    by it is still refused, naming the joints."""


class AssemblyBranchWarning(KinetworkWarning):
    """A kinematic loop assembled at the start on another branch than its guesses lie on
    (the pistons of MSL's EngineV6 below the crankshaft, with the default guesses): the
    model simulates that assembly; the warning names the loop, its joints and where they
    start, so that guesses (q0_guess) can pick the one meant."""


class KinetworkDeprecationWarning(KinetworkWarning, DeprecationWarning):
    """A name kinetwork still accepts for a release (``kinetwork.simulation``, now
    ``kinetwork.solver``): a DeprecationWarning, filtered as Python filters those, carrying
    its Problem like every kinetwork warning."""
