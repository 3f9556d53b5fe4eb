"""The experiment settings a model carries (``Model.simulation``), checked alike by files and
by ``simulate``; and the limits of what one run may cost."""

from ..util import finite, quote, suggest

SIMULATION_KEYS = ("t_end", "n_points", "method", "rtol", "atol", "step", "max_step")

#: the most steps a fixed-step run may take: beyond, a tiny step would run for days
MAX_STEPS = 10**9
#: the most memory the output of one run may take (8-byte values)
MAX_OUTPUT_BYTES = 2 * 2**30
#: the most points an output grid may have: time and one value each fill MAX_OUTPUT_BYTES
MAX_POINTS = MAX_OUTPUT_BYTES // 16


def check_setting(key, value):
    """The problem with one experiment setting, or None; files and ``simulate`` share it."""
    where = f"simulation.{key}"
    number = isinstance(value, (int, float)) and not isinstance(value, bool)
    if key not in SIMULATION_KEYS:
        return (f"{where}: unknown setting{suggest(key, SIMULATION_KEYS)}; "
                f"settings are {', '.join(SIMULATION_KEYS)}")
    if key == "method":
        if not isinstance(value, str) or not value:
            return f"{where}: must be a method name, got {quote(value, 40)}"
    elif key == "n_points":
        if not number or not isinstance(value, int) or value < 2:
            return f"{where}: must be an integer >= 2, got {quote(value, 40)}"
        if value > MAX_POINTS:
            return (f"{where} = {_count(value)}: the output alone (time and one value per "
                    f"point) would need {_bytes(16 * value)}, more than the "
                    f"{_bytes(MAX_OUTPUT_BYTES)} a run may keep; at most {MAX_POINTS} points")
    elif not number or not finite(value) or value <= 0:
        return f"{where}: must be a finite number > 0, got {quote(value, 40)}"
    return None


def check_settings(settings, t_start=0.0):
    """Every problem with a set of experiment settings (missing ones are not checked): each
    setting on its own, then what they cost together. A list, empty when all is well."""
    problems = [m for k, v in settings.items() if v is not None and (m := check_setting(k, v))]
    if problems:
        return problems
    t_end = settings.get("t_end")
    for key in ("step", "max_step"):
        step = settings.get(key)
        if t_end is not None and step is not None and t_end > t_start:
            problem = check_steps(t_end - t_start, step, key)
            if problem:
                problems.append(problem)
    return problems


def check_steps(span, step, key="step"):
    """The problem with steps of at most ``step`` (the setting ``key``) over ``span``
    seconds, or None."""
    steps = span / step
    if steps > MAX_STEPS:
        return (f"simulation.{key} = {step:g}: {_count(steps)} steps to cover {span:g} s, "
                f"more than the {_count(MAX_STEPS)} a run may take; use a larger {key}")
    return None


def check_output(n_points, n_values):
    """The problem with keeping ``n_values`` numbers per point (time, states, probe values)
    at ``n_points`` points in memory, or None."""
    need = 8 * n_points * n_values
    if need > MAX_OUTPUT_BYTES:
        return (f"simulation.n_points = {_count(n_points)}: the results ({n_values} values per "
                f"point: time, states and probe signals) would need {_bytes(need)}, more than "
                f"the {_bytes(MAX_OUTPUT_BYTES)} a run may keep; at most "
                f"{MAX_OUTPUT_BYTES // (8 * n_values)} points")
    return None


def _count(n):
    """An integer as such when short, else as 1.23e+45 (about 1e+5000 beyond floats)."""
    if isinstance(n, int) and n < 10**12:
        return f"{n}"
    if not finite(n):
        return f"about 1e+{int(n.bit_length() * 0.30103)}" if isinstance(n, int) else f"{n}"
    return f"{float(n):.3g}"


def _bytes(n):
    if not finite(n):
        return f"{_count(n)} bytes"
    for unit, size in (("TiB", 2**40), ("GiB", 2**30), ("MiB", 2**20), ("KiB", 2**10)):
        if n >= size:
            return f"{n / size:.3g} {unit}"
    return f"{n} bytes"
