"""Analysis of a model beyond one simulation: linearisation, equilibria, modes, frequency
response, parameter sensitivities and fitting, sweeps and Monte Carlo.

Every derivative here is CasADi's algorithmic differentiation of the compiled System, never a
finite difference. Each public name is imported on its own line, so that modules written side
by side each add one line.
"""

from .equilibria import Equilibrium, equilibrium
from .fitting import Fit, fit
from .linear import Linearization, linearize
from .modal import Mode, bode, modes, plot_bode
from .sensitivities import Sensitivity, sensitivity
from .sweep import Distribution, normal, sample, sweep, uniform
