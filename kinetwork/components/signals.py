"""Signal blocks: causal, real-valued; an output ``y`` feeds any number of inputs ``u``
(``u1``, ``u2``, ...; a PID has ``u_s``, the set point, and ``u_m``, the measurement).

A block gives its output from its inputs, its states x and time (``output``), and the rates
of its states (``rates``). ``feedthrough`` says whether the output depends on the inputs at
the same instant: a loop of signals through feedthrough blocks only is an algebraic loop.
Unwired optional inputs read as None. A block that needs the model's own dynamics (a
computed-torque controller) overrides ``evaluate``, which is handed them.
"""

import casadi as ca

from .base import Component, Param, Port

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
        return self.offset + ca.if_else(t >= self.start_time, self.height, 0)


class Ramp(PartialBlock, library=LIB):
    """y rises linearly by ``height`` over ``duration`` from start_time."""
    height = Param(1.0, doc="Height of the ramp")
    duration = Param(1.0, unit="s", min=0.0, doc="Duration of the ramp")
    offset = Param(0.0, doc="Output before the ramp")
    start_time = Param(0.0, unit="s", doc="Start of the ramp")

    def output(self, u, x, t):
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
        wave = self.amplitude * ca.sin(2 * ca.pi * self.f * (t - self.start_time) + self.phase)
        return self.offset + ca.if_else(t >= self.start_time, wave, 0)


class Gain(PartialSISO, library=LIB):
    """y = k u."""
    k = Param(doc="Gain")

    def output(self, u, x, t):
        return self.k * u["u"]


class Add(PartialBlock, library=LIB):
    """y = k1 u1 + k2 u2."""
    u1 = Port("signal_in", "Input 1")
    u2 = Port("signal_in", "Input 2")
    k1 = Param(1.0, doc="Gain of u1")
    k2 = Param(1.0, doc="Gain of u2")

    def output(self, u, x, t):
        return self.k1 * u["u1"] + self.k2 * u["u2"]


class Sum(PartialBlock, library=LIB):
    """y = u1 + u2 + u3 + u4 (unwired inputs count as zero)."""
    u1 = Port("signal_in", "Input 1")
    u2 = Port("signal_in", "Input 2", optional=True)
    u3 = Port("signal_in", "Input 3", optional=True)
    u4 = Port("signal_in", "Input 4", optional=True)

    def output(self, u, x, t):
        return sum((u[k] for k in ("u1", "u2", "u3", "u4") if u[k] is not None), ca.SX(0))


class Product(PartialBlock, library=LIB):
    """y = u1 u2."""
    u1 = Port("signal_in", "Input 1")
    u2 = Port("signal_in", "Input 2")

    def output(self, u, x, t):
        return u["u1"] * u["u2"]


class Limiter(PartialSISO, library=LIB):
    """y = u clipped to [u_min, u_max]."""
    u_max = Param(doc="Upper limit")
    u_min = Param(None, optional=True, doc="Lower limit (None: -u_max)")

    def output(self, u, x, t):
        low = -self.u_max if self.u_min is None else self.u_min
        return ca.fmin(ca.fmax(u["u"], low), self.u_max)


class Table(PartialBlock, library=LIB):
    """y interpolated linearly in ``table`` rows [x, y] at u (or at time t when u is not
    wired), extrapolated linearly from the end rows."""
    u = Port("signal_in", "Abscissa (unwired: time)", optional=True)
    table = Param(kind="table", doc="Rows [x, y], x increasing (at most 100 000)")
    #: a table of up to this many rows is an expression (``kinetwork equations`` prints it);
    #: a longer one a CasADi interpolant, which costs time linear in the rows to build and
    #: compile to C, where the expression's cost grows with their square (10 000 rows:
    #: 5 s to build, 100 000: 6 min)
    expression_rows = 100

    def output(self, u, x, t):
        at = t if u["u"] is None else u["u"]
        xs = [row[0] for row in self.table]
        ys = [row[1] for row in self.table]
        if len(xs) <= self.expression_rows:
            return ca.pw_lin(at, ca.DM(xs), ca.DM(ys))
        return ca.interpolant(f"{self.name}_table", "linear", [xs], ys)(at)


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
    u_s = Port("signal_in", "Set point")
    u_m = Port("signal_in", "Measurement")
    n_states = 2
    k = Param(1.0, nonzero=True, doc="Gain")
    Ti = Param(None, optional=True, unit="s", positive=True, doc="Integral time (None: no I)")
    Td = Param(0.0, unit="s", min=0.0, doc="Derivative time (0: no D)")
    Nd = Param(10.0, positive=True, doc="Derivative filter: gain at high frequency")
    Ni = Param(0.9, positive=True, doc="Anti-windup: Ni Ti is the back-calculation time")
    y_max = Param(None, optional=True, doc="Upper output limit (None: none)")
    y_min = Param(None, optional=True, doc="Lower output limit (None: -y_max)")
    xi_start = Param(0.0, doc="Initial integral state")

    def _parts(self, u, x):
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
