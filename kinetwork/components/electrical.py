"""Electrical library: pins with potential v [V] and current i [A] (positive into the
component), as Modelica.Electrical.Analog.

A component states its laws as residuals linear in its pins' potentials and currents
(``laws``), one per pin; its states (an inductor's current, a capacitor's voltage) get their
rates from ``rates``. ``kinetwork.equations.circuit`` gathers them with Kirchhoff's current law
at every connection set, and solves the circuit by structural analysis (the connection sets
are the alias elimination of the potentials; a block-lower-triangular sort of the rest).
What a component is handed, ``e``, reads ``e.v("p")``, ``e.i("p")``, ``e.x`` (its states),
``e.t``, ``e.u`` (the signal at u, or None when unwired), ``e.parameters`` (the model's
parameters as symbols), ``e.place(key)`` and ``e.fields(key)`` (where a parameter is, for
messages and as a Problem's fields) and, for an EMF, ``e.w`` (the speed of its flange
relative to its support). A law may be nonlinear (a diode): the circuit's solver then leaves
the unknowns it reads nonlinearly to IDAS.
"""

from ..errors import ModelError
from ..expr import casadi_functions, parse
from .base import Component, Param, Port, PortRef, library_attribute
from .loopjoints import Expansion
from .signals import ExpressionParam

LIB = "electrical"


class PartialTwoPin(Component):
    """Two pins p and n; the current i flows into p, through the component, out of n."""
    role = "electrical"
    p = Port("electrical", "Positive pin (the current i flows in here)")
    n = Port("electrical", "Negative pin")
    n_states = 0
    state_labels = ()
    state_units = ()
    #: the parameters giving the states' starts: one given makes its state preferred where
    #: a constraint leaves a choice (index reduction)
    start_params = ()

    def laws(self, e):
        """The two residuals: the current through (i_p + i_n = 0) and the component's law."""
        return [e.i("p") + e.i("n"), self.law(e.v("p") - e.v("n"), e.i("p"), e)]

    def law(self, v, i, e):
        raise NotImplementedError

    def rates(self, e):
        return []

    def initial(self):
        return []


class Resistor(PartialTwoPin, library=LIB):
    """Ideal linear resistor: v = R i (R positive, zero or negative, as MSL's)."""
    R = Param(unit="Ohm", doc="Resistance")

    def law(self, v, i, e):
        return v - self.R * i


class Conductor(PartialTwoPin, library=LIB):
    """Ideal linear conductor: i = G v (G positive, zero or negative), MSL's
    Analog.Basic.Conductor."""
    G = Param(unit="S", doc="Conductance")

    def law(self, v, i, e):
        return i - self.G * v


class NonlinearResistor(PartialTwoPin, library=LIB):
    """A resistor whose current from p to n is an expression of its voltage v = v_p - v_n
    (and of t and the model's parameters): MSL's Chua resistor is
    ``i="if_else(v < -Ve, Gb*(v + Ve) - Ga*Ve, if_else(v > Ve, Gb*(v - Ve) + Ga*Ve, Ga*v))"``.
    A nonlinear law makes the circuit a DAE that IDAS solves."""
    i = ExpressionParam(doc="Current from p to n, in the voltage v, t and the model's "
                            "parameters", unit="A")

    def law(self, v, i, e):
        if not isinstance(self.i, str):
            return i - self.i
        expr = parse(self.i)
        env = {**e.parameters, "t": e.t, "v": v}
        unknown = sorted(expr.names - set(env))
        if unknown:
            raise ModelError(f"{e.place('i')}: unknown name {unknown[0]!r} in {self.i!r}; "
                             f"names are v (the voltage), t and the model's parameters "
                             f"{', '.join(e.parameters) or '(none)'}", **e.fields("i"))
        import casadi as ca
        return i - ca.SX(expr.evaluate(env, casadi_functions()))


class Diode(PartialTwoPin, library=LIB):
    """Simple diode with a parallel ohmic resistance, MSL's Analog.Semiconductors.Diode
    (without its heat port): i = Ids (exlin(v/Vt, Maxexp) - 1) + v/R, the exponential
    continued linearly beyond the exponent Maxexp so that it cannot overflow."""
    Ids = Param(1e-6, unit="A", min=0.0, doc="Saturation current")
    Vt = Param(0.04, unit="V", positive=True, doc="Voltage equivalent of temperature (kT/qn)")
    Maxexp = Param(15.0, unit="1", positive=True,
                   doc="Max. exponent for linear continuation")
    R = Param(1e8, unit="Ohm", positive=True, doc="Parallel ohmic resistance")

    def law(self, v, i, e):
        import casadi as ca
        x = v / self.Vt
        exlin = ca.exp(ca.fmin(x, self.Maxexp)) * (1 + ca.fmax(x - self.Maxexp, 0))
        return i - (self.Ids * (exlin - 1) + v / self.R)


class Inductor(PartialTwoPin, library=LIB):
    """Ideal linear inductor: L di/dt = v; its current is a state."""
    L = Param(unit="H", positive=True, doc="Inductance")
    i0 = Param(0.0, unit="A", doc="Initial current")
    n_states = 1
    state_labels = ("i",)
    state_units = ("A",)
    start_params = ("i0",)

    def law(self, v, i, e):
        return i - e.x[0]

    def rates(self, e):
        return [(e.v("p") - e.v("n")) / self.L]

    def initial(self):
        return [self.i0]


class Capacitor(PartialTwoPin, library=LIB):
    """Ideal linear capacitor: C dv/dt = i; its voltage is a state."""
    C = Param(unit="F", positive=True, doc="Capacitance")
    v0 = Param(0.0, unit="V", doc="Initial voltage")
    n_states = 1
    state_labels = ("v",)
    state_units = ("V",)
    start_params = ("v0",)

    def law(self, v, i, e):
        return v - e.x[0]

    def rates(self, e):
        return [e.i("p") / self.C]

    def initial(self):
        return [self.v0]


class Ground(Component, library=LIB):
    """Ground: the potential 0 of a circuit; every circuit needs one."""
    role = "electrical"
    p = Port("electrical", "Pin at potential 0")
    n_states = 0
    state_labels = state_units = ()

    def laws(self, e):
        return [e.v("p")]

    def rates(self, e):
        return []

    def initial(self):
        return []


class PartialSource(PartialTwoPin):
    """A source of ``value()`` (an expression in time and model parameters), or of the
    signal at u when it is wired; one of them, not both."""
    u = Port("signal_in", "Signal giving the source's value (instead of the parameter)",
             optional=True)
    reference_key = None

    def source_value(self, e):
        return self.value() if e.u is None else e.u

    def signal_unit(self, port):
        return self.params[self.reference_key].unit if port == "u" else None


class VoltageSource(PartialSource, library=LIB):
    """Ideal voltage source: v = V (an expression in t, or the signal at u)."""
    V = Param(None, optional=True, unit="V", time=True,
              doc="Voltage v_p - v_n (when u is not wired)")
    reference_key = "V"

    def value(self):
        return self.V

    def law(self, v, i, e):
        return v - self.source_value(e)


class CurrentSource(PartialSource, library=LIB):
    """Ideal current source: the current I (an expression in t, or the signal at u) flows
    into pin p, through the source and out of pin n, as MSL's."""
    I = Param(None, optional=True, unit="A", time=True,  # noqa: E741 (MSL's name)
              doc="Current through the source, from p to n (when u is not wired)")
    reference_key = "I"

    def value(self):
        return self.I

    def law(self, v, i, e):
        return i - self.source_value(e)


class VoltageSensor(Component, library=LIB):
    """The voltage v_p - v_n as a signal; draws no current."""
    role = "electrical"
    quantity = "voltage"
    p = Port("electrical", "Positive pin")
    n = Port("electrical", "Negative pin")
    y = Port("signal_out", "Voltage v_p - v_n [V]", optional=True)

    def signal_unit(self, port):
        return "V" if port == "y" else None
    n_states = 0
    state_labels = state_units = ()

    def laws(self, e):
        return [e.i("p"), e.i("n")]

    def output(self, e):
        return e.v("p") - e.v("n")

    def rates(self, e):
        return []

    def initial(self):
        return []


class CurrentSensor(PartialTwoPin, library=LIB):
    """The current from p to n through the sensor as a signal; no voltage across it (wire it
    in series)."""
    quantity = "current"
    y = Port("signal_out", "Current into p [A]", optional=True)

    def signal_unit(self, port):
        return "A" if port == "y" else None

    def law(self, v, i, e):
        return v

    def output(self, e):
        return e.i("p")


class IdealOpAmp(Component, library=LIB):
    """Ideal operational amplifier, a nullator-norator pair (MSL's Analog.Ideal.IdealOpAmp):
    no voltage across and no current into the input port p1, n1; the output port p2, n2
    carries whatever current the circuit needs, with i_p2 + i_n2 = 0."""
    role = "electrical"
    p1 = Port("electrical", "Positive pin of the input port")
    n1 = Port("electrical", "Negative pin of the input port")
    p2 = Port("electrical", "Positive pin of the output port")
    n2 = Port("electrical", "Negative pin of the output port")
    n_states = 0
    state_labels = state_units = ()

    def laws(self, e):
        return [e.v("p1") - e.v("n1"), e.i("p1"), e.i("n1"), e.i("p2") + e.i("n2")]

    def rates(self, e):
        return []

    def initial(self):
        return []


class IdealOpAmp3Pin(Component, library=LIB):
    """Ideal operational amplifier with three pins (MSL's Analog.Ideal.IdealOpAmp3Pin): no
    voltage across and no current into the inputs in_p, in_n (a nullator); the output out
    takes any voltage and current (a norator to ground)."""
    role = "electrical"
    in_p = Port("electrical", "Positive input pin")
    in_n = Port("electrical", "Negative input pin")
    out = Port("electrical", "Output pin")
    n_states = 0
    state_labels = state_units = ()

    def laws(self, e):
        return [e.v("in_p") - e.v("in_n"), e.i("in_p"), e.i("in_n")]

    def rates(self, e):
        return []

    def initial(self):
        return []


class EMF(PartialTwoPin, library=LIB):
    """Ideal electromechanical converter (MSL's Analog.Basic.EMF): v = k w and the torque
    k i on the flange, w the speed of the flange relative to the support; its reaction goes
    to the support (unwired: the world)."""
    #: to the 1-D network it is a torque source whose torque follows the current through it
    role = "source"
    converter = True
    flange = Port("rotational", "Shaft driven by the converter")
    support = Port("rotational", "Housing (unwired: the world)", optional=True)
    k = Param(unit="N*m/A", doc="Transformation coefficient (V*s/rad)")

    def law(self, v, i, e):
        return v - self.k * e.w

    def flows(self, pos, vel, t, current):
        """Flows into the flanges for the current through the converter (MSL's
        flange.tau = -k i: it drives what the flange is wired to with k i)."""
        tau = self.k * current
        return {"flange": -tau, "support": tau}


class DCMotor(Component, library=LIB):
    """A permanent-magnet DC motor wired as in MSL's examples: armature resistance R and
    inductance L in series with an EMF of constant k, whose shaft turns a rotor of inertia J.
    Pins p and n take the armature voltage; flange is the rotor's far side."""
    p = Port("electrical", "Positive armature pin")
    n = Port("electrical", "Negative armature pin")
    flange = Port("rotational", "Shaft (the rotor's flange_b)")
    support = Port("rotational", "Housing (unwired: the world)", optional=True)
    R = Param(unit="Ohm", min=0.0, doc="Armature resistance")
    L = Param(unit="H", positive=True, doc="Armature inductance")
    k = Param(unit="N*m/A", doc="Torque constant (= back-EMF constant, V*s/rad)")
    J = Param(unit="kg*m^2", min=0.0, doc="Rotor inertia")
    i0 = Param(0.0, unit="A", doc="Initial armature current")
    w0 = Param(None, optional=True, unit="rad/s",
               doc="Initial rotor speed when the rotor turns freely (None: 0)")

    def expand(self):
        """Resistor ``Ra``, inductor ``La``, EMF ``emf`` and rotor ``rotor``, wired in MSL's
        order: p - Ra - La - emf - n, emf.flange - rotor.flange_a."""
        from .base import REGISTRY
        inertia = REGISTRY["rotational.Inertia"]
        parts = [Resistor("Ra", R=self.R), Inductor("La", L=self.L, i0=self.i0),
                 EMF("emf", k=self.k), inertia("rotor", J=self.J, w0=self.w0)]
        comps = {c.name: c for c in parts}

        def port(path):
            name, port_name = path.split(".")
            return PortRef(comps[name], port_name)
        wires = [("Ra.n", "La.p"), ("La.n", "emf.p"), ("emf.flange", "rotor.flange_a")]
        exposed = {"p": "Ra.p", "n": "emf.n", "flange": "rotor.flange_b",
                   "support": "emf.support"}
        return Expansion(self.name, comps, [(port(a), port(b)) for a, b in wires],
                         {k: port(v) for k, v in exposed.items()})

__getattr__ = library_attribute("electrical")
