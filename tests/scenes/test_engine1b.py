"""MSL's Engine1b (``models/engine1b.json``): Engine1a's mechanism, restructured as MSL's
Engine1b (piston pin b1, rod1, the crank-pin revolute b2 cut), with MSL's GasForce2 between
the cylinder's support and axis as one ``Force`` whose law is an expression with conditionals
in the sensed piston position and speed (``build(blocks=True)`` writes it as MSL's diagram
does, an ``Expression`` block driving the Force's input: tests/components/
test_force_expressions.py checks the two agree).

The reference is written apart from kinetwork: the slider-crank's Lagrangian in the crank
angle, derived by sympy from the parts' masses and inertias (MSL's BodyBox / BodyCylinder
formulas, density 7700), with the gas force's generalized force F(s, s') ds/dphi, integrated
by scipy's DOP853 piecewise: the pressure law switches between compression and expansion
where the piston stops (the dead centres, sin(phi) = 0, located as events)."""

import math
import pathlib

import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp

import kinetwork as kn

MODEL = pathlib.Path(__file__).resolve().parents[2] / "models" / "engine1b.json"
RHO, G, L_CYL, BORE = 7700.0, 9.81, 0.35, 0.1

#: MSL GasForce2's pressure [bar] in x = 1 - s/L: compression (v < 0) low / high x, expansion
#: high / low x
COMPRESSION = ("177.4132*x^4 - 287.2189*x^3 + 151.8252*x^2 - 24.9973*x + 2.4",
               "2836360*x^4 - 10569296*x^3 + 14761814*x^2 - 9158505*x + 2129670")
EXPANSION = ("-3929704*x^4 + 14748765*x^3 - 20747000*x^2 + 12964477*x - 3036495",
             "145.930*x^4 - 131.707*x^3 + 17.3438*x^2 + 17.9272*x + 2.4")


def gas_law(s="s", v="v"):
    """GasForce2's force on the piston along the cylinder (towards larger s) [N], as one
    expression in the piston's position s and speed v (names of an Expression's inputs, or
    signal outputs "pistonPosition.y") and the parameters L and d."""
    def poly(text):
        return "(" + text.replace("x", f"(1 - {s}/L)") + ")"
    return (f"1e5*if_else({v} < 0, if_else(1 - {s}/L < 0.986061, {poly(COMPRESSION[0])}, "
            f"{poly(COMPRESSION[1])}), if_else(1 - {s}/L > 0.933, {poly(EXPANSION[0])}, "
            f"{poly(EXPANSION[1])}))*pi*d^2/4")


def build(blocks=False):
    """Engine1b wired part for part as MSL 4's Examples.Loops.Engine1b (Engine1Base +
    Engine1bBase); the gas force one Force with its law in the sensed signals, or with
    ``blocks`` an Expression block (gasLaw) driving the Force's input, as MSL's diagram."""
    mb, rot, tr, sig = kn.multibody, kn.rotational, kn.translational, kn.signals
    m = kn.Model("Engine1b", parameters={"L": L_CYL, "d": BORE})
    m.description = (
        "Modelica.Mechanics.MultiBody.Examples.Loops.Engine1b (MSL 4.0; Utilities.Engine1Base "
        "and Engine1bBase): one cylinder of an engine, Engine1a's parts (crank1..4, mid, "
        "connectingRod, piston, cylPosition) restructured with the piston pin b1, rod1 and "
        "the crank-pin revolute b2 as the cut joint (MSL's RevolutePlanarLoopConstraint), and "
        "MSL's GasForce2(L = 0.35, d = 0.1) between the cylinder's support and axis: its "
        "pressure polynomials in x = 1 - s/L, chosen by v < 0 (compression) and x, are one "
        "expression with if_else, the law of one Force (gasForce) in the sensed piston "
        "position and speed (pistonPosition.y, pistonSpeed.y). The load inertia starts at 10 rad/s as Engine1Base starts it "
        "(MSL 4's Engine1b sets w(start = 0): at the top dead centre the gas force has no "
        "lever and the crank stays there). Reproduces the crank speed (probe crank.speed) "
        "and the gas force cycle over the piston position (MSL's figure gasForceCycle.png: "
        "probe stroke with gasForce's law), checked against an independent sympy/scipy "
        "slider-crank with the gas force in tests/scenes/test_engine1b.py.")
    add = m.add
    add(mb.Ground("world", gravity=[0, -G, 0]))
    add(mb.Revolute("bearing", axis=[1, 0, 0], q0=0.0, qd0=10.0))
    add(rot.Inertia("inertia", J=1.0))
    add(mb.BodyCylinder("crank1", r=[0.1, 0, 0], diameter=0.05))
    add(mb.BodyBox("crank2", r=[0, 0.1, 0], width_direction=[1, 0, 0], width=0.02,
                   height=0.05))
    add(mb.BodyCylinder("crank3", r=[0.1, 0, 0], diameter=0.03))
    add(mb.BodyBox("crank4", r=[0, -0.1, 0], width_direction=[1, 0, 0], width=0.02,
                   height=0.05))
    add(mb.FixedTranslation("mid", r=[0.05, 0, 0]))
    add(mb.FixedTranslation("cylPosition", r=[0.15, 0.45, 0]))
    add(mb.Prismatic("cylinder", axis=[0, -1, 0], q0_guess=0.05))
    add(mb.BodyCylinder("piston", r=[0, -0.1, 0], diameter=0.1))
    add(mb.FixedTranslation("rod3", r=[0, -0.1, 0]))
    add(mb.Revolute("b1", axis=[1, 0, 0]))
    add(mb.FixedTranslation("rod1", r=[0, -0.2, 0]))
    add(mb.BodyBox("connectingRod", r=[0, -0.2, 0], width_direction=[1, 0, 0], width=0.02,
                   height=0.06))
    add(mb.Revolute("b2", axis=[1, 0, 0], cut=True))
    add(tr.PositionSensor("pistonPosition"))
    add(tr.SpeedSensor("pistonSpeed"))
    if blocks:
        add(sig.Expression("gasLaw", expression=gas_law(), names=["s", "v"]))
        add(tr.Force("gasForce"))
    else:
        add(tr.Force("gasForce", f=gas_law("pistonPosition.y", "pistonSpeed.y")))
    add(kn.Probe("crank", quantities=["angle", "speed"]))
    add(kn.Probe("stroke", quantities=["position", "velocity"]))
    for a, b in [("world.frame", "bearing.frame_a"), ("crank2.frame_a", "crank1.frame_b"),
                 ("bearing.frame_b", "crank1.frame_a"), ("world.frame", "cylPosition.frame_a"),
                 ("crank3.frame_b", "crank4.frame_a"), ("inertia.flange_b", "bearing.axis"),
                 ("crank2.frame_b", "crank3.frame_a"), ("crank2.frame_b", "mid.frame_a"),
                 ("cylinder.frame_b", "rod3.frame_a"), ("cylPosition.frame_b",
                                                        "cylinder.frame_a"),
                 ("piston.frame_a", "cylinder.frame_b"), ("rod3.frame_b", "b1.frame_a"),
                 ("mid.frame_b", "b2.frame_a"), ("b2.frame_b", "connectingRod.frame_b"),
                 ("b2.frame_b", "rod1.frame_b"), ("b1.frame_b", "rod1.frame_a"),
                 ("pistonPosition.flange", "cylinder.axis"),
                 ("pistonSpeed.flange", "cylinder.axis"),
                 *([("pistonPosition.y", "gasLaw.u1"), ("pistonSpeed.y", "gasLaw.u2"),
                    ("gasLaw.y", "gasForce.u")] if blocks else []),
                 ("gasForce.flange", "cylinder.axis"),
                 ("gasForce.support", "cylinder.support"), ("crank.port", "bearing.axis"),
                 ("stroke.port", "cylinder.axis")]:
        m.connect(a, b)
    m.simulation = {"t_end": 0.5, "n_points": 501, "method": "auto", "rtol": 1e-8,
                  "atol": 1e-10}
    return m


# ---------------------------------------------------------------------------------------
# The reference: a slider-crank's Lagrangian in phi, apart from kinetwork
# ---------------------------------------------------------------------------------------

def _box(length, width, height):
    """Mass and moment of inertia about the width axis (the crank axis x) through the CM."""
    mass = RHO * length * width * height
    return mass, mass * (length**2 + height**2) / 12


def _cylinder(length, diameter):
    mass = RHO * math.pi * diameter**2 / 4 * length
    return mass, mass * diameter**2 / 8            # about its own axis


def reference_rhs():
    """d/dt (phi, w) and the piston position s(phi), from sympy's Lagrange equation."""
    phi, w = sp.symbols("phi w")
    _, j1 = _cylinder(0.1, 0.05)                   # crank1 on the axis
    m2, j2 = _box(0.1, 0.02, 0.05)                 # crank2, crank4: CM 0.05 off the axis
    m3, j3 = _cylinder(0.1, 0.03)                  # crank3: CM 0.1 off the axis
    mr, jr = _box(0.2, 0.02, 0.06)                 # connecting rod
    mp, _ = _cylinder(0.1, 0.1)                    # piston
    J = 1.0 + j1 + 2 * (j2 + m2 * 0.05**2) + j3 + m3 * 0.1**2
    # crank pin C, piston pin P in the (y, z) plane; the rod's length 0.2
    cy, cz = 0.1 * sp.cos(phi), 0.1 * sp.sin(phi)
    py = cy + sp.sqrt(0.2**2 - cz**2)
    s = 0.35 - py                                  # the prismatic's coordinate
    theta = sp.atan2(-cz, py - cy)                 # rod angle about x
    my, mz = (cy + py) / 2, cz / 2
    d = sp.diff
    mass = J + mp * d(s, phi)**2 + mr * (d(my, phi)**2 + d(mz, phi)**2) + jr * d(theta, phi)**2
    V = G * (m2 * 0.05 * sp.cos(phi) * 2 + m3 * 0.1 * sp.cos(phi)
             + mp * (py + 0.05) + mr * my)
    x = 1 - s / L_CYL
    area = math.pi * BORE**2 / 4
    pressures = [sp.sympify(p.replace("^", "**")).subs("x", x) * 1e5 * area
                 for p in (*COMPRESSION, *EXPANSION)]
    force, ds = sp.Symbol("F"), d(s, phi)
    acc = (force * ds - d(mass, phi) * w**2 / 2 - d(V, phi)) / mass
    f_acc = sp.lambdify((phi, w, force), acc, "math")
    f_x = sp.lambdify(phi, x, "math")
    f_p = [sp.lambdify(phi, p, "math") for p in pressures]
    f_s = sp.lambdify(phi, s, "math")

    def rhs(t, y, compression):
        xv = f_x(y[0])
        if compression:
            f = f_p[0](y[0]) if xv < 0.986061 else f_p[1](y[0])
        else:
            f = f_p[2](y[0]) if xv > 0.933 else f_p[3](y[0])
        return [y[1], f_acc(y[0], y[1], f)]
    return rhs, f_s


def reference(t_out):
    """Crank angle and speed at ``t_out``: DOP853 from dead centre to dead centre, where
    phi = k pi (the crank turns forward throughout): the piston moves up (v < 0, the
    compression branch) while pi < phi mod 2 pi < 2 pi."""
    rhs, f_s = reference_rhs()
    y, t0, k, out = np.array([0.0, 10.0]), 0.0, 0, []
    while True:
        def dead(t, y, _compression, k=k):
            return y[0] - (k + 1) * math.pi
        dead.terminal, dead.direction = True, 1
        sol = solve_ivp(rhs, (t0, t_out[-1]), y, method="DOP853", rtol=1e-13, atol=1e-12,
                        args=(k % 2 == 1,), events=dead, dense_output=True)
        inside = (t_out >= t0) & (t_out <= sol.t[-1])
        out += [(tk, *sol.sol(tk)) for tk in t_out[inside] if not out or tk > out[-1][0]]
        if sol.status != 1:
            break
        t0, y, k = sol.t[-1], sol.y[:, -1], k + 1
    out = np.array(out)
    return out[:, 1], out[:, 2], f_s


def test_the_example_file_is_what_the_builder_writes(tmp_path):
    build().save(tmp_path / "engine1b.json")
    assert (tmp_path / "engine1b.json").read_bytes() == MODEL.read_bytes()


def test_engine1b_crank_speed_follows_the_independent_slider_crank_with_gas_force():
    model = kn.load(MODEL)
    system = model.compile()         # the default: the projected ODE, CVODES Adams
    assert system.state_names[0] == "bearing.q" and system.state_names[-1] == "bearing.qd"
    assert system.dof == 1 and system.n_algebraic == 0
    t = np.linspace(0.0, 0.2, 41)
    res = kn.simulate(system, t_end=0.2, n_points=41, rtol=1e-11, atol=1e-11, jit=False)
    phi, w, f_s = reference(t)
    assert phi[-1] > 3 * np.pi                        # through three dead centres
    np.testing.assert_allclose(res["crank.angle"], phi, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(res["crank.speed"], w, rtol=1e-9)
    np.testing.assert_allclose(res["stroke.position"], [f_s(p) for p in phi], atol=1e-8)
