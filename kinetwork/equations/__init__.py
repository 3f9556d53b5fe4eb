"""From a validated model to its equations: assembly (Newton-Euler over the spanning tree),
1-D networks and blocks, loops, cut wrenches and the Signal descriptors of the probes, gathered
in an immutable ``System``."""

from ..graph.model import install_compiler
from .system import System

install_compiler(System)

__all__ = ["System"]
