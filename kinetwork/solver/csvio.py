"""Results as a CSV table any CSV reader takes as it is, with a sidecar for the rest.

``Results.to_csv("x.csv")`` writes two files, each atomically under the output policy
(``kinetwork.outputs``):

- ``x.csv``: the header row (``t``, then one column per probe quantity: ``probe1.angle``,
  vectors as ``probe1.position[0]``, ``[1]``, ``[2]``, orientations as
  ``probe1.orientation[0,1]``) and rows of numbers, nothing else, so ``pandas.read_csv``,
  ``numpy.loadtxt(..., skiprows=1)`` or a spreadsheet reads every column as numbers, whether the
  run finished or not;
- ``x.meta.json`` (the sidecar, :func:`sidecar`): what is not data. Every signal with its unit,
  shape, probe, quantity and the port measured; the run's settings; for a run that stopped
  early where and why (``partial``); for a table whose writing was stopped (a signal, a time
  limit) the rows written and why (``cut``); and the SHA-256 of the CSV, so a sidecar that
  no longer describes its table (the CSV edited, or written by another program) is noticed,
  never believed.

:func:`read_csv` reads the pair back into a :class:`Table`, read by name as ``Results`` is
(``table["probe1.position"]`` is (n, 3)), with units. A CSV without a sidecar reads too (units
unknown), and so does one of the older format that ended with a ``# partial: ...`` line.
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import os
import re
import warnings

import numpy as np

from ..errors import KinetworkWarning, ModelError
from ..util import suggest

FORMAT = "kinetwork.results"
VERSION = 1
SUFFIX = ".meta.json"
#: a column of a vector or matrix signal: ``name[i]`` or ``name[i,j]``
_ELEMENT = re.compile(r"^(?P<name>.+)\[(?P<index>\d+(?:,\d+)?)\]$")
#: the last line of a partial CSV before the sidecar (kinetwork 0.1's format)
_OLD_TRAILER = "# partial: "


class SidecarWarning(KinetworkWarning):
    """A CSV's sidecar left out: unreadable, of another kind, or describing another table
    (the CSV changed since it was written). The table is read without units."""


def sidecar(path: str | os.PathLike) -> str:
    """The sidecar of the CSV at ``path``: ``x.csv`` -> ``x.meta.json`` (any other name gets
    ``.meta.json`` appended: ``x.txt`` -> ``x.txt.meta.json``)."""
    text = os.fspath(path)
    base = text[:-4] if text.lower().endswith(".csv") else text
    return base + SUFFIX


def describe(results, rows: int, digest: str, cut: str | None) -> dict:
    """The sidecar's content for ``results`` written as ``rows`` rows hashing to ``digest``;
    ``cut``: why the writing stopped before the last row, or None."""
    signals = []
    for sig in results.signals.values():
        entry = {"name": sig.name, "unit": sig.unit, "shape": list(sig.shape),
                 "probe": sig.probe, "quantity": sig.quantity,
                 "columns": sig.column_names()}
        port = results.probe_targets.get(sig.probe)
        if port:
            entry["port"] = port
        signals.append(entry)
    partial = None
    if results.partial is not None:
        partial = {"t_reached": float(results.partial["t_reached"]),
                   "reason": " ".join(str(results.partial["reason"]).split())}
    if cut is not None:
        last = float(results.t[rows - 1]) if rows else None
        cut = {"reason": cut, "rows": rows, "t_written": last,
               "t_reached": float(results.t[-1]) if len(results.t) else None}
    return {"format": FORMAT, "version": VERSION, "csv": {"rows": rows, "sha256": digest},
            "columns": {"t": "s", **{c: s["unit"] for s in signals for c in s["columns"]}},
            "signals": signals, "settings": _plain(results.settings), "partial": partial,
            "cut": cut}


def _plain(value):
    """``value`` with what JSON cannot hold left out (CasADi objects, arrays as lists)."""
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()
                if _plain(v) is not None or v is None}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, (np.integer, np.floating)):
        return value.item()
    if isinstance(value, float) and not np.isfinite(value):
        return repr(value)
    if value is None or isinstance(value, (str, int, float, bool)):
        return value
    return None


class Table:
    """Results read back from a CSV file (:func:`read_csv`): ``table.t``, ``table["name"]``.

    Scalars read as (n,), vectors as (n, 3), orientations as (n, 3, 3), as ``Results`` gives
    them; a single column by its CSV name (``"probe1.position[1]"``) too.

    Attributes
    ----------
    t : numpy.ndarray
        The times [s].
    columns : list of str
        The CSV's header, ``t`` first.
    units : dict
        Column and signal name -> unit ("" where the sidecar is missing).
    partial : dict or None
        ``{"t_reached", "reason"}`` of a run that stopped early.
    cut : dict or None
        ``{"reason", "rows", "t_written", "t_reached"}`` of a table whose writing stopped.
    settings : dict
        The run's settings (t_end, method, rtol, ...), from the sidecar.
    signals : dict
        Signal name -> ``{"unit", "shape", "probe", "quantity", "port", "columns"}``.
    path, meta_path : str
        The CSV and its sidecar (None when it was not there or not believed).
    """

    def __init__(self, path, header, data, meta, meta_path):
        self.path, self.meta_path = os.fspath(path), meta_path
        self.columns = list(header)
        self._data = data
        self.t = data[:, 0]
        meta = meta or {}
        self.partial = meta.get("partial")
        self.cut = meta.get("cut")
        self.settings = dict(meta.get("settings") or {})
        self.signals = {s["name"]: dict(s) for s in meta.get("signals") or []
                        if set(s.get("columns", ())) <= set(header)}
        for name, columns in _grouped(header[1:]).items():
            self.signals.setdefault(name, {"unit": "", "shape": _shape(columns),
                                           "columns": columns})
        units = meta.get("columns") or {}
        self.units = {c: units.get(c, "s" if c == "t" else "") for c in header}
        self.units.update({name: s.get("unit", "") for name, s in self.signals.items()})

    @property
    def status(self) -> str:
        """``"ok"``, ``"partial"`` (the run stopped early) or ``"cut"`` (the writing did)."""
        return "cut" if self.cut else "partial" if self.partial else "ok"

    def keys(self) -> list[str]:
        return ["t", *self.signals]

    def __contains__(self, key: object) -> bool:
        return key in self.columns or key in self.signals

    def __len__(self) -> int:
        return len(self.t)

    def __getitem__(self, key: str) -> np.ndarray:
        if key in self.columns:
            return self._data[:, self.columns.index(key)]
        if key in self.signals:
            sig = self.signals[key]
            cols = [self.columns.index(c) for c in sig["columns"]]
            return self._data[:, cols].reshape(len(self.t), *sig["shape"])
        raise KeyError(f"{key!r:.200}{suggest(key, self.keys())}; available: "
                       f"{', '.join(self.keys())}")

    def to_pandas(self):
        """A ``pandas.DataFrame`` indexed by ``t``, one column per CSV column;
        ``df.attrs["units"]`` maps every column to its unit (as ``Results.to_pandas``)."""
        import pandas as pd
        frame = pd.DataFrame(self._data[:, 1:], columns=self.columns[1:],
                             index=pd.Index(self.t, name="t"))
        frame.attrs["units"] = {c: self.units[c] for c in self.columns[1:]}
        frame.attrs.update({k: v for k, v in self.settings.items()
                            if isinstance(v, (int, float, str, bool))})
        if self.partial:
            frame.attrs["partial_t_reached"] = self.partial["t_reached"]
            frame.attrs["partial_reason"] = self.partial["reason"]
        return frame

    def __repr__(self) -> str:
        span = f"t = {self.t[0]:g} .. {self.t[-1]:g} s" if len(self.t) else "no rows"
        return (f"<Table {os.path.basename(self.path)}: {len(self.t)} points, {span}, "
                f"{len(self.signals)} signals, {self.status}>")


def _grouped(columns):
    """Signal name -> its columns, from the CSV names alone (``a[0]``, ``a[1]`` -> ``a``)."""
    groups = {}
    for column in columns:
        m = _ELEMENT.match(column)
        groups.setdefault(m.group("name") if m else column, []).append(column)
    return groups


def _shape(columns):
    indices = [_ELEMENT.match(c) for c in columns]
    if not all(indices):
        return []
    parts = [tuple(int(i) for i in m.group("index").split(",")) for m in indices]
    return [max(p[k] for p in parts) + 1 for k in range(len(parts[0]))]


def read_csv(path: str | os.PathLike) -> Table:
    """Read a CSV of results (``Results.to_csv``, ``kinetwork run --out``) and its sidecar.

    Parameters
    ----------
    path : str or os.PathLike
        The CSV file; its sidecar (:func:`sidecar`) is read when it is there and describes
        this very table (its SHA-256 matches), else left out with a warning.

    Returns
    -------
    Table
        ``table.t``, ``table["probe1.angle"]`` (vectors as (n, 3)), ``table.units``,
        ``table.partial``, ``table.settings``, ``table.to_pandas()``.

    Raises
    ------
    ModelError
        Not a CSV table of numbers with a header row whose first column is ``t``.
    """
    where = os.fspath(path)
    try:
        with open(where, "rb") as fh:       # read whole: hashed as it is
            raw = fh.read()
    except OSError as exc:
        raise ModelError(f"{where}: cannot read it ({exc.strerror or exc})") from None
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise ModelError(f"{where}: not UTF-8 text (byte {exc.start})") from None
    lines = text.splitlines()
    partial = None
    if lines and lines[-1].startswith(_OLD_TRAILER):          # written before the sidecar
        partial = {"t_reached": None, "reason": lines.pop()[len(_OLD_TRAILER):]}
    try:
        header = next(csv.reader([lines[0]])) if lines else []
    except csv.Error as exc:
        raise ModelError(f"{where}: not a CSV table ({exc})") from None
    header = [h.strip() for h in header]
    if not header or header[0] != "t":
        raise ModelError(f"{where}: not a table of results (its header must start with 't')")
    if not any(line.strip() for line in lines[1:]):
        data = np.empty((0, len(header)))
    else:
        data = _numbers(where, lines[1:], len(header))
    meta, meta_path = _sidecar(where, raw)
    if meta is None and partial is not None:
        meta = {"partial": partial}
    return Table(where, header, data, meta, meta_path)


def _numbers(where, lines, width):
    """The rows of numbers of ``lines``: numpy's reader in C, else row by row to say where
    it is not."""
    try:
        return np.loadtxt(io.StringIO("\n".join(lines)), delimiter=",", ndmin=2,
                          dtype=float, comments=None).reshape(-1, width)
    except ValueError:
        return _rows(where, lines, width)


def _rows(where, lines, width):
    """The rows of numbers of ``lines``, or a ModelError naming the first bad one."""
    data = np.empty((len(lines), width))
    for k, row in enumerate(csv.reader(lines)):
        if len(row) != width:
            raise ModelError(f"{where}: row {k + 2} has {len(row)} values, the header {width}")
        try:
            data[k] = [float(v) for v in row]
        except ValueError as exc:
            raise ModelError(f"{where}: row {k + 2}: not a number ({exc})") from None
    return data


def _sidecar(where, raw):
    """(the sidecar's content, its path) when it describes this table, else (None, None)."""
    meta_path = sidecar(where)
    if not os.path.isfile(meta_path):
        return None, None
    try:
        with open(meta_path, encoding="utf-8") as fh:
            meta = json.load(fh)
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        warnings.warn(f"{meta_path}: not read ({exc}); {where} is read without units",
                      SidecarWarning, stacklevel=3)
        return None, None
    if not isinstance(meta, dict) or meta.get("format") != FORMAT:
        warnings.warn(f"{meta_path}: not a kinetwork results sidecar; {where} is read "
                      f"without units", SidecarWarning, stacklevel=3)
        return None, None
    digest = (meta.get("csv") or {}).get("sha256")
    if digest != hashlib.sha256(raw).hexdigest():
        warnings.warn(f"{meta_path} describes another table than {where} (the CSV changed "
                      f"since it was written); read without units, partial status or "
                      f"settings", SidecarWarning, stacklevel=3)
        return None, None
    return meta, meta_path
