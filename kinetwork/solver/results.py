"""Results: the time grid, states and probe signals of a simulation, read by name.

Each signal comes with its ``Signal`` descriptor (name, unit, shape, probe, quantity, the port
measured), made where the quantity was defined; results, CSV columns and plots read them, never
guessing a shape from a size.
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import os
import threading
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from ..upcalls import upcall
from ..util import suggest

#: held while the signals of a Results are computed on first read
_COMPUTING = threading.RLock()
#: rows of a CSV written at a time: between blocks a write can be stopped (SIGINT, SIGTERM,
#: a cancel) and keep the rows before
CSV_BLOCK_ROWS = 4096

if TYPE_CHECKING:                     # annotations only
    from ..equations.signals import Signal
    from ..equations.system import System
    import pandas
    import xarray
    from matplotlib.figure import Figure


#: the name of the time dimension of every xarray kinetwork gives (``Results.to_xarray``,
#: ``kn.sweep``, ``kn.sample``): ``t``, as ``res.t`` and the CSV's first column
TIME = "t"


def signal_dims(shape):
    """The xarray dimensions of one value of a signal of ``shape``: none for a scalar,
    ``axis`` (x, y, z) for a vector, ``row`` and ``col`` for an orientation."""
    return {0: (), 1: ("axis",), 2: ("row", "col")}[len(shape)]


def signal_coords(signals):
    """The coordinates of the dimensions ``signal_dims`` gives ``signals``."""
    shapes = {len(sig.shape): sig.shape for sig in signals}
    coords = {}
    if 1 in shapes and shapes[1] == (3,):
        coords["axis"] = ["x", "y", "z"]
    if 2 in shapes:
        coords.update(row=[1, 2, 3], col=[1, 2, 3])
    return coords


def later_outputs(system: System, f_out, width: int, t, X, p) -> Callable[[], np.ndarray]:
    """The probe signals (``width`` columns, by the Function ``f_out``) of states X at times
    t and parameters p as a callable that computes them when first called (``Results``'
    ``values``), from copies: writes into ``res.states`` do not change the signals."""
    t, X, p = np.array(t, dtype=float), np.array(X, dtype=float), np.array(p, dtype=float)

    def values():
        return system.outputs_into(t, X, p, np.empty((len(t), width)), f_out)
    return values


class Results:
    """Simulation output: ``res.t``, ``res["probe1.angle"]``, ``res.states``.

    Scalars read as (n_points,), vectors as (n_points, 3), orientations as (n_points, 3, 3).
    ``values``, every signal's columns side by side, may be a callable that computes them: it
    is called once, when a signal is first read.
    """

    def __init__(self, t: np.ndarray, states: np.ndarray, state_names: Sequence[str],
                 values: np.ndarray | Callable[[], np.ndarray], signals: Sequence[Signal],
                 stats: dict | None = None,
                 state_units: Sequence[str] | None = None, settings: dict | None = None,
                 probe_targets: dict[str, str] | None = None, system: System | None = None):
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
        #: the probe signals' values (n_points, their columns), or a callable that computes
        #: them when first read (a run's probes are worth nothing to a caller reading states)
        self._pending = values if callable(values) else None
        self._split = None if callable(values) else self._columns(values)

    #: what differs between two runs of the same System and settings (``kept``, ``renewed``)
    _RUN_OWN = ("t", "states", "stats", "partial", "_pending", "_split", "_system", "_recipe")

    def kept(self) -> dict:
        """What these Results share with every run of the same System and settings (names,
        signals, units, settings): what ``renewed`` makes a repeated run's Results of,
        without the System (a replay's recipe keeps it beside the System: no reference
        back)."""
        return {k: v for k, v in self.__dict__.items() if k not in self._RUN_OWN}

    @classmethod
    def renewed(cls, kept: dict, t: np.ndarray, states: np.ndarray,
                values: np.ndarray | Callable[[], np.ndarray], stats: dict, params,
                system: System | None) -> Results:
        """The Results that ``__init__`` makes of a run with the names, signals, units and
        settings ``kept`` (``kept()`` of an earlier run's), its own grid ``t`` and ``states``
        (float arrays of the right shape, the caller's to give away), ``values``, ``stats``
        and ``params``: every container the Results' own, as ``__init__`` makes them, in a
        third of its time (the seed's: 23 against 61 us; a replay, ``replay.py``)."""
        res = cls.__new__(cls)
        res.__dict__.update(kept)
        res.t, res.states = t, states
        res.state_names, res.signals = list(kept["state_names"]), dict(kept["signals"])
        res.units, res.probe_targets = dict(kept["units"]), dict(kept["probe_targets"])
        res.stats = stats
        res.settings = {**kept["settings"], "params": dict(params or {})}
        res.partial, res.system = None, system
        res._pending = values if callable(values) else None
        res._split = None if callable(values) else res._columns(values)
        return res

    def _columns(self, values):
        """{signal name: its values} from the table of every signal's columns."""
        out, col = {}, 0
        values = np.asarray(values, dtype=float).reshape(len(self.t), -1)
        for sig in self.signals.values():
            out[sig.name] = values[:, col:col + sig.size].reshape(len(self.t), *sig.shape)
            col += sig.size
        return out

    @property
    def _values(self):
        """{signal name: its values (n_points, *shape)}, computed on first read (once: two
        threads reading at once wait for one computation)."""
        if self._split is None:
            with _COMPUTING:
                if self._split is None:
                    self._split, self._pending = self._columns(self._pending()), None
        return self._split

    @property
    def system(self) -> System | None:
        """The System that made these results (None when not known). Results from a pickle
        compile it again on first use."""
        if self._system is None and self._recipe is not None:
            build, args = self._recipe
            self._system, self._recipe = build(*args), None
        return self._system

    @system.setter
    def system(self, value):
        self._system, self._recipe = value, None

    def __getstate__(self):
        """Pickled with the System as its recipe (its model's text, compiled again only if
        the results' System is asked for): CasADi's expressions do not pickle."""
        self._values                  # noqa: B018 (computed: the System is not pickled)
        state = dict(self.__dict__)
        if self._system is not None:
            state["_system"], state["_recipe"] = None, self._system.__reduce__()
        return state

    def __copy__(self):
        """A shallow copy sharing the System (no recipe made: see ``__getstate__``)."""
        twin = type(self).__new__(type(self))
        twin.__dict__.update(self.__dict__)
        return twin

    @property
    def method(self) -> str | None:
        """The integration method that produced these results (None if not recorded)."""
        return self.settings.get("method")

    @property
    def signal_names(self) -> list[str]:
        return list(self.signals)

    @property
    def probes(self) -> dict[str, list[str]]:
        """Probe name -> the quantities it recorded, in order."""
        out = {}
        for sig in self.signals.values():
            out.setdefault(sig.probe, []).append(sig.quantity)
        return out

    def keys(self) -> list[str]:
        return ["t", *self.signals, *self.state_names]

    def __getitem__(self, key: str) -> np.ndarray:
        if key == "t":
            return self.t
        if key in self.signals:
            return self._values[key]
        if key in self.state_names:
            return self.states[:, self.state_names.index(key)]
        raise KeyError(f"{key!r:.200}{suggest(key, self.keys())}; available: "
                       f"{', '.join(self.keys())}")

    def __contains__(self, key: object) -> bool:
        return key == "t" or key in self.signals or key in self.state_names

    def __len__(self) -> int:
        return len(self.t)

    def columns(self) -> tuple[list[str], np.ndarray]:
        """(header, 2-D array) of the CSV: t, then every probe signal, vectors expanded."""
        return self.column_names(), self._rows(0, len(self.t))

    def column_names(self) -> list[str]:
        """The CSV's header: t, then every probe signal, vectors expanded."""
        header = ["t"]
        for sig in self.signals.values():
            header += sig.column_names()
        return header

    def _rows(self, start, stop):
        """Rows ``start:stop`` of the CSV table (t, then every signal expanded)."""
        n = stop - start
        cols = [self.t[start:stop, None]]
        for name, sig in self.signals.items():
            cols.append(self._values[name][start:stop].reshape(n, sig.size))
        return np.hstack(cols)

    def to_csv(self, path: str | os.PathLike, overwrite: bool = False,
               cancel: Callable[[], object] | None = None, stop: Any = None) -> str | None:
        """Write t and every probe signal as a CSV table (a header row, then numbers only)
        and its sidecar ``x.meta.json`` (units, settings, how the run ended: see
        ``kinetwork.solver.csvio``; ``kn.read_csv`` reads both back), under the output policy
        (``kinetwork.outputs``): each atomically (a failed write leaves an old file whole),
        never over the model file these results came from, a special file or a folder, nor
        over a file of another kind unless ``overwrite``.

        ``pandas.read_csv`` reads the table as it is, every column as numbers, complete or
        partial: where and why a run stopped early is in the sidecar (``partial``). The rows
        are written in blocks; when ``cancel()`` turns true, or SIGINT or SIGTERM arrives,
        between two blocks, the table ends there and the sidecar says where the writing
        stopped (``cut``; the signal is raised again once both files are whole: a
        KeyboardInterrupt). ``stop`` is a command's ``kinetwork.outputs.StopFlag``, in place
        of ``cancel`` and the signals.

        Returns
        -------
        str or None
            Why the writing stopped before the last row, or None.
        """
        from ..outputs import StopFlag, Stopped, catching_signals, check, model_files, write
        from .csvio import describe, sidecar
        reads = model_files(self.system.model if self.system is not None else None)
        meta_path = sidecar(path)
        check(meta_path, "meta", what="the CSV's sidecar", reads=reads, force=overwrite)
        flag = stop if stop is not None else StopFlag(cancel=cancel)
        line = io.StringIO(newline="")
        csv.writer(line).writerow(self.column_names())     # names such as "R[0,1]" are quoted
        header = line.getvalue()
        n = len(self.t)
        written = {"rows": 0, "sha256": None}

        def fill(tmp, told):
            digest = hashlib.sha256(header.encode("utf-8"))
            rows = 0
            with open(tmp, "w", newline="", encoding="utf-8") as fh:
                fh.write(header)
                while rows < n and (rows == 0 or told() is None):
                    block = self._rows(rows, min(n, rows + CSV_BLOCK_ROWS))
                    text = "".join(",".join(map(repr, row)) + "\n" for row in block.tolist())
                    fh.write(text)
                    digest.update(text.encode("utf-8"))
                    rows += len(block)
            written.update(rows=rows, sha256=digest.hexdigest())

        def fill_meta(tmp, told):
            cut = told() if written["rows"] < n else None
            meta = describe(self, written["rows"], written["sha256"], cut)
            with open(tmp, "w", encoding="utf-8") as fh:
                json.dump(meta, fh, indent=1, allow_nan=False)
                fh.write("\n")

        def both():
            reason = write(path, fill, "csv", reads=reads, force=overwrite, stop=flag,
                           cooperative=True)
            write(meta_path, fill_meta, "meta", what="the CSV's sidecar", reads=reads,
                  force=overwrite, stop=flag, cooperative=True)
            return reason

        if stop is not None:
            return both()
        with catching_signals(flag):
            reason = both()
        if flag.signum is not None:
            raise Stopped(flag.signum)
        return reason

    def to_pandas(self, states: bool = False) -> pandas.DataFrame:
        """A ``pandas.DataFrame`` indexed by time ``t`` [s], one column per CSV column (vectors
        as ``name[0]``, ...); ``df.attrs["units"]`` maps every column to its unit, and
        ``df.attrs`` also holds the run's settings and, for a partial run, where it stopped.
        ``states=True`` adds the states as columns."""
        pd = _optional("pandas", "to_pandas")
        header, data = self.columns()
        frame = pd.DataFrame(data[:, 1:], columns=header[1:],
                             index=pd.Index(self.t, name="t"))
        units = {}
        for name, sig in self.signals.items():
            units.update(dict.fromkeys(sig.column_names(), sig.unit))
        if states:
            for name in self.state_names:
                frame[name] = self[name]
                units[name] = self.units.get(name, "")
        frame.attrs.update(self._attrs())
        frame.attrs["units"] = units
        return frame

    def to_xarray(self, states: bool = False) -> xarray.Dataset:
        """An ``xarray.Dataset``: coordinate ``t`` [s], one variable per signal (vectors along
        ``axis`` = x, y, z; orientations along ``row``, ``col``), each with ``attrs["units"]``,
        the probe and the port measured; the run's settings in the dataset's attrs.
        ``states=True`` adds the states as variables."""
        xr = _optional("xarray", "to_xarray")
        variables = {}
        for name, sig in self.signals.items():
            dims = (TIME,) + signal_dims(sig.shape)
            attrs = {"units": sig.unit, "probe": sig.probe, "quantity": sig.quantity}
            target = self.probe_targets.get(sig.probe)
            if target:
                attrs["port"] = target
            variables[name] = xr.Variable(dims, self._values[name], attrs)
        if states:
            for name in self.state_names:
                variables[name] = xr.Variable((TIME,), self[name],
                                              {"units": self.units.get(name, "")})
        coords = {TIME: (TIME, self.t, {"units": "s", "long_name": "time"}),
                  **signal_coords(self.signals.values())}
        return xr.Dataset(variables, coords=coords, attrs=self._attrs())

    def _attrs(self):
        """The run's settings and outcome as flat attributes (netCDF-safe values)."""
        out = {}
        for key, value in self.settings.items():
            if isinstance(value, (int, float, str, bool)):
                out[key] = value
        for key, value in (self.settings.get("params") or {}).items():
            if isinstance(value, (int, float)):
                out[f"param.{key}"] = float(value)
        if self.partial is not None:
            out["partial_t_reached"] = float(self.partial["t_reached"])
            out["partial_reason"] = str(self.partial["reason"])
        return out

    def summary(self) -> str:
        """A few lines on the run: points, time span, method and counters, how it ended."""
        lines = [repr(self)]
        if self.method:
            lines.append(f"method: {self.method}" + "".join(
                f", {k} = {self.settings[k]:g}" for k in ("rtol", "atol")
                if isinstance(self.settings.get(k), (int, float))))
        counters = {k: v for k, v in self.stats.items() if isinstance(v, (int, float))}
        if counters:
            lines.append(", ".join(f"{k.replace('_', ' ')}: {v:g}" for k, v in counters.items()))
        if self.partial is not None:
            lines.append(f"partial: stopped at t = {self.partial['t_reached']:g} s: "
                         f"{self.partial['reason']}")
        return "\n".join(lines)

    def _repr_html_(self):
        """Jupyter's rich display: the summary, a table of the signals with their units and
        final values, and the probe plots (an inline SVG)."""
        import html
        rows = []
        for name, sig in self.signals.items():
            last = np.asarray(self._values[name][-1])
            shown = np.array2string(last, precision=4, suppress_small=True, separator=", ") \
                if last.ndim else f"{float(last):.6g}"
            rows.append(f"<tr><td><code>{html.escape(name)}</code></td>"
                        f"<td>{html.escape(sig.unit)}</td><td>{html.escape(shown)}</td></tr>")
        text = "<br>".join(html.escape(line) for line in self.summary().splitlines())
        table = ("<table><thead><tr><th>signal</th><th>unit</th><th>at the end</th></tr>"
                 f"</thead><tbody>{''.join(rows)}</tbody></table>") if rows else ""
        figure = ""
        if self.signals and len(self.t) > 1:
            try:
                figure = _svg(upcall("plot")(self, _detached=True))
            except Exception as exc:        # a display must never raise in a notebook
                figure = f"<p>(no plot: {html.escape(str(exc))})</p>"
        return f"<div class='kinetwork-results'><p>{text}</p>{table}{figure}</div>"

    def plot(self, *names: str, **kwargs: Any) -> Figure:
        """Probe plots (a matplotlib Figure): every probe, or the probes and signals named
        (``res.plot("probe1.angle", "probe2")``); options as ``kinetwork.plot.plot_results``
        (``title``, ``hide_flat``, ``columns``, ...)."""
        return upcall("plot")(self, *names, **kwargs)

    def animate(self, path: str | os.PathLike | None = None, **kwargs: Any) -> Any:
        """3-D animation of the run: a self-contained HTML page at ``path`` (the three.js
        player inlined, opens without a network) and ``gif=``/``mp4=`` videos; returns the
        Animation (see ``kinetwork.animation.animate`` for the options)."""
        return upcall("animate")(self, path, **kwargs)

    def __repr__(self):
        return (f"<Results {len(self.t)} points, t = {self.t[0]:g} .. {self.t[-1]:g}, "
                f"{len(self.signals)} signals>")


def _optional(module, what):
    """Import an optional library, or say how to install it."""
    import importlib
    try:
        return importlib.import_module(module)
    except ImportError:
        raise ImportError(f"Results.{what} needs {module}: pip install 'kinetwork[data]' "
                          f"(or pip install {module})") from None


def _svg(fig):
    """A figure pyplot never saw (nothing to close, nothing shown twice) as inline SVG."""
    buffer = io.StringIO()
    fig.savefig(buffer, format="svg")
    text = buffer.getvalue()
    return text[text.index("<svg"):]
