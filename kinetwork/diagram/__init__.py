"""Wiring diagrams: a port-aware layered layout of a model and its drawing as SVG.

``auto_layout(model)`` places the components a model's ``layout`` does not: the idea of ELK's
layered algorithm (Sugiyama's method) with ports on fixed sides. The flow runs left to right:
a wire from a port on a block's right side (``frame_b``, ``flange_b``, an output) to one on
another's left side (``frame_a``, ``flange_a``, an input) puts the second block one layer
further. Parts hanging only on a block's top or bottom ports (the spring-damper on a joint's
support and axis, a probe on an axis) stand above or below it in its layer, as in Modelica
diagrams. Cycles are broken where a depth-first walk from the model's inputs closes them (a
controller's measured feedback runs back), layers are given by the longest path, long wires
get placeholders in the layers they cross, the order within layers comes from barycentre
sweeps on the ports' heights and then swaps of neighbours, and the heights from an isotonic
fit that keeps that order while straightening wires. Components a layout places stay put;
the others are laid out by connected groups around them, each moved to the nearest free
room.

``svg(model)`` draws the blocks, their ports in Modelica's colours, and wires routed
orthogonally around the blocks (a shortest path with a price on bends, crossings and
overlaps on a grid of lines beside the blocks), then spread apart where they share a track.
``Model._repr_svg_`` (a model shows as its diagram in Jupyter) calls ``svg`` through
``kinetwork.upcalls``.

The package: ``blocks`` (sizes, colours, port sides), ``layout`` (the layered layout),
``routing`` (the wires), ``drawing`` (the SVG), ``command`` (``kinetwork diagram``).
"""

from .command import cli_diagram
from .drawing import svg
from .layout import auto_layout

__all__ = ["auto_layout", "cli_diagram", "svg"]
