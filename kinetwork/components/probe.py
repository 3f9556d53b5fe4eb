"""Probe: records quantities of the port it is wired to, adding nothing to the physics.

Each quantity a probe can record is one ``Quantity`` entry of ``quantities.py``: its unit,
its shape and its formula over a *view* of the measured port. The equations layer hands the
formula a view whose attributes are the port's variables as CasADi expressions (built only
when a formula reads them):

- 1-D flange: ``pos``, ``vel``, ``acc`` (its position and their rates) and ``flow`` (the
  torque or force the network puts through it);
- frame: ``r`` (origin, world), ``R`` (orientation, world), ``w`` (angular velocity, world),
  ``f`` and ``t`` (the cut force, and the cut torque about the world origin), and ``der(e)``,
  the exact time derivative of any expression of those;
- signal: ``value``.

A new probe quantity is one entry there: the results, the CSV columns and the plots take its
name, unit and shape from the ``Signal`` descriptor built from it.
"""

from .base import ANY, Component, Param, Port
# the table lives apart so the reference of every component can list it (reference.py)
from .quantities import QUANTITIES, Quantity  # noqa: F401  (re-exported)

_ALL = sorted({q for qs in QUANTITIES.values() for q in qs})


class Probe(Component, library=""):
    """Measures the port it is wired to: 1-D flange or frame (see QUANTITIES)."""
    role = "probe"
    port = Port(ANY, "Wire to the port to measure")
    quantities = Param(None, optional=True, kind="names", choices=_ALL,
                       doc="What to record (default: all of the port's domain)")

    def asked(self, domain):
        """The quantity names recorded on a port of ``domain``, in order."""
        return list(QUANTITIES[domain]) if self.quantities is None else list(self.quantities)
