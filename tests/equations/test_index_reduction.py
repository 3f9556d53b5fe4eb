"""Index reduction of circuits (Pantelides, dummy derivatives) against closed forms and an
independent reference: a capacitor across a voltage source (i = C V'(t)), capacitors in
parallel (one capacitor of C1 + C2), inductors in series and an inductor in series with a
current source (closed forms), MSL's CauerLowPassAnalog against its index-1 equations
written by hand and integrated by scipy's DOP853; the states chosen as MSL's (a capacitor of
each loop demoted, the one whose start is given kept), reported by ``System`` and
``kinetwork validate``; a start that contradicts a constraint refused; the refusal of a
singular circuit the same in every process."""

import os
import subprocess
import sys

import numpy as np
import pytest
import scipy.integrate

import kinetwork as kn
from kinetwork.equations.structure import Singular, reduce_index

E = kn.electrical
TOL = dict(rtol=1e-10, atol=1e-12, jit=False)


def _circuit(parts, wires, name="circuit", parameters=None):
    m = kn.Model(name, parameters=parameters or {})
    for c in parts:
        m.add(c)
    for a, b in wires:
        m.connect(a, b)
    return m


def _across(V="sin(3*t)", **cap):
    """A capacitor (and a resistor) straight across a voltage source."""
    return _circuit([E.Ground("g"), E.VoltageSource("src", V=V), E.Capacitor("c", C=2.0, **cap),
                     E.Resistor("r", R=4.0), kn.Probe("pc", quantities=["current", "voltage"]),
                     kn.Probe("ps", quantities=["current"])],
                    [("src.p", "c.p"), ("c.n", "src.n"), ("g.p", "src.n"), ("r.p", "c.p"),
                     ("r.n", "c.n"), ("pc.port", "c.p"), ("ps.port", "src.p")])


def test_a_capacitor_across_a_voltage_source_follows_it():
    m = _across()
    system = m.compile()
    assert system.state_names == []
    assert list(system.demoted_states) == ["c.v"]
    assert "the source src" in system.demoted_states["c.v"]
    res = kn.simulate(m, t_end=2.0, n_points=41, **TOL)
    t = res.t
    assert np.max(abs(res["pc.voltage"] - np.sin(3 * t))) < 1e-12
    # i_C = C dV/dt, and the source delivers it and the resistor's V/R (into its p: -)
    assert np.max(abs(res["pc.current"] - 2.0 * 3 * np.cos(3 * t))) < 1e-12
    assert np.max(abs(res["ps.current"] + 6 * np.cos(3 * t) + np.sin(3 * t) / 4)) < 1e-12


def test_a_start_that_contradicts_the_constraint_is_refused():
    # V(0) = 0: a given v0 = 0 agrees and is accepted; v0 = 1 is not what the loop allows
    assert _across(v0=0.0).compile().state_names == []
    m = _across(v0=1.0)
    with pytest.raises(kn.ModelError, match=r"c\.v0 = 1: c\.v is no state .*the constraint "
                                            r"gives 0 at the start: remove v0") as caught:
        m.compile()
    assert (caught.value.problems[0].component, caught.value.problems[0].parameter) == ("c", "v0")


def _parallel(**starts):
    """Capacitors c1 || c2 charged through r from a step of 5 V: one capacitor c1 + c2."""
    return _circuit([E.Ground("g"), E.VoltageSource("src", V=5.0), E.Resistor("r", R=2.0),
                     E.Capacitor("c1", C=0.5, **starts.get("c1", {})),
                     E.Capacitor("c2", C=1.5, **starts.get("c2", {})),
                     kn.Probe("p2", quantities=["current"])],
                    [("src.p", "r.p"), ("r.n", "c1.p"), ("c1.p", "c2.p"), ("c1.n", "c2.n"),
                     ("c2.n", "src.n"), ("g.p", "src.n"), ("p2.port", "c2.p")])


@pytest.mark.parametrize("starts, kept, demoted", [
    ({}, ["c1.v"], "c2.v"),                              # the first placed stays a state
    ({"c2": {"v0": 1.0}}, ["c2.v"], "c1.v"),             # the one whose start is given
])
def test_capacitors_in_parallel_are_one_capacitor(starts, kept, demoted):
    m = _parallel(**starts)
    system = m.compile()
    assert system.state_names == kept
    assert list(system.demoted_states) == [demoted]
    assert "c1, c2" in system.demoted_states[demoted]
    res = kn.simulate(m, t_end=3.0, n_points=31, **TOL)
    v0 = starts.get("c2", {}).get("v0", 0.0)
    tau = 2.0 * (0.5 + 1.5)
    v = 5 + (v0 - 5) * np.exp(-res.t / tau)
    # the current into c2 is its share of the charging current
    assert np.max(abs(res["p2.current"] - 1.5 * np.gradient(v, res.t, edge_order=2))) < 2e-3
    assert np.max(abs(res["p2.current"] - 1.5 * (5 - v0) / tau * np.exp(-res.t / tau))) < 1e-9


def test_inductors_in_series_are_one_inductor():
    m = _circuit([E.Ground("g"), E.VoltageSource("src", V=2.0), E.Resistor("r", R=3.0),
                  E.Inductor("l1", L=0.5), E.Inductor("l2", L=1.5),
                  kn.Probe("p", quantities=["current", "voltage"])],
                 [("src.p", "r.p"), ("r.n", "l1.p"), ("l1.n", "l2.p"), ("l2.n", "src.n"),
                  ("g.p", "src.n"), ("p.port", "l2.p")])
    system = m.compile()
    assert system.state_names == ["l1.i"]
    assert list(system.demoted_states) == ["l2.i"]
    res = kn.simulate(m, t_end=1.0, n_points=21, **TOL)
    i = 2 / 3 * (1 - np.exp(-3 / 2 * res.t))
    assert np.max(abs(res["p.current"] - i)) < 1e-10
    # the voltage across l2 (its n is grounded): L2 di/dt
    assert np.max(abs(res["p.voltage"] - 1.5 * np.exp(-3 / 2 * res.t))) < 1e-10


def test_an_inductor_in_series_with_a_current_source():
    m = _circuit([E.Ground("g"), E.CurrentSource("src", I="sin(2*t)"), E.Inductor("l", L=0.5),
                  E.Resistor("r", R=2.0), kn.Probe("p", quantities=["voltage"])],
                 [("src.n", "l.p"), ("l.n", "r.p"), ("r.n", "src.p"),
                  ("g.p", "src.p"), ("p.port", "l.p")])
    system = m.compile()
    assert system.state_names == [] and list(system.demoted_states) == ["l.i"]
    res = kn.simulate(m, t_end=1.0, n_points=21, **TOL)
    assert np.max(abs(res["p.voltage"] - (0.5 * 2 * np.cos(2 * res.t)
                                          + 2 * np.sin(2 * res.t)))) < 1e-12


def test_a_signal_driven_source_across_a_capacitor_is_differentiated_through_its_blocks():
    """V from a first-order filter of a sine: its rate is the block's rate, so the current is
    C d/dt of the filter's output."""
    m = _circuit([E.Ground("g"), E.VoltageSource("src"), E.Capacitor("c", C=2.0),
                  kn.signals.Sine("sine", amplitude=1.0, f=0.5),
                  kn.signals.FirstOrder("filt", k=1.0, T=0.2),
                  kn.Probe("pc", quantities=["current"]), kn.Probe("pf", quantities=["value"])],
                 [("src.p", "c.p"), ("c.n", "src.n"), ("g.p", "src.n"), ("sine.y", "filt.u"),
                  ("filt.y", "src.u"), ("pc.port", "c.p"), ("pf.port", "filt.y")])
    system = m.compile()
    assert system.state_names == ["filt.x"] and list(system.demoted_states) == ["c.v"]
    res = kn.simulate(m, t_end=2.0, n_points=41, **TOL)
    y = res["pf.value"]
    dy = (np.sin(2 * np.pi * 0.5 * res.t) - y) / 0.2
    assert np.max(abs(res["pc.current"] - 2.0 * dy)) < 1e-10


L1, L2, C1, C3, C5 = 1.304, 0.8586, 1.072, 1.682, 0.7262
C2, C4 = 1 / (1.704992 ** 2 * L1), 1 / (1.179945 ** 2 * L2)


def cauer_low_pass(starts=True):
    """MSL's Electrical.Analog.Examples.CauerLowPassAnalog, wired and started as MSL's
    (C1, C3, C5 and the inductors with fixed starts; the step of 1 V at t = 1 s)."""
    given = (lambda **kw: kw) if starts else (lambda **kw: {})
    m = _circuit(
        [E.Ground("G"), E.Capacitor("C1", C="c1", **given(v0=0.0)), E.Capacitor("C2", C="c2"),
         E.Capacitor("C3", C="c3", **given(v0=0.0)), E.Capacitor("C4", C="c4"),
         E.Capacitor("C5", C="c5", **given(v0=0.0)), E.Inductor("L1", L="l1", **given(i0=0.0)),
         E.Inductor("L2", L="l2", **given(i0=0.0)), E.Resistor("R1", R=1.0),
         E.Resistor("R2", R=1.0), E.VoltageSource("V", V="if_else(t >= 1, 1, 0)"),
         kn.Probe("out", quantities=["voltage"]), kn.Probe("inp", quantities=["voltage"])],
        [("R1.n", "C1.p"), ("C1.n", "G.p"), ("L1.p", "C2.p"), ("L1.p", "C1.p"),
         ("L1.n", "C2.n"), ("C2.n", "C3.p"), ("C2.n", "C4.p"), ("C2.n", "L2.p"),
         ("L2.n", "C4.n"), ("C4.n", "C5.p"), ("C4.n", "R2.p"), ("C1.n", "C3.n"),
         ("C1.n", "C5.n"), ("R2.n", "C1.n"), ("R1.p", "V.p"), ("V.n", "G.p"),
         ("out.port", "R2.p"), ("inp.port", "V.p")],
        "CauerLowPassAnalog",
        dict(l1=L1, l2=L2, c1=C1, c2=C2, c3=C3, c4=C4, c5=C5))
    m.simulation = {"t_end": 60.0}
    return m


def cauer_reference(t):
    """R2.p.v of the same circuit in its index-1 form, written by hand: the node voltages
    u2, u3, u4 (C1, C3, C5) and the inductor currents; C2 and C4 couple the node equations'
    derivatives, a 3 x 3 mass matrix solved at each step."""
    mass = np.array([[C1 + C2, -C2, 0], [-C2, C2 + C3 + C4, -C4], [0, -C4, C4 + C5]])

    def rhs(_, x):
        u2, u3, u4, i1, i2 = x
        du = np.linalg.solve(mass, [(1.0 - u2) - i1, i1 - i2, i2 - u4])
        return [*du, (u2 - u3) / L1, (u3 - u4) / L2]
    sol = scipy.integrate.solve_ivp(rhs, (1.0, 60.0), np.zeros(5), method="DOP853",
                                    rtol=1e-12, atol=1e-14, dense_output=True)
    return np.where(t >= 1, sol.sol(np.maximum(t, 1.0))[2], 0.0)


@pytest.mark.parametrize("starts, kept", [
    (True, ["C1.v", "C3.v", "C5.v", "L1.i", "L2.i"]),      # MSL's: C2 and C4 demoted
    (False, ["C1.v", "C2.v", "C4.v", "L1.i", "L2.i"]),     # no start given: the first placed
])
def test_cauer_low_pass_analog_matches_its_index_one_equations(starts, kept):
    m = cauer_low_pass(starts)
    system = m.compile()
    assert system.state_names == kept
    assert len(system.demoted_states) == 2
    res = kn.simulate(m, t_end=60.0, n_points=601, **TOL)
    ref = cauer_reference(res.t)
    scale = np.max(abs(ref))
    assert 0.5 < scale < 0.7
    assert np.max(abs(res["out.voltage"] - ref)) < 1e-6 * scale
    assert np.max(abs(res["inp.voltage"] - (res.t >= 1))) < 1e-15


#: MSL's CauerLowPassOPV's connect() equations in its order, the interface pins n1..n14,
#: p1..p4 and out1 it wires through standing for the nodes they join
OPV_WIRES = """Op1.in_p, G.p
G1.p, Op2.in_p
R1.n, n1
n1, Op1.in_n
C2.n, n1
R2.n, n2
n1, n2
n2, n3
n3, C1.p
n3, R3.p
C1.n, n4
R3.n, n4
n4, Op1.out
R4.p, Op1.out
C5.p, Op1.out
R4.n, n5
n5, Op2.in_n
C3.p, n5
R5.n, n5
R5.p, p1
C2.p, p1
C3.n, n6
n6, Op2.out
R2.p, n6
Op2.out, R7.p
R7.n, n7
n7, Op3.in_n
C5.n, n7
R6.n, n8
n7, n8
C6.p, p2
n8, p2
C4.n, p2
C6.n, Op3.out
R9.p, Op3.out
Op3.out, out1
p1, out1
out1, C8.p
C4.p, p3
p3, R8.p
R8.n, n9
n9, n10
R9.n, n10
n10, Op4.in_n
n9, C7.p
C7.n, n11
R6.p, n11
n11, Op4.out
Op4.out, R10.p
G2.p, Op3.in_p
R11.n, n12
p3, n12
C9.n, n13
n12, n13
n13, Op5.out
C9.p, p4
R11.p, p4
R10.n, n14
p4, n14
Op5.in_n, n14
C8.n, n14
Op4.in_p, G3.p
Op5.in_p, G4.p
V.p, Ground1.p
V.n, R1.p"""


def cauer_low_pass_opv():
    """MSL's Electrical.Analog.Examples.CauerLowPassOPV: the same filter built of five ideal
    3-pin op-amps, nine capacitors (C1, C2, C3, C4 and C7 with fixed starts) and resistors
    of +-1 Ohm; the source wired reversed (a step of -1 V), so that the inverting network
    gives the analog filter's response."""
    m = kn.Model("CauerLowPassOPV", parameters=dict(l1=L1, l2=L2, c1=C1, c2=C2, c3=C3,
                                                    c4=C4, c5=C5))
    fixed = dict(v0=0.0)
    for c in (E.Capacitor("C1", C="c1 + c2", **fixed), E.Capacitor("C2", C="c2", **fixed),
              E.Capacitor("C3", C="l1", **fixed), E.Capacitor("C4", C="c4", **fixed),
              E.Capacitor("C5", C="c2"), E.Resistor("R1", R=1), E.Resistor("R2", R=1),
              E.Resistor("R3", R=1), E.IdealOpAmp3Pin("Op1"), E.Ground("G"),
              E.Resistor("R4", R=-1), E.Resistor("R5", R=-1), E.IdealOpAmp3Pin("Op2"),
              E.IdealOpAmp3Pin("Op3"), E.Ground("G1"), E.Resistor("R6", R=1),
              E.Resistor("R7", R=1), E.Capacitor("C6", C="c2 + c3 + c4"),
              E.Resistor("R8", R=-1), E.Resistor("R9", R=-1), E.Resistor("R10", R=1),
              E.IdealOpAmp3Pin("Op4"), E.IdealOpAmp3Pin("Op5"),
              E.Capacitor("C7", C="l2", **fixed), E.Capacitor("C8", C="c4"),
              E.Capacitor("C9", C="c4 + c5"), E.Resistor("R11", R=1), E.Ground("G2"),
              E.Ground("G3"), E.Ground("G4"), E.VoltageSource("V", V="if_else(t >= 1, 1, 0)"),
              E.Ground("Ground1"), kn.Probe("out", quantities=["voltage"])):
        m.add(c)
    parent = {}

    def root(x):
        while parent.setdefault(x, x) != x:
            x = parent[x]
        return x
    for line in OPV_WIRES.splitlines():
        a, b = (x.strip() for x in line.split(","))
        parent[root(a)] = root(b)
    nodes = {}
    for x in parent:
        if "." in x:
            nodes.setdefault(root(x), []).append(x)
    for pins in nodes.values():
        for other in pins[1:]:
            m.connect(pins[0], other)
    m.connect("out.port", "Op5.out")
    m.simulation = {"t_end": 60.0}
    return m


def test_cauer_low_pass_opv_is_the_analog_filter():
    """MSL: "identical to the CauerLowPassAnalog example": its output against the analog
    filter's hand-written equations; the op-amps' virtual grounds make four capacitor loops,
    and the capacitors MSL starts are the states."""
    m = cauer_low_pass_opv()
    system = m.compile()
    assert system.state_names == ["C1.v", "C2.v", "C3.v", "C4.v", "C7.v"]
    assert list(system.demoted_states) == ["C5.v", "C6.v", "C8.v", "C9.v"]
    res = kn.simulate(m, t_end=60.0, n_points=601, **TOL)
    ref = cauer_reference(res.t)
    assert np.max(abs(res["out.voltage"] - ref)) < 1e-6 * np.max(abs(ref))


def test_validate_shows_the_states_chosen_and_demoted(tmp_path, capsys):
    from kinetwork.cli import main
    path = tmp_path / "cauer.json"
    cauer_low_pass().save(path)
    assert main(["validate", str(path)]) == 0
    out = " ".join(capsys.readouterr().out.split())     # lines wrapped at 88 columns
    assert "states: 5 (C1.v [V], C3.v [V], C5.v [V], L1.i [A], L2.i [A])" in out
    assert "demoted by index reduction: C2.v (follows from C1.v, C3.v through the " \
           "constraint of C1, C2, C3)" in out
    assert "C4.v (follows from C3.v, C5.v through the constraint of C3, C4, C5)" in out


REFUSAL = """
import kinetwork as kn
E = kn.electrical
m = kn.Model("m")
for c in (E.Ground("g"), E.VoltageSource("a", V=1.0), E.VoltageSource("b", V=2.0),
          E.Capacitor("c", C=1.0), E.CurrentSource("i1", I=1.0), E.CurrentSource("i2", I=2.0),
          E.Resistor("r", R=1.0)):
    m.add(c)
for x, y in [("a.p", "b.p"), ("a.n", "b.n"), ("g.p", "a.n"), ("c.p", "a.p"), ("c.n", "a.n"),
             ("i1.n", "i2.p"), ("i2.n", "r.p"), ("r.n", "i1.p"), ("i1.p", "g.p")]:
    m.connect(x, y)
try:
    m.compile()
except kn.ModelError as exc:
    print(exc)
"""


def test_the_refusal_of_a_singular_circuit_is_the_same_in_every_process():
    """String hashes differ between processes (PYTHONHASHSEED): nothing the message says may
    follow a set's order."""
    outs = set()
    for seed in ("1", "2", "3"):
        env = {**os.environ, "PYTHONHASHSEED": seed}
        outs.add(subprocess.run([sys.executable, "-c", REFUSAL], capture_output=True,
                                text=True, env=env, check=True).stdout)
    assert len(outs) == 1
    message = outs.pop()
    assert "circuit: the equations of a, b" in message
    assert "structurally singular" in message


def test_pantelides_on_a_pendulum_in_cartesian_coordinates():
    """The classic index-3 test of the machinery itself: x'' = -T x, y'' = -T y - g,
    x^2 + y^2 = L^2, written first order (u = x', v = y'): the constraint is differentiated
    twice, one of (x, y) and one of (u, v) are demoted, the tension T is solved."""
    import casadi as ca
    t = ca.SX.sym("t")
    x, y, u, v, T = (ca.SX.sym(n) for n in "xyuvT")
    dx, dy, du, dv = (ca.SX.sym("d" + n) for n in "xyuv")
    eqs = [dx - u, dy - v, du + T * x, dv + T * y + 9.81, x ** 2 + y ** 2 - 1]
    red = reduce_index(eqs, [T], [x, y, u, v], [dx, dy, du, dv], [], t,
                       [(False, -k) for k in range(4)],
                       lambda e: np.array(ca.evalf(ca.substitute(
                           e, ca.vertcat(*ca.symvar(e)),
                           ca.DM(np.linspace(0.3, 0.9, len(ca.symvar(e)))))),
                           dtype=float).reshape(e.shape))
    assert sorted(red.states) == [0, 2]            # x and u kept: y and v demoted
    assert sorted(red.demoted) == [1, 3]
    # the constraint twice, the rate equations of x and y once (their derivatives' aliases)
    assert red.differentiated == {0: 1, 1: 1, 4: 2}
    assert len(red.equations) == len(red.unknowns)


def test_a_structurally_singular_system_names_its_parts():
    import casadi as ca
    t = ca.SX.sym("t")
    a, b = ca.SX.sym("a"), ca.SX.sym("b")
    with pytest.raises(Singular) as info:
        reduce_index([a - 1, a - 2], [a, b], [], [], [], t, [], None)
    assert info.value.equations == [0, 1] and info.value.unknowns == [1]


# -- constraints of the 1-D network through the circuit -------------------------------------
R = kn.rotational


def _electric_gear(**j2):
    """Two free rotors, each turned by an EMF, the EMFs' pins wired to each other: an ideal
    electric gear of ratio k2/k1 (k1 w1 = k2 w2), J1 driven by 1.5 N m."""
    return _circuit([R.Inertia("J1", J=2.0), R.Inertia("J2", J=0.5, **j2),
                     E.EMF("e1", k=0.3), E.EMF("e2", k=0.6), E.Ground("g"),
                     R.Torque("T", tau=1.5), kn.Probe("p1", quantities=["speed", "angle"]),
                     kn.Probe("p2", quantities=["speed"]), kn.Probe("pi", quantities=["current"])],
                    [("e1.flange", "J1.flange_a"), ("e2.flange", "J2.flange_a"),
                     ("e1.p", "e2.p"), ("e1.n", "e2.n"), ("g.p", "e1.n"),
                     ("T.flange", "J1.flange_b"), ("p1.port", "J1.flange_a"),
                     ("p2.port", "J2.flange_a"), ("pi.port", "e1.p")])


def test_two_rotors_tied_by_an_electric_gear_share_one_speed():
    """Today's 1-D rigid groups tie flanges through gears; two EMFs wired to each other tie
    two rotors through the circuit, a constraint the index reduction finds: J2's speed is
    demoted, the pair turns as one inertia J1 + J2 (k1/k2)^2, and the current is what J2's
    acceleration needs (k2 i = -J2 a2)."""
    m = _electric_gear()
    system = m.compile()
    assert system.state_names == ["J1.phi", "J1.w", "J2.phi"]
    assert system.demoted_states == {
        "J2.w": "follows from J1.w through the constraint of J1, J2, e1, e2"}
    res = kn.simulate(m, t_end=1.0, n_points=21, **TOL)
    a1 = 1.5 / (2.0 + 0.5 * (0.3 / 0.6) ** 2)
    assert np.max(abs(res["p1.speed"] - a1 * res.t)) < 1e-12
    assert np.max(abs(res["p1.angle"] - a1 * res.t ** 2 / 2)) < 1e-10
    assert np.max(abs(res["p2.speed"] - 0.3 / 0.6 * a1 * res.t)) < 1e-12
    # J2 a2 = torque of e2 = k2 i2, i2 the current into e2.p = -(into e1.p)
    assert np.max(abs(res["pi.current"] + 0.5 * 0.5 * a1 / 0.6)) < 1e-12


def test_a_start_on_the_demoted_rotor_must_agree_with_the_gear():
    assert _electric_gear(w0=0.0).compile().state_names == ["J1.phi", "J2.phi", "J2.w"]
    m = _circuit([R.Inertia("J", J=2.0, w0=1.0), E.EMF("e", k=0.5), E.Ground("g"),
                  E.VoltageSource("V", V="sin(t)")],
                 [("e.flange", "J.flange_a"), ("V.p", "e.p"), ("V.n", "e.n"), ("g.p", "e.n")])
    with pytest.raises(kn.ModelError, match=r"J\.w0 = 1: J\.w is no state \(follows from the "
                                            r"source V .*gives 0 at the start"):
        m.compile()


def test_a_voltage_source_across_an_emf_turns_its_rotor_at_v_over_k():
    m = _circuit([R.Inertia("J", J=2.0), E.EMF("e", k=0.5), E.Ground("g"),
                  E.VoltageSource("V", V="sin(t)"), kn.Probe("p", quantities=["speed", "angle"]),
                  kn.Probe("pi", quantities=["current"])],
                 [("e.flange", "J.flange_a"), ("V.p", "e.p"), ("V.n", "e.n"), ("g.p", "e.n"),
                  ("p.port", "J.flange_a"), ("pi.port", "e.p")])
    system = m.compile()
    assert system.state_names == ["J.phi"] and list(system.demoted_states) == ["J.w"]
    res = kn.simulate(m, t_end=2.0, n_points=21, **TOL)
    assert np.max(abs(res["p.speed"] - np.sin(res.t) / 0.5)) < 1e-12
    assert np.max(abs(res["p.angle"] - (1 - np.cos(res.t)) / 0.5)) < 1e-9
    # the torque J w' = k i: the current J cos(t) / k^2 into e.p
    assert np.max(abs(res["pi.current"] - 2.0 * np.cos(res.t) / 0.25)) < 1e-12


def test_a_capacitor_across_an_emf_adds_c_k_squared_to_the_rotor():
    m = _circuit([R.Inertia("J", J=2.0), E.EMF("e", k=0.5), E.Ground("g"),
                  E.Capacitor("C", C=4.0), R.Torque("T", tau=3.0),
                  kn.Probe("p", quantities=["speed"]), kn.Probe("pc", quantities=["voltage"])],
                 [("e.flange", "J.flange_a"), ("C.p", "e.p"), ("C.n", "e.n"), ("g.p", "e.n"),
                  ("p.port", "J.flange_a"), ("T.flange", "J.flange_b"), ("pc.port", "C.p")])
    system = m.compile()
    assert system.state_names == ["J.phi", "J.w"] and list(system.demoted_states) == ["C.v"]
    res = kn.simulate(m, t_end=1.0, n_points=11, **TOL)
    a = 3.0 / (2.0 + 4.0 * 0.5 ** 2)
    assert np.max(abs(res["p.speed"] - a * res.t)) < 1e-12
    assert np.max(abs(res["pc.voltage"] - 0.5 * a * res.t)) < 1e-12


def test_a_circuit_that_constrains_a_joint_is_refused_naming_it():
    mb = kn.multibody
    m = _circuit([mb.Ground("ground"), mb.Revolute("rev", axis=[0, 0, 1]),
                  mb.RigidBody("body", mass=1.0, r_cm=[0.5, 0, 0], inertia=[0, 0, 0.1]),
                  E.EMF("e", k=0.5), E.Ground("g"), E.VoltageSource("V", V="sin(t)")],
                 [("ground.frame", "rev.frame_a"), ("rev.frame_b", "body.frame_a"),
                  ("e.flange", "rev.axis"), ("e.support", "rev.support"), ("V.p", "e.p"),
                  ("V.n", "e.n"), ("g.p", "e.n")])
    with pytest.raises(kn.ModelError, match=r"e: the circuit fixes the voltage across e .*"
                                            r"constrains the speed at e\.flange, which is a "
                                            r"joint's axis") as caught:
        m.compile()
    assert (caught.value.problems[0].component, caught.value.problems[0].port) == ("e", "flange")


# -- large circuits ----------------------------------------------------------------------------
def ladder(n):
    """A Cauer-like ladder of n sections (L || C in series, C to ground): n + 1 capacitor
    loops, so the differentiated constraints make one linear block across the ladder."""
    parts = [E.Ground("g"), E.VoltageSource("V", V="sin(t)"), E.Resistor("R1", R=1.0),
             E.Resistor("R2", R=1.0), E.Capacitor("Cs0", C=1.0),
             kn.Probe("out", quantities=["voltage"])]
    wires = [("V.n", "g.p"), ("V.p", "R1.p"), ("Cs0.p", "R1.n"), ("Cs0.n", "g.p")]
    node = "R1.n"
    for k in range(n):
        parts += [E.Inductor(f"L{k}", L=1.0), E.Capacitor(f"Cp{k}", C=0.3),
                  E.Capacitor(f"Cs{k + 1}", C=1.0)]
        wires += [(f"L{k}.p", node), (f"Cp{k}.p", node), (f"L{k}.n", f"Cp{k}.n"),
                  (f"Cs{k + 1}.p", f"L{k}.n"), (f"Cs{k + 1}.n", "g.p")]
        node = f"L{k}.n"
    wires += [("R2.p", node), ("R2.n", "g.p"), ("out.port", node)]
    return _circuit(parts, wires, "ladder")


def test_a_large_block_is_eliminated_sparsely_and_gives_the_dense_answer(monkeypatch):
    """The differentiated constraints of a ladder couple every section in one linear block:
    solved by sparse elimination its right-hand side grows linearly with the ladder
    (a dense symbolic solve grows as its cube), and gives the dense solve's answer."""
    import kinetwork.equations.blocks as blocks
    sizes = {n: ladder(n).compile().size()["operations"] for n in (5, 20)}
    assert sizes[20] < 5 * sizes[5]
    sparse = kn.simulate(ladder(6), t_end=10.0, n_points=51, **TOL)
    monkeypatch.setattr(blocks, "SMALL_BLOCK", 10 ** 6)
    dense = kn.simulate(ladder(6), t_end=10.0, n_points=51, **TOL)
    assert 0.1 < np.max(abs(dense["out.voltage"])) < 1
    assert np.max(abs(sparse["out.voltage"] - dense["out.voltage"])) < 1e-12


def test_a_singular_part_of_a_large_circuit_is_named():
    """Two voltage sources in parallel across a section of the ladder: named, with the
    ladder's other hundred unknowns left out of the message."""
    m = ladder(5)
    m.add(E.VoltageSource("short", V=0.0))
    m.connect("short.p", "L0.p")
    m.connect("short.n", "L0.n")
    m.add(E.VoltageSource("short2", V=0.0))
    m.connect("short2.p", "L0.p")
    m.connect("short2.n", "L0.n")
    with pytest.raises(kn.ModelError, match="circuit: the equations of .*short, short2"):
        m.compile()


def test_a_loop_of_zero_resistances_is_singular_at_the_values():
    """Structurally regular (R a parameter), singular at R = 0: refused naming the block;
    the same circuit at R = 1 builds."""
    def loop(r):
        return _circuit([E.Ground("g"), E.VoltageSource("src", V=1.0), E.Resistor("r1", R="R"),
                         E.Resistor("r2", R="R")],
                        [("src.p", "r1.p"), ("r1.n", "r2.p"), ("r2.n", "src.n"),
                         ("g.p", "src.n")], parameters={"R": r})
    with pytest.raises(kn.ModelError, match=r"circuit: the equations of r1, r2.* cannot be "
                                            r"solved: singular at the parameters' values"):
        loop(0.0).compile()
    assert loop(1.0).compile().n_states == 0
