"""Rotational friction with stiction, elastic gaps and hard stops (the laws: ``friction.py``)."""

from .base import ONED, Param, Port
from .friction import (PartialBearingFriction, PartialElastoGap, PartialNormalForceFriction,
                       PartialStop, PartialTwoFlanges, stop_check)

class BearingFriction(PartialBearingFriction, library="rotational"):
    """Bearing friction with stiction (MSL's Rotational.Components.BearingFriction, Coulomb and
    viscous): stuck while the torque holding the flange to its support stays within
    peak * tau_c, else sliding against tau_c + d * w."""
    domain = "rotational"
    tau_c = Param(unit="N*m", min=0.0, doc="Coulomb friction torque")
    peak = Param(1.0, unit="1", min=1.0, doc="Static over Coulomb friction torque")
    d = Param(0.0, unit="N*m*s/rad", min=0.0, doc="Viscous friction coefficient")


class Brake(PartialTwoFlanges, PartialNormalForceFriction, library="rotational"):
    """Brake with stiction (MSL's Rotational.Components.Brake, constant mu): friction torque
    mu * cgeo * fn_max * f_normalized between the flange (flange_a and flange_b, rigidly
    joined) and its support; free (mode 2) while the normal force is <= 0."""
    domain = "rotational"
    mu = Param(unit="1", min=0.0, doc="Coefficient of kinetic friction")
    peak = Param(1.0, unit="1", min=1.0, doc="Static over kinetic friction coefficient")
    cgeo = Param(1.0, unit="m", min=0.0, doc="Geometry constant: torque = cgeo * mu * force")
    fn_max = Param(unit="N", min=0.0, doc="Largest normal force")
    f_normalized = Param(1.0, unit="1", time=True,
                         doc="Normal force / fn_max (when u is not wired)")
    d = Param(0.0, unit="N*m*s/rad", min=0.0, doc="Viscous friction coefficient")


class Clutch(PartialNormalForceFriction, library="rotational"):
    """Clutch with stiction (MSL's Rotational.Components.Clutch, constant mu): friction torque
    mu * cgeo * fn_max * f_normalized between flange_a and flange_b; free (mode 2, no
    Coulomb torque, nothing held) while the normal force is <= 0, as MSL's."""
    domain = "rotational"
    flange_a = Port(ONED, "Flange a")
    flange_b = Port(ONED, "Flange b")
    mu = Param(unit="1", min=0.0, doc="Coefficient of kinetic friction")
    peak = Param(1.0, unit="1", min=1.0, doc="Static over kinetic friction coefficient")
    cgeo = Param(1.0, unit="m", min=0.0, doc="Geometry constant: torque = cgeo * mu * force")
    fn_max = Param(unit="N", min=0.0, doc="Largest normal force")
    f_normalized = Param(1.0, unit="1", time=True,
                         doc="Normal force / fn_max (when u is not wired)")
    d = Param(0.0, unit="N*m*s/rad", min=0.0, doc="Viscous friction coefficient")


class ElastoGap(PartialElastoGap, library="rotational"):
    """Rotational spring and damper acting only while phi_rel < phi_rel0 (MSL's ElastoGap)."""
    domain = "rotational"
    c = Param(unit="N*m/rad", min=0.0, doc="Spring constant")
    d = Param(0.0, unit="N*m*s/rad", min=0.0, doc="Damping constant")
    phi_rel0 = Param(0.0, unit="rad", doc="Relative angle where contact begins")


class Stop(PartialStop, library="rotational"):
    """Hard end stops on a relative angle (a joint's axis against its support), with
    restitution e."""
    domain = "rotational"
    phi_min = Param(None, optional=True, unit="rad",
                    doc="Lower limit of flange_b relative to flange_a (None: none)")
    phi_max = Param(None, optional=True, unit="rad",
                    doc="Upper limit of flange_b relative to flange_a (None: none)")
    e = Param(0.8, unit="1", min=0.0, max=1.0, doc="Coefficient of restitution")
    v_rest = Param(1e-4, unit="rad/s", min=0.0,
                   doc="Impact speed below which the flange comes to rest on the limit")

    def check_values(self, values, place):
        return stop_check(values, place, "phi_min", "phi_max")
