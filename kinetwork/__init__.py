"""kinetwork: acausal, component-based multibody modeling with CasADi.

Wire components into a :class:`Model`, compile it to a :class:`System` of minimal
coordinates, :func:`simulate` it and read the probes from the :class:`Results`.

Layers, each importing only those before it: ``errors``, ``util``, ``expr``, ``spatial``
(helpers) -> ``components`` (what a user places) -> ``graph`` (model, topology, files) ->
``equations`` (the System) -> ``simulation`` (driver, methods, JIT cache, Results) -> the
faces: ``plot``, ``schema``, ``symbolic``, ``cli``.
"""

from . import animation as _animation  # noqa: F401  (installs Results.animate)
from . import diagram as _diagram  # noqa: F401  (installs Model._repr_svg_ for Jupyter)
from . import plot as _plot  # noqa: F401  (installs Results.plot)
from . import examples
from .analysis.sweep import normal, sample, sweep, uniform
from .components import electrical, multibody, rotational, signals, translational
from .components.probe import Probe
from .equations.system import System
from .errors import IdealisedInertiaWarning, ModelError, SimulationError
from .graph.io import dumps, load, loads
from .graph.model import Model
from .graph.subsystem import Subsystem
from .schema import schema
from .simulation.driver import simulate
from .simulation.methods import METHODS
from .simulation.results import Results
from .urdf import from_urdf
from .analysis import bode, equilibrium, fit, linearize, modes, plot_bode, sensitivity
# kn.plot is the function (kn.plot([res_a, res_b])), not its module
from .plot import plot  # noqa: E402  isort: skip

__version__ = "0.1.0"

__all__ = ["IdealisedInertiaWarning", "METHODS", "Model", "ModelError", "Probe", "Results",
           "SimulationError", "Subsystem", "System", "dumps", "examples", "from_urdf", "load",
           "loads", "electrical", "multibody", "plot", "rotational", "schema", "signals",
           "simulate", "translational"]
__all__ += ["bode", "equilibrium", "fit", "linearize", "modes", "plot_bode", "sensitivity"]
__all__ += ["normal", "sample", "sweep", "uniform"]
