"""Results: the time grid, states and probe signals of a simulation, read by name.

Each signal comes with its ``Signal`` descriptor (name, unit, shape, probe, quantity, the port
measured), made where the quantity was defined; results, CSV columns and plots read them, never
guessing a shape from a size.
"""

import csv
import io

import numpy as np

from ..util import atomic_write, suggest


class Results:
    """Simulation output: ``res.t``, ``res["probe1.angle"]``, ``res.states``.

    Scalars read as (n_points,), vectors as (n_points, 3), orientations as (n_points, 3, 3).
    """

    def __init__(self, t, states, state_names, values, signals, stats=None, state_units=None,
                 settings=None, probe_targets=None, system=None):
        self.t = np.asarray(t, dtype=float)
        self.states = np.asarray(states, dtype=float).reshape(len(self.t), len(state_names))
        self.state_names = list(state_names)
        #: the Signal descriptor of every probe signal, in order
        self.signals = {sig.name: sig for sig in signals}
        self.units = {name: sig.unit for name, sig in self.signals.items()}
        self.units.update(zip(self.state_names, state_units or [""] * len(self.state_names)))
        #: integrator counters: rhs_evaluations, jacobian_evaluations, steps (CasADi methods)
        self.stats = dict(stats or {})
        #: what was asked for: t_end, n_points, method, rtol, atol, params
        self.settings = dict(settings or {})
        #: probe name -> the port it measures ("shoulder.axis")
        self.probe_targets = dict(probe_targets or {})
        #: None, or {"t_reached", "reason"} when the run stopped before t_end
        self.partial = None
        #: the System that made these results, when known: what ``animate`` draws
        self.system = system
        self._values = {}
        col = 0
        values = np.asarray(values, dtype=float).reshape(len(self.t), -1)
        for sig in self.signals.values():
            block = values[:, col:col + sig.size]
            col += sig.size
            self._values[sig.name] = block.reshape(len(self.t), *sig.shape)

    @property
    def method(self):
        """The integration method that produced these results (None if not recorded)."""
        return self.settings.get("method")

    @property
    def signal_names(self):
        return list(self.signals)

    @property
    def probes(self):
        """Probe name -> the quantities it recorded, in order."""
        out = {}
        for sig in self.signals.values():
            out.setdefault(sig.probe, []).append(sig.quantity)
        return out

    def keys(self):
        return ["t", *self.signals, *self.state_names]

    def __getitem__(self, key):
        if key == "t":
            return self.t
        if key in self._values:
            return self._values[key]
        if key in self.state_names:
            return self.states[:, self.state_names.index(key)]
        raise KeyError(f"{key!r:.200}{suggest(key, self.keys())}; available: "
                       f"{', '.join(self.keys())}")

    def __contains__(self, key):
        return key == "t" or key in self._values or key in self.state_names

    def __len__(self):
        return len(self.t)

    def columns(self):
        """(header, 2-D array) of the CSV: t, then every probe signal, vectors expanded."""
        header, cols = ["t"], [self.t[:, None]]
        for name, sig in self.signals.items():
            header += sig.column_names()
            cols.append(self._values[name].reshape(len(self.t), sig.size))
        return header, np.hstack(cols)

    def to_csv(self, path):
        """Write t and every probe signal as CSV with a header row, atomically (a failed
        write leaves an old file whole). Partial results end with a comment line
        ``# partial: ...`` saying where and why the run stopped."""
        header, data = self.columns()
        text = io.StringIO(newline="")
        writer = csv.writer(text)
        writer.writerow(header)
        writer.writerows([repr(float(v)) for v in row] for row in data)
        if self.partial is not None:
            reason = " ".join(str(self.partial["reason"]).split())
            text.write(f"# partial: the run stopped at t = {self.partial['t_reached']!r} s: "
                       f"{reason}\n")

        def write(tmp):
            with open(tmp, "w", newline="") as fh:
                fh.write(text.getvalue())
        atomic_write(path, write)

    def plot(self, probes=None, **kwargs):
        """Probe plots: one row per probe, one panel per quantity (matplotlib Figure)."""
        if _plotter is None:
            raise RuntimeError("no plotter installed: import kinetwork")
        return _plotter(self, probes=probes, **kwargs)

    def animate(self, path=None, **kwargs):
        """3-D animation of the run: a self-contained HTML page at ``path`` (the three.js
        player inlined, opens without a network) and ``gif=``/``mp4=`` videos; returns the
        Animation (see ``kinetwork.animation.animate`` for the options)."""
        if _animator is None:
            raise RuntimeError("no animator installed: import kinetwork")
        return _animator(self, path, **kwargs)

    def __repr__(self):
        return (f"<Results {len(self.t)} points, t = {self.t[0]:g} .. {self.t[-1]:g}, "
                f"{len(self.signals)} signals>")


#: what draws ``Results.plot``: installed by ``kinetwork.plot`` when it is imported (the plot
#: is a face over the results, a layer above them)
_plotter = None


def install_plotter(plot):
    """Set the function ``plot(results, probes=None, **kwargs)`` -> Figure of
    ``Results.plot``."""
    global _plotter
    _plotter = plot


#: what draws ``Results.animate``: installed by ``kinetwork.animation`` when it is imported
_animator = None


def install_animator(animate):
    """Set the function ``animate(results, path=None, **kwargs)`` of ``Results.animate``."""
    global _animator
    _animator = animate
