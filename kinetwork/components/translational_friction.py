"""Translational friction with stiction, elastic gaps and stops (laws: ``friction.py``)."""

from .base import Param
from .friction import PartialBearingFriction, PartialElastoGap, PartialStop, stop_check


class Friction(PartialBearingFriction, library="translational"):
    """Dry friction with stiction between a sliding flange and its support (a mass on a rough
    surface: f_c = mu * m * g): stuck while the force holding it stays within peak * f_c, else
    sliding against f_c + d * v."""
    domain = "translational"
    f_c = Param(unit="N", min=0.0, doc="Coulomb friction force")
    peak = Param(1.0, unit="1", min=1.0, doc="Static over Coulomb friction force")
    d = Param(0.0, unit="N*s/m", min=0.0, doc="Viscous friction coefficient")


class ElastoGap(PartialElastoGap, library="translational"):
    """Translational spring and damper acting only while s_rel < s_rel0 (MSL's ElastoGap)."""
    domain = "translational"
    c = Param(unit="N/m", min=0.0, doc="Spring constant")
    d = Param(0.0, unit="N*s/m", min=0.0, doc="Damping constant")
    s_rel0 = Param(0.0, unit="m", doc="Relative distance where contact begins")


class Stop(PartialStop, library="translational"):
    """Hard end stops on a relative position (a slider against its support, a ball on the
    floor), with restitution e."""
    domain = "translational"
    s_min = Param(None, optional=True, unit="m",
                  doc="Lower limit of flange_b relative to flange_a (None: none)")
    s_max = Param(None, optional=True, unit="m",
                  doc="Upper limit of flange_b relative to flange_a (None: none)")
    e = Param(0.8, unit="1", min=0.0, max=1.0, doc="Coefficient of restitution")
    v_rest = Param(1e-4, unit="m/s", min=0.0,
                   doc="Impact speed below which the flange comes to rest on the limit")

    def check_values(self, values, place):
        return stop_check(values, place, "s_min", "s_max")
