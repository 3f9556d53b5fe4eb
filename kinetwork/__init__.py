"""kinetwork: acausal, component-based multibody modeling with CasADi.

Wire components into a :class:`Model`, compile it to a :class:`System` of minimal
coordinates, :func:`simulate` it and read the probes from the :class:`Results`.

Layers, each importing only those before it: ``errors``, ``outputs`` (the output policy),
``util``, ``expr``, ``units``, ``spatial``, ``upcalls`` (helpers) -> ``components`` (what a
user places) -> ``graph`` (model, topology, files) -> ``equations`` (the System) -> ``solver``
(the integration plan, driver, methods, JIT cache, Results; ``kinetwork.simulation``, its old
name, is a deprecated alias) -> the faces: ``plot``, ``schema``, ``symbolic``, ``animation``,
``diagram``, ``analysis``, ``studio``, ``fmu``, ``cli``. The four methods of a lower layer
that hand work up (``Model.compile``, ``Model._repr_svg_``, ``Results.plot``,
``Results.animate``) name the function they call in one table, ``kinetwork.upcalls``;
nothing is installed at import time.

``import kinetwork`` is quick: the names below are imported on first use (PEP 562), so a
script pays for CasADi, networkx and scipy when it builds a model, not when it imports the
package. What it does do: numpy's first import after it goes through ``_QuietBlas`` (its
BLAS threads told to sleep soon; the environment left as it was).
"""

import contextlib
import importlib
import importlib.util
import os
import sys

from .errors import (AssemblyBranchWarning, IdealisedInertiaWarning,
                     KinetworkDeprecationWarning, KinetworkWarning, ModelError, Problem,
                     SimulationError)

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
    "simulate": ("solver.plan", "simulate"),
    "METHODS": ("solver.methods", "METHODS"),
    "Results": ("solver.results", "Results"),
    "read_csv": ("solver.csvio", "read_csv"),
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
    "export_fmu": ("fmu.build", "export_fmu"),
    "uniform": ("analysis.sweep", "uniform"),
}

__all__ = ["AssemblyBranchWarning", "IdealisedInertiaWarning", "KinetworkDeprecationWarning",
           "KinetworkWarning", "ModelError", "Problem", "SimulationError", *_LAZY]


#: OpenBLAS's idle threads (numpy's BLAS) wait 2 ** this many cycles for work before they
#: sleep: see ``_QuietBlas``
BLAS_THREAD_TIMEOUT = 22


class _QuietBlas:
    """An import finder for numpy's first import after kinetwork's: it loads numpy with
    OpenBLAS's idle threads waiting 2 ** BLAS_THREAD_TIMEOUT cycles for work (a millisecond
    or two) before they sleep, rather than its 2 ** 28 (about 0.1 s). They spun that long
    as numpy loaded: 0.04-0.1 s of CPU in every process (a tenth of EngineV6's cached first
    answer), and again after each threaded BLAS call, which kinetwork's small matrices do
    not make. OpenBLAS reads ``OPENBLAS_THREAD_TIMEOUT`` as it loads: it is set around
    numpy's import only, so the environment is as it was after it and no process started
    later inherits it. Nothing when the user set it, or numpy came first. The usual finders
    find numpy; this one only wraps its loading, once."""

    done = False

    def find_spec(self, name, path=None, target=None):
        if self.done or name != "numpy":
            return None
        # (not out of sys.meta_path here: the import system is going through it)
        self.done = True
        if "OPENBLAS_THREAD_TIMEOUT" in os.environ:
            return None
        try:
            spec = importlib.util.find_spec(name)
            run = spec.loader.exec_module
        except Exception:          # noqa: BLE001 -- an unusual loader: numpy as it comes
            return None

        def exec_module(module):
            os.environ["OPENBLAS_THREAD_TIMEOUT"] = str(BLAS_THREAD_TIMEOUT)
            try:
                run(module)
            finally:
                os.environ.pop("OPENBLAS_THREAD_TIMEOUT", None)
                with contextlib.suppress(ValueError):
                    sys.meta_path.remove(self)
        spec.loader.exec_module = exec_module
        return spec


if "numpy" not in sys.modules:
    sys.meta_path.insert(0, _QuietBlas())


def __getattr__(name):
    try:
        module, attribute = _LAZY[name]
    except KeyError:
        raise AttributeError(f"module 'kinetwork' has no attribute {name!r}") from None
    found = importlib.import_module(f"{__name__}.{module}")
    value = found if attribute is None else getattr(found, attribute)
    globals()[name] = value       # the next use is a plain lookup
    return value


def __dir__():
    return sorted(set(globals()) | set(_LAZY))
