"""Analysis of a model beyond one simulation: linearisation, equilibria, modes, frequency
response, parameter sensitivities and fitting, sweeps and Monte Carlo.

Every derivative here is CasADi's algorithmic differentiation of the compiled System, never a
finite difference. Names are imported on first use.
"""

import importlib

#: public name -> its module here; imported on first use (PEP 562), so the command line's
#: parsers, which live beside them, do not load every analysis to run a simulation
_NAMES = {
    "Equilibrium": "equilibria", "equilibrium": "equilibria",
    "Fit": "fitting", "fit": "fitting",
    "Linearization": "linear", "linearize": "linear",
    "Mode": "modal", "bode": "modal", "modes": "modal", "plot_bode": "modal",
    "Sensitivity": "sensitivities", "sensitivity": "sensitivities",
    "Distribution": "sweep", "normal": "sweep", "sample": "sweep", "sweep": "sweep",
    "uniform": "sweep",
}
__all__ = list(_NAMES)


def __getattr__(name):
    try:
        module = importlib.import_module(f"{__name__}.{_NAMES[name]}")
    except KeyError:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}") from None
    return getattr(module, name)


def __dir__():
    return sorted(set(globals()) | set(_NAMES))
