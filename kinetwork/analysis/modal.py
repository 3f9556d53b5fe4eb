"""Modes and frequency response of a linearisation: natural frequencies, damping ratios,
mode shapes named by joint coordinate, and Bode plots in the house style (``kinetwork.plot``:
a panel per quantity, units on every axis).
"""

from dataclasses import dataclass

import numpy as np

from ..errors import ModelError
from ..util import quote, suggest
from .linear import Linearization, linearize

#: entries of a mode shape a REPL echo of a Mode shows (the largest)
REPR_SHAPE = 4


@dataclass
class Mode:
    """One eigenvalue of A (of a complex pair, the one with positive imaginary part).

    ``frequency`` is the natural frequency |lambda| [rad/s] (``hz`` in Hz), ``damping`` the
    ratio -Re(lambda)/|lambda| (1: critically damped or a real mode, < 0: unstable),
    ``damped_frequency`` Im(lambda); ``shape`` the eigenvector on the joint coordinates,
    scaled so its largest entry is 1 (complex: the phases of the coordinates)."""
    eigenvalue: complex
    frequency: float
    damping: float
    damped_frequency: float
    shape: dict

    @property
    def hz(self):
        return self.frequency / (2 * np.pi)

    @property
    def oscillatory(self):
        return self.damped_frequency > 0

    def __repr__(self):
        # the largest entries of the shape, in joint order: a robot's mode stays one line
        items = list(self.shape.items())
        largest = sorted(range(len(items)), key=lambda i: -abs(items[i][1]))[:REPR_SHAPE]
        shape = ", ".join(f"{k}: {_short(v)}" for i, (k, v) in enumerate(items)
                          if i in largest)
        if len(items) > REPR_SHAPE:
            shape += f", ... ({len(items) - REPR_SHAPE} smaller)"
        return (f"<Mode {self.frequency:.6g} rad/s ({self.hz:.4g} Hz), damping "
                f"{self.damping:.4g}; {shape}>")


def _short(v):
    return f"{v.real:.3g}" if abs(v.imag) < 1e-9 else f"{v:.3g}"


def modes(model, **linearize_args):
    """The modes of a Linearization (or of ``kn.linearize(model, **linearize_args)``),
    slowest first: one Mode per real eigenvalue and per complex pair."""
    lin = model if isinstance(model, Linearization) else linearize(model, **linearize_args)
    values, vectors = np.linalg.eig(lin.A) if lin.A.size else (np.zeros(0), np.zeros((0, 0)))
    coords = _coordinates(lin)
    out = []
    for lam, vec in zip(values, vectors.T):
        if lam.imag < -1e-12 * max(1.0, abs(lam)):
            continue                      # the other half of a pair
        freq = abs(lam)
        damping = -lam.real / freq if freq > 0 else 1.0
        shape = vec[coords] if coords else vec
        big = shape[np.argmax(np.abs(shape))] if shape.size else 1.0
        # a mode the joints take no part in (a controller's filter): a shape of zeros
        moves = abs(big) > 1e-9 * np.max(np.abs(vec))
        shape = shape / big if moves else np.zeros_like(shape)
        names = [lin.state_names[k] for k in coords] if coords else lin.state_names
        out.append(Mode(complex(lam), float(freq), float(damping), float(max(lam.imag, 0.0)),
                        dict(zip(names, shape.astype(complex)))))
    return sorted(out, key=lambda m: (m.frequency, m.damping))


def _coordinates(lin):
    """Positions of the joint coordinates among the states (those the speeds rate)."""
    system = getattr(getattr(lin, "plant", None), "system", None)
    names = set(system.coordinate_names) if system is not None else set()
    return [k for k, n in enumerate(lin.state_names) if n in names]


def bode(lin, input=None, output=None, omega=None):
    """Frequency response of one input to one output: (omega [rad/s], magnitude (the ratio,
    in output unit per input unit), phase [deg], unwrapped). ``input`` and ``output`` are
    names (default: the first); ``omega`` defaults to 500 points over the decades around the
    modes."""
    i, o = _channel(lin.input_names, input, "input"), _channel(lin.output_names, output,
                                                               "output")
    omega = default_omega(lin) if omega is None else np.asarray(omega, dtype=float)
    H = lin.frequency_response(omega)[o, i]
    return omega, np.abs(H), np.degrees(np.unwrap(np.angle(H)))


def default_omega(lin, n=500):
    """Frequencies two decades either side of the modes' natural frequencies."""
    freqs = np.abs(lin.eigenvalues)
    freqs = freqs[freqs > 0]
    low = np.min(freqs) / 100 if freqs.size else 0.01
    high = np.max(freqs) * 100 if freqs.size else 100.0
    return np.logspace(np.log10(low), np.log10(high), n)


def _channel(names, name, what):
    if not names:
        raise ModelError(f"bode: the linearisation has no {what}s (name them in "
                         f"kn.linearize's {what}s=[...])")
    if name is None:
        return 0
    if name not in names:
        raise ModelError(f"bode: {quote(name)} is not an {what}{suggest(name, names)}; "
                         f"{what}s are {', '.join(names)}")
    return names.index(name)


def plot_bode(lin, inputs=None, outputs=None, omega=None, figsize=None):
    """Bode plots of every input (columns) to every output (row pairs: magnitude in dB of
    the ratio, phase in degrees), frequency in rad/s, units on the axes.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from ..plot import pyplot
    from ..plotlayout import unit_label
    inputs = lin.input_names if inputs is None else \
        [inputs] if isinstance(inputs, str) else list(inputs)
    outputs = lin.output_names if outputs is None else \
        [outputs] if isinstance(outputs, str) else list(outputs)
    for name in inputs:
        _channel(lin.input_names, name, "input")
    for name in outputs:
        _channel(lin.output_names, name, "output")
    if not inputs or not outputs:
        raise ModelError("bode: name at least one input and one output")
    omega = default_omega(lin) if omega is None else np.asarray(omega, dtype=float)
    plt = pyplot()
    n_rows, n_cols = 2 * len(outputs), len(inputs)
    fig, axes = plt.subplots(n_rows, n_cols, squeeze=False, sharex=True, layout="constrained",
                             figsize=figsize or (0.4 + 4.0 * n_cols, 0.3 + 2.0 * n_rows))
    units = dict(zip(lin.input_names, lin.input_units))
    out_units = dict(zip(lin.output_names, lin.output_units))
    for j, u in enumerate(inputs):
        for i, y in enumerate(outputs):
            w, mag, phase = bode(lin, u, y, omega)
            ratio = f"{unit_label(out_units[y] or '1')}/{unit_label(units[u] or '1')}"
            top, low = axes[2 * i, j], axes[2 * i + 1, j]
            with np.errstate(divide="ignore"):
                top.semilogx(w, 20 * np.log10(mag))
            low.semilogx(w, phase)
            top.set_title(f"{u} \u2192 {y}", fontsize="medium")
            top.set_ylabel(f"magnitude [dB of {ratio}]")
            low.set_ylabel("phase [deg]")
            for ax in (top, low):
                ax.grid(True, which="both", alpha=0.3)
    for j in range(n_cols):
        axes[-1, j].set_xlabel("frequency [rad/s]")
    return fig
