"""Distributions of parameters for ``kn.sample``: ``kn.normal(1, 0.05)``, ``kn.uniform(0.5, 2)``;
any frozen ``scipy.stats`` distribution (an object with ``rvs(size=, random_state=)``) works
the same."""

import math

import numpy as np

from ..errors import ModelError


class Distribution:
    """A distribution of one parameter for ``sample``: ``kn.normal(1, 0.05)``,
    ``kn.uniform(0.5, 2)``. Any object with scipy's ``rvs(size=, random_state=)`` (a frozen
    ``scipy.stats`` distribution) is accepted by ``sample`` as well."""

    def __init__(self, text, draw):
        self.text, self._draw = text, draw

    def rvs(self, size, random_state):
        return self._draw(np.random.default_rng(random_state), size)

    def __repr__(self):
        return self.text


def normal(mean, std):
    """Normal distribution of mean ``mean`` and standard deviation ``std`` (>= 0)."""
    mean, std = real(mean, "normal: mean"), real(std, "normal: std")
    if std < 0:
        raise ModelError(f"normal: std must be >= 0, got {std:g}")
    return Distribution(f"normal({mean:g}, {std:g})", lambda rng, n: rng.normal(mean, std, n))


def uniform(low, high):
    """Uniform distribution on [low, high)."""
    low, high = real(low, "uniform: low"), real(high, "uniform: high")
    if high < low:
        raise ModelError(f"uniform: high must be >= low, got low = {low:g}, high = {high:g}")
    return Distribution(f"uniform({low:g}, {high:g})",
                        lambda rng, n: rng.uniform(low, high, n))


def real(value, where):
    """``value`` as a finite float, or a ModelError naming ``where``."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.number)) or \
            not math.isfinite(value):
        raise ModelError(f"{where}: must be a finite number, got {value!r:.40}")
    return float(value)


def draw(distributions, n, seed, convert=None):
    """The drawn values (n, k) of each named distribution (or given sequence of n values,
    each read by ``convert(name, value, where)``), in the order of the dict, from one
    generator seeded with ``seed``."""
    convert = convert or (lambda name, value, where: real(value, where))
    rng = np.random.default_rng(seed)
    columns = []
    for name, dist in distributions.items():
        if hasattr(dist, "rvs"):
            drawn = np.asarray(dist.rvs(size=n, random_state=rng), dtype=float).ravel()
        elif hasattr(dist, "__len__") and not isinstance(dist, (str, bytes)):
            drawn = np.array([convert(name, v, f"sample: {name}[{i}]")
                              for i, v in enumerate(dist)])
        else:
            raise ModelError(f"sample: {name!r}: give a distribution (kn.normal, kn.uniform, "
                             f"a scipy.stats one) or {n} values, got {dist!r:.60}")
        if drawn.shape != (n,):
            raise ModelError(f"sample: {name!r}: {len(drawn)} values for n = {n} members")
        if not np.all(np.isfinite(drawn)):
            raise ModelError(f"sample: {name!r}: the distribution gave values that are not "
                             f"finite")
        columns.append(drawn)
    return np.column_stack(columns)
