"""The electrical laws beyond the linear ones, against closed forms and independent models:
MSL's Conductor (i = G v) and Resistor with a negative R, MSL's Semiconductors.Diode (its
exponential and its linear continuation beyond Maxexp in closed form; a half-wave rectifier
against scipy with the diode solved by brentq at every evaluation), and a resistor whose
current is an expression of its voltage (a linear law equals a Resistor; MSL's ChuaCircuit
against scipy's DOP853 on the same equations written by hand)."""

import math

import numpy as np
import pytest
import scipy.integrate
import scipy.optimize

import kinetwork as kn

E = kn.electrical
TOL = dict(rtol=1e-10, atol=1e-12, jit=False)


def _circuit(parts, wires, parameters=None):
    m = kn.Model("circuit", parameters=parameters or {})
    for c in parts:
        m.add(c)
    for a, b in wires:
        m.connect(a, b)
    return m


def test_a_conductor_charges_a_capacitor_as_the_resistor_of_1_over_g():
    m = _circuit([E.Ground("g"), E.VoltageSource("src", V=10.0), E.Conductor("cd", G=0.002),
                  E.Capacitor("c", C=1e-4, v0=2.0), kn.Probe("pc", quantities=["voltage"])],
                 [("src.p", "cd.p"), ("cd.n", "c.p"), ("c.n", "src.n"), ("g.p", "src.n"),
                  ("pc.port", "c.p")])
    res = kn.simulate(m, t_end=0.2, n_points=21, **TOL)
    tau = 1e-4 / 0.002
    assert np.max(abs(res["pc.voltage"] - (10 - 8 * np.exp(-res.t / tau)))) < 1e-9


def test_a_negative_resistance_as_msl_allows_it():
    """R = -1 in series with R = 3: 2 Ohm in all (MSL's CauerLowPassOPV uses R = -1)."""
    m = _circuit([E.Ground("g"), E.VoltageSource("src", V=4.0), E.Resistor("neg", R=-1.0),
                  E.Resistor("r", R=3.0), kn.Probe("p", quantities=["current"])],
                 [("src.p", "neg.p"), ("neg.n", "r.p"), ("r.n", "src.n"), ("g.p", "src.n"),
                  ("p.port", "r.p")])
    res = kn.simulate(m, t_end=0.1, n_points=3, **TOL)
    assert np.allclose(res["p.current"], 2.0, rtol=1e-14)


def _diode_current(v, Ids=1e-6, Vt=0.04, Maxexp=15.0, R=1e8):
    """MSL's Diode written out again: exlin(x, Maxexp) = exp(x), continued linearly."""
    x = v / Vt
    ex = math.exp(Maxexp) * (1 + x - Maxexp) if x > Maxexp else math.exp(x)
    return Ids * (ex - 1) + v / R


@pytest.mark.parametrize("current", [1e-3, 0.2, 50.0])
def test_a_diode_under_a_current_source(current):
    """A current I through the diode: its voltage solves I = i(v); beyond Maxexp (the largest
    current) the law is linear, so v has a closed form there."""
    m = _circuit([E.Ground("g"), E.CurrentSource("src", I=current), E.Diode("d"),
                  kn.Probe("pd", quantities=["voltage"])],
                 [("src.p", "g.p"), ("src.n", "d.p"), ("d.n", "g.p"), ("pd.port", "d.p")])
    system = m.compile()
    assert system.algebraic_names == ["src.n.v"] and system.algebraic_units == ["V"]
    res = kn.simulate(m, t_end=0.1, n_points=3, **TOL)
    v = scipy.optimize.brentq(lambda v: _diode_current(v) - current, -1, 10, xtol=1e-15)
    if v / 0.04 > 15:
        e15 = math.exp(15)
        v_lin = (current + 1e-6 - 1e-6 * e15 * (1 - 15)) / (1e-6 * e15 / 0.04 + 1e-8)
        assert v_lin == pytest.approx(v, rel=1e-12)
    assert np.allclose(res["pd.voltage"], v, rtol=1e-10, atol=0)


def test_a_half_wave_rectifier_matches_scipy():
    """A sine through R into a diode charging C with a load: the capacitor's voltage against
    DOP853 on the hand-written ODE, the diode's voltage found by brentq at every step."""
    m = _circuit([E.Ground("g"), E.VoltageSource("src", V="2*sin(2*pi*t)"),
                  E.Resistor("r", R=10.0), E.Diode("d"), E.Capacitor("c", C=0.05),
                  E.Resistor("load", R=50.0), kn.Probe("pc", quantities=["voltage"]),
                  kn.Probe("pd", quantities=["current"])],
                 [("src.p", "r.p"), ("r.n", "d.p"), ("d.n", "c.p"), ("c.n", "g.p"),
                  ("src.n", "g.p"), ("load.p", "c.p"), ("load.n", "g.p"), ("pc.port", "c.p"),
                  ("pd.port", "d.p")])
    assert "1 nonlinear blocks, 1 algebraic variables" in m.compile().asm.net.circuit
    res = kn.simulate(m, t_end=2.0, n_points=101, **TOL)

    def vd(t, vc):
        v_in = 2 * math.sin(2 * math.pi * t)
        return scipy.optimize.brentq(lambda v: (v_in - vc - v) / 10 - _diode_current(v),
                                     -50, 50, xtol=1e-15, rtol=1e-15)

    def rhs(t, x):
        return [(_diode_current(vd(t, x[0])) - x[0] / 50) / 0.05]
    sol = scipy.integrate.solve_ivp(rhs, (0, 2), [0.0], method="DOP853", rtol=1e-12,
                                    atol=1e-14, dense_output=True)
    vc = sol.sol(res.t)[0]
    assert 0.7 < np.max(vc) < 0.8
    assert np.max(abs(res["pc.voltage"] - vc)) < 1e-8
    i_d = [_diode_current(vd(t, v)) for t, v in zip(res.t, vc)]
    assert np.max(abs(res["pd.current"] - i_d)) < 1e-8


def test_a_linear_law_is_a_resistor():
    def rc(resistor):
        m = _circuit([E.Ground("g"), E.VoltageSource("src", V="3*sin(t)"), resistor,
                      E.Capacitor("c", C=0.5), kn.Probe("pc", quantities=["voltage"])],
                     [("src.p", "r.p"), ("r.n", "c.p"), ("c.n", "src.n"), ("g.p", "src.n"),
                      ("pc.port", "c.p")], {"R0": 2.0})
        return kn.simulate(m, t_end=3.0, n_points=31, **TOL)["pc.voltage"]
    law = rc(E.NonlinearResistor("r", i="v/R0"))
    assert np.max(abs(law - rc(E.Resistor("r", R="R0")))) < 1e-12


CHUA = "if_else(v < -Ve, Gb*(v + Ve) - Ga*Ve, if_else(v > Ve, Gb*(v - Ve) + Ga*Ve, Ga*v))"


def chua_circuit():
    """MSL's Electrical.Analog.Examples.ChuaCircuit, its NonlinearResistor as an expression."""
    m = _circuit([E.Inductor("L", L=18, i0=0), E.Resistor("Ro", R=12.5e-3),
                  E.Conductor("G", G=0.565), E.Capacitor("C1", C=10, v0=4),
                  E.Capacitor("C2", C=100, v0=0), E.NonlinearResistor("Nr", i=CHUA),
                  E.Ground("Gnd"), kn.Probe("p1", quantities=["voltage"])],
                 [("L.n", "Ro.p"), ("C2.p", "G.p"), ("L.p", "G.p"), ("G.n", "Nr.p"),
                  ("C1.p", "G.n"), ("Ro.n", "Gnd.p"), ("C2.n", "Gnd.p"), ("Gnd.p", "C1.n"),
                  ("Gnd.p", "Nr.n"), ("p1.port", "C1.p")],
                 {"Ga": -0.757576, "Gb": -0.409091, "Ve": 1.0})
    return m


def test_chua_circuit_matches_its_hand_written_equations():
    """Chaotic over MSL's 5e4 s; over 300 s two independent integrations still agree to
    the tolerance's order."""
    m = chua_circuit()
    assert m.compile().state_names == ["L.i", "C1.v", "C2.v"]
    res = kn.simulate(m, t_end=300.0, n_points=601, **TOL)
    Ga, Gb, Ve = -0.757576, -0.409091, 1.0

    def nr(v):
        return Gb * (v + Ve) - Ga * Ve if v < -Ve else (
            Gb * (v - Ve) + Ga * Ve if v > Ve else Ga * v)

    def rhs(_, x):
        v1, v2, i = x
        return [(0.565 * (v2 - v1) - nr(v1)) / 10, (-i - 0.565 * (v2 - v1)) / 100,
                (v2 - 12.5e-3 * i) / 18]
    sol = scipy.integrate.solve_ivp(rhs, (0, 300), [4, 0, 0], method="DOP853", rtol=1e-13,
                                    atol=1e-13, dense_output=True)
    ref = sol.sol(res.t)[0]
    assert np.max(abs(ref)) > 2
    assert np.max(abs(res["p1.voltage"] - ref)) < 1e-6 * np.max(abs(ref))


def test_the_law_names_what_it_may_read(tmp_path):
    m = _circuit([E.Ground("g"), E.VoltageSource("src", V=1.0),
                  E.NonlinearResistor("r", i="v/Rx")],
                 [("src.p", "r.p"), ("r.n", "src.n"), ("g.p", "src.n")], {"R0": 2.0})
    with pytest.raises(kn.ModelError, match=r"r\.i: unknown name 'Rx' in 'v/Rx'; names are v "
                                            r"\(the voltage\), t and the model's parameters R0") \
            as caught:
        m.compile()
    assert (caught.value.problems[0].component, caught.value.problems[0].parameter) == ("r", "i")
    m = chua_circuit()
    m.save(tmp_path / "chua.json")
    again = kn.load(tmp_path / "chua.json")
    assert again.components["Nr"].i == CHUA


def test_help_shows_the_laws_units():
    assert "Ids : A, >= 0, default 1e-06" in kn.electrical.Diode.__doc__
    assert "G : S" in kn.electrical.Conductor.__doc__
    assert "i : expression in A, required" in kn.electrical.NonlinearResistor.__doc__


def test_an_ode_method_on_a_diode_circuit_says_why_not():
    m = _circuit([E.Ground("g"), E.VoltageSource("src", V=1.0), E.Resistor("r", R=10.0),
                  E.Diode("d")],
                 [("src.p", "r.p"), ("r.n", "d.p"), ("d.n", "src.n"), ("g.p", "src.n")])
    with pytest.raises(kn.ModelError, match=r"integrates ODEs only.*algebraic variables "
                                            r"\(r\.n\.v: .*nonlinear circuit"):
        kn.simulate(m, t_end=0.1, method="cvodes")
