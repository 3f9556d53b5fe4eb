"""The two exceptions every user-facing refusal or failure goes through."""


#: problems a ModelError keeps, and shows in its message: a file of a million broken
#: components is reported by its first problems and their count, not a million lines
MAX_PROBLEMS, SHOWN_PROBLEMS = 1000, 100


class ModelError(ValueError):
    """Bad input: a model, file or parameter that cannot be accepted.

    ``problems`` lists every diagnostic found (each a string naming its place; the first
    MAX_PROBLEMS of ``count``); the message joins them (the first SHOWN_PROBLEMS), so one
    raise reports all of them at once.
    """

    def __init__(self, problems, count=None):
        if isinstance(problems, str):
            problems = [problems]
        problems = list(problems)
        #: how many problems were found, of which ``problems`` keeps the first MAX_PROBLEMS
        #: (``count``: of a ModelError raised again with its problems placed)
        self.count = max(len(problems), count or 0)
        self.problems = problems[:MAX_PROBLEMS]
        if self.count == 1:
            message = self.problems[0]
        else:
            shown = self.problems[:SHOWN_PROBLEMS]
            message = f"{self.count} problems:\n" + "\n".join(f"  - {p}" for p in shown)
            if self.count > len(shown):
                message += (f"\n  ... and {self.count - len(shown)} more (the same kind of "
                            f"mistake repeated, most likely)")
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
