"""Signal blocks: causal, real-valued; an output ``y`` feeds any number of inputs ``u``
(``u1``, ``u2``, ...; a PID has ``u_s``, the set point, and ``u_m``, the measurement).

A block gives its output from its inputs, its states x and time (``output``), and the rates
of its states (``rates``). ``feedthrough`` says whether the output depends on the inputs at
the same instant: a loop of signals through feedthrough blocks only is an algebraic loop.
Unwired optional inputs read as None. A block that needs the model's own dynamics (a
computed-torque controller) overrides ``evaluate``, which is handed them. The blocks that
interpolate tables (``Table``, ``Table2D``) are in ``tables.py``, of this library too.
"""

import numpy as np

from ..errors import ModelError
from ..expr import parse
from ..util import check_number, quote
from .base import REQUIRED, Component, Param, Port, library_attribute

LIB = "signals"


class PartialBlock(Component):
    """A block with one output."""
    role = "block"
    y = Port("signal_out", "Output", optional=True)
    n_states = 0
    feedthrough = True

    def output(self, u, x, t):
        raise NotImplementedError

    def evaluate(self, u, x, t, mechanics):
        """The output, for blocks that may use ``mechanics`` (the model's inverse dynamics,
        see ``kinetwork.equations.network``); most ignore it."""
        return self.output(u, x, t)

    def rates(self, u, x, t):
        return []

    def initial(self):
        return []


class PartialSISO(PartialBlock):
    u = Port("signal_in", "Input")


class Constant(PartialBlock, library=LIB):
    """y = k."""
    k = Param(doc="Value")

    def output(self, u, x, t):
        return self.k


class Input(PartialBlock, library=LIB):
    """A named external input: y = value in a simulation; the input channel ``kn.linearize``
    and ``kn.equilibrium`` take by this block's name (``value`` is its operating point)."""
    value = Param(0.0, time=True, doc="Value of the input (an expression in t allowed)")

    def output(self, u, x, t):
        return self.value


class Step(PartialBlock, library=LIB):
    """y = offset, then offset + height from start_time on."""
    height = Param(1.0, doc="Height of the step")
    offset = Param(0.0, doc="Output before the step")
    start_time = Param(0.0, unit="s", doc="Time of the step")

    def output(self, u, x, t):
        import casadi as ca
        return self.offset + ca.if_else(t >= self.start_time, self.height, 0)


class Ramp(PartialBlock, library=LIB):
    """y rises linearly by ``height`` over ``duration`` from start_time."""
    height = Param(1.0, doc="Height of the ramp")
    duration = Param(1.0, unit="s", min=0.0, doc="Duration of the ramp")
    offset = Param(0.0, doc="Output before the ramp")
    start_time = Param(0.0, unit="s", doc="Start of the ramp")

    def output(self, u, x, t):
        import casadi as ca
        frac = ca.fmin(ca.fmax((t - self.start_time) / ca.fmax(self.duration, 1e-300), 0), 1)
        return self.offset + self.height * frac


class Sine(PartialBlock, library=LIB):
    """y = offset + amplitude sin(2 pi f (t - start_time) + phase) from start_time on."""
    amplitude = Param(1.0, doc="Amplitude")
    f = Param(1.0, unit="Hz", doc="Frequency")
    phase = Param(0.0, unit="rad", doc="Phase")
    offset = Param(0.0, doc="Offset")
    start_time = Param(0.0, unit="s", doc="Start of the sine")

    def output(self, u, x, t):
        import casadi as ca
        wave = self.amplitude * ca.sin(2 * ca.pi * self.f * (t - self.start_time) + self.phase)
        return self.offset + ca.if_else(t >= self.start_time, wave, 0)


class PartialPeriodic(PartialBlock):
    """A periodic signal from start_time on, as MSL's periodic sources: ``nperiod`` periods
    (< 0: without end), ``offset`` before and after. Its edges and kinks are time events."""
    period = Param(1.0, unit="s", positive=True, doc="Time for one period")
    nperiod = Param(-1.0, unit="1", doc="Number of periods (< 0: without end)")
    offset = Param(0.0, doc="Output before start_time (added to it after)")
    start_time = Param(0.0, unit="s", doc="Start of the first period")

    def wave(self, phase):
        """The output less the offset, at ``phase`` in [0, period) of a period."""
        raise NotImplementedError

    def output(self, u, x, t):
        import casadi as ca
        tau = t - self.start_time
        running = tau >= 0
        n = ca.SX(self.nperiod)
        last = tau < n * self.period
        # the phase runs from the start (and stops after the last period): no events of
        # periods that are not shown
        phase = ca.fmax(tau, 0)
        if n.is_constant():
            running = running * last if float(n) >= 0 else running
            if float(n) >= 0:
                phase = ca.fmin(phase, n * self.period)
        else:
            running = running * ca.if_else(n < 0, 1, last)
        return self.offset + running * self.wave(ca.fmod(phase, self.period))


class Pulse(PartialPeriodic, library=LIB):
    """A pulse train as MSL's Blocks.Sources.Pulse: amplitude for the first ``width`` % of
    each period, 0 for the rest (plus offset)."""
    amplitude = Param(1.0, doc="Amplitude of the pulses")
    width = Param(50.0, unit="1", min=0.0, max=100.0, doc="Width of a pulse, % of the period")

    def wave(self, phase):
        return self.amplitude * (phase < self.width / 100 * self.period)


class SawTooth(PartialPeriodic, library=LIB):
    """A saw tooth as MSL's Blocks.Sources.SawTooth: rising from 0 to amplitude over each
    period, falling back at once (plus offset)."""
    amplitude = Param(1.0, doc="Amplitude of the teeth")

    def wave(self, phase):
        return self.amplitude * phase / self.period


class Trapezoid(PartialPeriodic, library=LIB):
    """A trapezoid train as MSL's Blocks.Sources.Trapezoid: in each period, rising from 0 to
    amplitude over ``rising``, holding it for ``width``, falling back over ``falling``, 0 for
    the rest (plus offset)."""
    amplitude = Param(1.0, doc="Amplitude of the trapezoids")
    rising = Param(0.0, unit="s", min=0.0, doc="Rising duration")
    width = Param(0.5, unit="s", min=0.0, doc="Duration at the amplitude")
    falling = Param(0.0, unit="s", min=0.0, doc="Falling duration")

    def check_values(self, values, place):
        total = [values[k] for k in ("rising", "width", "falling", "period")]
        if all(isinstance(v, (int, float)) for v in total) and \
                sum(total[:3]) > total[3] * (1 + 1e-12):
            return [f"{place('period')} = {total[3]}: shorter than rising + width + falling "
                    f"= {sum(total[:3])}"]
        return []

    def wave(self, phase):
        import casadi as ca
        up, hold = self.rising, self.rising + self.width
        down = hold + self.falling
        rise = phase / ca.fmax(up, 1e-300)
        fall = (down - phase) / ca.fmax(self.falling, 1e-300)
        shape = ca.if_else(phase < up, rise,
                           ca.if_else(phase < hold, 1, ca.if_else(phase < down, fall, 0)))
        return self.amplitude * shape


class Gain(PartialSISO, library=LIB):
    """y = k u."""
    k = Param(doc="Gain")

    def output(self, u, x, t):
        return self.k * u["u"]


class Add(PartialBlock, library=LIB):
    """y = k1 u1 + k2 u2."""
    same_unit_ports = (("u1", "u2", "y"),)
    u1 = Port("signal_in", "Input 1")
    u2 = Port("signal_in", "Input 2")
    k1 = Param(1.0, doc="Gain of u1")
    k2 = Param(1.0, doc="Gain of u2")

    def output(self, u, x, t):
        return self.k1 * u["u1"] + self.k2 * u["u2"]


class Sum(PartialBlock, library=LIB):
    """y = u1 + u2 + u3 + u4 (unwired inputs count as zero)."""
    same_unit_ports = (("u1", "u2", "u3", "u4", "y"),)
    u1 = Port("signal_in", "Input 1")
    u2 = Port("signal_in", "Input 2", optional=True)
    u3 = Port("signal_in", "Input 3", optional=True)
    u4 = Port("signal_in", "Input 4", optional=True)

    def output(self, u, x, t):
        import casadi as ca
        return sum((u[k] for k in ("u1", "u2", "u3", "u4") if u[k] is not None), ca.SX(0))


class Product(PartialBlock, library=LIB):
    """y = u1 u2."""
    u1 = Port("signal_in", "Input 1")
    u2 = Port("signal_in", "Input 2")

    def output(self, u, x, t):
        return u["u1"] * u["u2"]


class Limiter(PartialSISO, library=LIB):
    """y = u clipped to [u_min, u_max]."""
    same_unit_ports = (("u", "y"),)
    u_max = Param(doc="Upper limit")
    u_min = Param(None, optional=True, doc="Lower limit (None: -u_max)")

    def output(self, u, x, t):
        import casadi as ca
        low = -self.u_max if self.u_min is None else self.u_min
        return ca.fmin(ca.fmax(u["u"], low), self.u_max)


class Integrator(PartialSISO, library=LIB):
    """y = y_start + k * integral of u."""
    n_states = 1
    feedthrough = False
    k = Param(1.0, doc="Gain")
    y_start = Param(0.0, doc="Initial output")

    def output(self, u, x, t):
        return x[0]

    def rates(self, u, x, t):
        return [self.k * u["u"]]

    def initial(self):
        return [self.y_start]


class FirstOrder(PartialSISO, library=LIB):
    """T dy/dt + y = k u."""
    n_states = 1
    feedthrough = False
    k = Param(1.0, doc="Gain")
    T = Param(unit="s", positive=True, doc="Time constant")
    y_start = Param(0.0, doc="Initial output")

    def output(self, u, x, t):
        return x[0]

    def rates(self, u, x, t):
        return [(self.k * u["u"] - x[0]) / self.T]

    def initial(self):
        return [self.y_start]


class Derivative(PartialSISO, library=LIB):
    """A filtered derivative: y = k s / (T s + 1) u."""
    n_states = 1
    k = Param(1.0, doc="Gain")
    T = Param(0.01, unit="s", positive=True, doc="Filter time constant")
    x_start = Param(0.0, doc="Initial filter state (the input it starts from)")

    def output(self, u, x, t):
        return self.k * (u["u"] - x[0]) / self.T

    def rates(self, u, x, t):
        return [(u["u"] - x[0]) / self.T]

    def initial(self):
        return [self.x_start]


class PID(PartialBlock, library=LIB):
    """Limited PID controller with anti-windup, as Modelica's LimPID: with e = u_s - u_m,
    y = clip(k (e + I + D), y_min, y_max), dI/dt = (e + (y - y_unlimited) / (k Ni)) / Ti
    (back-calculation stops the integral winding up at the limits) and
    D = Td s / (1 + s Td / Nd) e. Ti = None drops the integral, Td = 0 the derivative."""
    same_unit_ports = (("u_s", "u_m"),)
    u_s = Port("signal_in", "Set point")
    u_m = Port("signal_in", "Measurement")
    n_states = 2
    k = Param(1.0, nonzero=True, doc="Gain")
    Ti = Param(None, optional=True, unit="s", positive=True, doc="Integral time (None: no I)")
    Td = Param(0.0, unit="s", min=0.0, doc="Derivative time (0: no D)")
    Nd = Param(10.0, unit="1", positive=True, doc="Derivative filter: gain at high frequency")
    Ni = Param(0.9, unit="1", positive=True,
               doc="Anti-windup: Ni Ti is the back-calculation time")
    y_max = Param(None, optional=True, doc="Upper output limit (None: none)")
    y_min = Param(None, optional=True, doc="Lower output limit (None: -y_max)")
    xi_start = Param(0.0, doc="Initial integral state")

    def _parts(self, u, x):
        import casadi as ca
        e = u["u_s"] - u["u_m"]
        integral = x[0] if self.Ti is not None else 0
        deriv = self._when_d(self.Nd * (e - x[1]))
        unlimited = self.k * (e + integral + deriv)
        y = unlimited
        if self.y_max is not None:
            low = -self.y_max if self.y_min is None else self.y_min
            y = ca.fmin(ca.fmax(unlimited, low), self.y_max)
        return e, y, unlimited

    def _when_d(self, value):
        """``value`` where the derivative part is on (Td > 0), else 0. Td may be a symbol (a
        model parameter set per run): then the choice is made at run time, and the division
        by Td = 0 in the branch not taken is discarded, not propagated."""
        import casadi as ca
        td = ca.SX(self.Td)
        if td.is_constant():
            return value if float(td) > 0 else 0
        return ca.if_else(td > 0, value, 0)

    def output(self, u, x, t):
        return self._parts(u, x)[1]

    def rates(self, u, x, t):
        e, y, unlimited = self._parts(u, x)
        di = (e + (y - unlimited) / (self.k * self.Ni)) / self.Ti if self.Ti is not None else 0
        dd = self._when_d((e - x[1]) * self.Nd / self.Td)
        return [di, dd]

    def initial(self):
        return [self.xi_start, 0.0]


class InverseDynamics(PartialBlock, library=LIB):
    """The model's own inverse dynamics, the heart of a computed-torque controller: the
    generalized force joint ``joint`` needs for the joint accelerations a1, a2, ... (one per
    joint coordinate, in model order; unwired: 0) at the present joint angles and speeds,
    y = [M(q) a + C(q, qd) qd + G(q) - Q(q, qd)]_joint, with M including geared rotors and Q
    the springs and dampers of the 1-D network (sources and line forces are not in it)."""
    a1 = Port("signal_in", "Acceleration of the first joint coordinate")
    a2 = Port("signal_in", "Acceleration of the second", optional=True)
    a3 = Port("signal_in", "Acceleration of the third", optional=True)
    a4 = Port("signal_in", "Acceleration of the fourth", optional=True)
    joint = Param(kind="name", doc="Joint (one degree of freedom) whose force is the output")

    def evaluate(self, u, x, t, mechanics):
        n = mechanics.n_speeds
        if n > 4:
            raise mechanics.refuse(self, None, f"InverseDynamics takes at most 4 joint "
                                               f"coordinates; this model has {n}")
        speed = mechanics.speed_of(self.joint)
        if speed is None:
            raise mechanics.refuse(self, "joint", f"{self.joint!r} is not a joint with one "
                                                  f"degree of freedom of this model")
        a = [u[f"a{i + 1}"] if u[f"a{i + 1}"] is not None else 0 for i in range(n)]
        return mechanics.inverse(a)[speed]


class ExpressionParam(Param):
    """A parameter holding an expression whose free names are only known when the model is
    compiled (the block's inputs as well as model parameters and t): parsed and checked for
    form here, its names checked by the block that evaluates it."""

    def __init__(self, default=REQUIRED, *, doc="", unit=""):
        super().__init__(default, kind="expression", doc=doc, unit=unit)

    def normalize(self, value, where):
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            return float(check_number(value, where, "a number or an expression"))
        if not isinstance(value, str) or not value.strip():
            raise ModelError(f"{where}: must be an expression (a string), got {quote(value)}")
        try:
            expr = parse(value)
        except ModelError as exc:
            raise ModelError(f"{where}: {exc}") from None
        dotted = sorted(n for n in expr.names if "." in n)
        if dotted:
            raise ModelError(f"{where}: {quote(dotted[0])} is not a name here: use the "
                             f"block's inputs, t and the model's parameters")
        return value


class Expression(PartialBlock, library=LIB):
    """y = an expression in the inputs u1 .. u4 (or the names given them in ``names``), time
    t and the model's parameters, as MSL's RealExpression with inputs: a force law in sensor
    signals is one block (``"-p0*A*(1 + s/L)"``). Differentiated exactly by CasADi."""
    u1 = Port("signal_in", "Input 1", optional=True)
    u2 = Port("signal_in", "Input 2", optional=True)
    u3 = Port("signal_in", "Input 3", optional=True)
    u4 = Port("signal_in", "Input 4", optional=True)
    expression = ExpressionParam(doc="The output, in u1..u4 (or their names), t and the "
                                     "model's parameters")
    names = Param(None, optional=True, kind="names",
                  doc="Names of u1, u2, ... in the expression (default: u1, u2, ...)")
    inputs = ("u1", "u2", "u3", "u4")

    def evaluate(self, u, x, t, mechanics):
        import casadi as ca
        from ..expr import casadi_functions
        if not isinstance(self.expression, str):
            return ca.SX(self.expression)
        aliases = list(self.names or [])
        if len(aliases) > len(self.inputs):
            raise mechanics.refuse(self, "names", f"{len(aliases)} names for "
                                                  f"{len(self.inputs)} inputs")
        parameters = mechanics.parameters
        clash = sorted(set(aliases) & (set(parameters) | {"t", *self.inputs}))
        if clash:
            raise mechanics.refuse(self, "names", f"{clash[0]!r} is also a model parameter, "
                                                  f"t or an input's port name: choose another")
        env = {**parameters, "t": t}
        wired = {}
        for k, port in enumerate(self.inputs):
            wired[port] = u[port]
            if k < len(aliases):
                wired[aliases[k]] = u[port]
        env.update({name: v for name, v in wired.items() if v is not None})
        expr = parse(self.expression)
        unknown = sorted(expr.names - set(env) - set(wired))
        if unknown:
            raise mechanics.refuse(self, "expression", f"unknown name {unknown[0]!r} in "
                                   f"{self.expression!r}; names are the inputs "
                                   f"{', '.join(aliases or self.inputs)}, t and the model's "
                                   f"parameters {', '.join(parameters) or '(none)'}")
        unwired = sorted(n for n in expr.names if n in wired and wired[n] is None)
        if unwired:
            port = (self.inputs[aliases.index(unwired[0])] if unwired[0] in aliases
                    else unwired[0])
            raise mechanics.refuse(self, "expression", f"uses {unwired[0]!r}, but "
                                   f"{self.name}.{port} is not wired")
        return ca.SX(expr.evaluate(env, casadi_functions()))


class VectorParam(Param):
    """One number per axis (a list of any length, or one number for one axis)."""

    def __init__(self, default=REQUIRED, *, unit="", positive=False, doc=""):
        super().__init__(default, unit=unit, kind="vector", doc=doc)
        self.positive = positive

    def normalize(self, value, where):
        if isinstance(value, np.ndarray):
            value = value.tolist()
        if not isinstance(value, (list, tuple)):
            value = [value]
        if not value or len(value) > 100:
            raise ModelError(f"{where}: must be 1 to 100 numbers (one per axis), got "
                             f"{quote(value)}")
        out = [float(check_number(v, f"{where}[{i}]")) for i, v in enumerate(value)]
        bad = [i for i, v in enumerate(out) if self.positive and not v > 0]
        if bad:
            raise ModelError(f"{where}[{bad[0]}]: must be > 0, got {out[bad[0]]}")
        return out


class KinematicPTP(PartialBlock, library=LIB):
    """Point-to-point motion of one or several axes as MSL's Blocks.Sources.KinematicPTP:
    each axis moves from q_begin to q_end, accelerating at its limit, coasting at its speed
    limit, braking at its limit, all axes on one normalised path (the slowest sets the
    timing, so they start and stop together). The output is axis ``axis``'s angle
    (``quantity`` "q"), speed ("qd") or acceleration ("qdd"); exact, piecewise polynomial in
    t, so an exact Position may follow it."""
    q_begin = VectorParam(doc="Start positions, one per axis")
    q_end = VectorParam(doc="End positions, one per axis")
    qd_max = VectorParam(positive=True, doc="Largest speeds (> 0), one per axis")
    qdd_max = VectorParam(positive=True, doc="Largest accelerations (> 0), one per axis")
    start_time = Param(0.0, unit="s", doc="Start of the motion")
    axis = Param(1, unit="1", min=1, doc="Which axis the output is (1: the first)")
    quantity = Param("q", kind="choice", choices=("q", "qd", "qdd"),
                     doc="The output: the axis's position, speed or acceleration")

    def check_values(self, values, place):
        n = len(values["q_begin"])
        for key in ("q_end", "qd_max", "qdd_max"):
            if len(values[key]) != n:
                return [f"{place(key)}: {len(values[key])} axes, but q_begin has {n}"]
        axis = values["axis"]
        if isinstance(axis, (int, float)) and not (1 <= axis <= n and axis == int(axis)):
            return [f"{place('axis')} = {axis}: must be a whole number from 1 to {n}"]
        return []

    def timing(self):
        """MSL's KinematicPTP: the normalised path's largest speed and acceleration and its
        phase ends (acceleration, coasting, end), after start_time; or None at rest."""
        delta = np.subtract(self.q_end, self.q_begin)
        sd_inv = max(abs(delta / np.array(self.qd_max)))
        sdd_inv = max(abs(delta / np.array(self.qdd_max)))
        if sd_inv <= 1e-15 or sdd_inv <= 1e-15:
            return None
        sd, sdd = 1 / sd_inv, 1 / sdd_inv
        ta1, ta2 = np.sqrt(1 / sdd), sd / sdd
        if ta2 >= ta1:                     # no coasting: the speed limit is never reached
            return sdd * ta1, sdd, ta1, ta1, 2 * ta1
        return sd, sdd, ta2, 1 / sd, 1 / sd + ta2

    def output(self, u, x, t):
        import casadi as ca
        k = int(float(ca.DM(self.axis))) - 1         # a number: it picks an axis
        delta = self.q_end[k] - self.q_begin[k]
        base = self.q_begin[k] if self.quantity == "q" else 0.0
        timing = self.timing()
        if timing is None:
            return ca.SX(base)
        sd, sdd, ta, tv, te = timing
        tau = t - self.start_time
        # r, r', r'' of the normalised path in its phases (accelerate, coast, brake, rest)
        r_a = [sdd / 2 * tau**2, sdd * tau, sdd]
        ra = sdd / 2 * ta**2
        r_c = [ra + sd * (tau - ta), sd, 0.0]
        rv = ra + sd * (tv - ta)
        r_b = [rv + sd * (tau - tv) - sdd / 2 * (tau - tv)**2, sd - sdd * (tau - tv), -sdd]
        r_e = [rv + sd * (te - tv) - sdd / 2 * (te - tv)**2, 0.0, 0.0]
        which = ("q", "qd", "qdd").index(self.quantity)
        r = ca.if_else(tau < 0, 0.0,
                       ca.if_else(tau < ta, r_a[which],
                                  ca.if_else(tau < tv, r_c[which],
                                             ca.if_else(tau < te, r_b[which], r_e[which]))))
        return base + delta * r

__getattr__ = library_attribute("signals")
