"""Loop joints (kinetwork/components/loopjoints.py) against independent references: rods
(SphericalSpherical, UniversalSpherical) and the planar JointRRR close the planar four-bar of
``tests/scenes/reference_loops.py`` on its closed-form kinematics and its one-degree-of-freedom
Lagrange equation, an RSSR spatial four-bar follows the closed form of its coupler's length,
MSL's Fourbar2 (UniversalSpherical) moves as the same loop built from a Universal and a
Spherical joint and as MSL's Fourbar1 (six revolutes) with a massless rod, and the rod force a
probe reads balances the rocker's own equation of motion."""

import pathlib

import numpy as np
import pytest

import kinetwork as kn
import scenes
from close import assert_same_json_file
from scenes import reference_loops as ref

ROOT = pathlib.Path(__file__).resolve().parents[2]
mb = kn.multibody
#: the planar four-bar of reference_loops (crank a, coupler b, rocker c, ground d)
A, B, C, D = 0.3, 1.0, 0.8, 1.0
G = 9.81
#: tight enough that the trajectory errors below are the formulation's, not the tolerance's
TIGHT = {"loops": "projected", "method": "dop853", "rtol": 1e-12, "atol": 1e-12}


def simulate(model, loops="partition", t_end=2.0, n_points=201, **options):
    return kn.simulate(model.compile(loops=loops), t_end=t_end, n_points=n_points, **options)


def tight(model, **options):
    opts = {**TIGHT, **options}
    return simulate(model, opts.pop("loops"), **opts)


def wrap(x):
    return np.angle(np.exp(1j * np.asarray(x)))


def rod_fourbar(kind, theta0=1.0, masses=(1.0, 0.0, 1.5)):
    """The reference four-bar with its coupler a massless rod joint ``kind`` between the crank
    tip and the rocker tip: crank A about z at the origin, rocker D about z at (d, 0)."""
    m = kn.Model(f"fourbar_{kind}", parameters={"g": G})
    m.add(mb.Ground("ground", gravity=[0, "-g", 0]))
    m.add(mb.Revolute("A", q0=theta0))
    m.connect("ground.frame", "A.frame_a")
    crank_tip = scenes.loops._rod(m, "crank", "A.frame_b", repr(A), masses[0], A)
    m.add(mb.FixedTranslation("base", r=[D, 0, 0]))
    m.connect("ground.frame", "base.frame_a")
    m.add(mb.Revolute("D", q0_guess=float(ref.fourbar_closure(theta0)[1])))
    m.connect("base.frame_b", "D.frame_a")
    rocker_tip = scenes.loops._rod(m, "rocker", "D.frame_b", repr(C), masses[2], C)
    if kind == "SphericalSpherical":
        m.add(mb.SphericalSpherical("rod", length=B))
    else:
        m.add(mb.UniversalSpherical("rod", n_a=[0, 0, 1], r_rod=[B, 0, 0]))
    m.connect(crank_tip, "rod.frame_a")
    m.connect("rod.frame_b", rocker_tip)
    for name, port, quantities in (("crank_probe", "A.axis", ["angle", "speed"]),
                                   ("rocker_probe", "D.axis",
                                    ["angle", "speed", "acceleration"]),
                                   ("rod_a", "rod.frame_a", ["force", "torque"]),
                                   ("rod_b", "rod.frame_b", ["position", "force", "torque"])):
        m.add(kn.Probe(name, quantities=quantities))
        m.connect(f"{name}.port", port)
    return m


ROD_KINDS = ["SphericalSpherical", "UniversalSpherical"]


@pytest.mark.parametrize("kind", ROD_KINDS)
def test_a_rod_closes_the_planar_fourbar_with_one_equation(kind):
    """Crank angle and speed are the states, the rocker angle is solved from the rod's one
    closure equation, and the rocker follows the closed-form closure of the crank angle."""
    model = rod_fourbar(kind)
    system = model.compile(loops="partition")
    assert [c.component.name for c in system.topology.cuts] == ["rod"]
    assert system.state_names == ["A.q", "A.qd"] and system.algebraic_names == ["D.q"]
    assert (system.eq.loop_rows, system.eq.loop_redundant) == (1, 0)
    res = kn.simulate(system, t_end=2.0, n_points=201)
    psi = ref.fourbar_closure(res["crank_probe.angle"])[1]
    assert np.max(np.abs(wrap(res["rocker_probe.angle"] - psi))) < 1e-9
    assert np.max(system.constraint_residual(res.states)) < 1e-12


@pytest.mark.parametrize("kind", ROD_KINDS)
def test_a_rod_fourbar_follows_the_lagrange_reference_with_a_massless_coupler(kind):
    res = tight(rod_fourbar(kind))
    r = ref.fourbar_simulate(1.0, 0.0, res.t, m2=0.0)
    assert np.max(np.abs(res["crank_probe.angle"] - r["theta"])) < 1e-9
    assert np.max(np.abs(res["crank_probe.speed"] - r["thetad"])) < 1e-8
    assert np.max(np.abs(res["rocker_probe.angle"] - r["psi"])) < 1e-9


@pytest.mark.parametrize("loops", ["projected", "baumgarte"])
def test_the_rod_closure_enters_every_formulation(loops):
    """The same motion from the ODE formulations: the projected one holds the closure to
    round-off, Baumgarte's keeps it small."""
    system = rod_fourbar("SphericalSpherical").compile(loops=loops)
    res = kn.simulate(system, t_end=2.0, n_points=201, method="dop853", rtol=1e-11,
                      atol=1e-11)
    r = ref.fourbar_simulate(1.0, 0.0, res.t, m2=0.0)
    assert np.max(np.abs(res["crank_probe.angle"] - r["theta"])) < 1e-7
    assert np.max(system.constraint_residual(res.states)) < 1e-8


def test_the_rod_force_is_along_the_rod_and_balances_the_rocker():
    """The probes on the rod's two frames read one force along the rod (the multiplier of its
    closure equation) and no torque; the rocker's moment balance about its pivot, written
    from the simulated rocker angle and its rates alone, holds with minus that force at its
    tip."""
    res = tight(rod_fourbar("SphericalSpherical"), n_points=101)
    fa, fb = res["rod_a.force"], res["rod_b.force"]
    scale = np.max(np.abs(fb))
    assert scale > 1.0
    np.testing.assert_allclose(fa, -fb, atol=1e-12 * scale)
    assert np.max(np.abs(res["rod_a.torque"])) < 1e-12 * scale
    assert np.max(np.abs(res["rod_b.torque"])) < 1e-12 * scale
    theta = res["crank_probe.angle"]
    tip_a = A * np.stack([np.cos(theta), np.sin(theta), 0 * theta], -1)
    e = res["rod_b.position"] - tip_a
    e /= np.linalg.norm(e, axis=1)[:, None]
    assert np.max(np.linalg.norm(np.cross(e, fb), axis=1)) < 1e-10 * scale
    # the rocker: J_D psi'' = (C - D) x F + (c/2 e_psi) x m3 g, F = -fb on the rocker at C
    m3 = 1.5
    psi, psidd = res["rocker_probe.angle"], res["rocker_probe.acceleration"]
    lever = C * np.stack([np.cos(psi), np.sin(psi)], -1)
    moment = lever[:, 0] * -fb[:, 1] - lever[:, 1] * -fb[:, 0] - m3 * G * C / 2 * np.cos(psi)
    J_D = m3 * C * C / 12 + m3 * (C / 2) ** 2
    np.testing.assert_allclose(J_D * psidd, moment, atol=1e-9 * scale)


def test_a_pressed_rod_reads_a_positive_rod_force():
    """A 2 kg bob on a horizontal arm propped from below by a rod: a structure (no degree of
    freedom left) whose rod carries the weight, f_rod = -force . e = m g (MSL's sign:
    positive when the rod is pressed)."""
    m = kn.Model("prop")
    m.add(mb.Ground("ground"))
    m.add(mb.Revolute("A"))
    m.add(mb.FixedTranslation("arm", r=[1, 0, 0]))
    m.add(mb.RigidBody("bob", mass=2.0, r_cm=[1, 0, 0]))
    m.add(mb.FixedTranslation("foot", r=[1, -1, 0]))
    m.add(mb.SphericalSpherical("prop", length=1.0))
    m.add(kn.Probe("p", quantities=["force"]))
    for a, b in [("ground.frame", "A.frame_a"), ("A.frame_b", "arm.frame_a"),
                 ("A.frame_b", "bob.frame_a"), ("ground.frame", "foot.frame_a"),
                 ("foot.frame_b", "prop.frame_a"), ("prop.frame_b", "arm.frame_b"),
                 ("p.port", "prop.frame_b")]:
        m.connect(a, b)
    system = m.compile(loops="partition")
    assert system.state_names == [] and system.algebraic_names == ["A.q"]
    force = kn.simulate(system, t_end=1.0, n_points=11)["p.force"]
    e = np.array([0.0, 1.0, 0.0])                     # from the foot (frame_a) up to the arm
    np.testing.assert_allclose(-force @ e, 2.0 * 9.81, rtol=1e-12)
    np.testing.assert_allclose(force[:, [0, 2]], 0, atol=1e-12)


def rot(n, angle):
    """Rodrigues' rotation by ``angle`` about ``n`` (numpy)."""
    n = np.asarray(n, dtype=float) / np.linalg.norm(n)
    K = np.array([[0, -n[2], n[1]], [n[2], 0, -n[0]], [-n[1], n[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


#: the RSSR: crank about z at the origin, rocker about a skew axis n_d at D0 (its tip c0 from
#: the pivot at psi = 0), the coupler a SphericalSpherical as long as the tips are apart at 0
RSSR = {"a0": np.array([0.3, 0.0, 0.0]), "D0": np.array([0.4, 0.9, 0.3]),
        "n_d": np.array([1.0, 0.2, 0.1]), "c0": np.array([0.0, 0.0, 0.7])}
RSSR["L"] = float(np.linalg.norm(RSSR["a0"] - RSSR["D0"] - RSSR["c0"]))


def rssr_closed_form(theta, branch):
    """The rocker angles psi with |B(theta) - C(psi)| = L. Writing C(psi) = D0 + c_par +
    cos(psi) c_perp + sin(psi) n x c0 (Rodrigues) and w = B - D0 - c_par, the length
    condition is P cos(psi) + Q sin(psi) = R with P = 2 w.c_perp, Q = 2 w.(n x c0) and
    R = |w|^2 + |c_perp|^2 - L^2, so psi = atan2(Q, P) + branch * arccos(R / hypot(P, Q))."""
    n = RSSR["n_d"] / np.linalg.norm(RSSR["n_d"])
    c0 = RSSR["c0"]
    c_par = n * (n @ c0)
    c_perp, c_x = c0 - c_par, np.cross(n, c0)
    out = []
    for th in np.atleast_1d(theta):
        w = rot([0, 0, 1], th) @ RSSR["a0"] - RSSR["D0"] - c_par
        P, Q = 2 * w @ c_perp, 2 * w @ c_x
        R = w @ w + c_perp @ c_perp - RSSR["L"] ** 2
        out.append(np.arctan2(Q, P) + branch * np.arccos(R / np.hypot(P, Q)))
    return np.array(out)


def rssr():
    m = kn.Model("rssr", parameters={"g": G})
    a0, D0, n_d, c0 = (RSSR[k].tolist() for k in ("a0", "D0", "n_d", "c0"))
    m.add(mb.Ground("ground", gravity=[0, 0, "-g"]))
    m.add(mb.Revolute("A", axis=[0, 0, 1], q0=0.0, qd0=2.0))
    m.add(mb.FixedTranslation("crank", r=a0))
    m.add(mb.RigidBody("crank_mass", mass=1.0, r_cm=[0.15, 0, 0], inertia=[0, 0.0075, 0.0075]))
    m.add(mb.FixedTranslation("base", r=D0))
    m.add(mb.Revolute("D", axis=n_d))
    m.add(mb.FixedTranslation("rocker", r=c0))
    m.add(mb.RigidBody("rocker_mass", mass=1.0, r_cm=[0, 0, 0.35],
                       inertia=[0.49 / 12, 0.49 / 12, 0]))
    m.add(mb.SphericalSpherical("coupler", length=RSSR["L"]))
    m.add(kn.Probe("crank_probe", quantities=["angle"]))
    m.add(kn.Probe("rocker_probe", quantities=["angle"]))
    for a, b in [("ground.frame", "A.frame_a"), ("A.frame_b", "crank.frame_a"),
                 ("A.frame_b", "crank_mass.frame_a"), ("ground.frame", "base.frame_a"),
                 ("base.frame_b", "D.frame_a"), ("D.frame_b", "rocker.frame_a"),
                 ("D.frame_b", "rocker_mass.frame_a"), ("crank.frame_b", "coupler.frame_a"),
                 ("coupler.frame_b", "rocker.frame_b"), ("crank_probe.port", "A.axis"),
                 ("rocker_probe.port", "D.axis")]:
        m.connect(a, b)
    return m


def test_an_rssr_spatial_fourbar_follows_the_closed_form_of_its_coupler():
    """The crank turns fully (under gravity along -z, started at 2 rad/s); at every output
    the rocker angle is the closed form's, on the branch of the start (psi = 0)."""
    system = rssr().compile(loops="partition")
    assert system.algebraic_names == ["D.q"] and system.eq.loop_rows == 1
    res = kn.simulate(system, t_end=5.0, n_points=501, rtol=1e-10, atol=1e-12)
    theta, psi = res["crank_probe.angle"], res["rocker_probe.angle"]
    assert np.ptp(theta) > 2 * np.pi and np.ptp(psi) > 0.5
    branch = -1 if abs(wrap(rssr_closed_form(0.0, -1)[0])) < 1e-12 else 1
    assert abs(wrap(rssr_closed_form(0.0, branch)[0])) < 1e-12
    assert np.max(np.abs(wrap(psi - rssr_closed_form(theta, branch)))) < 1e-9


# -- MSL's Fourbar2 (UniversalSpherical) against the same loop built from other joints ---------

#: MSL's Fourbar1 and Fourbar2: j1's start speed (300 deg/s) and the rod from b2's tip to b1's
W0 = 5.235987755983
R_ROD = [-1.0, 0.3, 0.1]
MSL = ("Modelica.Mechanics.MultiBody.Examples.Loops.{} (Modelica Standard Library 4.0), "
       "built as MSL wires it: revolute j1 about x driving the crank b1 (BodyCylinder to "
       "{{0, 0.5, 0.1}}, diameter 0.05 m, steel), prismatic j2 along x, 1.2 m from the origin, "
       "carrying b2 (BodyCylinder to {{0, 0.2, 0}}); {} World gravity -9.81 m/s^2 along y; j1 "
       "starts at 0 rad and 300 deg/s, j2 at s = -0.2 m (solved from the loop). Reproduces "
       "MSL's outputs j1_phi, j1_w, j2_s and j2_v over StopTime = 5 s (probes j1_probe and "
       "j2_probe; MSL's figure is the mechanism's drawing), checked in "
       "tests/equations/test_loop_joints.py against the same loop built of other joints.")


def msl_fourbar(coupler):
    """MSL's four-bar of Examples.Loops with the loop closed by ``coupler``:
    "UniversalSpherical" (Fourbar2), "Fourbar1" (MSL's six revolutes around the rod b3, a
    BodyCylinder), "revolutes" (the same joints around a massless rod: Fourbar2's loop) or
    "chain" (a Universal, axis 1 y and axis 2 normal to it and the rod as MSL's
    UniversalSpherical, the rod and a cut Spherical)."""
    names = {"UniversalSpherical": ("fourbar2", "Fourbar2", "the loop closes through a "
                                    "UniversalSpherical joint from b2's tip to b1's, a massless "
                                    "rod {-1, 0.3, 0.1} with its universal axis 1 along y: one "
                                    "closure equation, one algebraic variable (j2.s). MSL's "
                                    "FixedFrame on frame_ia is a probe of its orientation here; "
                                    "rodLength is |rRod_ia| (MSL computes the same from j2.s)."),
             "Fourbar1": ("fourbar1", "Fourbar1", "the loop closes through a universal joint "
                          "of two revolutes (rev about y, rev1 about z) at b2's tip, the rod "
                          "b3 (BodyCylinder {-1, 0.3, 0.1}) and three revolutes (j3, j4, j5 "
                          "about x, y, z) at b1's tip: six closure equations.")}
    name, source, what = names.get(coupler, (f"fourbar_{coupler}", None, ""))
    m = kn.Model(name, description=MSL.format(source, what) if source else "",
                 simulation={"t_end": 5.0, "n_points": 501, "method": "auto", "rtol": 1e-8,
                             "atol": 1e-10})
    base = "b0" if coupler in ("Fourbar1", "revolutes") else "b3"
    m.add(mb.Ground("world"))
    m.add(mb.Revolute("j1", axis=[1, 0, 0], q0=0.0, qd0=W0))
    m.add(mb.Prismatic("j2", axis=[1, 0, 0], q0_guess=-0.2))
    m.add(mb.BodyCylinder("b1", r=[0, 0.5, 0.1], diameter=0.05))
    m.add(mb.BodyCylinder("b2", r=[0, 0.2, 0], diameter=0.05))
    m.add(mb.FixedTranslation(base, r=[1.2, 0, 0]))
    wires = [("world.frame", "j1.frame_a"), ("j1.frame_b", "b1.frame_a"),
             ("world.frame", f"{base}.frame_a"), (f"{base}.frame_b", "j2.frame_a"),
             ("j2.frame_b", "b2.frame_a")]
    if coupler == "UniversalSpherical":
        m.add(mb.UniversalSpherical("universalSpherical", n_a=[0, 1, 0], r_rod=R_ROD))
        wires += [("b2.frame_b", "universalSpherical.frame_a"),
                  ("b1.frame_b", "universalSpherical.frame_b")]
    elif coupler == "chain":
        e2 = np.cross([0, 1, 0], R_ROD)
        m.add(mb.Universal("U", n_a=[0, 1, 0], n_b=(e2 / np.linalg.norm(e2)).tolist()))
        m.add(mb.FixedTranslation("rod", r=R_ROD))
        m.add(mb.Spherical("S"))
        wires += [("b2.frame_b", "U.frame_a"), ("U.frame_b", "rod.frame_a"),
                  ("rod.frame_b", "S.frame_a"), ("S.frame_b", "b1.frame_b")]
    else:
        rod = "b3" if coupler == "Fourbar1" else "rod"
        m.add(mb.Revolute("rev", axis=[0, 1, 0]))
        m.add(mb.Revolute("rev1"))
        m.add(mb.BodyCylinder(rod, r=R_ROD, diameter=0.05) if rod == "b3" else
              mb.FixedTranslation(rod, r=R_ROD))
        for joint, axis in (("j3", [1, 0, 0]), ("j4", [0, 1, 0]), ("j5", [0, 0, 1])):
            m.add(mb.Revolute(joint, axis=axis))
        wires += [("rev.frame_a", "b2.frame_b"), ("rev.frame_b", "rev1.frame_a"),
                  ("rev1.frame_b", f"{rod}.frame_a"), ("b1.frame_b", "j3.frame_a"),
                  ("j3.frame_b", "j4.frame_a"), ("j4.frame_b", "j5.frame_a"),
                  ("j5.frame_b", f"{rod}.frame_b")]
    probes = [("j1_probe", "j1.axis", ["angle", "speed"]),
              ("j2_probe", "j2.axis", ["position", "velocity"])]
    if coupler == "UniversalSpherical":
        probes += [("rod_frame", "universalSpherical.frame_ia", ["orientation"]),
                   ("rod_end", "universalSpherical.frame_b", ["force", "torque"])]
    elif coupler == "chain":
        probes += [("rod_frame", "U.frame_b", ["orientation"])]
    for probe, port, quantities in probes:
        m.add(kn.Probe(probe, quantities=quantities))
        wires.append((f"{probe}.port", port))
    for a, b in wires:
        m.connect(a, b)
    return m


#: the example files this module writes (python tests/equations/test_loop_joints.py)
FILES = {"fourbar1": "Fourbar1", "fourbar2": "UniversalSpherical"}


@pytest.mark.parametrize("name", FILES)
def test_the_msl_fourbar_files_are_the_builders(name, tmp_path):
    msl_fourbar(FILES[name]).save(tmp_path / "built.json")
    assert_same_json_file(tmp_path / "built.json", ROOT / "models" / f"{name}.json")


@pytest.fixture(scope="module")
def fourbar2_runs():
    return {coupler: tight(msl_fourbar(coupler), t_end=3.0, n_points=301)
            for coupler in ("UniversalSpherical", "chain", "revolutes")}


def test_fourbar2_has_one_closure_equation():
    system = kn.load(ROOT / "models" / "fourbar2.json").compile(loops="partition")
    assert system.state_names == ["j1.q", "j1.qd"] and system.algebraic_names == ["j2.q"]
    assert system.eq.loop_rows == 1
    assert system.z0[0] == pytest.approx(-0.2, abs=1e-12)      # MSL's j2.s start


@pytest.mark.parametrize("other", ["chain", "revolutes"])
def test_fourbar2_moves_as_the_same_loop_of_other_joints(fourbar2_runs, other):
    us, them = fourbar2_runs["UniversalSpherical"], fourbar2_runs[other]
    assert np.ptp(us["j1_probe.angle"]) > 2 * np.pi              # the crank goes round
    assert np.max(np.abs(us["j1_probe.angle"] - them["j1_probe.angle"])) < 1e-8
    assert np.max(np.abs(us["j2_probe.position"] - them["j2_probe.position"])) < 1e-8


def test_frame_ia_turns_as_the_universal_joint_of_the_chain(fourbar2_runs):
    us, chain = fourbar2_runs["UniversalSpherical"], fourbar2_runs["chain"]
    R = us["rod_frame.orientation"]
    assert np.max(np.abs(R - chain["rod_frame.orientation"])) < 1e-8
    assert np.max(np.abs(R[0] - np.eye(3))) < 1e-12               # parallel to frame_a at 0
    f, t = us["rod_end.force"], us["rod_end.torque"]
    assert np.max(np.abs(t)) < 1e-9 * np.max(np.abs(f))         # a ball joint at frame_b


def test_fourbar1_is_msls_six_revolute_loop():
    system = kn.load(ROOT / "models" / "fourbar1.json").compile(loops="partition")
    assert system.state_names == ["j1.q", "j1.qd"] and len(system.algebraic_names) == 6
    assert (system.eq.loop_rows, system.eq.loop_redundant) == (6, 6)
    res = kn.simulate(system, t_end=0.5, n_points=51)
    assert np.max(system.constraint_residual(res.states)) < 1e-10


# -- JointRRR -----------------------------------------------------------------------------------

def rrr_fourbar(theta0=1.0, masses=(1.0, 2.0, 1.5)):
    """scenes.fourbar with its joints B, C, D and coupler and rocker rods replaced by one
    JointRRR from the crank tip to the ground pivot D: rod 1 the coupler (its body on
    frame_ia), rod 2 the rocker (its body on frame_ib, at D), the third revolute at D."""
    m = kn.Model("fourbar_rrr", parameters={"b": B, "c": C, "g": G})
    m.add(mb.Ground("ground", gravity=[0, "-g", 0]))
    m.add(mb.Revolute("A", q0=theta0))
    m.connect("ground.frame", "A.frame_a")
    crank_tip = scenes.loops._rod(m, "crank", "A.frame_b", repr(A), masses[0], A)
    phi, psi = (float(v) for v in ref.fourbar_closure(theta0))
    m.add(mb.JointRRR("rrr", r_rod1=["b", 0, 0], r_rod2=["c", 0, 0],
                      q0_guess=[phi - theta0, psi - phi, psi]))
    m.add(mb.FixedTranslation("base", r=[D, 0, 0]))
    m.add(mb.RigidBody("coupler_mass", mass=masses[1], r_cm=["b/2", 0, 0],
                       inertia=[0, 0, masses[1] * B * B / 12]))
    m.add(mb.RigidBody("rocker_mass", mass=masses[2], r_cm=["c/2", 0, 0],
                       inertia=[0, 0, masses[2] * C * C / 12]))
    m.add(kn.Probe("crank_probe", quantities=["angle", "speed"]))
    m.add(kn.Probe("rocker_probe", quantities=["angle"]))
    m.add(kn.Probe("coupler_point", quantities=["position"]))
    for a, b in [(crank_tip, "rrr.frame_a"), ("ground.frame", "base.frame_a"),
                 ("rrr.frame_b", "base.frame_b"), ("rrr.frame_ia", "coupler_mass.frame_a"),
                 ("rrr.frame_ib", "rocker_mass.frame_a"), ("crank_probe.port", "A.axis"),
                 ("rocker_probe.port", "rrr.axis"), ("coupler_point.port", "rrr.frame_im")]:
        m.connect(a, b)
    return m


def test_joint_rrr_is_three_revolutes_with_the_last_one_cut():
    system = rrr_fourbar().compile(loops="partition")
    assert system.state_names == ["A.q", "A.qd"]
    assert system.algebraic_names == ["rrr.rev1.q", "rrr.rev2.q", "rrr.rev3.q"]
    assert [c.component.name for c in system.topology.cuts] == ["rrr.rev3"]
    res = kn.simulate(system, t_end=2.0, n_points=201)
    theta = res["crank_probe.angle"]
    phi, psi = ref.fourbar_closure(theta)
    # MSL's third revolute turns from frame_b (on the ground) to frame_ib (along the
    # rocker): its angle is the rocker's, psi
    assert np.max(np.abs(wrap(res["rocker_probe.angle"] - psi))) < 1e-9
    C_point = np.stack([D + C * np.cos(psi), C * np.sin(psi)], -1)
    assert np.max(np.abs(res["coupler_point.position"][:, :2] - C_point)) < 1e-9


def test_joint_rrr_moves_as_the_three_revolutes_it_stands_for():
    res = tight(rrr_fourbar())
    revolutes = tight(scenes.fourbar())
    r = ref.fourbar_simulate(1.0, 0.0, res.t)
    assert np.max(np.abs(res["crank_probe.angle"] - revolutes["crank_probe.angle"])) < 1e-10
    assert np.max(np.abs(res["crank_probe.angle"] - r["theta"])) < 1e-9


def test_joint_rrr_axis_is_msls_angle_of_frame_ib_relative_to_frame_b():
    """A Position on the JointRRR's axis (its reaction on ``bearing``, MSL's name) turns the
    rocker to the angle it prescribes: MSL's third revolute goes from frame_b (on the
    ground at D) to frame_ib (along the rocker), so its angle is the rocker's, psi, and the
    middle joint sits at D + c (cos psi, sin psi)."""
    m = rrr_fourbar()
    m.components["A"].q0 = None
    m.add(kn.rotational.Position("drive", phi_ref="1.6 + 0.2*sin(3*t)"))
    m.connect("drive.flange", "rrr.axis")
    m.connect("drive.support", "rrr.bearing")
    res = kn.simulate(m, t_end=1.0, n_points=21, rtol=1e-10, atol=1e-12)
    psi = 1.6 + 0.2 * np.sin(3 * res.t)
    np.testing.assert_allclose(res["rocker_probe.angle"], psi, atol=1e-9)
    C_point = np.stack([D + C * np.cos(psi), C * np.sin(psi)], -1)
    np.testing.assert_allclose(res["coupler_point.position"][:, :2], C_point, atol=1e-9)


def test_joint_rrr_round_trips_through_a_file(tmp_path):
    model = rrr_fourbar()
    model.save(tmp_path / "rrr.json")
    again = kn.load(tmp_path / "rrr.json")
    assert again.components["rrr"].type_name == "multibody.JointRRR"
    assert list(again.components) == list(model.components)
    np.testing.assert_array_equal(again.compile(loops="partition").z0, model.compile(loops="partition").z0)


def test_joint_rrr_in_a_subsystem_takes_its_parameters():
    """An aggregate inside a subsystem: its parts read the subsystem's parameters."""
    link = rrr_fourbar()
    link.expose("crank_axis", "A.axis")
    outer = kn.Model("outer", parameters={"coupler": B})
    outer.add(kn.Subsystem("fb", link, params={"b": "coupler"}))
    outer.add(kn.Probe("p", quantities=["angle"]))
    outer.connect("p.port", "fb.crank_axis")
    system = outer.compile(loops="partition")
    assert "fb.rrr.rev1.q" in system.algebraic_names
    np.testing.assert_allclose(system.z0, rrr_fourbar().compile(loops="partition").z0, atol=1e-12)


# -- refusals -----------------------------------------------------------------------------------

def _pendulum_on(rod):
    m = kn.Model("hanging")
    m.add(mb.Ground("ground"))
    m.add(rod)
    m.add(mb.RigidBody("bob", mass=1.0))
    m.connect("ground.frame", f"{rod.name}.frame_a")
    m.connect(f"{rod.name}.frame_b", "bob.frame_a")
    return m


@pytest.mark.parametrize("rod", [mb.SphericalSpherical("rod", length=1.0),
                                 mb.UniversalSpherical("rod")], ids=lambda r: r.type_name)
def test_a_rod_that_closes_no_loop_is_refused(rod):
    with pytest.raises(kn.ModelError, match="rod closes no kinematic loop .* holds only the "
                                            "distance of its frames"):
        _pendulum_on(rod).validate()


def test_two_rods_in_one_loop_are_refused():
    """A point mass between two rods, in one loop: only one of them can close it."""
    model = rod_fourbar("SphericalSpherical")
    model.add(mb.RigidBody("knee", mass=0.1))
    model.add(mb.SphericalSpherical("rod2", length=B / 2))
    model.connect("rod2.frame_a", "crank_mass.frame_a")
    model.connect("rod2.frame_b", "knee.frame_a")
    model.add(mb.SphericalSpherical("rod3", length=B / 2))
    model.connect("rod3.frame_a", "knee.frame_a")
    model.connect("rod3.frame_b", "rocker.frame_b")
    with pytest.raises(kn.ModelError, match="rod[23] closes no kinematic loop"):
        model.validate()


def test_frame_ia_is_for_probes_only():
    model = rod_fourbar("UniversalSpherical")
    model.add(mb.RigidBody("lump", mass=1.0))
    model.connect("rod.frame_ia", "lump.frame_a")
    with pytest.raises(kn.ModelError, match=r"rod.frame_ia is for probes only, but "
                                            r"lump.frame_a is wired to it"):
        model.validate()


def test_a_universal_axis_along_the_rod_is_refused():
    model = rod_fourbar("UniversalSpherical")
    model.components["rod"].n_a = [2, 0, 0]
    with pytest.raises(kn.ModelError, match=r"rod.n_a = \[2.0, 0.0, 0.0\]: lies along the rod"):
        model.validate()


def test_a_rod_of_no_length_is_refused():
    with pytest.raises(kn.ModelError, match="rod.length = 0.0 m: must be > 0"):
        rod_fourbar("SphericalSpherical").components["rod"].length = 0.0


def test_a_joint_rrr_outside_a_loop_is_refused():
    m = kn.Model("arm")
    m.add(mb.Ground("ground"))
    m.add(mb.JointRRR("rrr"))
    m.add(mb.RigidBody("tip", mass=1.0))
    m.connect("ground.frame", "rrr.frame_a")
    m.connect("rrr.frame_b", "tip.frame_a")
    with pytest.raises(kn.ModelError, match="rrr is marked cut but closes no kinematic "
                                            "loop"):
        m.validate()


if __name__ == "__main__":
    for name, coupler in FILES.items():
        path = ROOT / "models" / f"{name}.json"
        msl_fourbar(coupler).save(path)
        print("wrote", path)
