"""kinetwork: acausal, component-based multibody modeling with CasADi.

Wire components into a :class:`Model`, compile it to a :class:`System` of minimal
coordinates, :func:`simulate` it and read the probes from the :class:`Results`.
"""

from .components import multibody, rotational, signals, translational
from .components.probe import Probe
from .errors import ModelError, SimulationError
from .graph.io import dumps, load, loads
from .schema import schema
from .graph.model import Model
from .solver.integrate import METHODS, simulate
from .solver.results import Results
from .solver.system import System

__version__ = "0.1.0"

__all__ = ["METHODS", "Model", "ModelError", "Probe", "Results", "SimulationError", "System",
           "dumps", "load", "loads", "multibody", "rotational", "schema", "signals",
           "simulate",
           "translational"]
