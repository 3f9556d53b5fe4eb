"""kinetwork: acausal, component-based multibody modeling with CasADi.

Wire components into a :class:`Model`, compile it to a :class:`System` of minimal
coordinates, :func:`simulate` it and read the probes from the :class:`Results`.

Layers, each importing only those before it: ``errors``, ``util``, ``expr``, ``spatial``
(helpers) -> ``components`` (what a user places) -> ``graph`` (model, topology, files) ->
``equations`` (the System) -> ``simulation`` (driver, methods, JIT cache, Results) -> the
faces: ``plot``, ``schema``, ``symbolic``, ``animation``, ``diagram``, ``analysis``, ``cli``.

``import kinetwork`` is quick: the names below are imported on first use (PEP 562), so a
script pays for CasADi, networkx and scipy when it builds a model, not when it imports the
package. The first use also installs the faces on the core classes (``Model.compile`` from
``equations``, ``Results.plot``, ``Results.animate``, ``Model._repr_svg_``).
"""

import importlib

from .errors import AssemblyBranchWarning, IdealisedInertiaWarning, ModelError, SimulationError

__version__ = "0.1.0"

#: public name -> (module below kinetwork, attribute; None: the module itself)
_LAZY = {
    "Model": ("graph.model", "Model"),
    "Subsystem": ("graph.subsystem", "Subsystem"),
    "load": ("graph.io", "load"),
    "loads": ("graph.io", "loads"),
    "dumps": ("graph.io", "dumps"),
    "Probe": ("components.probe", "Probe"),
    "multibody": ("components.multibody", None),
    "rotational": ("components.rotational", None),
    "translational": ("components.translational", None),
    "electrical": ("components.electrical", None),
    "signals": ("components.signals", None),
    "System": ("equations.system", "System"),
    "simulate": ("solver.driver", "simulate"),
    "METHODS": ("solver.methods", "METHODS"),
    "Results": ("solver.results", "Results"),
    "schema": ("schema", None),       # the module, callable: kn.schema()
    "from_urdf": ("urdf", "from_urdf"),
    "examples": ("examples", None),
    "plot": ("plot", None),           # the module, callable: kn.plot([res_a, res_b])
    "linearize": ("analysis.linear", "linearize"),
    "equilibrium": ("analysis.equilibria", "equilibrium"),
    "modes": ("analysis.modal", "modes"),
    "bode": ("analysis.modal", "bode"),
    "plot_bode": ("analysis.modal", "plot_bode"),
    "sensitivity": ("analysis.sensitivities", "sensitivity"),
    "fit": ("analysis.fitting", "fit"),
    "sweep": ("analysis.sweep", "sweep"),
    "sample": ("analysis.sweep", "sample"),
    "normal": ("analysis.sweep", "normal"),
    "uniform": ("analysis.sweep", "uniform"),
}

__all__ = ["AssemblyBranchWarning", "IdealisedInertiaWarning", "ModelError", "SimulationError", *_LAZY]

#: modules that install themselves on the core classes when imported
_FACES = ("equations", "plot")


def _install():
    for module in _FACES:
        importlib.import_module(f"{__name__}.{module}")
    # the animation and the diagram (with urllib, xml and their own code, 50 ms of every
    # ``kinetwork run``) are imported when first used, not when the first model is built
    graph = importlib.import_module(f"{__name__}.graph.model")
    if "_repr_svg_" not in vars(graph.Model):
        graph.Model._repr_svg_ = _repr_svg_
    results = importlib.import_module(f"{__name__}.solver.results")
    if results._animator is None:
        results.install_animator(_animate)


def _repr_svg_(model):
    """A model's diagram, for Jupyter: ``kinetwork.diagram`` replaces this when imported."""
    return importlib.import_module(f"{__name__}.diagram")._repr_svg_(model)


def _animate(results, path=None, **kwargs):
    """``Results.animate`` until ``kinetwork.animation`` is imported, which installs itself."""
    return importlib.import_module(f"{__name__}.animation").animate(results, path, **kwargs)


def __getattr__(name):
    try:
        module, attribute = _LAZY[name]
    except KeyError:
        raise AttributeError(f"module 'kinetwork' has no attribute {name!r}") from None
    _install()
    found = importlib.import_module(f"{__name__}.{module}")
    value = found if attribute is None else getattr(found, attribute)
    globals()[name] = value       # the next use is a plain lookup
    return value


def __dir__():
    return sorted(set(globals()) | set(_LAZY))
