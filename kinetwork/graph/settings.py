"""The experiment settings a model carries (``Model.simulation``), checked alike by files and
by ``simulate``."""

from ..util import finite, suggest

SIMULATION_KEYS = ("t_end", "n_points", "method", "rtol", "atol", "step")


def check_setting(key, value):
    """The problem with one experiment setting, or None; files and ``simulate`` share it."""
    where = f"simulation.{key}"
    number = isinstance(value, (int, float)) and not isinstance(value, bool)
    if key not in SIMULATION_KEYS:
        return (f"{where}: unknown setting{suggest(key, SIMULATION_KEYS)}; "
                f"settings are {', '.join(SIMULATION_KEYS)}")
    if key == "method":
        if not isinstance(value, str) or not value:
            return f"{where}: must be a method name, got {value!r:.40}"
    elif key == "n_points":
        if not number or not isinstance(value, int) or value < 2:
            return f"{where}: must be an integer >= 2, got {value!r:.40}"
    elif not number or not finite(value) or value <= 0:
        return f"{where}: must be a finite number > 0, got {value!r:.40}"
    return None
