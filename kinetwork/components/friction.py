"""Friction with stiction, elastic gaps and hard stops: 1-D elements with modes.

Each element acts between a flange ``b`` and a flange ``a`` (its support: unwired, the
world) and is in one of a few modes, which the integration driver changes at events
(``kinetwork.solver.events``). A mode is a state of the model (``brake.mode``, its rate
zero), so one compiled system serves every mode. The force into flange b is

    f = (1 - held(mode)) * law(rel, w_rel, mode) + F

where F is what the element holds with while it is held (stuck friction, a body resting on a
stop): solved with the dynamics from held * a_rel + (1 - held) * F = 0, so a held element
keeps its flanges together exactly, and F is 0 otherwise (``kinetwork.equations.modes``).

Every element declares an ``indicator``: positive while its mode holds, crossing zero where
it ends (a sliding speed reaching zero, a holding force reaching the static limit, a gap
closing), and ``next_mode``, what happens there, in numbers: the new mode and, for an
impact or a sticking, the relative speed right after it (an impulse through the mechanism).

Modes of friction: +1 sliding forward (w_rel > 0), -1 sliding backward, 0 stuck (MSL's
``Forward``, ``Backward``, ``Stuck``). No regularisation: a stuck element is exactly stuck.
"""

from .base import ONED, Component, Port
from .oned import named

#: a stuck friction holds up to its static limit and at it, to rounding: a load that keeps
#: it exactly at the limit (a ramp that levels off there, a controller's steady torque)
#: holds it, rather than starting a slide that stops at once (modes chattering)
EDGE = 1e-12


class PartialHybrid(Component):
    """An element with modes between its ``side_b`` flange and its ``side_a`` flange."""
    role = "source"          # its law may read a signal (a brake's normal force)
    hybrid = True
    side_a, side_b = "flange_a", "flange_b"
    #: mode names, for the events reported
    modes = {}

    def held(self, mode):
        """1 where the mode holds the flanges together, else 0 (an SX of the mode)."""
        import casadi as ca
        return ca.SX(0)

    def law(self, rel, w_rel, mode, u):
        """The force into flange b when not held."""
        import casadi as ca
        return ca.SX(0)

    def free_mode(self, rel, w_rel):
        """The mode the state itself gives, without events (the equations shown as M, V, G:
        ``equations/modes.py``)."""
        import casadi as ca
        return ca.SX(0)

    def values(self, t, u):
        """Two numbers the events read (a static limit, a restitution), as SX."""
        import casadi as ca
        return ca.SX(0), ca.SX(0)

    def indicator(self, mode, rel, w_rel, force, values, power=None):
        raise NotImplementedError

    def first_mode(self, ev):
        """(mode, relative speed after, kind) at the start, from the numbers ``ev``."""
        raise NotImplementedError

    def next_mode(self, ev):
        """(mode, relative speed after or None, kind) where the indicator crossed zero."""
        raise NotImplementedError

    def flows(self, pos, vel, t, u=None):
        a, b = self.side_a, self.side_b
        rel, w_rel = pos[b] - pos[a], vel[b] - vel[a]
        f = (1 - self.held(self._mode)) * self.law(rel, w_rel, self._mode, u) + self._F
        return {a: -f, b: f}


class PartialFriction(PartialHybrid):
    """Coulomb friction with stiction and viscous friction: sliding, the force into flange b is
    mode * f_kinetic + d * w_rel (opposing the motion); stuck, whatever holds the flanges
    together, up to peak * f_kinetic in either direction."""
    modes = {-1: "sliding backward", 0: "stuck", 1: "sliding forward"}
    hold_mode = 0
    #: the modes an element at rest may take, decided together with the others at rest at
    #: the same instant (``solver/events.py``): stuck, or sliding the way it accelerates
    at_rest_modes = (0, 1, -1)

    def kinetic(self, u):
        raise NotImplementedError

    def held(self, mode):
        return 1 - mode * mode

    def law(self, rel, w_rel, mode, u):
        return mode * self.kinetic(u) + self.d * w_rel

    def free_mode(self, rel, w_rel):
        import casadi as ca
        return ca.sign(w_rel)

    def values(self, t, u):
        import casadi as ca
        return self.peak * self.kinetic(u), ca.SX(0)

    def indicator(self, mode, rel, w_rel, force, values, power=None):
        # sliding: the speed in the direction of sliding; stuck: the margin to the limit,
        # which holds up to and at the limit itself (MSL: stuck while |f| <= f_static)
        import casadi as ca
        margin = values[0] * (1 + EDGE) - ca.fabs(force)
        return mode * mode * (mode * w_rel) + (1 - mode * mode) * margin

    def first_mode(self, ev):
        if abs(ev.w_rel) > ev.tiny:
            return (1 if ev.w_rel > 0 else -1), None, None
        return self._at_rest(ev)

    def next_mode(self, ev):
        if ev.mode == 0:                      # the holding force reached the static limit
            return (1 if ev.force > 0 else -1), None, None
        return self._at_rest(ev)              # the sliding speed reached zero

    @staticmethod
    def _at_rest(ev):
        """At zero relative speed: stuck if the force that holds is within the static limit,
        else sliding the way that force pushes, from a speed of exactly zero (one a rounding
        the other way would read as the slide stopping at once, again and again)."""
        if abs(ev.stuck_force) <= ev.values[0] * (1 + EDGE):
            return 0, 0.0, None
        return (1 if ev.stuck_force > 0 else -1), 0.0, None


class PartialTwoFlanges(PartialFriction):
    """MSL's port layout of a friction between a shaft and its housing: flange_a and flange_b
    rigidly joined (one node: ``joined_ports``), so a drive train wires through it one to one
    as in MSL's diagrams; ``flange`` is that node too (wire it alone, as before)."""
    side_a, side_b = "support", "flange"
    flange = Port(ONED, "The shaft (flange_a and flange_b are this node too)", optional=True)
    flange_a = Port(ONED, "Flange a, rigidly joined to flange_b", optional=True)
    flange_b = Port(ONED, "Flange b, rigidly joined to flange_a", optional=True)
    support = Port(ONED, "Housing (unwired: the world)", optional=True)
    joined_ports = (("flange", "flange_a"), ("flange", "flange_b"))


class PartialBearingFriction(PartialTwoFlanges):
    """Coulomb friction of a constant force (torque): ``tau_c`` or ``f_c``."""
    f_kinetic = named("{flow}_c", "Coulomb friction force or torque")

    def kinetic(self, u):
        return self.f_kinetic


class PartialNormalForceFriction(PartialFriction):
    """Friction pressed by a normal force fn = fn_max * f_normalized (the signal at u, or the
    parameter), as MSL's Brake and Clutch: f_kinetic = mu * cgeo * fn, and free (mode 2,
    MSL's Free: no Coulomb friction, nothing held) while fn <= 0. Engaged, each mode also
    ends where fn falls to 0; free ends where fn rises above ``FREE_EDGE * (1 + fn_max)``
    (an indicator at zero would never be seen crossing), and the element then slides the way
    its relative speed goes, or at rest sticks if it can (MSL: from Free to Forward,
    Backward or Stuck)."""
    FREE = 2
    modes = {**PartialFriction.modes, FREE: "free"}
    u = Port("signal_in", "Normalized normal force f_normalized, 0..1 (instead of the "
                          "parameter)", optional=True)

    def normal_force(self, u):
        return self.fn_max * (self.f_normalized if u is None else u)

    def kinetic(self, u):
        import casadi as ca
        return self.mu * self.cgeo * ca.fmax(self.normal_force(u), 0)

    def held(self, mode):
        import casadi as ca
        return ca.if_else(mode == 0, 1, 0)

    def law(self, rel, w_rel, mode, u):
        import casadi as ca
        return ca.if_else(mode == self.FREE, 0, mode) * self.kinetic(u) + self.d * w_rel

    def values(self, t, u):
        return self.peak * self.kinetic(u), self.normal_force(u)

    def indicator(self, mode, rel, w_rel, force, values, power=None):
        import casadi as ca
        engaged = ca.fmin(super().indicator(mode, rel, w_rel, force, values), values[1])
        edge = EDGE * (1 + ca.fabs(self.fn_max))
        return ca.if_else(mode == self.FREE, edge - values[1], engaged)

    def disengaged(self, values):
        """Free at a state whose numbers (static limit, normal force) are ``values``."""
        return values[1] <= EDGE

    def first_mode(self, ev):
        if self.disengaged(ev.values):
            return self.FREE, None, None
        return super().first_mode(ev)

    def next_mode(self, ev):
        if ev.mode == self.FREE:                  # pressed again: engage
            return PartialFriction.first_mode(self, ev)
        if ev.values[1] <= 0:                     # the normal force is gone
            return self.FREE, None, None
        return super().next_mode(ev)


class PartialElastoGap(PartialHybrid):
    """MSL's ElastoGap: a linear spring and damper acting only while the gap is closed
    (rel < rel0); the damping force is limited so that it never pulls (MSL 4.0's law)."""
    modes = {0: "open", 1: "contact"}
    rel0 = named("{position}_rel0", "Relative position where contact begins")
    state_mode = True        # contact exactly while closed: a function of the state
    flange_a = Port(ONED, "Flange a")
    flange_b = Port(ONED, "Flange b")

    def law(self, rel, w_rel, mode, u):
        import casadi as ca
        spring = self.c * (rel - self.rel0)
        reach = ca.fabs(spring)
        return mode * (spring + ca.fmin(ca.fmax(self.d * w_rel, -reach), reach))

    def indicator(self, mode, rel, w_rel, force, values, power=None):
        return (1 - 2 * mode) * (rel - self.rel0)

    def free_mode(self, rel, w_rel):
        import casadi as ca
        return ca.if_else(rel < self.rel0, 1, 0)

    def first_mode(self, ev):
        return (1 if ev.indicator < 0 else 0), None, None     # ev: read in mode 0 (open)

    def next_mode(self, ev):
        return 1 - ev.mode, None, None


class PartialStop(PartialHybrid):
    """A hard stop: flange b moves freely relative to flange a between rel_min and rel_max
    (either may be unset) and bounces off a limit with the coefficient of restitution e (an
    impact: an impulse through the mechanism); an impact slower than v_rest leaves it resting
    on the limit until the force holding it there would have to pull."""
    modes = {0: "free", 1: "resting"}
    rel_min = named("{position}_min", "Lower limit")
    rel_max = named("{position}_max", "Upper limit")
    hold_mode = 1
    flange_a = Port(ONED, "Flange a (the reference side: a joint's support)")
    flange_b = Port(ONED, "Flange b (a joint's axis)")

    def held(self, mode):
        return mode

    def _side(self, rel):
        """+1 nearer the lower limit, -1 nearer the upper."""
        import casadi as ca
        if self.rel_min is None:
            return ca.SX(-1)
        if self.rel_max is None:
            return ca.SX(1)
        return ca.if_else(rel - self.rel_min <= self.rel_max - rel, 1, -1)

    def _gap(self, rel):
        import casadi as ca
        gaps = [g for g in (None if self.rel_min is None else rel - self.rel_min,
                            None if self.rel_max is None else self.rel_max - rel)
                if g is not None]
        return gaps[0] if len(gaps) == 1 else ca.fmin(*gaps)

    def values(self, t, u):
        import casadi as ca
        return ca.SX(self.e), ca.SX(self.v_rest)

    def indicator(self, mode, rel, w_rel, force, values, power=None):
        # free: the gap to the nearer limit; resting: the push of the limit (never a pull)
        return (1 - mode) * self._gap(rel) + mode * (-self._side(rel) * force)

    def first_mode(self, ev):
        if ev.indicator < -ev.tiny:
            raise ValueError("starts beyond its limit")
        if ev.indicator <= ev.tiny and ev.rate <= ev.tiny:
            # on its limit and not leaving it (ev.rate: the gap's rate): an impact at the
            # start if it moves in faster than v_rest and bounces, else resting there, which
            # lifts off at once where the limit would have to pull (the modes settled at the
            # start); left free, the gap would open below zero unseen (a ball at rest on the
            # floor at t = 0 falling through it)
            if -ev.rate > max(ev.values[1], ev.tiny) and ev.values[0] > 0:
                return 0, -ev.values[0] * ev.w_rel, "impact"
            return 1, 0.0, None
        return 0, None, None

    def next_mode(self, ev):
        if ev.mode == 1:
            return 0, None, "lift-off"
        if abs(ev.w_rel) > max(ev.values[1], ev.tiny):
            return 0, -ev.values[0] * ev.w_rel, "impact"
        return 1, 0.0, None


class GearModes:
    """The modes of a gear with an efficiency eta < 1 (``rotational.IdealGear``), standing in
    for it among the elements with modes: +1 while flange_a drives (power flows from a to
    b: torque_b = -ratio eta torque_a), -1 while flange_b does (torque_b = -ratio torque_a /
    eta). Its indicator is the power into the gear at flange_a, times the mode: where it turns
    (the speed or the torque changes sign), the other flange drives."""
    modes = {1: "flange_a driving", -1: "flange_b driving"}
    hold_mode = None

    def __init__(self, gear):
        self.gear, self.name = gear, gear.name

    def held(self, mode):
        return 0

    def values(self, t, u):
        import casadi as ca
        return ca.SX(0), ca.SX(0)

    def indicator(self, mode, rel, w_rel, force, values, power=None):
        return mode * power

    def first_mode(self, ev):
        return (1 if ev.indicator >= 0 else -1), None, None

    def next_mode(self, ev):
        return -ev.mode, None, None


def stop_check(values, place, lo, hi):
    """Problems of a stop's limits taken together: at least one, and in order."""
    a, b = values.get(lo), values.get(hi)
    if a is None and b is None:
        return [f"{place(lo)}: a stop needs a limit: give {lo}, {hi} or both"]
    if isinstance(a, (int, float)) and isinstance(b, (int, float)) and not a < b:
        return [f"{place(hi)} = {b}: must be > {lo} = {a}"]
    return []
