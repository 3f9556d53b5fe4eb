"""Kinematic loops against independent references: the closed-form closure and the
one-degree-of-freedom Lagrange equation of ``tests/scenes/reference_loops.py``, energy, and the
wrench balance of each link for the cut forces."""

import json
import math
import pathlib

import numpy as np
import pytest

import kinetwork as kn
import scenes
from scenes import double_pendulum
from scenes import reference_loops as ref

ROOT = pathlib.Path(__file__).resolve().parents[2]

mb = kn.multibody
T = np.linspace(0.0, 10.0, 1001)


@pytest.fixture(scope="module")
def fourbar_run():
    system = scenes.fourbar(theta0=1.0).compile(loops="partition")
    return system, kn.simulate(system), ref.fourbar_simulate(1.0, 0.0, T)


def test_fourbar_follows_the_one_dof_reference(fourbar_run):
    system, res, r = fourbar_run
    assert system.state_names == ["A.q", "A.qd"]               # crank angle and speed only
    assert system.algebraic_names == ["B.q", "D.q", "C.q"]
    assert np.max(np.abs(res["crank_probe.angle"] - r["theta"])) < 1e-6
    assert np.max(np.abs(res["crank_probe.speed"] - r["thetad"])) < 1e-5
    # dependent coordinates: B.q = phi - theta, D.q = psi (absolute angles of the reference)
    assert np.max(np.abs(res["B.q"] - (r["phi"] - r["theta"]))) < 1e-6
    assert np.max(np.abs(res["rocker_probe.angle"] - r["psi"])) < 1e-6
    assert np.max(system.constraint_residual(res.states)) < 1e-8


def test_fourbar_coupler_point_and_pivot_force(fourbar_run):
    """The cut force through pivot D against each link's own Newton-Euler balance, written
    from the reference's angles and their rates."""
    system, res, r = fourbar_run
    a, b, c, d, g = 0.3, 1.0, 0.8, 1.0, 9.81
    m2, m3 = 2.0, 1.5
    J2, J3 = m2 * b * b / 12, m3 * c * c / 12

    def unit(x):
        return np.stack([np.cos(x), np.sin(x)], -1)

    def perp(x):
        return np.stack([-np.sin(x), np.cos(x)], -1)

    th, thd, thdd = r["theta"], r["thetad"], r["thetadd"]
    ph, phd, phdd = r["phi"], r["phid"], r["phidd"]
    ps, psd, psdd = r["psi"], r["psid"], r["psidd"]
    aB = a * (thdd[:, None] * perp(th) - thd[:, None] ** 2 * unit(th))
    a2 = aB + b / 2 * (phdd[:, None] * perp(ph) - phd[:, None] ** 2 * unit(ph))
    a3 = c / 2 * (psdd[:, None] * perp(ps) - psd[:, None] ** 2 * unit(ps))
    grav = np.array([0.0, -g])
    cross = lambda u, v: u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]   # noqa: E731
    # unknown pin force F on the rocker at C (the coupler feels -F): moments of the rocker
    # about D and of the coupler about its centre of mass give two equations for F
    rC_D = c * unit(ps)
    F = np.empty((len(T), 2))
    for k in range(len(T)):
        # rocker about D: rC_D x F + r3 x m3 g = J3 psidd + r3 x m3 a3 (r3 = c/2 unit)
        r3 = c / 2 * unit(ps[k])
        rhs1 = J3 * psdd[k] + cross(r3, m3 * a3[k]) - cross(r3, m3 * grav)
        # coupler about its centre: (C - c2) x (-F) + (B - c2) x F_B = J2 phidd, with
        # F_B = m2 (a2 - g) + F, the force at B on the coupler
        half = b / 2 * unit(ph[k])
        rhs2 = J2 * phdd[k] - cross(-half, m2 * (a2[k] - grav))
        A = np.array([[-rC_D[k][1], rC_D[k][0]],
                      [-(-half[1] - half[1]), (-half[0] - half[0])]])
        F[k] = np.linalg.solve(A, [rhs1, rhs2])
    F_D = m3 * (a3 - grav) - F                # the ground's force on the rocker at D
    # exact at t = 0; then as good as the trajectory (1e-7 rad): 1e-6 of the largest force
    assert np.max(np.abs(res["pivot_D.force"][0, :2] - F_D[0])) < 1e-12 * np.max(np.abs(F_D))
    assert np.max(np.abs(res["pivot_D.force"][:, :2] - F_D)) < 1e-6 * np.max(np.abs(F_D))
    assert np.max(np.abs(res["pivot_D.force"][:, 2])) < 1e-9
    C = d * np.array([1.0, 0.0]) + c * unit(ps)
    assert np.max(np.abs(res["coupler_point.position"][:, :2] - C)) < 1e-6


def test_slider_crank_follows_the_one_dof_reference():
    system = scenes.slider_crank(theta0=0.5, thetad0=3.0).compile(loops="partition")
    res = kn.simulate(system)
    r = ref.slider_crank_simulate(0.5, 3.0, T)
    assert system.n_states == 2
    assert np.max(np.abs(res["crank_probe.angle"] - r["theta"])) < 1e-6
    assert np.max(np.abs(res["piston.position"] - r["x"])) < 1e-6
    assert np.max(np.abs(res["piston.velocity"] - r["xd"])) < 1e-5
    assert np.max(system.constraint_residual(res.states)) < 1e-8


def test_energy_of_undriven_planar_loops_is_conserved_over_100_s():
    """Energy by the references' own formulas (closure and energy in the crank angle)."""
    t = np.linspace(0.0, 100.0, 2001)
    for build, energy_of, angle in ((scenes.fourbar, ref.fourbar_energy, "crank_probe"),
                                    (scenes.slider_crank, ref.slider_crank_energy,
                                     "crank_probe")):
        system = build().compile()
        res = kn.simulate(system, t_end=100.0, n_points=len(t))
        E = energy_of(res[f"{angle}.angle"], res[f"{angle}.speed"])
        assert np.max(np.abs(E - E[0])) / np.max(np.abs(E)) < 1e-7, build.__name__
        assert np.max(system.constraint_residual(res.states)) < 1e-8


def test_energy_of_the_spatial_loop_is_conserved_over_100_s():
    """Kinetic energy 1/2 u^T M u (the tree's mass matrix at the full coordinates, speeds
    from the loop's velocity constraint) plus the potential of every body's centre."""
    import casadi as ca
    system = scenes.spatial_fourbar().compile()
    res = kn.simulate(system, t_end=100.0, n_points=2001)
    a = system.asm
    full = ca.vertcat(system.eq.x, system.eq.z)
    values = system.model.numeric_values()
    potential = 0
    for body, frame_set in system.topology.bodies:
        R, pos = a.pose(frame_set)
        m, c, _ = body.bound(values[body.name]).mass_properties()
        potential -= m * ca.dot(pos + R @ c, a.gravity)
    u = system.eq.u
    E = ca.Function("E", [full, a.p], [0.5 * u.T @ a.mass_matrix() @ u + potential])
    p = system.param_vector()
    values = np.array([float(E(row, p)) for row in res.states])
    assert np.max(np.abs(values - values[0])) / np.max(np.abs(values)) < 1e-7
    assert np.max(system.constraint_residual(res.states)) < 1e-8


def test_baumgarte_formulation_agrees_and_drifts_little():
    system = scenes.fourbar().compile(loops="baumgarte")
    assert system.n_states == 8 and system.n_algebraic == 0
    assert "Baumgarte" in system.formulation_note
    res = kn.simulate(system, method="dop853", rtol=1e-12, atol=1e-12)
    r = ref.fourbar_simulate(1.0, 0.0, T)
    assert np.max(np.abs(res["A.q"] - r["theta"])) < 1e-6
    assert np.max(system.constraint_residual(res.states)) < 1e-8


def test_ode_methods_refuse_the_dae_with_a_way_out():
    system = scenes.fourbar().compile(loops="partition")
    with pytest.raises(kn.ModelError, match="loops='baumgarte'"):
        kn.simulate(system, method="rk45")


def test_collocation_integrates_the_dae():
    system = scenes.fourbar(theta0=1.0).compile()
    res = kn.simulate(system, method="collocation", t_end=2.0, n_points=201, step=2e-3)
    r = ref.fourbar_simulate(1.0, 0.0, T[:201])
    assert np.max(np.abs(res["A.q"] - r["theta"])) < 1e-6


def test_user_chosen_cut_gives_the_same_motion():
    model = scenes.fourbar(probes=False)
    model.components["D"].cut = True
    system = model.compile(loops="partition")
    assert "D.q" not in system.state_names
    res = kn.simulate(system, t_end=2.0, n_points=201)
    r = ref.fourbar_simulate(1.0, 0.0, T[:201])
    assert np.max(np.abs(res["A.q"] - r["theta"])) < 1e-6
    assert [c.component.name for c in system.topology.cuts] == ["D"]


def test_a_loop_that_cannot_close_names_its_parts():
    model = scenes.fourbar(d=2.5, probes=False, guesses=(0.0, 0.0, 0.0))   # d > a + b + c
    with pytest.raises(kn.ModelError, match="kinematic loop through coupler, B, crank, A, "
                                            "base, D, rocker, C cannot close"):
        model.compile()


def test_a_given_angle_that_cannot_be_reached_is_refused():
    model = scenes.fourbar(probes=False)
    model.components["D"].q0 = 3.0                    # rocker pointing away: no assembly
    with pytest.raises(kn.ModelError, match="cannot close.*given q0 \\(A.q, D.q\\)"):
        model.compile()


def test_assembly_branch_follows_the_guess():
    up = scenes.fourbar(probes=False).compile(loops="partition")
    down_guess = scenes.fourbar_guesses(1.0)
    model = scenes.fourbar(probes=False, guesses=(-1.2, -1.0, 2.5))
    down = model.compile(loops="partition")
    zu, zd = up.z0, down.z0
    assert zu[1] > 0 and zd[1] < 0                        # rocker above / below the ground
    assert abs(zu[0] - down_guess[0]) < 1e-9


def test_spatial_loop_with_ball_joint_cut():
    system = scenes.spatial_fourbar().compile(loops="partition")
    assert system.n_states == 2 and system.n_algebraic == 3
    cut = system.topology.cuts[0].component.name
    assert cut == "S"                                     # the ball joint is cut
    res = kn.simulate(system, t_end=5.0, n_points=501)
    # the ball joint's frame_b is the rocker tip; the loop holds it at the coupler's length
    # from the crank tip (the Universal joint)
    theta = res["crank_probe.angle"]
    U = 0.3 * np.stack([np.cos(theta), np.sin(theta), 0 * theta], -1)
    coupler = np.sqrt(0.1 ** 2 + 0.9 ** 2 + (0.3 + 0.7) ** 2)
    assert np.max(np.abs(np.linalg.norm(res["ball.position"] - U, axis=1) - coupler)) < 1e-10
    assert np.ptp(theta) > 2 * np.pi                      # the crank turns round


def test_two_ball_joints_in_one_loop_are_refused_with_advice():
    data = json.loads(kn.dumps(scenes.spatial_fourbar(probes=False)))
    for comp in data["components"]:
        if comp["name"] == "U":
            comp.update(type="multibody.Spherical", params={})
    with pytest.raises(kn.ModelError, match="ball or free joint"):
        kn.loads(json.dumps(data)).compile()


def test_validate_states_the_reason_for_the_state_count(tmp_path, capsys):
    from kinetwork import cli
    path = tmp_path / "fourbar.json"
    scenes.fourbar().save(path)
    assert cli.main(["validate", "--compile", str(path)]) == 0
    out = capsys.readouterr().out
    # the default formulation: the dependent angles are carried only to start the projection
    assert "states: 5 (A.q [rad], B.q [rad], D.q [rad], C.q [rad], A.qd [rad/s])" in out
    assert "degrees of freedom: 1" in out and "projected formulation: 5 states for 1 degree " \
        "of" in out and "3 dependent coordinates are states only to" in out
    assert "loops: 1\n  coupler - B - crank - A - base - D - rocker - C (cut at C)" in out


def _wire(model, pairs):
    for a, b in pairs:
        model.connect(a, b)
    return model


def test_a_free_joint_in_a_loop_is_cut_and_constrains_nothing():
    """A pendulum bob that is also on a FreeMotion from the ground: the free joint is cut
    (it imposes nothing), so the pendulum swings as if it were not there."""
    def pendulum(extra):
        m = kn.Model("pendulum")
        m.add(mb.Ground("ground", gravity=[0, -9.81, 0]))
        m.add(mb.Revolute("hinge", q0=0.5))
        m.add(mb.FixedTranslation("rod", r=[0, -1, 0]))
        m.add(mb.RigidBody("bob", mass=1.0))
        pairs = [("ground.frame", "hinge.frame_a"), ("hinge.frame_b", "rod.frame_a"),
                 ("rod.frame_b", "bob.frame_a")]
        if extra:
            m.add(mb.FreeMotion("free"))
            pairs += [("ground.frame", "free.frame_a"), ("free.frame_b", "rod.frame_b")]
        return _wire(m, pairs).compile()
    with_free, alone = pendulum(True), pendulum(False)
    assert [c.component.name for c in with_free.topology.cuts] == ["free"]
    assert with_free.state_names == alone.state_names and not with_free.n_algebraic
    a = kn.simulate(with_free, t_end=2.0, n_points=11)["hinge.q"]
    b = kn.simulate(alone, t_end=2.0, n_points=11)["hinge.q"]
    assert np.max(np.abs(a - b)) < 1e-12


@pytest.mark.parametrize("length, closes", [(1.0, True), (1.1, False)])
def test_a_loop_of_rigid_parts(length, closes):
    m = kn.Model("rigid_loop")
    m.add(mb.Ground("ground"))
    m.add(mb.FixedTranslation("a", r=[1, 0, 0]))
    m.add(mb.FixedTranslation("b", r=[length, 0, 0]))
    m.add(mb.Revolute("j", q0=0.3))
    m.add(mb.RigidBody("body", mass=1, r_cm=[0, -1, 0]))
    _wire(m, [("ground.frame", "a.frame_a"), ("ground.frame", "b.frame_a"),
              ("a.frame_b", "b.frame_b"), ("a.frame_b", "j.frame_a"),
              ("j.frame_b", "body.frame_a")])
    if closes:
        system = m.compile()
        assert system.state_names == ["j.q", "j.qd"] and "fix no coordinate" in \
            system.formulation_note
    else:
        with pytest.raises(kn.ModelError, match="loop through a, b cannot close.*off by 0.1"):
            m.compile()


def test_a_locked_loop_has_no_states_and_holds_its_shape():
    """A triangle of three unit links on revolutes: zero degrees of freedom, every angle
    solved from the closure (equilateral: 60 degrees inside)."""
    m = kn.Model("triangle")
    m.add(mb.Ground("ground"))
    m.add(mb.Revolute("A", q0_guess=1.0))
    m.add(mb.FixedTranslation("ab", r=[1, 0, 0]))
    m.add(mb.Revolute("B", q0_guess=2.0))
    m.add(mb.FixedTranslation("bc", r=[1, 0, 0]))
    m.add(mb.FixedTranslation("base", r=[1, 0, 0]))
    m.add(mb.Revolute("C", q0_guess=2.0))
    m.add(mb.RigidBody("body", mass=1, r_cm=[0.5, 0, 0]))
    _wire(m, [("ground.frame", "A.frame_a"), ("A.frame_b", "ab.frame_a"),
              ("ab.frame_b", "B.frame_a"), ("B.frame_b", "bc.frame_a"),
              ("ground.frame", "base.frame_a"), ("base.frame_b", "C.frame_a"),
              ("C.frame_b", "bc.frame_b"), ("A.frame_b", "body.frame_a")])
    system = m.compile(loops="partition")
    assert system.dof == 0 and system.n_states == 0 and system.n_algebraic == 3
    res = kn.simulate(system, t_end=1.0, n_points=5)
    inner = np.mod(np.pi - np.abs(np.mod(res.states[:, 1] + np.pi, 2 * np.pi) - np.pi), np.pi)
    assert np.allclose(inner, np.pi / 3, atol=1e-12)


def test_projected_formulation_is_an_ode_that_holds_the_closure():
    system = scenes.fourbar().compile(loops="projected")
    assert system.n_states == 5 and system.n_algebraic == 0
    assert "Newton projection" in system.formulation_note
    res = kn.simulate(system)                             # auto: Adams on an ODE
    assert res.method == "cvodes-adams"
    r = ref.fourbar_simulate(1.0, 0.0, T)
    assert np.max(np.abs(res["crank_probe.angle"] - r["theta"])) < 1e-6
    assert np.max(np.abs(res["rocker_probe.angle"] - r["psi"])) < 1e-6
    assert np.max(system.constraint_residual(res.states)) < 1e-12
    # the carried starts stay near the projection, which is what the probes report
    D = system.state_names.index("D.q")
    assert np.max(np.abs(res.states[:, D] - res["rocker_probe.angle"])) < 1e-6


def test_rhs_of_the_dae_solves_the_closure_first():
    """system.rhs(t, x) of a partition model: the closure solved by Newton from the last
    solution, then the reduced dynamics; against the reference's Lagrange equation."""
    system = scenes.fourbar(probes=False).compile(loops="partition")
    for theta in np.linspace(1.0, -3.0, 9):              # walk round, each from the last
        for thetad in (0.0, 2.5):
            x = np.array([theta, thetad])
            assert np.allclose(system.rhs(0.0, x), ref.fourbar_rhs(0.0, x), rtol=1e-10,
                               atol=1e-10)


def test_initial_speed_of_a_dependent_joint_is_refused_with_the_way_out():
    model = scenes.fourbar(probes=False)
    model.components["D"].qd0 = 1.0                  # the rocker speed follows the crank
    with pytest.raises(kn.ModelError, match=r"qd0 of D.qd: this speed is fixed by the loop"
                                            r".*independent coordinate \(A.qd\)"):
        model.compile().x0


def test_dependent_speeds_follow_the_crank_speed():
    """At the start the rocker turns at psi'(theta) theta' (the reference's closure rate)."""
    system = scenes.fourbar(theta0=1.0, thetad0=2.0).compile()
    res = kn.simulate(system, t_end=0.1, n_points=2)
    r = ref.fourbar_simulate(1.0, 2.0, np.array([0.0, 0.1]))
    assert abs(res["rocker_probe.speed"][0] - r["psid"][0]) < 1e-12


def test_cut_flag_on_a_joint_outside_any_loop_is_refused():
    model = scenes.fourbar(probes=False)
    model.components["A"].cut = True                     # A is in the loop: fine
    assert [c.component.name for c in model.compile().topology.cuts] == ["A"]
    pendulum = double_pendulum()
    pendulum.components["elbow"].cut = True
    with pytest.raises(kn.ModelError, match="elbow is marked cut but closes no kinematic loop"):
        pendulum.compile()


def _slider_crank_definition():
    """models/slider_crank.json as a subsystem: its two ground attachments joined and exposed
    as ``base``; the crank angle ``theta0`` and the rod length ``l`` as parameters."""
    crank = kn.load(ROOT / "models" / "slider_crank.json")
    ground = crank.components.pop("ground")
    crank.connections = [(a, b) for a, b in crank.connections
                         if ground not in (a.component, b.component)]
    crank.connect("O.frame_a", "slider.frame_a")
    crank.expose("base", "O.frame_a")
    crank.set_parameter("theta0", 0.5)
    crank.components["O"].q0 = "theta0"
    for joint in ("A", "slider", "B"):              # no help: start from zero
        crank.components[joint].q0_guess = 0.0
    return crank


@pytest.mark.parametrize("theta0", [math.pi, -math.pi, 0.0, 2.5])
def test_a_slider_crank_assembles_at_its_dead_centres_from_zero_guesses(theta0):
    """MSL Engine1a starts its crank at pi: the closure's Jacobian is singular there and the
    zero guesses sit in a local minimum of the residual. The assembly is the closed form's
    (reference_loops.slider_crank_closure: slider at r cos(theta) + sqrt(l^2 - r^2 sin^2))."""
    scene = kn.Model("engine1a")
    scene.add(kn.multibody.Ground("ground", gravity=[0, -9.81, 0]))
    scene.add(kn.Subsystem("sc", _slider_crank_definition(), params={"theta0": theta0}))
    scene.connect("ground.frame", "sc.base")
    system = scene.compile(loops="partition")
    _, z = system.initial_full_p(system.param_vector())
    slider = z[system.algebraic_names.index("sc.slider.q")]
    r, l = 0.2, 0.6
    assert slider == pytest.approx(r * math.cos(theta0)
                                   + math.sqrt(l**2 - (r * math.sin(theta0))**2), abs=1e-12)
    res = kn.simulate(system, t_end=0.5, n_points=6)
    assert np.all(np.isfinite(res.states))


def test_only_the_loop_that_cannot_close_is_named():
    """Two slider-cranks on one ground: one at its dead centre (closes), one whose rod cannot
    reach the slider's axis (0.05 < r sin(0.5) = 0.096): only that one is named."""
    bad = _slider_crank_definition()
    bad.set_parameter("l", 0.05)
    scene = kn.Model("two")
    scene.add(kn.multibody.Ground("ground", gravity=[0, -9.81, 0]))
    scene.add(kn.Subsystem("good", _slider_crank_definition(), params={"theta0": math.pi}))
    scene.add(kn.Subsystem("bad", bad))
    scene.connect("ground.frame", "good.base")
    scene.connect("ground.frame", "bad.base")
    with pytest.raises(kn.ModelError, match="cannot close") as err:
        scene.compile()
    assert "bad.rod" in str(err.value) and "good." not in str(err.value)
