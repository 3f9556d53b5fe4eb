"""The two exceptions every user-facing refusal or failure goes through."""


class ModelError(ValueError):
    """Bad input: a model, file or parameter that cannot be accepted.

    ``problems`` lists every diagnostic found (each a string naming its place); the message
    joins them, so one raise reports all of them at once.
    """

    def __init__(self, problems):
        if isinstance(problems, str):
            problems = [problems]
        self.problems = list(problems)
        if len(self.problems) == 1:
            message = self.problems[0]
        else:
            message = f"{len(self.problems)} problems:\n" + "\n".join(
                f"  - {p}" for p in self.problems)
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


class IdealisedInertiaWarning(UserWarning):
    """A body's inertia no rigid body has (principal moments breaking the triangle
    inequality), accepted as an idealisation: MSL's examples give parts that only turn about
    one axis inertias such as diag(2, 0, 0). The model simulates; a mass matrix made singular
    by it is still refused, naming the joints."""


class AssemblyBranchWarning(UserWarning):
    """A kinematic loop assembled at the start on another branch than its guesses lie on
    (the pistons of MSL's EngineV6 below the crankshaft, with the default guesses): the
    model simulates that assembly; the warning names the loop, its joints and where they
    start, so that guesses (q0_guess) can pick the one meant."""
