"""From a validated model to its equations: assembly (Newton-Euler over the spanning tree),
1-D networks and blocks, loops, cut wrenches and the Signal descriptors of the probes, gathered
in an immutable ``System`` (what ``Model.compile`` builds: ``kinetwork.upcalls``)."""

from .system import System

__all__ = ["System"]
