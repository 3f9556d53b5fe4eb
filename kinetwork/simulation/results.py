"""Results: the time grid, states and probe signals of a simulation, read by name."""

import csv

import numpy as np

from ..components.base import suggest


class Results:
    """Simulation output: ``res.t``, ``res["probe1.angle"]``, ``res.states``.

    Scalars read as (n_points,), vectors as (n_points, 3), orientations as (n_points, 3, 3).
    """

    def __init__(self, t, states, state_names, signals, signal_names, sizes, units,
                 stats=None, state_units=None, settings=None, probe_targets=None):
        self.t = np.asarray(t, dtype=float)
        self.states = np.asarray(states, dtype=float).reshape(len(self.t), len(state_names))
        self.state_names = list(state_names)
        self.units = dict(units)
        self.units.update(zip(self.state_names, state_units or [""] * len(self.state_names)))
        #: integrator counters: rhs_evaluations, jacobian_evaluations, steps (CasADi methods)
        self.stats = dict(stats or {})
        #: what was asked for: t_end, n_points, method, rtol, atol, params
        self.settings = dict(settings or {})
        #: probe name -> the port it measures ("shoulder.axis")
        self.probe_targets = dict(probe_targets or {})
        self._signals = {}
        col = 0
        signals = np.asarray(signals, dtype=float).reshape(len(self.t), -1)
        for name in signal_names:
            size = sizes[name]
            block = signals[:, col:col + size]
            col += size
            self._signals[name] = (block[:, 0] if size == 1 else
                                   block if size == 3 else block.reshape(-1, 3, 3))

    @property
    def method(self):
        """The integration method that produced these results (None if not recorded)."""
        return self.settings.get("method")

    @property
    def signal_names(self):
        return list(self._signals)

    @property
    def probes(self):
        """Probe name -> the quantities it recorded, in order."""
        out = {}
        for name in self._signals:
            probe, quantity = name.split(".", 1)
            out.setdefault(probe, []).append(quantity)
        return out

    def keys(self):
        return ["t", *self._signals, *self.state_names]

    def __getitem__(self, key):
        if key == "t":
            return self.t
        if key in self._signals:
            return self._signals[key]
        if key in self.state_names:
            return self.states[:, self.state_names.index(key)]
        raise KeyError(f"{key!r}{suggest(key, self.keys())}; available: "
                       f"{', '.join(self.keys())}")

    def __contains__(self, key):
        return key == "t" or key in self._signals or key in self.state_names

    def __len__(self):
        return len(self.t)

    def columns(self):
        """(header, 2-D array) of the CSV: t, then every probe signal, vectors expanded."""
        header, cols = ["t"], [self.t[:, None]]
        for name, value in self._signals.items():
            if value.ndim == 1:
                header.append(name)
                cols.append(value[:, None])
            elif value.ndim == 2:
                header += [f"{name}[{i}]" for i in range(3)]
                cols.append(value)
            else:
                header += [f"{name}[{i},{j}]" for i in range(3) for j in range(3)]
                cols.append(value.reshape(len(self.t), 9))
        return header, np.hstack(cols)

    def to_csv(self, path):
        """Write t and every probe signal as CSV with a header row."""
        header, data = self.columns()
        with open(path, "w", newline="") as fh:
            writer = csv.writer(fh)
            writer.writerow(header)
            writer.writerows([repr(float(v)) for v in row] for row in data)

    def plot(self, probes=None, **kwargs):
        """Probe plots: one row per probe, one panel per quantity (matplotlib Figure)."""
        from ..plot import plot_results
        return plot_results(self, probes=probes, **kwargs)

    def __repr__(self):
        return (f"<Results {len(self.t)} points, t = {self.t[0]:g} .. {self.t[-1]:g}, "
                f"{len(self._signals)} signals>")
