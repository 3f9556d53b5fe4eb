"""Initial conditions as equations (``Model.initial``), their form checked alike by files
and by ``Model.set_initial``; ``kinetwork.equations.initial`` solves them.

Without them a model starts from its given states (a joint's q0, qd0, an inductor's i0).
With them, some states and model parameters are unknowns at the start, found by Newton from
equations on the states' derivatives at t = 0:

- ``steady``: every state's derivative is zero (all speeds and accelerations zero, every
  network state at rest); every state not ``fixed`` is an unknown;
- ``derivatives``: ``{state: value}``, given derivatives (``{"rev.qd": 0}``: no
  acceleration at the start); with ``steady``, they replace its zeros;
- ``fixed``: states that keep their given start (with ``steady`` only);
- ``solve``: model parameters (their values the first guess), and, without ``steady``,
  states, that are unknowns: MSL's InitSpringConstant is ``{"steady": true, "fixed":
  ["rev.q"], "solve": ["c"]}``, the spring constant holding the pendulum still at its start.

The unknowns and the equations must be as many; a system that cannot satisfy them is
refused with a ModelError naming them.
"""

from ..errors import ModelError
from ..util import check_number, quote, suggest

INITIAL_KEYS = ("steady", "derivatives", "fixed", "solve")


def check_initial(spec, where="initial"):
    """The problems with the form of an ``initial`` block, as a list (empty when well
    formed): names are checked against the compiled states when it is solved."""
    if not isinstance(spec, dict):
        return [f"{where}: must be an object, got {quote(spec, 40)}"]
    problems = [f"{where}.{quote(key, 40) if not isinstance(key, str) else key}: unknown key"
                f"{suggest(key, INITIAL_KEYS) if isinstance(key, str) else ''}; keys are "
                f"{', '.join(INITIAL_KEYS)}" for key in spec if key not in INITIAL_KEYS]
    if "steady" in spec and not isinstance(spec["steady"], bool):
        problems.append(f"{where}.steady: must be true or false, got {quote(spec['steady'], 40)}")
    for key in ("fixed", "solve"):
        names = spec.get(key, [])
        if not isinstance(names, list) or not all(isinstance(n, str) and n for n in names):
            problems.append(f"{where}.{key}: must be a list of names, got {quote(names, 60)}")
        elif len(set(names)) != len(names):
            problems.append(f"{where}.{key}: names repeated in {quote(names, 60)}")
    derivatives = spec.get("derivatives", {})
    if not isinstance(derivatives, dict):
        problems.append(f"{where}.derivatives: must be an object {{state: value}}, got "
                        f"{quote(derivatives, 60)}")
    else:
        for name, value in derivatives.items():
            try:
                check_number(value, f"{where}.derivatives.{name}")
            except ModelError as exc:
                problems.extend(exc.problems)
    if spec.get("fixed") and not spec.get("steady", False):
        problems.append(f"{where}.fixed: only with steady (without it every state keeps its "
                        f"start unless it is in solve)")
    return problems


def normalized(spec, where="initial"):
    """A checked copy of ``spec`` (a ModelError listing every problem otherwise)."""
    problems = check_initial(spec, where)
    if problems:
        raise ModelError(problems)
    out = {}
    if spec.get("steady"):
        out["steady"] = True
    if spec.get("derivatives"):
        out["derivatives"] = dict(spec["derivatives"])
    for key in ("fixed", "solve"):
        if spec.get(key):
            out[key] = list(spec[key])
    return out
