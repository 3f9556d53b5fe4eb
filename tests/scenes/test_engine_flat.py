"""MSL's EngineV6 built flat (``scenes.engine``): it validates, has one degree of freedom, runs
(the gas force speeds the crankshaft up), keeps every piston on the closed-form slider-crank
closure, balances its energy against the work of the gas and the load, saves to JSON and
loads back; one cylinder alone follows the independent slider-crank of ``reference_loops``.

The energy and kinematic references here are written from the geometry alone (closed-form
closure, Lagrangian of the one-coordinate mechanism), never from kinetwork's equations.
"""

import math

import numpy as np
import pytest
from scipy.integrate import cumulative_trapezoid

import kinetwork as kn
from kinetwork.expr import FUNCTIONS, parse
from scenes import engine as eng
from scenes import reference_loops as ref

T_END = 0.5
N_POINTS = 5001
TOL = {"rtol": 1e-8, "atol": 1e-10}
G = 9.81


@pytest.fixture(scope="module")
def v6():
    """The engine (without the output filter: two states that only smooth a signal) and its
    0.5 s run, compiled once for the module, to C: its gas forces' relations are located
    events, and in CasADi's virtual machine the run took 59 s on 2 loaded cores (15 s with a
    cold C cache)."""
    model = eng.build_engine_v6(filter=False)
    system = model.compile()
    res = kn.simulate(system, t_end=T_END, n_points=N_POINTS, jit=True, **TOL)
    return model, system, res


# ----------------------------------------------------------------------------- the parts


def test_msl_mass_properties_by_hand():
    """BodyBox / BodyCylinder formulas, checked against numbers worked out by hand."""
    parts = eng.cylinder_parts()
    m, r_cm, inertia = parts["piston"][1]            # d = 0.1, L = 0.1, along y
    assert m == pytest.approx(7700 * math.pi * 0.05 ** 2 * 0.1)       # 6.0476 kg
    np.testing.assert_allclose(r_cm, [0, 0.05, 0])
    np.testing.assert_allclose(np.diag(inertia), [m * (0.01 + 3 * 0.0025) / 12,
                                                  m * 0.0025 / 2,
                                                  m * (0.01 + 3 * 0.0025) / 12])
    m, r_cm, inertia = parts["connectingRod"][1]     # 0.22 x 0.02 (x) x 0.06 (z)
    assert m == pytest.approx(7700 * 0.22 * 0.02 * 0.06)             # 2.0328 kg
    np.testing.assert_allclose(r_cm, [0, -0.02 + 0.11, 0], atol=1e-15)
    np.testing.assert_allclose(np.diag(inertia), np.array(
        [0.22 ** 2 + 0.06 ** 2, 0.02 ** 2 + 0.06 ** 2, 0.22 ** 2 + 0.02 ** 2]) * m / 12)
    np.testing.assert_allclose(inertia, np.diag(np.diag(inertia)), atol=1e-18)
    m, r_cm, _ = parts["crank1"][1]                  # length 0.12 from r_shape = -0.01
    assert m == pytest.approx(7700 * math.pi * 0.025 ** 2 * 0.12)
    np.testing.assert_allclose(r_cm, [0.05, 0, 0], atol=1e-15)


def test_the_gas_force_law_is_gasforce2():
    """The Force's law, parsed and evaluated as the model does, is MSL's polynomials on both
    sides of v = 0 over the stroke; the expansion curve lies above the compression curve, so
    a cycle does net work."""
    L, s_top = eng.cylinder_length(), eng.s_top()
    assert L == pytest.approx(0.22) and s_top == pytest.approx(0.02)
    law = parse(eng.gas_force_law("s", "v", L))
    s = np.linspace(s_top, L, 201)
    for v, compression in ((-0.3, True), (0.3, False)):
        ours = [law.evaluate({"s": si, "v": v}, FUNCTIONS) for si in s]
        np.testing.assert_allclose(ours, eng.gas_force(s, compression, L), rtol=1e-13)
    s = np.linspace(s_top, L, 2001)
    work = np.trapezoid(eng.gas_force(s, False, L) - eng.gas_force(s, True, L), s)
    assert work > 1000.0                             # J per cylinder and revolution
    force = eng.build_engine_v6().components["cyl2_gasForce"]
    assert force._values["f"] == eng.gas_force_law("cyl2_gas_s.y", "cyl2_gas_v.y", L)


# ------------------------------------------------------------------------------ the model


def test_engine_validates_with_one_degree_of_freedom():
    model = eng.build_engine_v6()
    topology = model.validate()
    assert len(topology.loops) == 6
    # each loop is cut where MSL cuts it (its RevolutePlanarLoopConstraint b1)
    assert sorted(c.component.name for c in topology.cuts) == [f"cyl{i}_b1"
                                                               for i in range(1, 7)]
    system = model.compile(loops="partition")
    assert system.dof == 1
    # the crankshaft angle and speed, and the two filter stages of the engine torque
    assert system.state_names == ["bearing.q", "bearing.qd", "filter1.x", "filter2.x"]
    assert system.n_algebraic == 18                  # b1, b2, s of each cylinder
    for i in range(1, 7):
        assert f"cyl{i}_piston" in model.components
        assert f"cyl{i}_piston_body" in model.components


def test_engine_runs(v6):
    """Started at 10 rad/s, the gas force drives the crankshaft well past 100 rad/s in
    0.5 s (load J = 1 kg m^2, load2 only 2.5e-3 w^2 N m)."""
    _, _, res = v6
    w = res["crankshaft.speed"]
    assert w[0] == pytest.approx(10.0)
    assert w[-1] > 200.0
    # it speeds up on every 0.05 s window (the cylinders fire every 60 degrees)
    window = np.searchsorted(res.t, np.arange(0.0, T_END + 1e-9, 0.05))
    assert np.all(np.diff(w[window]) > 0)
    np.testing.assert_allclose(np.gradient(res["crankshaft.angle"], res.t), w,
                               rtol=1e-3, atol=0.1)


def test_pistons_on_the_closure(v6):
    """Every piston sits where the closed-form slider-crank puts it for the crank angle, in
    the stroke [0.02, 0.22] m of MSL's cylinder, and its velocity is ds/dphi w."""
    _, _, res = v6
    phi, w = res["crankshaft.angle"], res["crankshaft.speed"]
    for i, (offset, incl) in enumerate(eng.V6_CYLINDERS, start=1):
        angles = {"crankAngleOffset": math.radians(offset),
                  "cylinderInclination": math.radians(incl)}
        s = res[f"cyl{i}_piston_probe.position"]
        np.testing.assert_allclose(s, eng.closure(phi, **angles)["s"], rtol=0, atol=1e-9)
        assert s.min() > 0.02 - 1e-9 and s.max() < 0.22 + 1e-9
        h = 1e-6
        ds = (eng.closure(phi + h, **angles)["s"] - eng.closure(phi - h, **angles)["s"]) / 2 / h
        np.testing.assert_allclose(res[f"cyl{i}_piston_probe.velocity"], ds * w,
                                   rtol=0, atol=1e-6 * w.max())


def _v6_energy(phi, w, J_load=eng.ENGINE["J_load"]):
    """Kinetic + gravity energy of the engine at crank angle phi and speed w, from the
    geometry of Cylinder.mo and the parts' mass properties only: the crank pieces turn with
    the shaft, each rod moves in its cylinder's plane (angle beta from the axis), each piston
    along the axis. Gravity is -9.81 along world y."""
    p = eng.CYLINDER
    r, l = p["crankPinOffset"], p["rodLength"]
    parts = eng.cylinder_parts()
    # the crank pieces: centres in the crank frame (after crankAngle1), by chaining r
    crank, origin = [], np.zeros(3)
    for name in ("crank1", "crank2", "crank3", "crank4"):
        step, (m, r_cm, inertia) = parts[name]
        crank.append((m, origin + r_cm, inertia))
        origin = origin + np.asarray(step)
    J_crank = sum(I[0, 0] + m * (c[1] ** 2 + c[2] ** 2) for m, c, I in crank)
    m_rod, rod_cm, I_rod = parts["connectingRod"][1]
    c_rod = rod_cm[1]                                 # from b1 along the rod
    m_p, p_cm, _ = parts["piston"][1]
    mass = np.full_like(phi, J_load + 6 * J_crank)
    height = np.zeros_like(phi)
    for offset, incl in eng.V6_CYLINDERS:
        off, inc = math.radians(offset), math.radians(incl)
        theta, alpha = phi + off, phi + off - inc
        beta = -np.arcsin(r / l * np.sin(alpha))
        beta_p = -(r / l) * np.cos(alpha) / np.cos(beta)
        # (axis, transverse) coordinates in the cylinder's plane, and their alpha-derivatives
        rod = (r * np.cos(alpha) + c_rod * np.cos(beta), r * np.sin(alpha) + c_rod * np.sin(beta))
        rod_p = (-r * np.sin(alpha) - c_rod * np.sin(beta) * beta_p,
                 r * np.cos(alpha) + c_rod * np.cos(beta) * beta_p)
        pin = r * np.cos(alpha) + l * np.cos(beta)
        pin_p = -r * np.sin(alpha) - l * np.sin(beta) * beta_p
        mass += m_rod * (rod_p[0] ** 2 + rod_p[1] ** 2) + I_rod[0, 0] * beta_p ** 2 \
            + m_p * pin_p ** 2
        world_y = lambda a, t: a * np.cos(inc) - t * np.sin(inc)        # noqa: E731
        height += m_rod * world_y(*rod) + m_p * world_y(pin + p_cm[1], 0.0)
        height += sum(m * (c[1] * np.cos(theta) - c[2] * np.sin(theta)) for m, c, _ in crank)
    return 0.5 * mass * w ** 2 + G * height


def test_energy_balance(v6):
    """E(t) - E(0) = work of the gas forces + work of load2, with E from the geometry
    (``_v6_energy``) and the powers from the probes (force and velocity of each piston)."""
    _, _, res = v6
    phi, w = res["crankshaft.angle"], res["crankshaft.speed"]
    energy = _v6_energy(phi, w)
    power = sum(res[f"cyl{i}_piston_probe.force"] * res[f"cyl{i}_piston_probe.velocity"]
                for i in range(1, 7))
    k = eng.ENGINE["tau_nominal"] / eng.ENGINE["w_nominal"] ** 2
    power = power + k * w ** 3
    work = cumulative_trapezoid(power, res.t, initial=0.0)
    gained = energy - energy[0]
    assert gained[-1] > 1e4                          # J: the engine did run
    np.testing.assert_allclose(gained, work, rtol=0, atol=3e-5 * gained[-1])
    # the gas does work: net positive, and far above what the load takes
    gas = cumulative_trapezoid(power - k * w ** 3, res.t, initial=0.0)
    assert gas[-1] > 0.9 * gained[-1]


def test_save_and_load(v6, tmp_path):
    model, system, _ = v6
    path = tmp_path / "EngineV6.json"
    model.save(path)
    size = path.stat().st_size
    print(f"\nEngineV6.json: {size} bytes, {len(model.components)} components, "
          f"{len(model.connections)} connections")
    assert 20_000 < size < 500_000
    again = kn.load(path)
    assert set(again.components) == set(model.components)
    assert len(again.connections) == len(model.connections)
    assert again.compile().state_names == system.state_names


# ------------------------------------------------------------- one cylinder vs reference


def _reference_masses(J_load=0.0):
    """reference_loops' slider-crank parameters equivalent to one upright cylinder with the
    rod's centre at mid-length: the crank pieces (rigid with the shaft) have a first moment
    M along the crank and an inertia J about the shaft, which the reference's crank matches
    with m1 = 2 M / r and J1 = J - m1 r^2 / 4; rod and piston map one to one."""
    p = eng.CYLINDER
    r, l = p["crankPinOffset"], p["rodLength"]
    parts = eng.cylinder_parts(rod_shape_offset=0.0)
    origin, first, J = np.zeros(3), 0.0, J_load
    for name in ("crank1", "crank2", "crank3", "crank4"):
        step, (m, r_cm, inertia) = parts[name]
        c = origin + r_cm
        first += m * c[1]
        J += inertia[0, 0] + m * (c[1] ** 2 + c[2] ** 2)
        origin = origin + np.asarray(step)
    m1 = 2 * first / r
    m_rod, rod_cm, I_rod = parts["connectingRod"][1]
    assert rod_cm[1] == pytest.approx(l / 2)
    return {"r": r, "l": l, "e": 0.0, "m1": m1, "J1": J - m1 * r ** 2 / 4,
            "m2": m_rod, "J2": I_rod[0, 0], "m3": parts["piston"][1][0], "g": G}


@pytest.mark.parametrize("J_load", [None, 1.0])
def test_single_cylinder_matches_reference(J_load):
    """One upright cylinder, gravity in the loop's plane (-z), no gas: crank angle, speed and
    piston position follow reference_loops.slider_crank_simulate (its own Lagrangian)."""
    theta0, w0 = 0.5, 3.0
    model = eng.build_single_cylinder(phi0=theta0, w0=w0, J_load=J_load)
    # the projected formulation, for an explicit method as tight as the reference's
    system = model.compile(loops="projected")
    assert system.dof == 1
    res = kn.simulate(system, t_end=2.0, n_points=401, method="dop853", jit=False,
                      rtol=1e-12, atol=1e-12)
    params = _reference_masses(J_load or 0.0)
    want = ref.slider_crank_simulate(theta0, w0, res.t, **params)
    np.testing.assert_allclose(res["crankshaft.angle"], want["theta"], rtol=0, atol=1e-9)
    np.testing.assert_allclose(res["crankshaft.speed"], want["thetad"], rtol=0, atol=1e-8)
    top = eng.CYLINDER["cylinderTopPosition"] - eng.CYLINDER["pistonLength"]
    np.testing.assert_allclose(res["cyl1_piston_probe.position"], top - want["x"],
                               rtol=0, atol=1e-9)
    # not a trivial run: the crank swings through a good part of a turn
    assert np.ptp(want["theta"]) > 1.0


def test_default_guesses_that_assemble_a_piston_outside_its_cylinder_are_warned():
    """The V6 with every cylinder cut at b2 and the loop joints' guesses left at 0: Newton
    assembles cylinder 5 with its piston below the crankshaft (0.55 m down the cylinder, its
    stroke 0.02..0.22 m); kinetwork warns, naming the prismatic and the other branch, which
    the closed form confirms; guesses on the branch meant give no warning."""
    def v6(guesses):
        model = eng.build_engine_v6(gas=False, probes=False, J_load=None)
        for name, comp in model.components.items():
            if name.endswith(("_b1", "_b2", "_cylinder")):
                comp.cut = name.endswith("_b2")
                if not guesses:
                    comp.q0_guess = 0.0
        return model
    with pytest.warns(kn.AssemblyBranchWarning) as caught:
        system = v6(guesses=False).compile()
    assert len(caught) == 1
    message = str(caught[0].message)
    s5 = eng.closure(0.0, crankAngleOffset=math.radians(90.0),
                     cylinderInclination=math.radians(-30.0))["s"]
    assert "cyl5_cylinder.q = 0.550278 m (other branch: 0.189722" in message
    assert float(s5) == pytest.approx(0.189722, abs=1e-6)
    x0 = dict(zip(system.state_names, system.x0))
    assert x0["cyl5_cylinder.q"] == pytest.approx(0.550278, abs=1e-6)
    # its place as data: the joint whose guess picks the branch
    problem = caught[0].message.problem
    assert (problem.component, problem.parameter, problem.severity) == \
        ("cyl5_cylinder", "q0_guess", "warning")
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        v6(guesses=True).compile()
